# The GPU check's steps (scripts/gpu_check.sh run, which sources this file): the probe, the
# language corpus, the examples, the random programs, the benchmark, the JIT's threads and the
# accuracy sweep. Each writes its section of the report into $BODY and records its outcome
# with the helpers of gpu_check.sh (step, record, record_problems, out_of_time, limited).
# shellcheck shell=bash disable=SC2154 # the globals cmd_run sets (DIR, WORK, BODY, ...)
run_probe() {
  step 2 "gpu_probe"
  local t0
  t0="$(now)"
  PROBE_STATUS=0
  limited "$DIR/gpu_probe" >"$WORK/probe.md" 2>"$WORK/probe.err" || PROBE_STATUS=$?
  {
    echo "## The probe (gpu_probe, exit status $PROBE_STATUS)"
    echo
    cat "$WORK/probe.md"
    if [ "$PROBE_STATUS" != 0 ] && [ "$PROBE_STATUS" != 77 ]; then
      echo
      echo '```'
      tail -20 "$WORK/probe.err"
      echo '```'
    fi
    echo
  } >>"$BODY"
  case "$PROBE_STATUS" in
    0) record "gpu_probe" passed "measured the GPU ($(elapsed "$t0"))" ;;
    77) record "gpu_probe" skipped "no GPU here: $(head -1 "$WORK/probe.md")" ;;
    *) record "gpu_probe" FAILED "exit $PROBE_STATUS$(timed_out_note "$PROBE_STATUS"):" \
      "$(tail -1 "$WORK/probe.err")" ;;
  esac
}

