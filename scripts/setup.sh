#!/usr/bin/env bash
# Quick start: installs dependencies, builds Simit (Release) and runs the main job, which
# checks every example program (until the interpreter exists).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build="${SIMIT_BUILD_DIR:-$SIMIT_ROOT/build}"
ensure_deps
configure_build "$build" Release
cmake --build "$build" -j2 --target simit
mapfile -d '' programs < <(example_programs)
"$build/tools/simit" check "${programs[@]}"
echo "setup: ${#programs[@]} example program(s) check clean; the command is $build/tools/simit"
