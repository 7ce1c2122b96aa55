#!/usr/bin/env bash
# What the interpreter's statement trap point costs when nothing is armed (no breakpoint, no
# debugger): the fem example on the bunny, interpreter milliseconds per frame, in a build with
# the trap point (SIMIT_STATEMENT_HOOK=ON) against one without it (OFF). The two builds run
# alternately, round after round, so that a change in the machine's load hits both; the
# medians of every frame's time are compared. A benchmark, not a test.
#
#   bench/hook_overhead.sh [ROUNDS [FRAMES]]        (default 5 rounds of 3 frames per build)
#
# Build folders: $HOOK_ON_BUILD and $HOOK_OFF_BUILD (default build-hook-on, build-hook-off);
# an existing folder keeps its other settings and only gets SIMIT_STATEMENT_HOOK set.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../scripts/common.sh"

ROUNDS=${1:-5}
FRAMES=${2:-3}
ON_DIR=${HOOK_ON_BUILD:-$SIMIT_ROOT/build-hook-on}
OFF_DIR=${HOOK_OFF_BUILD:-$SIMIT_ROOT/build-hook-off}
SCENE=$SIMIT_ROOT/examples/fem/bunny.toml

build() {  # build DIR ON|OFF
  if [ -f "$1/CMakeCache.txt" ]; then
    cmake "$1" -DSIMIT_STATEMENT_HOOK="$2" >/dev/null
  else
    configure_build "$1" Release -DSIMIT_BUILD_TESTS=OFF -DSIMIT_STATEMENT_HOOK="$2" >/dev/null
  fi
  ninja -C "$1" simit >/dev/null
}
build "$ON_DIR" ON
build "$OFF_DIR" OFF

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
run() {  # run on|off: appends one line per frame (ms) to $work/NAME.ms
  local bin=$ON_DIR/tools/simit
  [ "$1" = off ] && bin=$OFF_DIR/tools/simit
  rm -rf "$work/out"
  "$bin" run "$SCENE" --frames "$FRAMES" --output "$work/out" >/dev/null
  tail -n +2 "$work/out/bunny_stats.csv" | cut -d, -f3 >>"$work/$1.ms"
}
for ((r = 1; r <= ROUNDS; r++)); do
  if ((r % 2)); then run on; run off; else run off; run on; fi
  echo "round $r/$ROUNDS done" >&2
done

python3 - "$work/on.ms" "$work/off.ms" <<'PY'
import statistics, sys
on = [float(x) for x in open(sys.argv[1])]
off = [float(x) for x in open(sys.argv[2])]
m_on, m_off = statistics.median(on), statistics.median(off)
print(f"fem on the bunny, {len(on)} frames per build")
print(f"trap point compiled in (no hook armed): median {m_on:.1f} ms/frame (min {min(on):.1f})")
print(f"trap point compiled out:                median {m_off:.1f} ms/frame (min {min(off):.1f})")
print(f"overhead: {100.0 * (m_on / m_off - 1.0):+.2f}% (medians), {100.0 * (min(on) / min(off) - 1.0):+.2f}% (minima)")
PY
