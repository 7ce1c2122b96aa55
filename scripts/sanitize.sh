#!/usr/bin/env bash
# Builds Simit with sanitizers (RelWithDebInfo, without the generic twin) and runs tests there;
# the first report stops its test. Extra arguments go to ctest.
#
#   scripts/sanitize.sh [CTEST ARGS]           AddressSanitizer + UndefinedBehaviorSanitizer over
#                                              the whole suite, in build-sanitize (without the
#                                              JIT unless SIMIT_WITH_LLVM=ON: build-sanitize-jit)
#   scripts/sanitize.sh --thread [CTEST ARGS]  ThreadSanitizer, with the JIT, in build-tsan, over
#                                              the threaded tests (thread pool, executors, a
#                                              scene's frame writer, the corpus, random programs
#                                              and examples on 3 threads)
#
# With the JIT only our code is instrumented (LLVM and the compiled kernels are not: two
# kernels' writes are kept apart by construction, and the tests compare every thread count's
# bits with one thread's), and leak checks are off: LLVM keeps process-lifetime allocations.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

if [ "${1:-}" = --thread ]; then
  shift
  build="${SIMIT_SANITIZE_BUILD_DIR:-$SIMIT_ROOT/build-tsan}"
  ensure_deps --tests --llvm
  configure_build "$build" RelWithDebInfo -DSIMIT_BUILD_TESTS=ON -DSIMIT_TSAN=ON \
    -DSIMIT_WITH_LLVM=ON -DSIMIT_GENERIC_TWIN=OFF
  # The threaded tests live in jit_tests and scene_tests and run through simit: only those
  # are built.
  cmake --build "$build" -j2 --target jit_tests scene_tests simit
  export TSAN_OPTIONS="${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1}"
  if [ $# -eq 0 ]; then
    set -- -R "ThreadPool|ParallelFor|ThreadedExecutor|DeferAssembly|PrunedMatrix|Executor\.|FrameWriter|BackgroundFrames|lang_corpus_jit_threads3|jit_agrees_threads3_(fem|springs)"
  fi
  ctest --test-dir "$build" --output-on-failure -j1 "$@"
  exit
fi

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
