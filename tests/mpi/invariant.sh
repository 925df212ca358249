# The invariant of distributed refinement (README, "MPI"): under mpirun with
# P = 1, 2, 3, 4 ranks (oversubscribed on 2 cores; the markings other than
# index with P = 2, 3), in 2D, 3D and 4D, with every marking, from meshes with and without bisection state and tags, the
# result's cells, as sets of vertex coordinates, are the serial run's. Read
# back with VTK's parallel reader (the .pvtu, as ParaView opens it) and its
# serial one (the gathered .vtu, P = 2, 3). The gathered file is the same bytes for
# every P > 1, and its tagged entities are the serial run's.
# $1: the bisect of a -DBISECT_MPI=ON build; $2: the source tree.
source "$(dirname "$0")/../cli/lib.bash"
cd "$WORK"
R=$ROOT/data/regions
same=$ROOT/tests/mpi/same_cells.py
run_mpi() { # P ARGS...
  local p=$1; shift
  mpirun --allow-run-as-root --oversubscribe -np "$p" "$BISECT" "$@"
}
"$BISECT" generate kuhn --dim 2 --cells 4 -o square.vtu -q
"$BISECT" generate kuhn --dim 3 --cells 2 -o cube.vtu -q
"$BISECT" generate kuhn --dim 4 --cells 1 -o hypercube.vtu -q
echo '{"type": "sphere", "center": [0.3, 0.4, 0.2], "radius": 0.25}' >sphere.json
# A file that carries bisection state: the ball refined once everywhere.
"$BISECT" refine "$ROOT/data/ball.msh" --region "$R/everything3d.json" -o ball-state.vtu -q \
  --quality-csv none
cases=(
  "square.vtu $R/circle.json 8 index"
  "square.vtu $R/circle.json 8 longest"
  "square.vtu $R/circle.json 8 sorted"
  "cube.vtu sphere.json 6 index"
  "cube.vtu sphere.json 6 longest"
  "cube.vtu sphere.json 6 sorted"
  "$ROOT/data/ball.msh $R/hemisphere.json 2 index"
  "ball-state.vtu $R/hemisphere.json 1 longest"
  "$ROOT/data/box-tagged.msh $R/hemisphere.json 2 index"
  "hypercube.vtu $R/moving-sphere.json 7 index"
  "hypercube.vtu $R/moving-sphere.json 7 longest"
  "hypercube.vtu $R/moving-sphere.json 6 sorted"
)
n=0
for c in "${cases[@]}"; do
  read -r mesh region iters marking <<<"$c"
  expect_exit 0 "$BISECT" refine "$mesh" --region "$region" -n "$iters" -m "$marking" \
    -o serial.vtu --quality-csv none -q -f
  serial_info=$("$BISECT" info serial.vtu | grep -E '^(cells|vertices|tagged)')
  # Every P for the index marking, two for the others (the suite's time).
  ranks="2 3"
  [[ $marking == index ]] && ranks="1 2 3 4"
  for p in $ranks; do
    expect_exit 0 run_mpi "$p" refine "$mesh" --region "$region" -n "$iters" -m "$marking" \
      -o parts.pvtu --quality-csv none -q -f
    [[ $(ls parts_*.vtu | wc -l) == "$p" ]] || fail "$c, P=$p: not $p pieces"
    /usr/bin/python3 "$same" serial.vtu parts.pvtu >same.txt || { cat same.txt >&2; fail "$c, P=$p: the .pvtu's cells differ from the serial run's"; }
    ((p == 2 || p == 3)) || { n=$((n + 1)); rm -f parts_*.vtu; continue; }
    expect_exit 0 run_mpi "$p" refine "$mesh" --region "$region" -n "$iters" -m "$marking" \
      -o gathered-$p.vtu --quality-csv none -q -f
    /usr/bin/python3 "$same" serial.vtu gathered-$p.vtu >same.txt || { cat same.txt >&2; fail "$c, P=$p: the gathered cells differ from the serial run's"; }
    [[ $("$BISECT" info gathered-$p.vtu | grep -E '^(cells|vertices|tagged)') == "$serial_info" ]] ||
      fail "$c, P=$p: bisect info of the gathered mesh differs from the serial run's"
    # (P = 1 with a .vtu output is the serial run itself)
    ((p <= 2)) || cmp -s gathered-2.vtu gathered-$p.vtu ||
      fail "$c: the gathered file for P=$p differs from P=2's"
    rm -f parts_*.vtu
    n=$((n + 1))
  done
