#!/usr/bin/env bash
# 3D + time by extrusion (seed 001): the Kuhn cube [0,1]^3 (4^3 cubes, 384
# tets) is 4-coloured by propagation and extruded over 4 slabs of [0,1]
# (4 pentatopes per tet and slab, consistently tagged: no Stage 1), then
# refined around the sphere of radius 1/5 whose centre moves from (0,0,0) to
# (0,0,1) as t goes 0 -> 1 (data/regions/moving-sphere.json, seed 000 §5.3).
# Writes the 4D mesh, the quality CSV, a PNG of min/max quality and the
# sections t = 0, 1/2, 1; prints the element counts.
#
# Usage: scripts/reproduce_spacetime_3d.sh [OUT_DIR]   (default out/spacetime_3d)
# Env: BISECT (default build/bisect), CELLS (default 4), SLABS (default 4),
#      ITERATIONS (default 12), PLOT=0: no PNG.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bisect=${BISECT:-$root/build/bisect}
out=${1:-$root/out/spacetime_3d}
cells=${CELLS:-4}
slabs=${SLABS:-4}
iterations=${ITERATIONS:-12}
[[ -x "$bisect" ]] || { echo "reproduce_spacetime_3d: no executable $bisect (build it: scripts/build.sh)" >&2; exit 1; }
mkdir -p "$out"
"$bisect" generate kuhn --dim 3 --cells "$cells" -o "$out/cube.vtu" --force
"$bisect" colour "$out/cube.vtu" -o "$out/cube-coloured.vtu" --force
"$bisect" extrude "$out/cube-coloured.vtu" --slices "0:1:$slabs" --method colouring -o "$out/spacetime.vtu" --force
"$bisect" check "$out/spacetime.vtu"
json_num() { grep -o "\"$1\":[0-9.e+-]*" | head -n1 | cut -d: -f2; }
summary=$("$bisect" refine "$out/spacetime.vtu" --region "$root/data/regions/moving-sphere.json" \
  --iterations "$iterations" -o "$out/refined.vtu" --quality-csv "$out/refined.csv" \
  --slices 0,0.5,1 --check --json --quiet --force)
printf '%-22s %12s %10s %8s %8s\n' mesh cells vertices "min q" "max q"
printf '%-22s %12s %10s\n' "extruded (input)" "$(json_num initial_cells <<<"$summary")" \
  "$(json_num initial_vertices <<<"$summary")"
printf '%-22s %12s %10s %8.4f %8.4f\n' "refined, $iterations its" "$(json_num cells <<<"$summary")" \
  "$(json_num vertices <<<"$summary")" "$(json_num min_quality <<<"$summary")" \
  "$(json_num max_quality <<<"$summary")"
for t in 0 0.5 1; do
  n=$("$bisect" info "$out/refined.t$t.vtu" | sed -n 's/^cells: //p')
  printf '%-22s %12s\n' "section t = $t (tets)" "$n"
done
if [[ "${PLOT:-1}" != 0 ]]; then
  /usr/bin/python3 "$root/scripts/plot_quality.py" "$out/refined.csv" --labels "extruded by colour" \
    --title "3D+t by extrusion (seed 001): moving sphere" -o "$out/quality.png"
fi