run_corpus() {
  step 3 "the language corpus (tests/lang) under ${TEST_EXECUTORS[*]}"
  out_of_time "corpus" 30 && return
  {
    echo "## The language corpus (simit test tests/lang)"
    echo
    [ -n "$GPU_NOTE" ] && echo "$GPU_NOTE" && echo
    echo "| executor | result | time |"
    echo "| --- | --- | ---: |"
  } >>"$BODY"
  local e status summary t0 failures=()
  for e in "${TEST_EXECUTORS[@]}"; do
    t0="$(now)"
    status=0
    limited "$SIMIT" test --executor "$e" tests/lang >"$WORK/lang.$e.out" 2>&1 || status=$?
    summary="$(tail -1 "$WORK/lang.$e.out")"
    if [ "$status" != 0 ]; then
      summary="exit $status$(timed_out_note "$status"): $summary"
      failures+=("$e")
    fi
    log "  $e: $summary ($(elapsed "$t0"))"
    echo "| $e | $summary | $(elapsed "$t0") |" >>"$BODY"
  done
  echo >>"$BODY"
  for e in "${failures[@]}"; do
    {
      echo "Under $e (the first 10 failures):"
      echo
      echo '```'
      grep '^FAIL' "$WORK/lang.$e.out" | head -10 || tail -5 "$WORK/lang.$e.out"
      echo '```'
      echo
    } >>"$BODY"
  done
  if [ ${#failures[@]} = 0 ]; then
    record "corpus" passed "${TEST_EXECUTORS[*]}${GPU_NOTE:+ (gpu skipped: no GPU)}"
  else
    record "corpus" FAILED "under ${failures[*]}"
  fi
}

run_examples() {
  step 4 "the examples, 10 frames, under ${EXECUTORS[*]}"
  out_of_time "examples" 30 && return
  {
    echo "## The examples, 10 frames (final positions, --final-csv)"
    echo
    [ -n "$GPU_NOTE" ] && echo "$GPU_NOTE" && echo
    echo "| example | executor | time | final positions |"
    echo "| --- | --- | ---: | --- |"
  } >>"$BODY"
  local example name csv verdict e status t0 bad=()
  for example in fem/bunny springs/bunny cloth/square; do
    name="${example//\//_}"
    for e in "${EXECUTORS[@]}"; do
      csv="$WORK/$name.$e.csv"
      t0="$(now)"
      status=0
      limited "$SIMIT" run "examples/$example.toml" --executor "$e" --frames 10 \
        --jit-cache off --output "$WORK/out.$name.$e" --final-csv "$csv" \
        >"$WORK/$name.$e.out" 2>&1 || status=$?
      if [ "$status" != 0 ]; then
        verdict="FAILED: exit $status$(timed_out_note "$status"): $(tail -1 "$WORK/$name.$e.out")"
        bad+=("$example $e")
      elif [ "$e" = interpreter ]; then
        verdict="$(wc -l <"$csv") positions"
      elif cmp -s "$WORK/$name.interpreter.csv" "$csv"; then
        verdict="byte for byte the interpreter's"
      else
        verdict="DIFFER from the interpreter's: $(cmp "$WORK/$name.interpreter.csv" "$csv" 2>&1 |
          head -1)"
        bad+=("$example $e")
      fi
      log "  $example $e: $verdict ($(elapsed "$t0"))"
      echo "| $example | $e | $(elapsed "$t0") | $verdict |" >>"$BODY"
    done
  done
  echo >>"$BODY"
  if [ ${#bad[@]} = 0 ]; then
    record "examples" passed "fem, springs, cloth under ${EXECUTORS[*]}: the interpreter's" \
      "bits${GPU_NOTE:+ (gpu skipped: no GPU)}"
  else
    record "examples" FAILED "$(
      IFS=,
      echo "${bad[*]}"
    )"
  fi
}

# The random programs (the RandomPrograms unit test, tests/jit/random_program_test.cpp) with
# SIMIT_TEST_GPU=1: each compared bit for bit between the interpreter and the GPU executor.
# They run as SHARDS processes side by side, each on its own seeds, which the GPU serves alike.
run_random_programs() {
  local count="${SIMIT_GPU_CHECK_PROGRAMS:-300}" seed="${SIMIT_GPU_CHECK_SEED:-1}"
  local shards="${SIMIT_GPU_CHECK_SHARDS:-}"
  if [ -z "$shards" ]; then
    shards=$(($(nproc) / 2))
    [ "$shards" -ge 2 ] || shards=2
    [ "$shards" -le 8 ] || shards=8
  fi
  step 5 "$count random programs under the GPU executor (SIMIT_TEST_GPU=1, $shards processes)"
  {
    echo "## Random programs under the GPU executor"
    echo
  } >>"$BODY"
  local what="$count programs from seed $seed, interpreter against gpu"
  if [ ! -x "$DIR/bin/jit_tests" ]; then
    echo "Not run: the bundle has no jit_tests (a bundle from before it carried them)." >>"$BODY"
    echo >>"$BODY"
    record "random programs" skipped "the bundle has no jit_tests"
    return
  fi
  if [ -n "$GPU_WHY" ]; then
    printf '%s\n\n' "Not run: $GPU_WHY (SIMIT_TEST_GPU=1 would fail)." >>"$BODY"
    record "random programs" skipped "$GPU_WHY (SIMIT_TEST_GPU=1 would fail)"
    return
  fi
  out_of_time "random programs" 60 && return
  local t0 k n first pids=() statuses=() starts=() sizes=() from=$seed
  local per=$(((count + shards - 1) / shards))
  t0="$(now)"
  for ((k = 0; k < shards && from < seed + count; k++)); do
    n=$((seed + count - from))
    [ "$n" -gt "$per" ] && n=$per
    SIMIT_TEST_GPU=1 SIMIT_RANDOM_PROGRAMS=$n SIMIT_RANDOM_SEED=$from \
      limited "$DIR/jit_tests" --gtest_filter='RandomPrograms.*' >"$WORK/random.$k.out" 2>&1 &
    pids+=($!)
    starts+=("$from")
    sizes+=("$n")
    from=$((from + n))
  done
  for k in "${!pids[@]}"; do
    statuses[k]=0
    wait "${pids[k]}" || statuses[k]=$?
  done
  local failed_shards=0 ran=0
  {
    echo "$what, in ${#pids[@]} processes: $(elapsed "$t0")."
    echo
    echo "| seeds | exit | compared with the interpreter | its summary |"
    echo "| --- | ---: | --- | --- |"
    for k in "${!pids[@]}"; do
      first="$(grep -m1 ' programs from seed ' "$WORK/random.$k.out" || true)"
      n="$(grep -m1 -o '^[0-9]* programs from seed' "$WORK/random.$k.out" | cut -d' ' -f1 ||
        true)"
      ran=$((ran + ${n:-0}))
      echo "| ${starts[k]} to $((starts[k] + sizes[k] - 1)) |" \
        "${statuses[k]}$(timed_out_note "${statuses[k]}") |" \
        "$(grep -m1 -o 'the [a-z]* executor.*' "$WORK/random.$k.out" || echo '-') |" \
        "${first:-no summary} |"
      [ "${statuses[k]}" = 0 ] || failed_shards=$((failed_shards + 1))
    done
    echo
    for k in "${!pids[@]}"; do
      [ "${statuses[k]}" = 0 ] && continue
      echo "Process $k's failures (the first 40 lines):"
      echo
      echo '```'
      grep -A12 'Failure' "$WORK/random.$k.out" | head -40 || tail -20 "$WORK/random.$k.out"
      echo '```'
      echo
    done
  } >>"$BODY"
  if [ "$failed_shards" = 0 ] && [ "$ran" = "$count" ]; then
    record "random programs" passed "$what: the interpreter's bits ($(elapsed "$t0"))"
  else
    record "random programs" FAILED "$what: $failed_shards of ${#pids[@]} processes failed," \
      "$ran programs reported"
  fi
}

# A build folder's layout (tools/simit, bench/EXAMPLE_baseline) of scripts that start the
# bundle's programs: what bench/run_bench.py and bench/accuracy.py take as --build.
bench_build_folder() {
  local build="$WORK/bench-build" name
  mkdir -p "$build/tools" "$build/bench"
  printf '#!/bin/sh\nexec "%s/simit" "$@"\n' "$DIR" >"$build/tools/simit"
  for name in fem springs cloth; do
    printf '#!/bin/sh\nexec "%s/%s_baseline" "$@"\n' "$DIR" "$name" >"$build/bench/${name}_baseline"
  done
  chmod +x "$build/tools/simit" "$build/bench/"*
  echo "$build"
}

# Why the benchmark scripts cannot run here ("" when they can): they need Python 3.11
# (tomllib) and the bundle's baselines.
bench_unavailable() {
  if ! command -v python3 >/dev/null; then
    echo "no python3 here"
  elif ! python3 -c 'import tomllib' 2>/dev/null; then
    echo "python3 here is $(python3 -c 'import sys; print(sys.version.split()[0])'), the" \
      "benchmark scripts need 3.11 (tomllib)"
  elif [ ! -x "$DIR/bin/fem_baseline" ]; then
    echo "the bundle has no baselines (a bundle from before it carried them)"
  fi
}

# Why a benchmark step with the GPU executor cannot run here ("" when it can).
gpu_bench_unavailable() {
  if [ -n "$GPU_WHY" ]; then echo "$GPU_WHY"; else bench_unavailable; fi
}

# skipped_because STEP WHY: when WHY is not empty, the step is not run: its section says why
# and the summary has it skipped. True when skipped.
skipped_because() {
  [ -n "$2" ] || return 1
  printf 'Not run: %s.\n\n' "$2" >>"$BODY"
  record "$1" skipped "$2"
}

# The JIT's threads on this machine's cores: fem dragon160k under the JIT
# and the OpenMP baseline at 1, 2, 4, ... threads up to the cores there are, one
# bench/run_bench.py run per count, and each count's speed-up over one thread.
run_thread_scaling() {
  step 7 "the JIT's threads: fem dragon160k at 1, 2, 4, ... $(nproc) threads, jit and baseline"
  echo "## Threads: fem dragon160k under the JIT and the OpenMP baseline" >>"$BODY"
  echo >>"$BODY"
  local why
  why="$(bench_unavailable)"
  [ -n "$why" ] || [ -e examples/data/dragon160k.node ] || why="no examples/data/dragon160k.node"
  skipped_because "threads" "$why" && return
  out_of_time "threads" 60 && return
  local build t0 status n counts=() bad=() row jit base jit1="" base1="" moved rate triad
  build="$(bench_build_folder)"
  for n in 1 2 4 8 16 32 64; do [ "$n" -le "$(nproc)" ] && counts+=("$n"); done
  [ "${counts[-1]}" = "$(nproc)" ] || counts+=("$(nproc)")
  t0="$(now)"
  {
    echo "ms a frame (3 frames, the median of frames 2 and 3), speed-up over 1 thread in brackets;"
    echo "the CG loop's bytes an iteration moves and the rate it reached (--jit-stats, 3 frames),"
    echo "against the STREAM triad's median on as many threads (bench/stream_triad, 24 MB: the"
    echo "caches; 768 MB: memory)."
    echo
    echo "| threads | jit ms | baseline ms | jit vs baseline | CG iteration | CG GB/s |" \
      "triad 24 MB GB/s | triad 768 MB GB/s |"
    echo "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  } >>"$BODY"
  for n in "${counts[@]}"; do
    out_of_time "threads, $n" 20 && break
    status=0
    limited python3 bench/run_bench.py --build "$build" --dragon160k --only fem/dragon160k \
      --executors jit --threads "$n" --out "$WORK/threads.$n.md" >"$WORK/threads.$n.out" 2>&1 ||
      status=$?
    log "  $n threads: exit $status ($(elapsed "$t0"))"
    # The ms/frame column (the sixth) of the jit and baseline rows.
    jit="$(awk -F'|' '$4 ~ /^ *jit *$/ { gsub(/ /, "", $7); print $7 }' "$WORK/threads.$n.md" \
      2>/dev/null || true)"
    base="$(awk -F'|' '$4 ~ /^ *baseline *$/ { gsub(/ /, "", $7); print $7 }' \
      "$WORK/threads.$n.md" 2>/dev/null || true)"
    if [ "$status" != 0 ] || [ -z "$jit" ] || [ -z "$base" ]; then
      bad+=("$n threads: exit $status$(timed_out_note "$status")")
      echo "| $n | failed | failed | | | | | |" >>"$WORK/threads.rows"
      continue
    fi
    [ -n "$jit1" ] || jit1="$jit"
    [ -n "$base1" ] || base1="$base"
    # "an iteration moves 21.5 MB (its matrices 13.9 MB); 300 iterations at 51.0 GB/s"
    limited "$DIR/simit" run examples/fem/dragon160k.toml --executor jit --threads "$n" \
      --frames 3 --output "$WORK/threads.out" --jit-stats >"$WORK/threads.$n.stats" 2>&1 || true
    moved="$(grep -o 'an iteration moves [0-9.]* [a-zA-Z]*' "$WORK/threads.$n.stats" |
      head -1 | sed 's/an iteration moves //' || true)"
    rate="$(grep -o 'iterations at [0-9.]* GB/s' "$WORK/threads.$n.stats" | head -1 |
      awk '{ print $3 }' || true)"
    triad="$(limited "$DIR/stream_triad" 24 768 --repeats 5 --threads "$n" 2>/dev/null |
      awk '/MB:/ { printf "%s%s", sep, $(NF - 1); sep = " | " }' || true)"
    case "$triad" in *"|"*) ;; *) triad="$triad | " ;; esac
    row="$(awk -v n="$n" -v j="$jit" -v b="$base" -v j1="$jit1" -v b1="$base1" 'BEGIN {
      printf "| %d | %s (%.2fx) | %s (%.2fx) | %.2fx |", n, j, j1 / j, b, b1 / b, j / b }')"
    echo "$row ${moved:-?} | ${rate:-?} | $triad |" >>"$WORK/threads.rows"
  done
  { cat "$WORK/threads.rows" 2>/dev/null || true; echo; } >>"$BODY"
  record_problems "threads" "${#counts[@]} thread counts ($(elapsed "$t0"))" "${bad[@]}"
}