done
# Marking by an indicator (--above, --top, --dorfler, with --depth): the
# marks of the input's cells, as in the serial run, ties included. The
# indicator is added with VTK's own writer (2D, 3D, 4D).
for dim in 2 3 4; do
  "$BISECT" generate kuhn --dim $dim --cells 3 -o k$dim.vtu -q
  /usr/bin/python3 - k$dim.vtu eta$dim.vtu <<'PY'
import sys, random, vtk
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(sys.argv[1]); r.Update()
g = r.GetOutput()
random.seed(7)
eta = vtk.vtkDoubleArray(); eta.SetName("eta")
values = [random.random() for _ in range(g.GetNumberOfCells())]
values[5] = values[6] = max(values)  # a tie: the lower input id goes first
for v in values:
    eta.InsertNextValue(v)
g.GetCellData().AddArray(eta)
w = vtk.vtkXMLUnstructuredGridWriter(); w.SetFileName(sys.argv[2]); w.SetInputData(g); w.Write()
PY
  for rule in "--above 0.7" "--top 0.1" "--dorfler 0.5" "--top 0.05 --depth 3"; do
    # shellcheck disable=SC2086
    "$BISECT" refine eta$dim.vtu --indicator eta $rule -o s.vtu -q -f --quality-csv none
    for p in 2 3; do
      # shellcheck disable=SC2086
      expect_exit 0 run_mpi $p refine eta$dim.vtu --indicator eta $rule -o d.pvtu -q -f --quality-csv none
      /usr/bin/python3 "$same" s.vtu d.pvtu >same.txt || { cat same.txt >&2; fail "${dim}D --indicator $rule, P=$p differs"; }
      n=$((n + 1))
    done
  done
  # With a region too: either marks a cell (2D: the lower-left quarter box).
  region=$R/everything${dim}d.json
  [[ $dim == 2 ]] && region=$R/box2d.json
  expect_exit 0 "$BISECT" refine eta$dim.vtu --indicator eta --top 0.1 --region "$region" \
    -o s.vtu -q -f --quality-csv none
  expect_exit 0 run_mpi 2 refine eta$dim.vtu --indicator eta --top 0.1 --region "$region" \
    -o d.pvtu -q -f --quality-csv none
  /usr/bin/python3 "$same" s.vtu d.pvtu >same.txt || { cat same.txt >&2; fail "${dim}D indicator + region differs"; }
done
# The precision limit (refine.hpp): a tiny sphere refined for 200 iterations
# stops with exit 3 before the iteration that would bisect an edge finer than
# doubles resolve, on every rank at once, and writes the mesh before it: the
# serial run's.
for dim in 2 3; do
  "$BISECT" generate kuhn --dim $dim --cells 2 -o kp.vtu -q -f
  if [[ $dim == 2 ]]; then c="0.3, 0.4"; else c="0.3, 0.4, 0.35"; fi
  echo "{\"type\": \"sphere\", \"center\": [$c], \"radius\": 1e-300}" >tiny.json
  expect_exit 3 "$BISECT" refine kp.vtu --region tiny.json -n 200 -o ps.vtu -q -f --quality-csv none
  expect_exit 3 run_mpi 3 refine kp.vtu --region tiny.json -n 200 -o pd.pvtu -f --quality-csv none
  grep -q 'stopping before iteration' "$WORK/err" || { cat "$WORK/err" >&2; fail "${dim}D: no stop line"; }
  /usr/bin/python3 "$same" ps.vtu pd.pvtu >same.txt || { cat same.txt >&2; fail "${dim}D: the mesh at the precision limit differs"; }
done
# --max-elements: the iteration that passes it (over all ranks) is undone on
# every rank; exit 3 with the serial run's mesh. --max-memory bounds each
# rank's estimate (exit 3, the mesh before that iteration written).
expect_exit 3 "$BISECT" refine hypercube.vtu --region "$R/moving-sphere.json" -n 12 --max-elements 5000 \
  -o s.vtu -q -f --quality-csv none
