#!/usr/bin/env bash
# Reproduces seed 000, Section 5.3: [0,1]^4 as 24 Freudenthal-Kuhn pentatopes,
# refined 25 times around the sphere of radius 1/5 whose centre moves from
# (0,0,0) to (0,0,1) as t goes 0 -> 1 (data/regions/moving-sphere.json), with
# each marking. Paper: 5,233,296 pentatopes and 251,457 vertices.
#
# Prints per marking: cells, vertices, min/max quality, closure cost (closure
# bisections per selected cell, over all iterations) and the similarity
# classes after CLASS_ITERATIONS iterations; writes the CSVs, a PNG and the
# sections t = 0, 1/2, 1 of the longest-marking mesh.
#
# Usage: scripts/reproduce_000_5_3.sh [OUT_DIR]   (default out/000_5_3)
# Env: BISECT (default build/bisect), ITERATIONS (default 25), MARKINGS
#      (default "longest index sorted"), CLASS_ITERATIONS (default 14), PLOT=0.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bisect=${BISECT:-$root/build/bisect}
out=${1:-$root/out/000_5_3}
iterations=${ITERATIONS:-25}
class_iterations=${CLASS_ITERATIONS:-14}
read -r -a markings <<<"${MARKINGS:-longest index sorted}"
[[ -x "$bisect" ]] || { echo "reproduce_000_5_3: no executable $bisect (build it: scripts/build.sh)" >&2; exit 1; }
mkdir -p "$out"
"$bisect" generate kuhn --dim 4 --cells 1 -o "$out/hypercube.vtu" --force
source "$root/scripts/lib_compare.bash"
compare_markings "$out/hypercube.vtu" "$root/data/regions/moving-sphere.json" "$iterations" \
  "$class_iterations" "$out" "${markings[@]}"
printf '%-10s %12s %10s\n' paper 5233296 251457
plot_markings "seed 000 §5.3: moving sphere" "$out" "${markings[@]}"
