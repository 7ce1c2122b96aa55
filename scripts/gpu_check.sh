#!/usr/bin/env bash
# The GPU check: a self-contained bundle built here, run on a machine with an NVIDIA GPU.
#
#   scripts/gpu_check.sh bundle [DIR]   builds simit, gpu_probe, jit_tests (the random
#                                       programs) and the examples' Eigen baselines (Release,
#                                       the JIT with LLVM linked in statically) in
#                                       build-gpu-release, and packs them with every shared
#                                       library they need and the dynamic loader into
#                                       DIR/simit-gpu-bundle.tar.xz (DIR: by default
#                                       build-gpu-bundle); then unpacks it, runs it here in an
#                                       empty environment, checks that each library it loads
#                                       comes from the bundle and reports its sizes
#   scripts/gpu_check.sh run [DIR]      on the GPU machine, in the repository root, with DIR
#                                       there (unpacked into a temporary folder), in order:
#                                       the probe; the language corpus and the fem, springs and
#                                       cloth examples (10 frames) under each executor, final
#                                       positions compared byte for byte with the
#                                       interpreter's; 300 random programs under the GPU
#                                       executor against the interpreter (jit_tests,
#                                       SIMIT_TEST_GPU=1); the benchmark with the GPU executor
#                                       (bench/run_bench.py); the JIT's threads, fem
#                                       dragon160k at 1, 2, 4, ... threads beside the OpenMP
#                                       baseline; then a thin bench/accuracy.py sweep. Writes
#                                       bench/results/gpu_check.md (and a copy
#                                       into $OUT when that is set), rewritten after each step:
#                                       a table of each step's outcome (passed, FAILED or
#                                       skipped, and why), then what each measured. A failing
#                                       step does not stop the later ones; the exit status is
#                                       1 when one failed
#
# run's environment: SIMIT_GPU_CHECK_BUDGET, the seconds the whole run may take (540: a step
# that would start with too little left is skipped, saying so), SIMIT_GPU_CHECK_STEP_LIMIT
# (300, the most one command may take), SIMIT_GPU_CHECK_PROGRAMS, _SEED and _SHARDS (300
# random programs from seed 1 in half as many processes as there are cores, 2 to 8),
# SIMIT_GPU_CHECK_FRAMES and _THREADS (the benchmark's: 4 frames, every core),
# SIMIT_GPU_CHECK_REPORT (the report's path). SIMIT_TEST_GPU_EMULATION=1 runs the GPU steps
# without a GPU, over host memory (a rehearsal of the script; the report says so).
#
# The GPU machine's CPU is not this one: the bundle is built with SIMIT_NATIVE=OFF (plain
# x86-64, which every x86-64 CPU runs; the JIT still compiles for the CPU it runs on). Its C
# library is not known either: the bundle carries its own (libc, libm and the loader) and
# starts each program through that loader, so only the kernel and the NVIDIA driver
# (libcuda.so.1, found in /usr/local/nvidia/lib64, $SIMIT_CUDA_LIB_DIR or through ldconfig)
# come from the machine.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

usage() {
  sed -n '2,/^set /{/^#/p}' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  exit 2
}

# The loader and the glibc libraries carried beside the programs. libdl, libpthread and librt
# are not needed by simit itself, but by the NVIDIA driver it loads: taken from the machine's
# glibc they would not match the carried libc.
GLIBC_EXTRAS=(libdl.so.2 libpthread.so.0 librt.so.1 libm.so.6 libc.so.6)
# The one file of a bundle folder: the bundle, packed.
ARCHIVE=simit-gpu-bundle.tar.xz
# The bundled programs and where the build puts them: simit, the probe, the unit tests of the
# JIT (for the random programs under the GPU executor), the examples' Eigen baselines (the
# benchmark's reference rows) and the STREAM triad (the memory bandwidth at each thread count).
declare -A BUNDLED=(
  [simit]=tools/simit [gpu_probe]=bench/gpu_probe [jit_tests]=tests/jit_tests
  [fem_baseline]=bench/fem_baseline [springs_baseline]=bench/springs_baseline
  [cloth_baseline]=bench/cloth_baseline [stream_triad]=bench/stream_triad
)

