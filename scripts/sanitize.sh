#!/usr/bin/env bash
# Builds Simit with AddressSanitizer and UndefinedBehaviorSanitizer (RelWithDebInfo, without
# the generic twin, and without the JIT unless SIMIT_WITH_LLVM=ON) in BUILD (default
# build-sanitize, build-sanitize-jit with the JIT) and runs the whole ctest suite there; the
# first report stops its test. Extra arguments go to ctest. With the JIT only our code is
# instrumented (LLVM and the compiled kernels are not), and leak checks are off: LLVM keeps
# process-lifetime allocations.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

llvm="${SIMIT_WITH_LLVM:-OFF}"
if [ "$llvm" = ON ]; then
  build="${SIMIT_SANITIZE_BUILD_DIR:-$SIMIT_ROOT/build-sanitize-jit}"
  ensure_deps --tests --llvm
  leaks=0
else
  build="${SIMIT_SANITIZE_BUILD_DIR:-$SIMIT_ROOT/build-sanitize}"
  ensure_deps --tests
  leaks=1
fi
configure_build "$build" RelWithDebInfo -DSIMIT_BUILD_TESTS=ON -DSIMIT_SANITIZE=ON \
  -DSIMIT_WITH_LLVM="$llvm" -DSIMIT_GENERIC_TWIN=OFF
cmake --build "$build" -j2
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=$leaks:strict_string_checks=1:detect_stack_use_after_return=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
ctest --test-dir "$build" --output-on-failure -j2 "$@"
