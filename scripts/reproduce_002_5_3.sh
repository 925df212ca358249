#!/usr/bin/env bash
# Reproduces seed 002, Section 5.3 (Figure 13): a 2D+t space-time mesh of the
# "hyper-cylinder" (x-1/2)^2 + (y-1/2)^2 <= 1, 0 <= t <= 1 (data/cylinder.msh,
# t stored as the third coordinate) refined 50 times around the iso-surface
# V = -10 of the two-body potential V = -G (m1/|x-p1(t)| + m2/|x-p2(t)|),
# G = m1 = m2 = 1, p1(t) = (1/2, 1/8 + 3t/8), p2(t) = (1/2, 7/8 - 3t/8)
# (data/regions/two-body.json). Each iteration takes the cells the
# iso-surface crosses (F_k) and bisects the 10% of them with the largest
# e = sum_i |h_i^T Hess V(x_i) h_i| (the levelset region's Hessian indicator).
#
# Paper: T_0 has 3,781 tets and 712 vertices (ours: 3,739 and 708, our own
# Gmsh mesh; theirs is unpublished); T_50 has 8,356,894 tets and 1,504,344
# vertices.
#
# The paper says F_k is the set of tets "that intersect H", H being the
# cylinder; READINGS picks the readings of that sentence to run:
#   iso       F_k = the tets the iso-surface V = -10 crosses (default; the
#             reading the paper's figures show)
#   cylinder  F_k = the tets meeting the solid cylinder H, i.e. every tet
#   lateral   F_k = the tets touching the lateral surface of H
# `cylinder` grows by about 1.26x per iteration and passes the paper's count
# near iteration 29; it is stopped by MAX_ELEMENTS (exit 3, reported).
#
# The time slices t = 0, 1/2, 1 (Figure 11) of each reading's final mesh are
# written as 2D triangle meshes <reading>.t<T>.vtu.
#
# Usage: scripts/reproduce_002_5_3.sh [OUT_DIR]   (default out/002_5_3)
# Env: BISECT (default build/bisect), ITERATIONS (default 50), MARKING
#      (default longest), READINGS (default "iso"; e.g. "iso cylinder
#      lateral"), MAX_ELEMENTS (default 12,000,000; 0 = no limit), PLOT=0: no
#      PNG. The iso run takes a few minutes and about 1 GB of memory.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bisect=${BISECT:-$root/build/bisect}
out=${1:-$root/out/002_5_3}
iterations=${ITERATIONS:-50}
marking=${MARKING:-longest}
readings=${READINGS:-iso}
max_elements=${MAX_ELEMENTS:-12000000}
[[ -x "$bisect" ]] || { echo "reproduce_002_5_3: no executable $bisect (build it: scripts/build.sh, or set BISECT)" >&2; exit 1; }
mkdir -p "$out"
limit=(); [[ "$max_elements" != 0 ]] && limit=(--max-elements "$max_elements")

# The other readings: the same V as the indicator, F_k from the cylinder.
body=$(tr -s ' \n' ' ' <"$root/data/regions/two-body.json")
potential=$(grep -o '"expression": "[^"]*"' <<<"$body")
constants=$(grep -o '"constants": {[^}]*}' <<<"$body")
for r in cylinder lateral; do
  solid=$([[ $r == cylinder ]] && echo true || echo false)
  cat >"$out/$r.json" <<EOF
{"type": "levelset", "variables": ["x", "y", "t"], $constants,
 "expression": "(x - 0.5)^2 + (y - 0.5)^2", "value": 1, "solid": $solid,
 "indicator": {"type": "hessian", "fraction": 0.1, $potential}}
EOF
done

json_num() { grep -o "\"$1\":[0-9.e+-]*" | head -n1 | cut -d: -f2; }
results=()
csvs=()
labels=()
for r in $readings; do
  case $r in
    iso) spec=$root/data/regions/two-body.json ;;
    cylinder | lateral) spec=$out/$r.json ;;
    *) echo "reproduce_002_5_3: unknown reading '$r' (expected iso, cylinder, lateral)" >&2; exit 1 ;;
  esac
  echo "reading $r: refining data/cylinder.msh around $spec, $iterations iterations, marking $marking" >&2
  rc=0
  summary=$("$bisect" refine "$root/data/cylinder.msh" --region "$spec" --iterations "$iterations" \
    --marking "$marking" -o "$out/$r.vtu" --quality-csv "$out/$r.csv" "${limit[@]}" \
    --slices 0,0.5,1 --json --quiet --force) || rc=$?
  if ((rc == 3)); then echo "note: reading $r stopped at the element limit (exit 3)" >&2
  elif ((rc != 0)); then echo "reproduce_002_5_3: bisect refine failed (exit $rc)" >&2; exit "$rc"; fi
  echo "$summary" >"$out/$r.summary.json"
  # Seconds in the iterations themselves (the CSV's last column), and in all.
  loop=$(awk -F, 'NR > 1 {s += $NF} END {printf "%.1f", s}' "$out/$r.csv")
  results+=("$(printf '%-10s %5s %12s %10s %8.4f %8.4f %8s %8.1f' "$r" "$(json_num iterations <<<"$summary")" \
    "$(json_num cells <<<"$summary")" "$(json_num vertices <<<"$summary")" \
    "$(json_num min_quality <<<"$summary")" "$(json_num max_quality <<<"$summary")" \
    "$loop" "$(json_num seconds <<<"$summary")")")
  csvs+=("$out/$r.csv")
  labels+=("$r")
done
printf '%-10s %5s %12s %10s %8s %8s %8s %8s\n' reading iter tetrahedra vertices "min q" "max q" "loop s" "total s"
printf '%s\n' "${results[@]}"
printf '%-10s %5s %12s %10s\n' paper 50 8356894 1504344
echo "time slices t = 0, 1/2, 1: $out/<reading>.t0.vtu, .t0.5.vtu, .t1.vtu (2D triangle meshes)"
if [[ "${PLOT:-1}" != 0 ]]; then
  /usr/bin/python3 "$root/scripts/plot_quality.py" "${csvs[@]}" --labels "$(IFS=,; echo "${labels[*]}")" \
    --title "seed 002 §5.3: two-body iso-surface ($marking)" -o "$out/quality.png"
fi
