#!/usr/bin/env bash
# Reproduces seed 000, Section 5.1 (Figure 9): one equilateral pentatope with
# its marks forced to type P_AA, another forced to A_PO, each refined
# uniformly 20 times. Paper: the minimum and maximum quality fall during the
# first steps, then cycle with period 4.
#
# The forced marks come from `bisect generate simplex --dim 4 --type T`,
# which stores an explicit edge order (cell array bisect:edge_rank) whose
# level-0/1/2 marks have type T; the first two bisections follow those marks
# (Stage 1), then Maubach's cycle.
#
# Prints per type: min/max quality per iteration, the detected period, and the
# similarity classes of each generation up to CLASS_ITERATIONS.
#
# Usage: scripts/reproduce_000_5_1.sh [OUT_DIR]   (default out/000_5_1)
# Env: BISECT (default build/bisect), ITERATIONS (default 20),
#      CLASS_ITERATIONS (default 12), PLOT=0: no PNG.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bisect=${BISECT:-$root/build/bisect}
out=${1:-$root/out/000_5_1}
iterations=${ITERATIONS:-20}
class_iterations=${CLASS_ITERATIONS:-12}
[[ -x "$bisect" ]] || { echo "reproduce_000_5_1: no executable $bisect (build it: scripts/build.sh)" >&2; exit 1; }
mkdir -p "$out"
region=$out/everything.json
cat >"$region" <<'JSON'
{"name": "everything", "comment": "holds the whole pentatope: uniform refinement",
 "type": "box", "min": [-10, -10, -10, -10], "max": [10, 10, 10, 10]}
JSON
classes() { "$bisect" quality "$1" --classes | awk -F': *' '/^classes:/ {print $2}'; }

csvs=()
for type in P_AA A_PO; do
  "$bisect" generate simplex --dim 4 --shape equilateral --type "$type" -o "$out/$type.vtu" --force >/dev/null
  # The equilateral pentatope spans t in [0, 0.79]: slices at 0, 0.4 and 0.79 * 0.95.
  "$bisect" refine "$out/$type.vtu" --region "$region" --iterations "$iterations" \
    -o "$out/$type-$iterations.vtu" --quality-csv "$out/$type.csv" --slices 0,0.4,0.75 --quiet --force
  csvs+=("$out/$type.csv")
  echo "== $type: $(awk -F, 'END {print $2}' "$out/$type.csv") pentatopes after $iterations iterations"
  awk -F, -v type="$type" '
    NR == 1 {for (i = 1; i <= NF; i++) col[$i] = i; next}
    {k = $1; lo[k] = $col["min_quality"]; hi[k] = $col["max_quality"]; n = k}
    END {
      line = "   min q:"; for (k = 1; k <= n; k++) line = line sprintf(" %.3f", lo[k]); print line
      line = "   max q:"; for (k = 1; k <= n; k++) line = line sprintf(" %.3f", hi[k]); print line
      for (p = 1; p <= 8; p++) {           # smallest period holding from some k0 on
        for (k0 = 1; k0 + p <= n; k0++) {
          ok = 1
          for (k = k0; k + p <= n; k++)
            if (lo[k] - lo[k + p] > 1e-9 || lo[k + p] - lo[k] > 1e-9 ||
                hi[k] - hi[k + p] > 1e-9 || hi[k + p] - hi[k] > 1e-9) ok = 0
          if (ok && n - k0 >= 2 * p) {printf "   period %d from iteration %d on (paper: 4)\n", p, k0; exit}
        }
      }
      print "   no period found"
    }' "$out/$type.csv"
  per_k=()
  for ((k = 1; k <= class_iterations; k++)); do
    "$bisect" refine "$out/$type.vtu" --region "$region" --iterations "$k" -o "$out/$type-k.vtu" \
      --quality-csv "$out/$type-k.csv" --quiet --force
    per_k+=("$(classes "$out/$type-k.vtu")")
  done
  rm -f "$out/$type-k.vtu" "$out/$type-k.csv"
  echo "   similarity classes in generations 1..$class_iterations: ${per_k[*]}"
done
if [[ "${PLOT:-1}" != 0 ]]; then
  /usr/bin/python3 "$root/scripts/plot_quality.py" "${csvs[@]}" --labels P_AA,A_PO \
    --title "seed 000 §5.1: equilateral pentatope, uniform refinement" -o "$out/quality.png"
  echo "plot: $out/quality.png"
fi
