#!/usr/bin/env bash
# A run-time error in a distributed run (scenes/escape.toml: frame 2 fails on whichever rank
# holds the first point to pass x = 1.3): every rank stops, the exit status is not zero, the
# program's message is printed, and frames 0 and 1 are written whole, nothing after them.
# Usage: error_run.sh SIMIT SCENE WORK MPIRUN ARGS...
set -uo pipefail
simit="$1" scene="$2" work="$3"
shift 3
rm -rf "$work"
mkdir -p "$work"
timeout 120 "$@" "$simit" run --distributed "$scene" --output "$work/out" > "$work/stdout" 2> "$work/stderr"
status=$?
fail() { echo "FAILED: $1"; cat "$work/stderr"; exit 1; }
[ "$status" -eq 124 ] && fail "the ranks did not stop (timeout)"
[ "$status" -ne 0 ] || fail "exit status 0"
grep -q "runtime error: point left the box at x = " "$work/stderr" || fail "no error message"
grep -q "mapping over element [0-9]* of set 'points'" "$work/stderr" || fail "no element named"
for f in bunny_000000.vtu bunny_000001.vtu bunny.pvd; do
  [ -s "$work/out/$f" ] || fail "$f missing"
done
[ -e "$work/out/bunny_000002.vtu" ] && fail "frame 2 written"
leftovers=$(find "$work/out" -name '*.tmp*' | wc -l)
[ "$leftovers" -eq 0 ] || fail "temporary files left: $leftovers"
echo "ok: exit status $status, the error printed, frames 0 and 1 written, nothing after"
