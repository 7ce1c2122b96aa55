#!/usr/bin/env bash
# Installs dependencies (with the test-only ones), builds Simit with its tests (Release) and runs
# every test with ctest.
# Extra arguments go to ctest (for example: -L fast, -R lang_corpus).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build="${SIMIT_BUILD_DIR:-$SIMIT_ROOT/build}"
ensure_deps --tests
configure_build "$build" Release -DSIMIT_BUILD_TESTS=ON
cmake --build "$build" -j2
ctest --test-dir "$build" --output-on-failure -j2 "$@"