expect_exit 3 run_mpi 3 refine hypercube.vtu --region "$R/moving-sphere.json" -n 12 --max-elements 5000 \
  -o d.pvtu -f --quality-csv none
grep -q 'stopping before iteration 11: it would pass --max-elements 5,000' "$WORK/err" ||
  { cat "$WORK/err" >&2; fail "--max-elements under mpirun: no stop line"; }
/usr/bin/python3 "$same" s.vtu d.pvtu >same.txt || { cat same.txt >&2; fail "the mesh at --max-elements differs"; }
expect_exit 3 run_mpi 2 refine hypercube.vtu --region "$R/moving-sphere.json" -n 12 --max-memory 0.00001 \
  -o d.pvtu -f --quality-csv none
grep -q 'stopping before iteration [0-9]*: rank [01]: it would need about' "$WORK/err" ||
  { cat "$WORK/err" >&2; fail "--max-memory under mpirun: no stop line"; }
[[ -e d.pvtu ]] || fail "--max-memory under mpirun wrote no mesh"
# Parts that grow unequal are made again (rebalance): the moving sphere
# refines one end of the hypercube first.
expect_exit 0 run_mpi 2 refine hypercube.vtu --region "$R/moving-sphere.json" -n 12 -o r.pvtu -q -f \
  --quality-csv r.csv --json
/usr/bin/python3 - "$WORK/out" r.csv <<'PY' || fail "no rebalance, or parts left unbalanced"
import csv, json, sys
j = json.load(open(sys.argv[1]))
rows = list(csv.DictReader(open(sys.argv[2])))
assert j["ranks"] == 2 and j["rebalances"] >= 1, j
for r in rows[1:-1]:  # after every iteration but the last: at most 10% over the mean
    assert float(r["imbalance_after_rebalance"]) <= 1.1, r
assert any(float(r["imbalance"]) > 1.1 for r in rows), "the case never needed a rebalance"
PY
"$BISECT" refine hypercube.vtu --region "$R/moving-sphere.json" -n 12 -o s.vtu -q -f --quality-csv none
/usr/bin/python3 "$same" s.vtu r.pvtu >same.txt || { cat same.txt >&2; fail "rebalanced run differs"; }
# The gathered file continues the sequence: refining it serially gives what
# refining the serial output does.
"$BISECT" refine square.vtu --region "$R/circle.json" -n 3 -m longest -o a.vtu -q -f --quality-csv none
expect_exit 0 run_mpi 3 refine square.vtu --region "$R/circle.json" -n 3 -m longest -o b.vtu -q -f \
  --quality-csv none
"$BISECT" refine a.vtu --region "$R/circle.json" -n 2 -o a2.vtu -q -f --quality-csv none
"$BISECT" refine b.vtu --region "$R/circle.json" -n 2 -o b2.vtu -q -f --quality-csv none
/usr/bin/python3 "$same" a2.vtu b2.vtu >same.txt || { cat same.txt >&2; fail "continuing a gathered file differs"; }
# A .pvtu is read back as one mesh (read_pvtu: pieces merged by their
# bisect:global_id, the tags kept once): refining it serially, or on another
# number of ranks, continues the same sequence. (On 2 ranks this case once
# dropped an edge whose end the receiving part made later in the same round.)
"$BISECT" refine "$ROOT/data/ball.msh" --region "$R/hemisphere.json" -n 5 -o s5.vtu -q -f --quality-csv none
expect_exit 0 run_mpi 3 refine "$ROOT/data/ball.msh" --region "$R/hemisphere.json" -n 3 -o p3.pvtu -q -f \
  --quality-csv none
