#!/usr/bin/env bash
# Remakes the bundled meshes in data/ from their .geo files with Debian's gmsh
# (4.8; `scripts/install-deps.sh` installs it). The .geo
# files fix every size, the random seed and single-threaded meshing, so two runs
# give byte-identical files. Each mesh is re-read by gmsh as a validity check.
# Usage: scripts/make_data.sh [--check]  (--check: remake into a temp dir and
# compare with the committed files instead of overwriting them).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
command -v gmsh >/dev/null || { echo "make_data: gmsh not found (apt-get install gmsh)" >&2; exit 1; }

dest=$root/data
check=0
if [[ "${1:-}" == --check ]]; then
  check=1
  dest=$(mktemp -d)
  trap 'rm -rf "$dest"' EXIT
fi

# Prints "nodes N triangles T tetrahedra K" for a Gmsh 4.1 ASCII file.
count() {
  awk '/^\$Nodes/ {getline; split($0,h," "); nodes=h[2]}
       /^\$Elements/ {inel=1; getline; next}
       /^\$EndElements/ {inel=0}
       inel && left==0 {split($0,b," "); cnt[b[3]]+=b[4]; left=b[4]; next}
       inel && left>0 {left--}
       END {printf "nodes %d triangles %d tetrahedra %d\n", nodes, cnt[2], cnt[4]}' "$1"
}

# make NAME DIM: data/NAME.geo -> NAME.msh (MSH 4.1 ASCII), then re-read it.
make() {
  local name=$1 dim=$2 out=$dest/$1.msh
  gmsh "$root/data/$name.geo" "-$dim" -format msh41 -o "$out" >/dev/null
  gmsh "$out" -0 -o "$dest/.reread.msh" >/dev/null   # fails on an unreadable file
  rm -f "$dest/.reread.msh"
  echo "$name.msh: $(count "$out") ($(wc -c <"$out") bytes)"
  if ((check)); then
    cmp -s "$out" "$root/data/$name.msh" && echo "  same as data/$name.msh" \
      || { echo "  DIFFERS from data/$name.msh" >&2; return 1; }
  fi
}

make ball 3
make square 2
make cylinder 3
make octant 3
