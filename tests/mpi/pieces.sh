# A .pvtu read by every rank, a stretch of its pieces each (read_pvtu_parts
# of distributed.hpp; README, "MPI"): refining or coarsening the .pvtu of a
# distributed run on P = 1..4 ranks equals doing so serially (2D, 3D with
# tags, 4D; --origin cell by cell; the gathered file the same bytes for
# P = 2 and 3), the --json says the pieces were read in parallel, a .pvtu
# without bisect:global_id (VTK's own writer) is read by rank 0 as before,
# and pieces that are each valid but wrong where they meet (a piece listed
# twice, a made point moved off its parent edge's midpoint, a global id on
# two points) are refused with one line, exit 1, nothing written.
# $1: the bisect of a -DBISECT_MPI=ON build; $2: the source tree.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
R=$ROOT/data/regions
same=$ROOT/tests/mpi/same_cells.py
parallel_read() { # the --json in $WORK/out says the pieces were read in parallel: $1 true|false
  grep -q "\"pieces_read_in_parallel\":$1" "$WORK/out" || { cat "$WORK/out" >&2; fail "pieces_read_in_parallel is not $1"; }
}
"$BISECT" generate kuhn --dim 2 --cells 4 -o square.vtu -q
"$BISECT" generate kuhn --dim 4 --cells 1 -o hypercube.vtu -q
n=0
for c in "square.vtu $R/circle.json 4 3" "$ROOT/data/box-tagged.msh $R/hemisphere.json 2 1" \
  "hypercube.vtu $R/moving-sphere.json 6 4"; do
  read -r mesh region first more <<<"$c"
  total=$((first + more))
  "$BISECT" refine "$mesh" --region "$region" -n "$total" --origin -o s.vtu -q -f --quality-csv none
  expect_exit 0 run_mpi 3 refine "$mesh" --region "$region" -n "$first" --origin -o p.pvtu -q -f \
    --quality-csv none
  "$BISECT" refine p.pvtu --region "$region" -n "$more" --origin -o c.vtu -q -f --quality-csv none
  /usr/bin/python3 "$same" s.vtu c.vtu >same.txt || { cat same.txt >&2; fail "$c: serial refine of the .pvtu differs"; }
  for p in 1 2 3 4; do
    expect_exit 0 run_mpi $p refine p.pvtu --region "$region" -n "$more" -o q.pvtu -q -f \
      --quality-csv none --json
    parallel_read true
    /usr/bin/python3 "$same" s.vtu q.pvtu >same.txt || { cat same.txt >&2; fail "$c: the .pvtu refined on $p ranks differs"; }
    n=$((n + 1))
  done
  for p in 2 3; do
    expect_exit 0 run_mpi $p refine p.pvtu --region "$region" -n "$more" --origin -o g$p.vtu -q -f \
      --quality-csv none
    # bisect:origin: each cell's index in the .pvtu as read_pvtu orders them
    /usr/bin/python3 "$same" c.vtu g$p.vtu --array bisect:origin >same.txt ||
      { cat same.txt >&2; fail "$c, P=$p: the gathered cells or their bisect:origin differ"; }
    [[ $("$BISECT" info g$p.vtu | grep -E '^(cells|vertices|tagged)') == $("$BISECT" info s.vtu | grep -E '^(cells|vertices|tagged)') ]] ||
      fail "$c, P=$p: bisect info of the gathered mesh differs from the serial run's"
  done
  cmp -s g2.vtu g3.vtu || fail "$c: the gathered file for P=3 differs from P=2's"
  # Coarsening the .pvtu read in parallel (the passes still run on rank 0).
  "$BISECT" coarsen p.pvtu --all -n 2 -o sc.vtu -q -f
  for p in 1 3; do
    expect_exit 0 run_mpi $p coarsen p.pvtu --all -n 2 -o dc.pvtu -q -f --json
    parallel_read true
    /usr/bin/python3 "$same" sc.vtu dc.pvtu >same.txt || { cat same.txt >&2; fail "$c: coarsening the .pvtu on $p ranks differs"; }
  done
  # --check (the whole input's Euler characteristic): rank 0 reads it.
  expect_exit 0 run_mpi 2 coarsen p.pvtu --all -n 2 --check -o dg.vtu -q -f --json
  parallel_read false
  /usr/bin/python3 "$same" sc.vtu dg.vtu >same.txt || { cat same.txt >&2; fail "$c: coarsen --check of the .pvtu differs"; }