[[ $("$BISECT" info p3.pvtu | sed -n 's/^cells: //p') -gt 6009 ]] || fail "bisect info of a .pvtu"
"$BISECT" info p3.pvtu | grep -q '^tagged entities: [0-9]* of dimension 2' || fail "the .pvtu lost its tags"
"$BISECT" refine p3.pvtu --region "$R/hemisphere.json" -n 2 -o c5.vtu -q -f --quality-csv none
/usr/bin/python3 "$same" s5.vtu c5.vtu >same.txt || { cat same.txt >&2; fail "serial refine of a .pvtu differs"; }
[[ $("$BISECT" info c5.vtu | grep '^tagged') == $("$BISECT" info s5.vtu | grep '^tagged') ]] ||
  fail "tags of a refined .pvtu differ"
for p in 2 4; do
  expect_exit 0 run_mpi $p refine p3.pvtu --region "$R/hemisphere.json" -n 2 -o q5.pvtu -q -f --quality-csv none
  /usr/bin/python3 "$same" s5.vtu q5.pvtu >same.txt || { cat same.txt >&2; fail "a .pvtu refined on $p ranks differs"; }
done
# The gathered file carries the bisection tree: coarsening it undoes what
# coarsening the serial output undoes (tests the tree's parents and levels).
for c in "cube.vtu sphere.json 5" "$ROOT/data/ball.msh $R/hemisphere.json 3" "hypercube.vtu $R/moving-sphere.json 6"; do
  read -r mesh region iters <<<"$c"
  "$BISECT" refine "$mesh" --region "$region" -n "$iters" -o s.vtu -q -f --quality-csv none
  expect_exit 0 run_mpi 3 refine "$mesh" --region "$region" -n "$iters" -o g.vtu -q -f --quality-csv none
  "$BISECT" coarsen s.vtu --all -n 2 -o sc.vtu -q -f
  expect_exit 0 "$BISECT" coarsen g.vtu --all -n 2 -o gc.vtu -q -f
  /usr/bin/python3 "$same" sc.vtu gc.vtu >same.txt || { cat same.txt >&2; fail "$c: coarsening the gathered file differs"; }
  cells() { "$BISECT" info "$1" | sed -n 's/^cells: //p'; }
  (($(cells gc.vtu) < $(cells g.vtu))) || fail "$c: coarsening the gathered file removed nothing"
done
# Coarsening across ranks (coarsen() of distributed.hpp): --all and a
# region (to the end, -n 0), from a file and from the .pvtu of a distributed
# refine (its pieces carry the tree, by coordinates), on P = 1..4 ranks, as a
# .pvtu and gathered, equals coarsening the serial run's output; so does
# coarsening the .pvtu serially. The tagged box's 3-rank pieces do not all
# hold a tagged curve; the 4D case rebalances.
echo '{"type": "sphere", "center": [0.3, 0.4, 0.2], "radius": 0.3}' >ball3.json
# Coarsened where x <= 0.5 (a box over the half of each domain).
echo '{"type": "box", "min": [-1, -1], "max": [0.5, 2]}' >half2.json
echo '{"type": "box", "min": [-1, -1, -1], "max": [0.5, 2, 2]}' >half3.json
echo '{"type": "box", "min": [-1, -1, -1, -1], "max": [0.5, 2, 2, 2]}' >half4.json
for c in "square.vtu $R/circle.json 6 half2.json" "cube.vtu sphere.json 5 half3.json" \
  "$ROOT/data/box-tagged.msh ball3.json 4 half3.json" \
  "hypercube.vtu $R/moving-sphere.json 10 half4.json"; do
  read -r mesh region iters half <<<"$c"
  "$BISECT" refine "$mesh" --region "$region" -n "$iters" -o s.vtu -q -f --quality-csv none
  expect_exit 0 run_mpi 3 refine "$mesh" --region "$region" -n "$iters" -o p.pvtu -q -f \
    --quality-csv none
  for mode in "--all -n 2" "--region $half -n 0"; do
    # shellcheck disable=SC2086
    "$BISECT" coarsen s.vtu $mode -o sc.vtu -q -f
    (($("$BISECT" info sc.vtu | sed -n 's/^cells: //p') < $("$BISECT" info s.vtu | sed -n 's/^cells: //p'))) ||
      fail "$c $mode: the serial coarsening removed nothing"
    # shellcheck disable=SC2086
    expect_exit 0 "$BISECT" coarsen p.pvtu $mode -o pc.vtu -q -f
    /usr/bin/python3 "$same" sc.vtu pc.vtu >same.txt || { cat same.txt >&2; fail "$c $mode: coarsening the .pvtu serially differs"; }
    [[ $("$BISECT" info pc.vtu | grep '^tagged') == $("$BISECT" info sc.vtu | grep '^tagged') ]] ||
      fail "$c $mode: the tags of the coarsened .pvtu differ"
    for p in 1 2 3 4; do
      # shellcheck disable=SC2086
      expect_exit 0 run_mpi $p coarsen p.pvtu $mode -o dc.pvtu -q -f
      /usr/bin/python3 "$same" sc.vtu dc.pvtu >same.txt || { cat same.txt >&2; fail "$c $mode: coarsening on $p ranks differs"; }
      n=$((n + 1))
    done
    # shellcheck disable=SC2086
    expect_exit 0 run_mpi 2 coarsen s.vtu $mode -o dg.vtu -q -f
    /usr/bin/python3 "$same" sc.vtu dg.vtu >same.txt || { cat same.txt >&2; fail "$c $mode: the gathered coarsening differs"; }
    [[ $("$BISECT" info dg.vtu | grep -E '^(cells|vertices|tagged)') == $("$BISECT" info sc.vtu | grep -E '^(cells|vertices|tagged)') ]] ||
      fail "$c $mode: bisect info of the gathered coarsening differs"
  done
