#!/usr/bin/env bash
# Installs every build and test dependency of Simit from Debian packages (run as root; idempotent).
# With --tests also the packages only the tests use (scripts/test.sh passes it); with --llvm
# also LLVM 19, which the JIT needs (a build configured with -DSIMIT_WITH_LLVM=ON; setup.sh and
# test.sh pass it) and zstd, which LLVM's static libraries link; with --bench also matplotlib,
# which bench/accuracy.py draws its plots with (Debian's python3-matplotlib, for /usr/bin/python3).
# The Python module (python/) builds with pybind11 for Debian's /usr/bin/python3 and needs numpy.
# METIS (libmetis-dev) is the distributed layer's partitioner (src/dist, `simit partition`), and
# OpenMPI (openmpi-bin, libopenmpi-dev) its ranks (src/dist/mpi; the tests labelled mpi), and
# PETSc (libpetsc-real-dev, built with OpenMPI) the direct solves of a distributed run.
set -euo pipefail

packages=(
  build-essential g++ cmake ninja-build pkg-config git
  libeigen3-dev libsuitesparse-dev libreadline-dev
  libgtest-dev libgmock-dev libcli11-dev libtomlplusplus-dev nlohmann-json3-dev libfmt-dev
  libpng-dev libtinyobjloader-dev clang libclang-rt-14-dev tmux python3
  clang-format pybind11-dev python3-dev python3-numpy
  libmetis-dev openmpi-bin libopenmpi-dev libpetsc-real-dev
)
# Test-only: VTK's Python reader, which the scene tests open the .vtu frames with; pytest for
# the Python module's tests, scipy and matplotlib for the ones of its matrices and example.
test_packages=(python3-vtk9 python3-pytest python3-scipy python3-matplotlib nodejs)
command -v npm >/dev/null || test_packages+=(npm)  # tests/dap; NodeSource's nodejs bundles it
# Benchmark-only: the plots of bench/accuracy.py.
bench_packages=(python3-matplotlib)
for arg in "$@"; do
  case "$arg" in
    --tests) packages+=("${test_packages[@]}") ;;
    --llvm) packages+=(llvm-19-dev libzstd-dev) ;;  # zstd: LLVM's static libraries need it
    --bench) packages+=("${bench_packages[@]}") ;;
    *) echo "install_deps: unknown option $arg (expected --tests, --llvm or --bench)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages present"
  exit 0
fi

if [ "$(id -u)" -ne 0 ]; then
  echo "install_deps: missing packages: ${missing[*]}" >&2
  echo "install_deps: run this script as root (or with sudo) to install them" >&2
  exit 1
fi

echo "install_deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
