#!/usr/bin/env bash
# Reproduces seed 000, Section 5.2: the unit sphere's octant (data/octant.msh,
# 38 nodes and 77 tets; the paper's has 40 and 95) copied to t = 0 and t = 1,
# the 76 points triangulated by 4D Delaunay (Qhull; `extrude --hull`, since a
# faceted octant is not convex and Delaunay fills the points' hull), then
# refined 17 times around the hypersphere |x| = 1/4 at the origin
# (data/regions/hypersphere.json), with each marking.
# Paper: 8,072,909 pentatopes, 433,887 vertices, minimum quality 0.11.
#
# Prints per marking: cells, vertices, min/max quality, closure cost (closure
# bisections per selected cell, summed over the iterations) and the
# similarity classes of the mesh after CLASS_ITERATIONS iterations. Writes the
# quality CSVs, a PNG, and the sections t = 0, 1/2, 1 of the longest-marking
# mesh.
#
# Usage: scripts/reproduce_000_5_2.sh [OUT_DIR]   (default out/000_5_2)
# Env: BISECT (default build/bisect), ITERATIONS (default 17), MARKINGS
#      (default "longest index sorted"), CLASS_ITERATIONS (default 10),
#      PLOT=0: no PNG.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bisect=${BISECT:-$root/build/bisect}
out=${1:-$root/out/000_5_2}
iterations=${ITERATIONS:-17}
class_iterations=${CLASS_ITERATIONS:-10}
read -r -a markings <<<"${MARKINGS:-longest index sorted}"
[[ -x "$bisect" ]] || { echo "reproduce_000_5_2: no executable $bisect (build it: scripts/build.sh)" >&2; exit 1; }
mkdir -p "$out"
"$bisect" extrude "$root/data/octant.msh" --slices 0,1 --method delaunay --hull -o "$out/octant4d.vtu" --force
region=$root/data/regions/hypersphere.json
source "$root/scripts/lib_compare.bash"
compare_markings "$out/octant4d.vtu" "$region" "$iterations" "$class_iterations" "$out" "${markings[@]}"
printf '%-10s %12s %10s %8s\n' paper 8072909 433887 0.11
plot_markings "seed 000 §5.2: octant x [0,1], hypersphere r = 1/4" "$out" "${markings[@]}"
