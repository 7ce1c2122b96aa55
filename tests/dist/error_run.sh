#!/usr/bin/env bash
# A distributed run that stops in frame 2 on rank 1 alone (scenes/escape.toml: a run-time
# error at the one point the scene marks, which rank 1 owns; scenes/escape_nan.toml: a NaN
# there, which rank 1's finite check finds): every rank stops, the exit status is not zero,
# the message (it contains MESSAGE) is printed once, with the line naming rank 1 as the one
# that stopped the run, and frames 0 and 1 are written whole (each a .pvtu and its pieces),
# nothing after them.
# Usage: error_run.sh SIMIT SCENE WORK MESSAGE MPIRUN ARGS...
set -uo pipefail
simit="$1" scene="$2" work="$3" message="$4"
shift 4
rm -rf "$work"
mkdir -p "$work"
timeout 120 "$@" "$simit" run --distributed "$scene" --output "$work/out" > "$work/stdout" 2> "$work/stderr"
status=$?
fail() { echo "FAILED: $1"; cat "$work/stderr"; exit 1; }
[ "$status" -eq 124 ] && fail "the ranks did not stop (timeout)"
[ "$status" -ne 0 ] || fail "exit status 0"
count=$(grep -cF "$message" "$work/stderr")
[ "$count" -eq 1 ] || fail "the message '$message' printed $count times, not once"
grep -qF "simit: rank 1 of 2 stopped the run" "$work/stderr" || fail "no line naming rank 1"
for f in bunny_000000.pvtu bunny_000001.pvtu bunny_000001_p0.vtu bunny_000001_p1.vtu bunny.pvd; do
  [ -s "$work/out/$f" ] || fail "$f missing"
done
[ -e "$work/out/bunny_000002.pvtu" ] && fail "frame 2 written"
# An atomic file's temporary: FILE.XXXXXX.
leftovers=$(find "$work/out" -regextype posix-extended -regex '.*\.(vtu|pvtu|pvd)\.[A-Za-z0-9]{6}' | wc -l)
[ "$leftovers" -eq 0 ] || fail "temporary files left: $leftovers"
echo "ok: exit status $status, the message printed, frames 0 and 1 written, nothing after"
