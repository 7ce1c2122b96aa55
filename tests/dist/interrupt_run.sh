#!/usr/bin/env bash
# Ctrl-C on a distributed run: mpirun passes SIGINT to every rank, and the run stops on all of
# them, with a status that is not zero, the frames written so far whole, no temporary file left
# and no rank still running. Usage: interrupt_run.sh SIMIT SCENE WORK MPIRUN ARGS...
set -uo pipefail
simit="$1" scene="$2" work="$3"
shift 3
rm -rf "$work"
mkdir -p "$work"
"$@" "$simit" run --distributed "$scene" --frames 100000 --output "$work/out" \
  > "$work/stdout" 2> "$work/stderr" &
pid=$!
fail() { echo "FAILED: $1"; cat "$work/stderr"; kill -KILL "$pid" 2>/dev/null; exit 1; }
# Frame 1 written: the ranks are in their frames.
for _ in $(seq 1200); do
  [ -e "$work/out/bunny_000001.pvtu" ] && break
  kill -0 "$pid" 2>/dev/null || fail "the run ended before frame 1"
  sleep 0.1
done
[ -e "$work/out/bunny_000001.pvtu" ] || fail "no frame 1 after 120 s"
kill -INT "$pid"
for _ in $(seq 300); do
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
kill -0 "$pid" 2>/dev/null && fail "the ranks still run 30 s after Ctrl-C"
wait "$pid"
status=$?
[ "$status" -ne 0 ] || fail "exit status 0"
pgrep -f -- "--output $work/out" > /dev/null && fail "a rank is still running"
[ -s "$work/out/bunny.pvd" ] || fail "no .pvd"
# An atomic file's temporary: FILE.XXXXXX.
leftovers=$(find "$work/out" -regextype posix-extended -regex '.*\.(vtu|pvtu|pvd)\.[A-Za-z0-9]{6}' | wc -l)
[ "$leftovers" -eq 0 ] || fail "temporary files left: $leftovers"
frames=$(find "$work/out" -name 'bunny_*.pvtu' | wc -l)
echo "ok: exit status $status after Ctrl-C, $frames frames written whole, no rank left"
