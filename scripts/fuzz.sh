#!/usr/bin/env bash
# Builds the libFuzzer target of the frontend with clang and runs it for SECONDS (default 60),
# seeded with the sections of the language corpus and the examples. Crashes are written to
# the build folder.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

seconds="${1:-60}"
build="${SIMIT_FUZZ_BUILD_DIR:-$SIMIT_ROOT/build-fuzz}"
ensure_deps
configure_build "$build" RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DSIMIT_FUZZ=ON \
  -DSIMIT_WITH_LLVM=OFF
cmake --build "$build" -j2 --target frontend_fuzz
# Seeds: one file per section of every test file and example. Whole test files are tens of
# kilobytes; single sections keep the inputs small and the executions many.
seeds="$build/fuzz-seeds"
rm -rf "$seeds"
mkdir -p "$seeds"
while IFS= read -r -d '' file; do
  csplit --quiet --elide-empty-files --prefix="$seeds/$(basename "$file" .sim)_" \
    --suffix-format='%03d.sim' "$file" '/^%%%/' '{*}'
done < <(find "$SIMIT_ROOT/tests/lang" "$SIMIT_ROOT/examples" -name '*.sim' -print0)
corpus="$build/fuzz-corpus"
mkdir -p "$corpus"
cd "$build"
# New inputs go to the first folder.
./tests/fuzz/frontend_fuzz "$corpus" "$seeds" -dict="$SIMIT_ROOT/tests/fuzz/simit.dict" \
  -max_len=4096 -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