# The benchmark (bench/run_bench.py) with the GPU executor: the small cases beside the
# interpreter, whose positions are the reference of the error column, the large ones beside
# the JIT only (the interpreter takes tens of seconds a frame there; the JIT's positions are
# the interpreter's bits, as the steps above check).
run_benchmark() {
  local frames="${SIMIT_GPU_CHECK_FRAMES:-4}" threads="${SIMIT_GPU_CHECK_THREADS:-$(nproc)}"
  step 6 "the benchmark (bench/run_bench.py, $frames frames, $threads threads) with the GPU executor"
  {
    echo "## The benchmark (bench/run_bench.py --executors ...,gpu, $frames frames)"
    echo
    echo "The JIT, the GPU executor's solver loops and the baselines on $threads threads" \
      "(--threads $threads), the interpreter on one."
  } >>"$BODY"
  echo >>"$BODY"
  skipped_because "benchmark" "$(gpu_bench_unavailable)" && return
  out_of_time "benchmark" 60 && return
  # shellcheck disable=SC2054 # the commas are run_bench.py's lists
  local build big=(--cloth 64,256) t0 status part label bad=() only
  build="$(bench_build_folder)"
  [ -e examples/data/dragon160k.node ] && big+=(--dragon160k)
  t0="$(now)"
  for part in small large; do
    # shellcheck disable=SC2054 # the commas are run_bench.py's lists
    if [ "$part" = small ]; then
      label="beside the interpreter (rel. err against its positions)"
      only=(--executors interpreter,jit,gpu --only fem/bunny --only fem/dragon40k
        --only springs/bunny --only cloth/square64)
    else
      label="beside the JIT (rel. err against its positions)"
      only=(--executors jit,gpu,gpu-float32 --only fem/dragon160k --only cloth/square256)
    fi
    out_of_time "benchmark, $part cases" 30 && continue
    status=0
    limited python3 bench/run_bench.py --build "$build" --frames "$frames" --threads "$threads" \
      "${big[@]}" \
      "${only[@]}" --timeout "$(time_left)" --out "$WORK/bench.$part.md" \
      >"$WORK/bench.$part.out" 2>&1 || status=$?
    log "  $part cases: exit $status ($(elapsed "$t0"))"
    {
      echo "### The $part cases, $label"
      echo
      if [ -s "$WORK/bench.$part.md" ]; then cat "$WORK/bench.$part.md"; else
        echo "No table: run_bench.py exited $status$(timed_out_note "$status"):"
        echo
        echo '```'
        tail -15 "$WORK/bench.$part.out"
        echo '```'
      fi
      echo
      grep -v ' trace: ' "$WORK/bench.$part.out" | sed -n 's/^note: /- /p' || true
      grep -q '^note: .* gpu trace: ' "$WORK/bench.$part.out" && {
        echo
        echo "<details><summary>The GPU executor's traces (--jit-stats)</summary>"
        echo
        echo '```'
        # The case, then the trace as simit's --jit-stats prints it under its header.
        printf '%-24s %s\n' case "site                         compile ms    calls     run ms     cpu ms ir nodes  status"
        sed -n 's/^note: \(.*\) gpu trace: /\1\t/p' "$WORK/bench.$part.out" |
          awk -F'\t' '{ printf "%-24s %s\n", $1, $2 }'
        echo '```'
        echo "</details>"
      }
      echo
    } >>"$BODY"
    if [ "$status" != 0 ] || [ ! -s "$WORK/bench.$part.md" ]; then
      bad+=("$part cases: exit $status$(timed_out_note "$status")")
    elif grep -q '(failed)' "$WORK/bench.$part.md"; then
      bad+=("$part cases: a run failed")
    elif grep '| gpu |' "$WORK/bench.$part.md" | grep -vq 'same bits'; then
      bad+=("$part cases: the GPU's positions differ from the reference's")
    elif ! grep -q '| gpu |' "$WORK/bench.$part.md"; then
      bad+=("$part cases: no gpu rows")
    fi
  done
  record_problems "benchmark" \
    "fem, springs, cloth under gpu, the reference's bits ($(elapsed "$t0"))" "${bad[@]}"
}

