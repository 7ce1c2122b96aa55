#!/usr/bin/env bash
# Builds Simit with AddressSanitizer and UndefinedBehaviorSanitizer (RelWithDebInfo, without
# the JIT and the generic twin) in BUILD (default build-sanitize) and runs the whole ctest
# suite there; the first report stops its test. Extra arguments go to ctest.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build="${SIMIT_SANITIZE_BUILD_DIR:-$SIMIT_ROOT/build-sanitize}"
ensure_deps --tests
configure_build "$build" RelWithDebInfo -DSIMIT_BUILD_TESTS=ON -DSIMIT_SANITIZE=ON \
  -DSIMIT_WITH_LLVM=OFF -DSIMIT_GENERIC_TWIN=OFF
cmake --build "$build" -j2
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
ctest --test-dir "$build" --output-on-failure -j2 "$@"
