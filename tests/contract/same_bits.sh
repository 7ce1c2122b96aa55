#!/usr/bin/env bash
# The arithmetic contract's test (docs/arithmetic.md): simit built with -march=native and
# simit-generic built without it must write byte-identical results for the same scenes and
# programs. Usage: same_bits.sh SIMIT SIMIT_GENERIC|"" SOURCE_DIR WORK_DIR [WHY_NO_GENERIC]
# Exit 77 (skipped) when there is no generic build.
set -euo pipefail
native="$1" generic="$2" root="$3" work="$4"
if [ -z "$generic" ]; then
  echo "skipped: no simit-generic to compare with (${5:-not built})"
  exit 77
fi
rm -rf "$work"
mkdir -p "$work/native" "$work/generic"
differ=0

same() {  # what file-of-native file-of-generic
  if cmp "$2" "$3"; then
    echo "same bits: $1"
  else
    echo "DIFFERENT: $1 ($2 vs $3)"
    differ=1
  fi
}

# A stats CSV without its timing columns (ms, assembly_ms, solve_ms).
untimed() {
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) keep[i] = ($i !~ /(^|_)ms$/) }
           { line = ""; for (i = 1; i <= NF; i++) if (keep[i]) line = line (line == "" ? "" : ",") $i
             print line }' "$1"
}

scene() {  # name scene.toml frames [options...]
  local name="$1" toml="$2" frames="$3" build exe
  shift 3
  for build in native generic; do
    exe=$native
    [ "$build" = generic ] && exe=$generic
    "$exe" run "$toml" --frames "$frames" --output "$work/$build/$name" \
      --final-csv "$work/$build/$name.csv" "$@" > "$work/$build/$name.log"
  done
  same "$name: final positions (--final-csv)" "$work/native/$name.csv" "$work/generic/$name.csv"
  local f
  for f in "$work/native/$name"/*; do
    local base
    base=$(basename "$f")
    case "$base" in
      *.csv)
        untimed "$f" > "$work/native/$name.$base.untimed"
        untimed "$work/generic/$name/$base" > "$work/generic/$name.$base.untimed"
        same "$name: $base without timings" "$work/native/$name.$base.untimed" \
          "$work/generic/$name.$base.untimed" ;;
      *) same "$name: $base" "$f" "$work/generic/$name/$base" ;;
    esac
  done
}

program() {  # name file.sim function args...
  local name="$1" file="$2"
  shift 2
  "$native" run "$file" --call "$@" > "$work/native/$name.out"
  "$generic" run "$file" --call "$@" > "$work/generic/$name.out"
  same "$name: printed results" "$work/native/$name.out" "$work/generic/$name.out"
}

# Frames enough for CG, assembly and the energy sums to run many times, few enough for CI.
scene fem_bar2k "$root/tests/scene/fem_bar2k.toml" 2
scene fem_bunny "$root/examples/fem/bunny.toml" 1
scene springs_bunny "$root/examples/springs/bunny.toml" 3
scene cloth_square "$root/examples/cloth/square.toml" 1
# --float32: binary32 sums (the runtime's Binary32Sums, which no compiler may drop).
scene fem_bunny_float32 "$root/examples/fem/bunny.toml" 1 --float32
scene springs_bunny_float32 "$root/examples/springs/bunny.toml" 2 --float32
for f in products inverses complexes decompositions; do
  program "dense_$f" "$root/tests/contract/dense.sim" "$f" 0.7
done
program neohookean_stress "$root/tests/interp/programs/neohookean.sim" neohookean_stress \
  "[1.1, 0.2, -0.1; 0.05, 0.9, 0.3; -0.2, 0.1, 1.2]" 0.37 1.9

if [ "$differ" -ne 0 ]; then
  echo "the native and generic builds differ (docs/arithmetic.md)"
  exit 1
fi
echo "the native and generic builds agree bit for bit"
