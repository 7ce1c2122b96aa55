#!/usr/bin/env bash
# Quick start: installs dependencies, builds Simit (Release), checks every example program
# and runs the main job: the fem example on the bunny (FRAMES frames, default 10), written as
# a ParaView series into build/fem-bunny/.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build="${SIMIT_BUILD_DIR:-$SIMIT_ROOT/build}"
ensure_deps --llvm
configure_build "$build" Release -DSIMIT_WITH_LLVM=ON
cmake --build "$build" -j2 --target simit
mapfile -d '' programs < <(example_programs)
"$build/tools/simit" check "${programs[@]}"
echo "setup: ${#programs[@]} example program(s) check clean"
"$build/tools/simit" run "$SIMIT_ROOT/examples/fem/bunny.toml" --frames "${FRAMES:-10}" \
  --output "$build/fem-bunny" --backend jit
echo "setup: open $build/fem-bunny/bunny.pvd in ParaView (bunny.png beside it is a picture of"
echo "setup: the last frame); the command is $build/tools/simit"
