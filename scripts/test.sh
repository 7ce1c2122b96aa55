#!/usr/bin/env bash
# Installs dependencies (with the test-only ones and LLVM 19), builds Simit with its tests and
# the JIT (Release) and runs every test with ctest.
# Extra arguments go to ctest (for example: -L fast, -R lang_corpus). SIMIT_WITH_LLVM=OFF
# builds without the JIT (its tests then do not exist); SIMIT_CMAKE_ARGS adds configure options.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build="${SIMIT_BUILD_DIR:-$SIMIT_ROOT/build}"
llvm="${SIMIT_WITH_LLVM:-ON}"
if [ "$llvm" = ON ]; then ensure_deps --tests --llvm; else ensure_deps --tests; fi
# The DAP client tests' node packages (tests/dap, pinned by its package-lock.json), before the
# configure, which registers those tests only when they are there.
if command -v npm >/dev/null; then
  npm ci --prefix "$SIMIT_ROOT/tests/dap" --no-audit --no-fund
fi
# shellcheck disable=SC2086  # SIMIT_CMAKE_ARGS is a list of options
configure_build "$build" Release -DSIMIT_BUILD_TESTS=ON -DSIMIT_WITH_LLVM="$llvm" ${SIMIT_CMAKE_ARGS:-}
cmake --build "$build" -j2
ctest --test-dir "$build" --output-on-failure -j2 "$@"
