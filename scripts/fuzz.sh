#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) and runs them: the frontend for SECONDS
# (default 60), seeded with the sections of the language corpus and the examples, then each
# other target (mesh readers, scenes, literals, debugger commands) for SECONDS/6, at least 10,
# seeded with tests/fuzz/seeds/TARGET and tests/fuzz/regressions/TARGET.
# `fuzz.sh SECONDS TARGET...` runs only the targets named (frontend, tetgen, gmsh, obj, scene,
# literal, debugger, dap), each for SECONDS. Inputs that crash are written to
# BUILD/fuzz-findings and listed at the end; the script then fails.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

all_targets=(frontend tetgen gmsh obj scene literal debugger dap)
seconds="${1:-60}"
shift || true
targets=("$@")
short=$((seconds / 6 > 10 ? seconds / 6 : 10))
if [ ${#targets[@]} -eq 0 ]; then targets=("${all_targets[@]}"); else short="$seconds"; fi

build="${SIMIT_FUZZ_BUILD_DIR:-$SIMIT_ROOT/build-fuzz}"
ensure_deps --tests
configure_build "$build" RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DSIMIT_FUZZ=ON \
  -DSIMIT_WITH_LLVM=OFF
cmake --build "$build" -j2 --target "${targets[@]/%/_fuzz}"

fuzz_src="$SIMIT_ROOT/tests/fuzz"
# The harnesses' scratch folders, apart from other runs' (a fuzzer that stops on a crash leaves
# its folder behind).
export TMPDIR="$build/fuzz-tmp"
mkdir -p "$TMPDIR"
findings="$build/fuzz-findings"
rm -rf "$findings"
mkdir -p "$findings"

# Seeds of the frontend: one file per section of every test file and example. Whole test
# files are tens of kilobytes; single sections keep the inputs small and the executions many.
frontend_seeds() {
  local seeds="$build/fuzz-seeds/frontend"
  rm -rf "$seeds"
  mkdir -p "$seeds"
  while IFS= read -r -d '' file; do
    csplit --quiet --elide-empty-files --prefix="$seeds/$(basename "$file" .sim)_" \
      --suffix-format='%03d.sim' "$file" '/^%%%/' '{*}'
  done < <(find "$SIMIT_ROOT/tests/lang" "$SIMIT_ROOT/examples" -name '*.sim' -print0)
  echo "$seeds"
}

# run_target NAME SECONDS: new inputs go to BUILD/fuzz-corpus/NAME, kept between runs.
run_target() {
  local name="$1" time="$2" dirs=() options=()
  local corpus="$build/fuzz-corpus/$name"
  mkdir -p "$corpus"
  dirs+=("$corpus")
  if [ "$name" = frontend ]; then
    dirs+=("$(frontend_seeds)")
    options+=(-dict="$fuzz_src/simit.dict")
  else
    dirs+=("$fuzz_src/seeds/$name")
  fi
  [ -d "$fuzz_src/regressions/$name" ] && dirs+=("$fuzz_src/regressions/$name")
  echo "== fuzzing $name for $time s"
  "$build/tests/fuzz/${name}_fuzz" "${dirs[@]}" "${options[@]}" -max_len=4096 \
    -max_total_time="$time" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$findings/$name-" || echo "== $name: the fuzzer stopped with a finding"
}

for name in "${targets[@]}"; do
  if [ "$name" = frontend ]; then run_target "$name" "$seconds"; else run_target "$name" "$short"; fi
done

found=$(find "$findings" -type f | sort)
if [ -n "$found" ]; then
  echo "Findings (replay with BUILD/tests/fuzz/TARGET_fuzz FILE; keep each, once fixed, in"
  echo "tests/fuzz/regressions/TARGET):"
  echo "$found"
  exit 1
fi
echo "No findings."
