#!/usr/bin/env bash
# The GPU check: a self-contained bundle built here, run on a machine with an NVIDIA GPU.
#
#   scripts/gpu_check.sh bundle [DIR]   builds simit and gpu_probe (Release, the JIT with LLVM
#                                       linked in statically) in build-gpu-release, and packs
#                                       them with every shared library they need and the dynamic
#                                       loader into DIR/simit-gpu-bundle.tar.xz (DIR: by default
#                                       build-gpu-bundle); then unpacks it, runs it here in an
#                                       empty environment and checks that each library it loads
#                                       comes from the bundle
#   scripts/gpu_check.sh run [DIR]      on the GPU machine, in the repository root, with DIR
#                                       there (unpacked into a temporary folder): the probe,
#                                       the language corpus and the fem, springs and cloth
#                                       examples (10 frames) under each executor, final
#                                       positions compared byte for byte with the interpreter's;
#                                       writes bench/results/gpu_check.md (and a copy into $OUT
#                                       when that is set)
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
  sed -n '2,/^$/p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  exit 2
}

# The loader and the glibc libraries carried beside the programs. libdl, libpthread and librt
# are not needed by simit itself, but by the NVIDIA driver it loads: taken from the machine's
# glibc they would not match the carried libc.
GLIBC_EXTRAS=(libdl.so.2 libpthread.so.0 librt.so.1 libm.so.6 libc.so.6)
# The one file of a bundle folder: the bundle, packed.
ARCHIVE=simit-gpu-bundle.tar.xz

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
  configure_build "$build" Release -DSIMIT_WITH_LLVM=ON -DSIMIT_NATIVE=OFF \
    -DSIMIT_BUILD_TESTS=OFF -DSIMIT_PYTHON=OFF -DSIMIT_BUILD_BENCH=OFF \
    -DCMAKE_EXE_LINKER_FLAGS="" >/dev/null
  echo "gpu_check: building simit and gpu_probe (under $lock)"
  flock "$lock" cmake --build "$build" -j2 --target simit gpu_probe
  local exe probe
  exe="$build/tools/simit"
  probe="$build/bench/gpu_probe"
  if ldd "$exe" | grep -q 'libLLVM'; then
    echo "gpu_check: $exe links the shared libLLVM (zstd's development files missing?); the" \
      "bundle needs LLVM linked in statically" >&2
    exit 1
  fi

  # The bundle is assembled unpacked in the build folder, then packed: xz brings its ~60 MiB
  # of code and libraries to a fraction, and the repository's own files travel beside it
  # within the same 64 MiB.
  local stage="$build/bundle"
  echo "gpu_check: assembling $stage"
  rm -rf "${stage:?}"
  mkdir -p "$stage/bin" "$stage/lib"
  strip -o "$stage/bin/simit" "$exe"
  strip -o "$stage/bin/gpu_probe" "$probe"
  local soname path
  while read -r soname path; do
    [ -e "$stage/lib/$soname" ] || cp -L "$path" "$stage/lib/$soname"
  done < <({
    shared_libraries "$exe"
    shared_libraries "$probe"
  } | sort -u)
  local libc_dir
  libc_dir="$(dirname "$(awk '$1 == "libc.so.6" { print $2 }' < <(shared_libraries "$exe"))")"
  for soname in "${GLIBC_EXTRAS[@]}"; do
    [ -e "$stage/lib/$soname" ] || cp -L "$libc_dir/$soname" "$stage/lib/$soname"
  done
  chmod -R u+w "$stage/lib"
  write_wrapper "$stage" simit
  write_wrapper "$stage" gpu_probe

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
  foreign="$(grep -o 'calling init: .*' "$tmp/test.err" | sed 's/calling init: //' |
    grep -v "^$dir/lib/" || true)"
  if [ -n "$foreign" ]; then
    echo "gpu_check: libraries loaded from outside the bundle's lib/:" >&2
    echo "$foreign" >&2
    exit 1
  fi
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
  echo "  newest glibc symbol asked for: $(newest_glibc "$dir/bin/simit") (simit)," \
    "$(newest_glibc "$dir/bin/gpu_probe") (gpu_probe); glibc $(ldd --version |
      head -1 | awk '{ print $NF }') carried"
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

