#!/usr/bin/env bash
# What the interpreter's statement trap point costs when nothing is armed (no breakpoint, no
# debugger): the fem example on the bunny, interpreter milliseconds per frame, in a build with
# the trap point (SIMIT_STATEMENT_HOOK=ON) against one without it (OFF). The two builds run
# alternately, round after round, so that a change in the machine's load hits both; it prints
# the medians of each run's CPU time (the steadier figure on a shared machine) and of every
# frame's wall time. A benchmark, not a test.
#
#   bench/hook_overhead.sh [ROUNDS [FRAMES]]        (default 5 rounds of 3 frames per build)
#
# Build folders: $HOOK_ON_BUILD and $HOOK_OFF_BUILD (default build-hook-on, build-hook-off);
# an existing folder keeps its other settings and only gets SIMIT_STATEMENT_HOOK set.
# With COUNT_INSTRUCTIONS=1 (needs valgrind) it also counts the instructions of one run of one
# frame per build under cachegrind: a figure the machine's load does not disturb.
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
  ninja -C "$1" -j "${JOBS:-$(nproc)}" simit >/dev/null
}
build "$ON_DIR" ON
build "$OFF_DIR" OFF

python3 - "$ON_DIR/tools/simit" "$OFF_DIR/tools/simit" "$SCENE" "$ROUNDS" "$FRAMES" <<'PY'
import csv, os, resource, statistics, subprocess, sys, tempfile

on_bin, off_bin, scene, rounds, frames = sys.argv[1:6]
rounds, frames = int(rounds), int(frames)
cpu = {"on": [], "off": []}   # CPU seconds of a whole run (user + system)
wall = {"on": [], "off": []}  # ms of every frame (the scene's CSV)
with tempfile.TemporaryDirectory() as work:
    def run(name):
        out = os.path.join(work, name)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([on_bin if name == "on" else off_bin, "run", scene, "--frames", str(frames),
                        "--output", out], check=True, stdout=subprocess.DEVNULL)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu[name].append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        with open(os.path.join(out, "bunny_stats.csv")) as f:
            wall[name] += [float(row["ms"]) for row in csv.DictReader(f)]
    for r in range(rounds):
        for name in (("on", "off") if r % 2 == 0 else ("off", "on")):
            run(name)
        print(f"round {r + 1}/{rounds} done", file=sys.stderr)

def line(what, on, off, unit):
    m_on, m_off = statistics.median(on), statistics.median(off)
    print(f"{what}: compiled in {m_on:.3f} {unit}, compiled out {m_off:.3f} {unit}, "
          f"overhead {100.0 * (m_on / m_off - 1.0):+.2f}% (medians; minima "
          f"{100.0 * (min(on) / min(off) - 1.0):+.2f}%)")

print(f"fem on the bunny, {rounds} runs of {frames} frames per build, alternating")
line("CPU time per run (parse, meshes, init and frames)", cpu["on"], cpu["off"], "s")
line("wall time per frame", wall["on"], wall["off"], "ms")
PY

if [ "${COUNT_INSTRUCTIONS:-0}" = 1 ]; then
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  for b in on off; do
    dir=$ON_DIR
    [ $b = off ] && dir=$OFF_DIR
    valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null \
      "$dir/tools/simit" run "$SCENE" --frames 1 --output "$work/$b" 2>"$work/$b.log" >/dev/null
    sed -n 's/.*I *refs: *//p' "$work/$b.log" | tr -d , >"$work/$b.ir"
  done
  python3 -c "import sys; on, off = (int(open(f).read()) for f in sys.argv[1:3]); print(f'instructions of one run of 1 frame: compiled in {on:,}, compiled out {off:,}, overhead {100.0 * (on / off - 1.0):+.3f}%')" "$work/on.ir" "$work/off.ir"
fi
