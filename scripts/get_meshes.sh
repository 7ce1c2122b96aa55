#!/usr/bin/env bash
# Makes larger dragon meshes of the fem example by refining dragon40k with TetGen (Debian
# package `tetgen`); dragon40k itself comes from the original Simit project's apps/data
# folder (dragon40k.node and dragon40k.ele, MIT license) and ships in examples/data, as does
# dragon160k (made with `dragon160k 4.85e-4`).
# Usage: scripts/get_meshes.sh INDIR [OUTDIR] [NAME MAXVOL]...
#   INDIR holds dragon40k.node and dragon40k.ele (examples/data does); OUTDIR defaults to
#   examples/data.
# Without NAME/MAXVOL pairs it makes dragon1m (~994k tets, about 45 MB, not stored).
#   -r refine an existing mesh, -z number from 0, -q quality bound,
#   -Y keep the boundary (TetGen 1.5.0 aborts on this mesh without it),
#   -a maximum tet volume, -Q quiet.
set -euo pipefail
usage="usage: scripts/get_meshes.sh INDIR [OUTDIR] [NAME MAXVOL]..."
in="$(cd "${1:?$usage}" && pwd)"; shift
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$root/examples/data"
if [ $# -eq 1 ] || [ $(($# % 2)) -eq 1 ]; then out="$1"; shift; fi
mkdir -p "$out"
for f in dragon40k.node dragon40k.ele; do
  [ -f "$in/$f" ] || { echo "$in/$f is missing" >&2; exit 1; }
done
command -v tetgen >/dev/null || { echo "tetgen is missing: apt-get install -y tetgen" >&2; exit 1; }
[ $# -gt 0 ] || set -- dragon1m 5.8e-5
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
cp "$in/dragon40k.node" "$in/dragon40k.ele" "$work/"
while [ $# -ge 2 ]; do
  name="$1" vol="$2"; shift 2
  ( cd "$work" && tetgen -rzqYQ -a"$vol" dragon40k )
  mv "$work/dragon40k.1.node" "$out/$name.node"
  mv "$work/dragon40k.1.ele" "$out/$name.ele"
  rm -f "$work"/dragon40k.1.*
  echo "$name: $(head -1 "$out/$name.ele" | awk '{print $1}') tets, $(head -1 "$out/$name.node" | awk '{print $1}') vertices"
done