# seconds since the epoch with milliseconds, for timing steps.
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f s", b - a }'; }

# Runs a step with a time limit (when coreutils' timeout is there).
limited() {
  if command -v timeout >/dev/null; then timeout "$STEP_LIMIT" "$@"; else "$@"; fi
}

cmd_run() {
  local dir
  dir="$(realpath -m "${1:-$SIMIT_ROOT/build-gpu-bundle}")"
  STEP_LIMIT="${SIMIT_GPU_CHECK_STEP_LIMIT:-300}"
  local report="${SIMIT_GPU_CHECK_REPORT:-$SIMIT_ROOT/bench/results/gpu_check.md}"
  tmp="$(mktemp -d)" # global: the EXIT trap runs after this function's locals are gone
  trap 'rm -rf "$tmp"' EXIT
  cd "$SIMIT_ROOT"
  # DIR holds the packed bundle (what `bundle` makes), or is an unpacked one.
  if [ -f "$dir/$ARCHIVE" ]; then
    log "unpacking $dir/$ARCHIVE"
    unpack_bundle "$dir/$ARCHIVE" "$tmp/bundle"
    dir="$tmp/bundle"
  fi
  SIMIT="$dir/simit"
  if [ ! -x "$SIMIT" ] || [ ! -x "$dir/bin/simit" ]; then
    log "no bundle in $dir (scripts/gpu_check.sh bundle makes one)"
    exit 1
  fi
  local failed=0 body="$tmp/body.md"
  : >"$body"

  log "[1/5] the bundle starts here"
  local version
  if ! version="$("$SIMIT" --version 2>&1)"; then
    log "the bundle's simit does not start: $version"
    failed=1
  fi

  log "[2/5] gpu_probe"
  local probe_status=0 t0
  t0="$(now)"
  limited "$dir/gpu_probe" >"$tmp/probe.md" 2>"$tmp/probe.err" || probe_status=$?
  log "  gpu_probe exited $probe_status after $(elapsed "$t0")"
  {
    echo "## The probe (gpu_probe, exit status $probe_status)"
    echo
    cat "$tmp/probe.md"
    if [ "$probe_status" != 0 ] && [ "$probe_status" != 77 ]; then
      echo
      echo '```'
      tail -20 "$tmp/probe.err"
      echo '```'
      failed=1
    fi
    echo
  } >>"$body"

  # The interpreter, the JIT (the bundle's code generation on this machine's CPU) and, where
  # there is one, the GPU executor.
  local executors=(interpreter jit) test_executors=(interpreter jit) gpu_note=""
  if ! has_gpu_executor run; then
    gpu_note="The GPU executor is not built yet (simit run --help lists no gpu among --executor's values): its steps are skipped."
  elif [ "$probe_status" = 77 ]; then
    gpu_note="No GPU here (the probe says why): the GPU executor's steps are skipped."
  else
    executors+=(gpu)
    has_gpu_executor test && test_executors+=(gpu)
  fi
  [ -z "$gpu_note" ] || log "  $gpu_note"

  log "[3/5] the language corpus (tests/lang) under ${test_executors[*]}"
  {
    echo "## The language corpus (simit test tests/lang)"
    echo
    [ -n "$gpu_note" ] && echo "$gpu_note" && echo
    echo "| executor | result | time |"
    echo "| --- | --- | ---: |"
  } >>"$body"
  local e status summary
  for e in "${test_executors[@]}"; do
    t0="$(now)"
    status=0
    limited "$SIMIT" test --executor "$e" tests/lang >"$tmp/lang.$e.out" 2>&1 || status=$?
    summary="$(tail -1 "$tmp/lang.$e.out")"
    [ "$status" = 0 ] || {
      failed=1
      summary="exit $status: $summary"
    }
    log "  $e: $summary ($(elapsed "$t0"))"
    echo "| $e | $summary | $(elapsed "$t0") |" >>"$body"
  done
  echo >>"$body"

  log "[4/5] the examples, 10 frames, under ${executors[*]}"
  {
    echo "## The examples, 10 frames (final positions, --final-csv)"
    echo
    echo "| example | executor | time | final positions |"
    echo "| --- | --- | ---: | --- |"
  } >>"$body"
  local example name csv verdict
  for example in fem/bunny springs/bunny cloth/square; do
    name="${example//\//_}"
    for e in "${executors[@]}"; do
      csv="$tmp/$name.$e.csv"
      t0="$(now)"
      status=0
      limited "$SIMIT" run "examples/$example.toml" --executor "$e" --frames 10 \
        --jit-cache off --output "$tmp/out.$name.$e" --final-csv "$csv" \
        >"$tmp/$name.$e.out" 2>&1 || status=$?
      if [ "$status" != 0 ]; then
        verdict="FAILED: exit $status: $(tail -1 "$tmp/$name.$e.out")"
        failed=1
      elif [ "$e" = interpreter ]; then
        verdict="$(wc -l <"$csv") positions"
      elif cmp -s "$tmp/$name.interpreter.csv" "$csv"; then
        verdict="byte for byte the interpreter's"
      else
        verdict="DIFFER from the interpreter's: $(cmp "$tmp/$name.interpreter.csv" "$csv" 2>&1 |
          head -1)"
        failed=1
      fi
      log "  $example $e: $verdict ($(elapsed "$t0"))"
      echo "| $example | $e | $(elapsed "$t0") | $verdict |" >>"$body"
    done
  done
  echo >>"$body"

  log "[5/5] random programs"
  {
    echo "## Random programs"
    echo
    if [ -x "$dir/bin/random_programs" ]; then
      t0="$(now)"
      status=0
      SIMIT_RANDOM_PROGRAMS=300 limited "$dir/bin/random_programs" >"$tmp/random.out" 2>&1 ||
        status=$?
      [ "$status" = 0 ] || failed=1
      echo "300 programs: exit $status after $(elapsed "$t0")"
      echo
      echo '```'
      tail -5 "$tmp/random.out"
      echo '```'
    else
      echo "Not run: the bundle has no runner for them (the random-program comparison is the" \
        "RandomPrograms unit test, interpreter against the JIT, which is not bundled)."
    fi
    echo
  } >>"$body"
  log "  $(tail -2 "$body" | head -1)"

  # The GPU and its driver head the report: from nvidia-smi, else from the probe's table.
  local gpu driver
  gpu="$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1 || true)"
  driver="$(nvidia-smi --query-gpu=driver_version --format=csv,noheader 2>/dev/null |
    head -1 || true)"
  [ -n "$gpu" ] || gpu="$(sed -n 's/^| device [0-9]* | \(.*\) |$/\1/p' "$tmp/probe.md" | head -1)"
  local cuda
  cuda="$(sed -n 's/^| driver | \(.*\) |$/\1/p' "$tmp/probe.md" | head -1)"
  mkdir -p "$(dirname "$report")"
  {
    echo "# GPU check"
    echo
    echo "GPU: ${gpu:-none found}; driver ${driver:-not reported}${cuda:+ ($cuda)}"
    echo
    echo "Run $(date -u '+%Y-%m-%d %H:%M UTC') on $(nproc) cores by scripts/gpu_check.sh run;" \
      "${version:-simit did not start}; commit $(git rev-parse --short HEAD 2>/dev/null ||
        echo unknown). Result: $([ "$failed" = 0 ] && echo 'all passed' || echo 'FAILURES')."
    echo
    cat "$body"
  } >"$report"
  log "report: $report"
  if [ -n "${OUT:-}" ]; then
    cp "$report" "$OUT/"
    log "copied to $OUT/$(basename "$report")"
  fi
  return "$failed"
}

case "${1:-}" in
  bundle) shift && cmd_bundle "$@" ;;
  run) shift && cmd_run "$@" ;;
  *) usage ;;
esac
