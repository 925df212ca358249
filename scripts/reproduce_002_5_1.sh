#!/usr/bin/env bash
# Reproduces seed 002, Section 5.1 (Figures 7 and 8): twelve uniform
# refinements of one tetrahedron (equilateral, cartesian, random). Uniform
# refinement = refining around a solid box that holds the whole mesh. Done
# twice: with the index-order marking and with the longest-edge marking.
#
# Paper: Q_k has 2^k tetrahedra (Q_12: 4096); at most 5 iterations generate
# all 36 similarity classes; afterwards the minimum quality is bounded and the
# min/max qualities cycle with period 3.
#
# Usage: scripts/reproduce_002_5_1.sh [OUT_DIR]   (default out/002_5_1)
# Env: BISECT (default build/bisect), ITERATIONS (default 12),
#      PLOT=0 to skip the PNGs (they need /usr/bin/python3 + matplotlib).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bisect=${BISECT:-$root/build/bisect}
out=${1:-$root/out/002_5_1}
iterations=${ITERATIONS:-12}
[[ -x "$bisect" ]] || { echo "reproduce_002_5_1: no executable $bisect (build it: scripts/build.sh, or set BISECT)" >&2; exit 1; }
mkdir -p "$out"

# A solid box around every generated simplex (they all lie in [-1,2]^3).
region=$out/everything.json
cat >"$region" <<'JSON'
{"name": "everything", "comment": "holds the whole mesh: every cell is refined (uniform refinement)",
 "type": "box", "min": [-10, -10, -10], "max": [10, 10, 10]}
JSON

# json_int KEY: the integer value of "KEY" in the JSON object on stdin.
json_int() { grep -o "\"$1\"[[:space:]]*:[[:space:]]*[0-9]*" | head -n1 | grep -o '[0-9]*$'; }
# classes MESH: similarity-class count printed by `bisect quality --classes`.
classes() { "$bisect" quality "$1" --classes | awk -F': *' '/^classes:/ {print $2}'; }

shapes=(equilateral cartesian random)
for marking in index longest; do
  dir=$out/$marking
  mkdir -p "$dir"
  echo "== marking: $marking (output in $dir)"
  for shape in "${shapes[@]}"; do
    seed=(); [[ $shape == random ]] && seed=(--seed 1)
    "$bisect" generate simplex --dim 3 --shape "$shape" "${seed[@]}" -o "$dir/$shape.vtu" --force >/dev/null
    summary=$("$bisect" refine "$dir/$shape.vtu" --region "$region" --iterations "$iterations" \
                --marking "$marking" --quality-csv "$dir/$shape.csv" -o "$dir/$shape-$iterations.vtu" \
                --json --quiet --force)
    echo "$summary" >"$dir/$shape-$iterations.json"
    cells=$(json_int cells <<<"$summary")
    # Similarity classes of each Q_k, k = 0..iterations (each Q_k refined afresh).
    per_k=()
    for ((k = 0; k <= iterations; k++)); do
      if ((k == iterations)); then mesh=$dir/$shape-$iterations.vtu; else
        mesh=$dir/$shape-k.vtu
        "$bisect" refine "$dir/$shape.vtu" --region "$region" --iterations "$k" --marking "$marking" \
          -o "$mesh" --quiet --force >/dev/null
      fi
      per_k+=("$(classes "$mesh")")
    done
    rm -f "$dir/$shape-k.vtu"
    # Minimum quality per iteration, from the CSV (column min_quality).
    minq=$(awk -F, 'NR==1 {for (i=1;i<=NF;i++) if ($i=="min_quality") c=i; next}
                    {printf "%s%.3f", (NR>2?" ":""), $c}' "$dir/$shape.csv")
    printf '%-12s cells %6s (paper: 2^%d = %d)   classes in Q_%d: %s (paper: 36 classes over all Q_k, all reached by k = 5)\n' \
      "$shape" "$cells" "$iterations" "$((1 << iterations))" "$iterations" "${per_k[-1]}"
    echo "             classes in Q_0..Q_$iterations: ${per_k[*]}"
    echo "             min quality per iteration:  $minq"
  done
  if [[ "${PLOT:-1}" != 0 ]]; then
    /usr/bin/python3 "$root/scripts/plot_quality.py" "$dir/equilateral.csv" "$dir/cartesian.csv" "$dir/random.csv" \
      --labels "equilateral,cartesian,random" --title "seed 002 Fig. 7 ($marking marking)" -o "$out/quality-$marking.png"
  fi
done
echo "Paper (Fig. 7): the minimum quality reaches its lowest value by iteration 5, then cycles with period 3."