# A thin sweep of bench/accuracy.py: the error of each point against a converged reference,
# under the JIT and the GPU executor side by side (equal errors: the same bits), float64 and
# float32.
run_accuracy() {
  local frames="${SIMIT_GPU_CHECK_FRAMES:-4}"
  step 8 "bench/accuracy.py, a thin sweep, jit and gpu"
  echo "## Speed against error (bench/accuracy.py --executor jit,gpu, $frames frames)" >>"$BODY"
  echo >>"$BODY"
  skipped_because "accuracy" "$(gpu_bench_unavailable)" && return
  out_of_time "accuracy" 45 && return
  local build t0 status example points bad=() differ
  build="$(bench_build_folder)"
  t0="$(now)"
  for example in fem springs cloth; do
    points=1e-6,1e-10 # CG's tolerance on r'r (fem, springs); cloth: steps a frame
    [ "$example" = cloth ] && points=25,100
    status=0
    limited python3 bench/accuracy.py --build "$build" --executor jit,gpu --example "$example" \
      --points "$points" --frames "$frames" --no-plot --table --out "$WORK/accuracy" \
      >"$WORK/accuracy.$example.out" 2>&1 || status=$?
    log "  $example: exit $status ($(elapsed "$t0"))"
    {
      echo "### $example ($(grep -m1 -o 'reference: .*' "$WORK/accuracy.$example.out" ||
        echo 'no reference'))"
      echo
      if [ "$status" = 0 ]; then
        grep '^|' "$WORK/accuracy.$example.out" || true
      else
        echo "accuracy.py --example $example exited $status$(timed_out_note "$status"):"
        echo
        echo '```'
        tail -10 "$WORK/accuracy.$example.out"
        echo '```'
      fi
      echo
    } >>"$BODY"
    [ "$status" = 0 ] || bad+=("$example: exit $status$(timed_out_note "$status")")
  done
  # The GPU's errors are the JIT's, point by point (the same positions).
  differ="$(cat "$WORK"/accuracy/accuracy_*_jit.csv 2>/dev/null | grep -v '^#' |
    awk -F, '$1 != "example" { print $1, $3, $5, $6, $7, $8, $18, $19 }' | sort |
    diff - <(cat "$WORK"/accuracy/accuracy_*_gpu.csv 2>/dev/null | grep -v '^#' |
      awk -F, '$1 != "example" { print $1, $3, $5, $6, $7, $8, $18, $19 }' | sort) || true)"
  [ -z "$differ" ] || bad+=("the GPU's errors differ from the JIT's")
  record_problems "accuracy" \
    "fem, springs, cloth: the GPU's errors are the JIT's ($(elapsed "$t0"))" "${bad[@]}"
}
