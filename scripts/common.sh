# Helpers shared by the build scripts (sourced, not run).

SIMIT_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# Installs missing Debian packages: directly as root, through sudo otherwise. When
# everything is present install_deps.sh succeeds without root and sudo is not needed.
# Arguments go to install_deps.sh (--tests: also the test-only packages).
ensure_deps() {
  if [ "$(id -u)" -eq 0 ]; then
    "$SIMIT_ROOT/scripts/install_deps.sh" "$@"
  elif ! "$SIMIT_ROOT/scripts/install_deps.sh" "$@" 2>/dev/null; then
    sudo "$SIMIT_ROOT/scripts/install_deps.sh" "$@"
  fi
}

# configure_build DIR BUILD_TYPE [CMAKE_ARGS...]
configure_build() {
  local dir="$1" type="$2"
  shift 2
  cmake -S "$SIMIT_ROOT" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE="$type" "$@"
}

# The example programs, sorted, NUL-separated.
example_programs() {
  find "$SIMIT_ROOT/examples" -name '*.sim' -print0 | sort -z
}
