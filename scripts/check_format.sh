#!/usr/bin/env bash
# Checks that every tracked C++ source (*.cpp, *.h under src/ include/ tools/ repl/ tests/
# bench/) is formatted as .clang-format says; prints the files that are not and exits 1 then.
# Changes nothing: `clang-format -i FILE` formats one. CLANG_FORMAT names the binary (default
# clang-format; install_deps.sh installs Debian 12's, version 14, whose output CI expects).
# -v also prints clang-format's diagnostics (line and column of each difference).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

verbose=0
for arg in "$@"; do
  case "$arg" in
    -v) verbose=1 ;;
    *) echo "usage: check_format.sh [-v]" >&2; exit 2 ;;
  esac
done

clang_format="${CLANG_FORMAT:-clang-format}"
if ! command -v "$clang_format" >/dev/null; then
  echo "check_format: $clang_format not found (scripts/install_deps.sh installs it)" >&2
  exit 2
fi

cd "$SIMIT_ROOT"
dirs=(src include tools repl tests bench)
pathspecs=()
for d in "${dirs[@]}"; do pathspecs+=("$d/*.cpp" "$d/*.h"); done
# Tracked files only (the index, not untracked scratch files); one deleted in the work tree but
# not yet in the index is skipped.
mapfile -d '' files < <(git ls-files -z -- "${pathspecs[@]}")

bad=()
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  if ! diagnostics=$("$clang_format" --dry-run -Werror "$f" 2>&1); then
    bad+=("$f")
    if [ "$verbose" -eq 1 ]; then printf '%s\n' "$diagnostics" >&2; fi
  fi
done

if [ ${#bad[@]} -gt 0 ]; then
  printf '%s\n' "${bad[@]}"
  echo "check_format: ${#bad[@]} of ${#files[@]} files are not clang-formatted" \
    "(clang-format -i FILE formats one; -v shows where)" >&2
  exit 1
fi
echo "check_format: all ${#files[@]} files are clang-formatted"