# The wrapper that starts bin/NAME through the carried loader and libraries.
write_wrapper() {
  local dir="$1" name="$2"
  cat >"$dir/$name" <<EOF
#!/bin/sh
# Starts bin/$name with the loader and the libraries carried in lib/ (scripts/gpu_check.sh).
# The NVIDIA driver, libcuda.so.1, is the machine's own: its folder comes after lib/.
case "\$0" in */*) here=\${0%/*} ;; *) here=. ;; esac
here=\$(cd "\$here" && pwd)
path=\$here/lib
for d in \${SIMIT_CUDA_LIB_DIR:-} /usr/local/nvidia/lib64 /usr/local/nvidia/lib; do
  if [ -e "\$d/libcuda.so.1" ]; then path=\$path:\$d; break; fi
done
case "\$path" in
  *:*) ;;
  *) for ldconfig in /sbin/ldconfig /usr/sbin/ldconfig; do
       [ -x "\$ldconfig" ] || continue
       lib=\$("\$ldconfig" -p 2>/dev/null | while read -r name rest; do
         [ "\$name" = libcuda.so.1 ] && case "\$rest" in *x86-64*) echo "\${rest##* => }"; break ;; esac
       done)
       [ -n "\$lib" ] && path=\$path:\${lib%/*}
       break
     done ;;
esac
exec "\$here/lib/ld-linux-x86-64.so.2" --library-path "\$path" --argv0 "\$0" "\$here/bin/$name" "\$@"
EOF
  chmod +x "$dir/$name"
}

# The files every library of `ldd BINARY` resolves to, one "SONAME PATH" a line; the loader
# as "ld-linux-x86-64.so.2 PATH".
shared_libraries() {
  ldd "$1" | awk '
    $2 == "=>" && $3 ~ /^\// { print $1, $3 }
    $1 ~ /^\/.*ld-linux/ { print "ld-linux-x86-64.so.2", $1 }'
}

# The newest glibc symbol version BINARY asks for.
newest_glibc() {
  objdump -T "$1" | grep -o 'GLIBC_[0-9][0-9.]*' | sort -uV | tail -1
}

cmd_bundle() {
  local dir build lock
  dir="$(realpath -m "${1:-$SIMIT_ROOT/build-gpu-bundle}")"
  build="${SIMIT_GPU_BUILD_DIR:-$SIMIT_ROOT/build-gpu-release}"
  lock="${SIMIT_BUILD_LOCK:-/tmp/simit-build.lock}"
  [ "$(uname -m)" = x86_64 ] || {
    echo "gpu_check: the GPU machine is x86-64; this machine is $(uname -m)" >&2
    exit 1
  }
  echo "gpu_check: configuring $build"
  # libstdc++ and libgcc stay shared, carried like the rest: the shared libraries simit needs
  # (toml++, tinyobjloader, libgfortran under LAPACK) load them anyway, and a static copy in
  # simit (whose symbols it exports, for the JIT) would make two of each in the process.
  # Tests and benchmarks are configured, but only the bundled targets are built.
  configure_build "$build" Release -DSIMIT_WITH_LLVM=ON -DSIMIT_NATIVE=OFF \
    -DSIMIT_BUILD_TESTS=ON -DSIMIT_PYTHON=OFF -DSIMIT_BUILD_BENCH=ON \
    -DCMAKE_EXE_LINKER_FLAGS="" >/dev/null
  local name targets=()
  for name in "${!BUNDLED[@]}"; do targets+=(--target "$name"); done
  echo "gpu_check: building ${!BUNDLED[*]} (under $lock)"
  flock "$lock" cmake --build "$build" -j2 "${targets[@]}"
  for name in simit jit_tests; do
    if ldd "$build/${BUNDLED[$name]}" | grep -q 'libLLVM'; then
      echo "gpu_check: $name links the shared libLLVM (zstd's development files missing?);" \
        "the bundle needs LLVM linked in statically" >&2
      exit 1
    fi
  done

  # The bundle is assembled unpacked in the build folder, then packed: xz brings its ~60 MiB
  # of code and libraries to a fraction, and the repository's own files travel beside it
  # within the same 64 MiB.
  local stage="$build/bundle"
  echo "gpu_check: assembling $stage"
  rm -rf "${stage:?}"
  mkdir -p "$stage/bin" "$stage/lib"
  for name in "${!BUNDLED[@]}"; do
    strip -o "$stage/bin/$name" "$build/${BUNDLED[$name]}"
    write_wrapper "$stage" "$name"
  done
  local soname path
  while read -r soname path; do
    [ -e "$stage/lib/$soname" ] || cp -L "$path" "$stage/lib/$soname"
  done < <(for name in "${!BUNDLED[@]}"; do shared_libraries "$build/${BUNDLED[$name]}"; done |
    sort -u)
  local libc_dir
  libc_dir="$(dirname "$(awk '$1 == "libc.so.6" { print $2 }' < <(shared_libraries \
    "$build/tools/simit"))")"
  for soname in "${GLIBC_EXTRAS[@]}"; do
    [ -e "$stage/lib/$soname" ] || cp -L "$libc_dir/$soname" "$stage/lib/$soname"
  done
  chmod -R u+w "$stage/lib"

  echo "gpu_check: packing $dir/$ARCHIVE"
  mkdir -p "$dir"
  tar -C "$stage" -cf - . | xz -9 -T2 >"$dir/$ARCHIVE.tmp"
  mv "$dir/$ARCHIVE.tmp" "$dir/$ARCHIVE"
  check_bundle "$dir" "$(du -sb "$stage" | cut -f1)"
}

# unpack_bundle ARCHIVE DEST: with xz where the machine has it, else with Python's tarfile.
unpack_bundle() {
  rm -rf "${2:?}"
  mkdir -p "$2"
  if command -v xz >/dev/null; then
    xz -dc "$1" | tar -x -C "$2"
  elif command -v python3 >/dev/null; then
    python3 -c 'import sys, tarfile; tarfile.open(sys.argv[1]).extractall(sys.argv[2])' "$1" "$2"
  else
    echo "gpu_check: neither xz nor python3 here to unpack $1" >&2
    return 1
  fi
}

# only_bundle_libraries LD_DEBUG_LOG PROGRAM BUNDLE: fails naming every library PROGRAM loaded
# from outside BUNDLE/lib (an LD_DEBUG=libs log).
only_bundle_libraries() {
  local foreign
  foreign="$(grep -o 'calling init: .*' "$1" | sed 's/calling init: //' |
    grep -v "^$3/lib/" || true)"
  if [ -n "$foreign" ]; then
    echo "gpu_check: $2 loads libraries from outside the bundle's lib/:" >&2
    echo "$foreign" >&2
    exit 1
  fi
}

# The bundle unpacked from DIR's archive and run here with an empty environment: each library
# loaded must come from its lib/. (A subshell: its temporary folder goes when it ends.)
check_bundle() (
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' EXIT
  echo "gpu_check: checking the bundle, unpacked, in an empty environment"
  unpack_bundle "$1/$ARCHIVE" "$tmp/bundle"
  dir="$tmp/bundle"
  # Through the loader itself, as the wrapper starts it: LD_DEBUG would list the wrapper's
  # shell's libraries too.
  (cd "$SIMIT_ROOT" && env -i LD_DEBUG=libs "$dir/lib/ld-linux-x86-64.so.2" --library-path \
    "$dir/lib" "$dir/bin/simit" test tests/lang/functions.sim >"$tmp/test.out" 2>"$tmp/test.err") || {
    cat "$tmp/test.out" "$tmp/test.err" >&2
    echo "gpu_check: the bundle's simit test failed" >&2
    exit 1
  }
  only_bundle_libraries "$tmp/test.err" simit "$dir"
  echo "  simit test tests/lang/functions.sim: $(tail -1 "$tmp/test.out");" \
    "$(grep -c 'calling init: ' "$tmp/test.err") libraries loaded, all from the bundle's lib/"
  (cd "$SIMIT_ROOT" && env -i "$dir/simit" run examples/fem/bunny.toml --executor jit \
    --frames 2 --jit-cache off --output "$tmp/fem" --final-csv "$tmp/fem.csv" >"$tmp/run.out") || {
    cat "$tmp/run.out" >&2
    echo "gpu_check: the bundle's simit run failed" >&2
    exit 1
  }
  echo "  simit run examples/fem/bunny.toml --executor jit --frames 2: $(wc -l <"$tmp/fem.csv")" \
    "final positions"
  status=0
  env -i "$dir/gpu_probe" --launches 10 --graph-kernels 10 --copy-mib 1 --reps 1 \
    >"$tmp/probe.out" 2>&1 || status=$?
  case "$status" in
    0) echo "  gpu_probe: measured a GPU here" ;;
    77) echo "  gpu_probe: exit 77 here: $(head -1 "$tmp/probe.out")" ;;
    *)
      cat "$tmp/probe.out" >&2
      echo "gpu_check: the bundle's gpu_probe exited $status" >&2
      exit 1
      ;;
  esac
  # The random programs' runner, through the loader as above (its libraries checked too):
  # three programs under the JIT, then SIMIT_TEST_GPU=1, which fails where there is no GPU.
  (cd "$SIMIT_ROOT" && env -i LD_DEBUG=libs SIMIT_RANDOM_PROGRAMS=3 \
    "$dir/lib/ld-linux-x86-64.so.2" --library-path "$dir/lib" "$dir/bin/jit_tests" \
    --gtest_filter='RandomPrograms.*' >"$tmp/random.out" 2>"$tmp/random.err") || {
    cat "$tmp/random.out" "$tmp/random.err" >&2
    echo "gpu_check: the bundle's jit_tests failed" >&2
    exit 1
  }
  only_bundle_libraries "$tmp/random.err" jit_tests "$dir"
  echo "  jit_tests: $(grep -m1 ' programs from seed ' "$tmp/random.out" | cut -d: -f1)" \
    "under the JIT; its libraries all from the bundle's lib/"
  status=0
  env -i SIMIT_TEST_GPU=1 SIMIT_RANDOM_PROGRAMS=3 "$dir/jit_tests" \
    --gtest_filter='RandomPrograms.*' >"$tmp/random_gpu.out" 2>&1 || status=$?
  if [ "$status" = 0 ]; then
    echo "  jit_tests with SIMIT_TEST_GPU=1: $(grep -m1 ' programs from seed ' \
      "$tmp/random_gpu.out" | cut -d: -f1) on the GPU here"
  elif grep -q 'SIMIT_TEST_GPU=1 asks for the GPU executor' "$tmp/random_gpu.out"; then
    echo "  jit_tests with SIMIT_TEST_GPU=1 fails here, as it should without a GPU:" \
      "$(grep -m1 -o 'no GPU to run on.*' "$tmp/random_gpu.out")"
  else
    cat "$tmp/random_gpu.out" >&2
    echo "gpu_check: the bundle's jit_tests with SIMIT_TEST_GPU=1 exited $status" >&2
    exit 1
  fi
  for name in fem springs cloth; do
    input=examples/data/bunny.1.node
    [ "$name" = cloth ] && input=8
    (cd "$SIMIT_ROOT" && env -i "$dir/${name}_baseline" "$input" 1 >"$tmp/$name.out" 2>&1) || {
      cat "$tmp/$name.out" >&2
      echo "gpu_check: the bundle's ${name}_baseline failed" >&2
      exit 1
    }
  done
  echo "  fem, springs and cloth baselines: one frame each"
  echo "  newest glibc symbol asked for: $(newest_glibc "$dir/bin/simit") (simit)," \
    "$(newest_glibc "$dir/bin/jit_tests") (jit_tests)," \
    "$(newest_glibc "$dir/bin/gpu_probe") (gpu_probe); glibc $(ldd --version |
      head -1 | awk '{ print $NF }') carried"
  echo "  unpacked sizes: $(cd "$dir" && du -b bin/* | sort -rn |
    awk '{ printf "%s%s %.1f MiB", sep, substr($2, 5), $1 / 1048576; sep = ", " }'),"\
    "lib/ $(du -sb "$dir/lib" | awk '{ printf "%.1f MiB", $1 / 1048576 }')"
  size="$(stat -c %s "$1/$ARCHIVE")"
  tree="$(cd "$SIMIT_ROOT" && git ls-files -z --cached --others --exclude-standard |
    xargs -0 stat -c %s 2>/dev/null | awk '{ s += $1 } END { print s + 0 }')"
  mib() { awk -v b="$1" 'BEGIN { printf "%.1f MiB", b / 1048576 }'; }
  echo "  bundle: $(mib "$2") unpacked, $(mib "$size") packed ($1/$ARCHIVE);" \
    "with the repository's files ($(mib "$tree")) $(mib $((size + tree))) travel"
  if [ $((size + tree)) -gt $((64 * 1048576)) ]; then
    echo "gpu_check: over the 64 MiB that may travel to the GPU machine" >&2
    exit 1
  fi
  echo "  room left of the 64 MiB: $(mib $((64 * 1048576 - size - tree)))"
  echo "gpu_check: bundle ready: $1 (carry it to the GPU machine; run it there with" \
    "scripts/gpu_check.sh run ${1#"$SIMIT_ROOT"/})"
)

# ---- run

log() { echo "gpu_check: $*" >&2; }

# True when `simit SUBCOMMAND --help` lists gpu among --executor's values.
has_gpu_executor() {
  local values
  values="$("$SIMIT" "$1" --help 2>/dev/null | awk '$1 ~ /^--executor/ { print $2; exit }')" ||
    true
  case "|$values|" in *"|gpu|"*) return 0 ;; esac
  return 1
}

# seconds since the epoch with nanoseconds, for timing steps.
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f s", b - a }'; }
# Whole seconds left of the run's budget (SIMIT_GPU_CHECK_BUDGET from the start).
time_left() { echo $((DEADLINE - $(date +%s))); }

# Runs a step's command with a time limit: STEP_LIMIT, or less when the run's budget has less
# left (with coreutils' timeout, which stops the command's whole process group).
limited() {
  local limit left
  limit="$STEP_LIMIT"
  left="$(time_left)"
  [ "$left" -lt "$limit" ] && limit="$left"
  [ "$limit" -lt 1 ] && limit=1
  if command -v timeout >/dev/null; then timeout "$limit" "$@"; else "$@"; fi
}

# Exit status of `timeout` when it stopped the command.
timed_out_note() { if [ "$1" = 124 ]; then echo " (stopped by the time limit)"; fi; }

# record STEP OUTCOME WHAT: one line of the report's summary (passed, FAILED or skipped, and
# why); a failure fails the run. The report is rewritten after each step, so that a run
# stopped from outside still leaves what it measured.
record() {
  echo "| $1 | $2 | ${*:3} |" >>"$SUMMARY"
  [ "$2" = FAILED ] && FAILED=1
  CURRENT=""
  log "  => $2: ${*:3}"
  write_report
}

# record_problems STEP WHAT [PROBLEM...]: the step passed (WHAT) when no problem is given,
# else it FAILED with the problems, separated by semicolons.
record_problems() {
  local name="$1" what="$2"
  shift 2
  if [ $# = 0 ]; then
    record "$name" passed "$what"
  else
    record "$name" FAILED "$(
      IFS=';'
      echo "$*"
    )"
  fi
}

# A step that has less than MIN seconds of the budget left is skipped: true when skipped.
out_of_time() {
  local left
  left="$(time_left)"
  [ "$left" -ge "$2" ] && return 1
  record "$1" skipped "the run's time budget (SIMIT_GPU_CHECK_BUDGET=$BUDGET s) has ${left} s left"
  return 0
}

# The report: the GPU, the summary of the steps so far (and the one under way, which a run
# stopped from outside never finished), then their sections.
write_report() {
  local gpu="$GPU_NAME" cuda
  [ -n "$gpu" ] || gpu="$(sed -n 's/^| device [0-9]* | \(.*\) |$/\1/p' "$WORK/probe.md" \
    2>/dev/null | head -1 || true)"
  cuda="$(sed -n 's/^| driver | \(.*\) |$/\1/p' "$WORK/probe.md" 2>/dev/null | head -1 || true)"
  mkdir -p "$(dirname "$REPORT")"
  {
    echo "# GPU check"
    echo
    echo "GPU: ${gpu:-none found}; driver ${GPU_DRIVER:-not reported}${cuda:+ ($cuda)}"
    echo
    if [ "$EMULATED" = 1 ]; then
      echo "**Emulated** (SIMIT_TEST_GPU_EMULATION=1): the GPU executor's data path ran over" \
        "host memory with the CPU's kernels; no GPU was used, and its times say nothing of one."
      echo
    fi
    echo "Run $(date -u '+%Y-%m-%d %H:%M UTC') on $(nproc) cores by scripts/gpu_check.sh run" \
      "(budget $BUDGET s, $(elapsed "$STARTED") used);" \
      "${VERSION:-simit did not start}; commit $(git rev-parse --short HEAD 2>/dev/null ||
        echo unknown). Result: $([ "$FAILED" = 0 ] && echo 'no step failed' || echo 'FAILURES')."
    echo
    echo "| step | outcome | what |"
    echo "| --- | --- | --- |"
    cat "$SUMMARY"
    [ -z "$CURRENT" ] || echo "| $CURRENT | not finished | under way when this was written |"
    echo
    cat "$BODY"
  } >"$REPORT.tmp"
  mv "$REPORT.tmp" "$REPORT"
  if [ -n "${OUT:-}" ] && [ -d "$OUT" ]; then cp "$REPORT" "$OUT/"; fi
}

STEPS=8
step() {
  log "[$1/$STEPS] $2"
  CURRENT="$2"
  write_report
}

# The steps (run_probe ... run_accuracy).
source "$(dirname "${BASH_SOURCE[0]}")/gpu_check_steps.sh"

cmd_run() {
  DIR="$(realpath -m "${1:-$SIMIT_ROOT/build-gpu-bundle}")"
  STEP_LIMIT="${SIMIT_GPU_CHECK_STEP_LIMIT:-300}"
  BUDGET="${SIMIT_GPU_CHECK_BUDGET:-540}"
  STARTED="$(now)"
  DEADLINE=$(($(date +%s) + BUDGET))
  REPORT="${SIMIT_GPU_CHECK_REPORT:-$SIMIT_ROOT/bench/results/gpu_check.md}"
  EMULATED=0
  if [ -n "${SIMIT_TEST_GPU_EMULATION:-}" ] && [ "$SIMIT_TEST_GPU_EMULATION" != 0 ]; then
    EMULATED=1
  fi
  WORK="$(mktemp -d)" # global: the EXIT trap runs after this function's locals are gone
  trap 'rm -rf "$WORK"' EXIT
  cd "$SIMIT_ROOT"
  BODY="$WORK/body.md"
  SUMMARY="$WORK/summary.md"
  FAILED=0
  CURRENT=""
  VERSION=""
  # The GPU and its driver head the report: from nvidia-smi, else from the probe's table.
  GPU_NAME="$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1 || true)"
  GPU_DRIVER="$(nvidia-smi --query-gpu=driver_version --format=csv,noheader 2>/dev/null |
    head -1 || true)"
  : >"$BODY"
  : >"$SUMMARY"

  step 1 "the bundle starts here"
  # DIR holds the packed bundle (what `bundle` makes), or is an unpacked one.
  if [ -f "$DIR/$ARCHIVE" ]; then
    log "  unpacking $DIR/$ARCHIVE"
    if ! unpack_bundle "$DIR/$ARCHIVE" "$WORK/bundle"; then
      record "bundle" FAILED "$DIR/$ARCHIVE does not unpack"
      exit 1
    fi
    DIR="$WORK/bundle"
  fi
  SIMIT="$DIR/simit"
  if [ ! -x "$SIMIT" ] || [ ! -x "$DIR/bin/simit" ]; then
    record "bundle" FAILED "no bundle in $DIR (scripts/gpu_check.sh bundle makes one)"
    exit 1
  fi
  if VERSION="$("$SIMIT" --version 2>&1)"; then
    record "bundle" passed "$VERSION starts"
  else
    record "bundle" FAILED "the bundle's simit does not start: $VERSION"
    VERSION=""
  fi

  run_probe

  # The interpreter, the JIT (the bundle's code generation on this machine's CPU) and, where
  # there is one (or emulated), the GPU executor.
  EXECUTORS=(interpreter jit)
  TEST_EXECUTORS=(interpreter jit)
  GPU_NOTE=""
  # GPU_WHY: why the GPU steps are skipped, in the summary; GPU_NOTE: the same in a section.
  GPU_WHY=""
  if ! has_gpu_executor run; then
    GPU_WHY="this simit has no GPU executor (simit run --help lists no gpu)"
    GPU_NOTE="The GPU executor is not built yet (simit run --help lists no gpu among --executor's values): its steps are skipped."
  elif [ "$PROBE_STATUS" = 77 ] && [ "$EMULATED" = 0 ]; then
    GPU_WHY="no GPU here: $(grep -m1 . "$WORK/probe.md" | sed 's/^No GPU probed: //' || true)"
    GPU_NOTE="The GPU executor's steps are skipped: $GPU_WHY (gpu_probe)."
  else
    EXECUTORS+=(gpu)
    has_gpu_executor test && TEST_EXECUTORS+=(gpu)
  fi
  [ -z "$GPU_NOTE" ] || log "  $GPU_NOTE"
  [ "$EMULATED" = 0 ] || log "  emulated: SIMIT_TEST_GPU_EMULATION=1, no GPU is used"

  run_corpus
  run_examples
  run_random_programs
  run_benchmark
  run_thread_scaling
  run_accuracy

  write_report
  log "report: $REPORT"
  [ -n "${OUT:-}" ] && [ -d "$OUT" ] && log "copied to $OUT/$(basename "$REPORT")"
  return "$FAILED"
}

case "${1:-}" in
  bundle) shift && cmd_bundle "$@" ;;
  run) shift && cmd_run "$@" ;;
  *) usage ;;
esac