done
# By an indicator (--below): the cell array the refinement carried.
for dim in 2 3 4; do
  "$BISECT" refine eta$dim.vtu --indicator eta --top 0.3 --depth 2 -o s.vtu -q -f --quality-csv none
  "$BISECT" coarsen s.vtu --indicator eta --below 0.5 -o sc.vtu -q -f
  for p in 2 3; do
    expect_exit 0 run_mpi $p coarsen s.vtu --indicator eta --below 0.5 -o dc.pvtu -q -f
    /usr/bin/python3 "$same" sc.vtu dc.pvtu >same.txt || { cat same.txt >&2; fail "${dim}D coarsen --indicator on $p ranks differs"; }
  done
done
# A levelset region: each part selects as the whole mesh would; with an
# indicator (a fraction of the selected cells, ranked) the ranking is over
# all parts (select_cells of distributed.hpp), ties by the cells'
# coordinates: an indicator expression "1" makes every score 0, so the ties
# decide every cell kept.
echo '{"type": "levelset", "variables": ["x", "y", "z"], "expression": "x^2 + y^2 + z^2", "value": 0.3}' >ls.json
echo '{"type": "levelset", "variables": ["x", "y", "z"], "expression": "x^2 + y^2 + z^2", "value": 0.3, "indicator": {"type": "hessian", "fraction": 0.5}}' >lsi.json
echo '{"type": "levelset", "variables": ["x", "y", "z"], "expression": "x^2 + y^2 + z^2", "value": 0.3, "indicator": {"type": "hessian", "fraction": 0.3, "expression": "1"}}' >lst.json
for spec in ls.json lsi.json lst.json; do
  "$BISECT" refine cube.vtu --region $spec -n 6 -o s.vtu -q -f --quality-csv none
  for p in 2 3; do
    expect_exit 0 run_mpi $p refine cube.vtu --region $spec -n 6 -o d.pvtu -q -f --quality-csv none
    /usr/bin/python3 "$same" s.vtu d.pvtu >same.txt || { cat same.txt >&2; fail "levelset region $spec on $p ranks differs"; }
  done
done
# Options a distributed coarsen does not take, and a mesh without a tree.
expect_exit 1 run_mpi 2 coarsen - --all -o x.pvtu -q -f <s.vtu
grep -q 'needs a serial run' "$WORK/err" || fail "coarsen of standard input under mpirun: no clear refusal"
expect_exit 1 run_mpi 2 coarsen cube.vtu --all -o x.pvtu -f
grep -q 'cube.vtu: carries no bisection tree' "$WORK/err" || fail "coarsen of a mesh without a tree: no clear refusal"
[[ ! -e x.pvtu ]] || fail "a refused coarsen wrote x.pvtu"
echo "mpi invariant: $n distributed runs (P = 1..4) equal to the serial ones, as .pvtu and gathered"
