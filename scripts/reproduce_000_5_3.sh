#!/usr/bin/env bash
# Reproduces seed 000, Section 5.3: [0,1]^4 as 24 Freudenthal-Kuhn pentatopes,
# refined 25 times around the sphere of radius 1/5 whose centre moves from
# (0,0,0) to (0,0,1) as t goes 0 -> 1 (data/regions/moving-sphere.json), with
# each marking. Paper: 5,233,296 pentatopes and 251,457 vertices.
#
# Usage: scripts/reproduce_000_5_3.sh [OUT_DIR]   (default out/000_5_3)
# Env: BISECT (default build/bisect), ITERATIONS (default 25), PLOT=0: no PNG.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bisect=${BISECT:-$root/build/bisect}
out=${1:-$root/out/000_5_3}
iterations=${ITERATIONS:-25}
[[ -x "$bisect" ]] || { echo "reproduce_000_5_3: no executable $bisect (build it: scripts/build.sh)" >&2; exit 1; }
mkdir -p "$out"
"$bisect" generate kuhn --dim 4 --cells 1 -o "$out/hypercube.vtu" --force
json_num() { grep -o "\"$1\":[0-9.e+-]*" | head -n1 | cut -d: -f2; }
printf '%-10s %12s %10s %8s %8s\n' marking pentatopes vertices "min q" "max q"
csvs=()
for marking in longest index sorted; do
  summary=$("$bisect" refine "$out/hypercube.vtu" --region "$root/data/regions/moving-sphere.json" \
    --iterations "$iterations" --marking $marking -o "$out/$marking.vtu" \
    --quality-csv "$out/$marking.csv" --json --quiet --force)
  printf '%-10s %12s %10s %8.4f %8.4f\n' $marking "$(json_num cells <<<"$summary")" \
    "$(json_num vertices <<<"$summary")" "$(json_num min_quality <<<"$summary")" \
    "$(json_num max_quality <<<"$summary")"
  csvs+=("$out/$marking.csv")
done
printf '%-10s %12s %10s\n' paper 5233296 251457
if [[ "${PLOT:-1}" != 0 ]]; then
  /usr/bin/python3 "$root/scripts/plot_quality.py" "${csvs[@]}" --labels longest,index,sorted \
    --title "seed 000 §5.3: moving sphere" -o "$out/quality.png"
fi