done
# A .pvtu of a run whose input had a tree: its input vertices made by
# bisection keep their parents through the parallel read into the gathered
# file, so coarsening that to the end gives back the coarse square.
"$BISECT" refine square.vtu --region "$R/circle.json" -n 2 -o t0.vtu -q -f --quality-csv none
expect_exit 0 run_mpi 3 refine t0.vtu --region "$R/circle.json" -n 2 -o tp.pvtu -q -f --quality-csv none
expect_exit 0 run_mpi 2 refine tp.pvtu --region "$R/circle.json" -n 2 -o tg.vtu -q -f --quality-csv none
"$BISECT" coarsen tg.vtu --all -n 0 -o tc.vtu -q -f
/usr/bin/python3 "$same" square.vtu tc.vtu >same.txt || { cat same.txt >&2; fail "the gathered file lost the input's tree"; }
# A .pvtu from VTK's own parallel writer (no bisect:global_id, no state):
# rank 0 reads and marks it, as a .vtu.
"$BISECT" refine square.vtu --region "$R/circle.json" -n 2 -o a.vtu -q -f --quality-csv none
/usr/bin/python3 - a.vtu vtk.pvtu <<'PY'
import sys, vtk
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(sys.argv[1]); r.Update()
piece = vtk.vtkExtractUnstructuredGridPiece()  # each piece its share of the cells
piece.SetInputConnection(r.GetOutputPort())
w = vtk.vtkXMLPUnstructuredGridWriter(); w.SetFileName(sys.argv[2])
w.SetInputConnection(piece.GetOutputPort())
w.SetNumberOfPieces(2); w.SetStartPiece(0); w.SetEndPiece(1); w.Write()
PY
"$BISECT" refine vtk.pvtu --region "$R/circle.json" -n 3 -o s.vtu -q -f --quality-csv none
expect_exit 0 run_mpi 2 refine vtk.pvtu --region "$R/circle.json" -n 3 -o d.pvtu -q -f --quality-csv none --json
parallel_read false
/usr/bin/python3 "$same" s.vtu d.pvtu >same.txt || { cat same.txt >&2; fail "VTK's .pvtu refined on 2 ranks differs"; }
# Pieces each valid, wrong where they meet.
run_mpi 3 refine hypercube.vtu --region "$R/moving-sphere.json" -n 5 -o p.pvtu -q -f --quality-csv none
sed 's#\(<Piece Source="p_0.vtu"/>\)#\1\n    \1#' p.pvtu >twice.pvtu
for p in 1 2; do
  expect_exit 1 run_mpi $p refine twice.pvtu --region "$R/moving-sphere.json" -o x.pvtu -f
  one_bisect_line_naming "twice.pvtu: duplicate cells"
  grep -qF "where the pieces meet" "$WORK/err" || { cat "$WORK/err" >&2; fail "the message does not say where"; }
  [[ ! -e x.pvtu && ! -e x_0.vtu ]] || fail "a refused read wrote output"
done
# A point made by bisection moved (in the piece that holds it with the
# larger x; the pieces then disagree on it, and it is no midpoint), and a
# global id given to a second point.
/usr/bin/python3 - p_1.vtu moved_1.vtu gid_1.vtu <<'PY'
import sys, vtk
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(sys.argv[1]); r.Update()
g = r.GetOutput()
gid = g.GetPointData().GetArray("bisect:global_id")
made = [i for i in range(g.GetNumberOfPoints()) if gid.GetValue(i) == -1]
orig = [i for i in range(g.GetNumberOfPoints()) if gid.GetValue(i) >= 0]
assert made and len(orig) > 1
def write(grid, name):
    w = vtk.vtkXMLUnstructuredGridWriter(); w.SetFileName(name); w.SetInputData(grid); w.Write()
moved = vtk.vtkUnstructuredGrid(); moved.DeepCopy(g)
x = list(moved.GetPoint(made[0])); x[0] += 1e-3
moved.GetPoints().SetPoint(made[0], x)
write(moved, sys.argv[2])
dup = vtk.vtkUnstructuredGrid(); dup.DeepCopy(g)
dup.GetPointData().GetArray("bisect:global_id").SetValue(orig[1], gid.GetValue(orig[0]))
write(dup, sys.argv[3])
PY
sed 's#p_1.vtu#moved_1.vtu#' p.pvtu >moved.pvtu
sed 's#p_1.vtu#gid_1.vtu#' p.pvtu >gid.pvtu
for p in 1 3; do
  expect_exit 1 run_mpi $p refine moved.pvtu --region "$R/moving-sphere.json" -o x.pvtu -f
  one_bisect_line_naming "moved.pvtu: "
  grep -qE "not the midpoint|is a point of no piece" "$WORK/err" || { cat "$WORK/err" >&2; fail "a moved point: no clear message"; }
  expect_exit 1 run_mpi $p refine gid.pvtu --region "$R/moving-sphere.json" -o x.pvtu -f
  one_bisect_line_naming "gid.pvtu: "
  grep -qE "names two points|once each" "$WORK/err" || { cat "$WORK/err" >&2; fail "a global id on two points: no clear message"; }
  [[ ! -e x.pvtu && ! -e x_0.vtu ]] || fail "a refused read wrote output"
done
echo "mpi pieces: $n refinements of a .pvtu read on P = 1..4 ranks equal to the serial ones"
