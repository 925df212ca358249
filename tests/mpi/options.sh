# The serial refine's output options under mpirun (README, "MPI"): --origin
# (the bisect:origin cell array travels with the cells, in the .pvtu's
# pieces and gathered), -o - with --format (gathered, written to standard
# output by rank 0), --slices (sections of the gathered mesh), each equal to
# the serial run's; and the combinations that are refused, with one line.
# $1: the bisect of a -DBISECT_MPI=ON build; $2: the source tree.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
R=$ROOT/data/regions
same=$ROOT/tests/mpi/same_cells.py
"$BISECT" generate kuhn --dim 2 --cells 4 -o square.vtu -q
"$BISECT" generate kuhn --dim 3 --cells 2 -o cube.vtu -q
"$BISECT" generate kuhn --dim 4 --cells 1 -o hypercube.vtu -q
echo '{"type": "sphere", "center": [0.3, 0.4, 0.2], "radius": 0.25}' >sphere.json
n=0
# --origin: each cell's input cell, cell by cell the serial run's; the 4D
# case rebalances, so the array also travels with migrated cells.
for c in "square.vtu $R/circle.json 6" "cube.vtu sphere.json 5" \
  "$ROOT/data/box-tagged.msh $R/hemisphere.json 2" "hypercube.vtu $R/moving-sphere.json 8"; do
  read -r mesh region iters <<<"$c"
  "$BISECT" refine "$mesh" --region "$region" -n "$iters" --origin -o s.vtu -q -f --quality-csv none
  for p in 2 3; do
    expect_exit 0 run_mpi $p refine "$mesh" --region "$region" -n "$iters" --origin -o d.pvtu -q -f \
      --quality-csv none
    /usr/bin/python3 "$same" s.vtu d.pvtu --array bisect:origin >same.txt ||
      { cat same.txt >&2; fail "$c, P=$p: bisect:origin in the .pvtu differs"; }
    expect_exit 0 run_mpi $p refine "$mesh" --region "$region" -n "$iters" --origin -o g.vtu -q -f \
      --quality-csv none
    /usr/bin/python3 "$same" s.vtu g.vtu --array bisect:origin >same.txt ||
      { cat same.txt >&2; fail "$c, P=$p: bisect:origin in the gathered file differs"; }
    n=$((n + 1))
  done
done
# -o - --format: the gathered mesh on standard output, the same bytes as the
# gathered file (rank 0 writes it; mpirun passes it on), .vtu and .msh.
run_mpi 3 refine cube.vtu --region sphere.json -n 5 -o g.vtu -q -f --quality-csv none
expect_exit 0 run_mpi 3 refine cube.vtu --region sphere.json -n 5 -o - --format vtu -q
cmp -s "$WORK/out" g.vtu || fail "-o - --format vtu under mpirun differs from the gathered file"
run_mpi 2 refine "$ROOT/data/box-tagged.msh" --region "$R/hemisphere.json" -n 2 -o g.msh -q -f \
  --quality-csv none
expect_exit 0 run_mpi 2 refine "$ROOT/data/box-tagged.msh" --region "$R/hemisphere.json" -n 2 \
  -o - --format msh -q
cmp -s "$WORK/out" g.msh || fail "-o - --format msh under mpirun differs from the gathered file"
# Without the format, or with --json (both on standard output): refused.
expect_exit 1 run_mpi 2 refine cube.vtu --region sphere.json -o - -q
grep -q 'give the format with --format' "$WORK/err" || { cat "$WORK/err" >&2; fail "-o - without --format"; }
expect_exit 1 run_mpi 2 refine cube.vtu --region sphere.json -o - --format vtu --json
grep -q 'choose one' "$WORK/err" || { cat "$WORK/err" >&2; fail "-o - with --json"; }
# --slices: sections of the gathered mesh, the serial run's sections (3D:
# triangles of a 2D+t mesh; 4D: tetrahedra).
for c in "cube.vtu sphere.json 5 0.2,0.6" "hypercube.vtu $R/moving-sphere.json 8 0.25,0.5"; do
  read -r mesh region iters slices <<<"$c"
  "$BISECT" refine "$mesh" --region "$region" -n "$iters" --slices "$slices" -o s.vtu -q -f \
    --quality-csv none
  expect_exit 0 run_mpi 2 refine "$mesh" --region "$region" -n "$iters" --slices "$slices" -o g.vtu -f \
    --quality-csv none
  count=0
  for section in s.t*.vtu; do
    other=g${section#s}
    [[ -e $other ]] || fail "$c: no $other beside $section"
    grep -qF "wrote $other" "$WORK/err" || { cat "$WORK/err" >&2; fail "$c: no 'wrote $other' line"; }
    /usr/bin/python3 "$same" "$section" "$other" >same.txt ||
      { cat same.txt >&2; fail "$c: $other differs from the serial $section"; }
    count=$((count + 1))
  done
  ((count >= 2)) || fail "$c: $count sections"
  rm -f s.t*.vtu g.t*.vtu
  n=$((n + 1))
done
# coarsen --origin under mpirun: the lowest input cell merged into each cell,
# cell by cell the serial coarsen's; and -o - --format vtu (the gathered bytes).
"$BISECT" refine cube.vtu --region sphere.json -n 5 -o r.vtu -q -f --quality-csv none
"$BISECT" coarsen r.vtu --all -n 2 --origin -o sc.vtu -q -f
for p in 2 3; do
  expect_exit 0 run_mpi $p coarsen r.vtu --all -n 2 --origin -o dc.pvtu -q -f
  /usr/bin/python3 "$same" sc.vtu dc.pvtu --array bisect:origin >same.txt ||
    { cat same.txt >&2; fail "coarsen --origin on $p ranks differs"; }
  n=$((n + 1))
done
run_mpi 2 coarsen r.vtu --all -n 2 -o dg.vtu -q -f
# --format with a .pvtu output: refused, one line, nothing written.
expect_exit 1 run_mpi 2 coarsen r.vtu --all --format vtu -o nope.pvtu -q -f
one_bisect_line_naming "--format with a .pvtu output"
[[ ! -e nope.pvtu ]] || fail "a refused coarsen wrote nope.pvtu"
expect_exit 0 run_mpi 2 coarsen r.vtu --all -n 2 -o - --format vtu -q
cmp -s "$WORK/out" dg.vtu || fail "coarsen -o - --format vtu under mpirun differs from the gathered file"
# Refused, one line each, nothing written: --slices of a 2D mesh, --slices
# or --format with a .pvtu output.
expect_exit 1 run_mpi 2 refine square.vtu --region "$R/circle.json" --slices 0.2,0.4 -o g2.vtu
one_bisect_line_naming "--slices needs a 3D (2D+t) or 4D mesh"
[[ ! -e g2.vtu ]] || fail "a refused --slices wrote its output"
expect_exit 1 run_mpi 2 refine cube.vtu --region sphere.json --slices 0.2,0.4 -o p.pvtu
one_bisect_line_naming "--slices with a .pvtu output"
expect_exit 1 run_mpi 2 refine cube.vtu --region sphere.json --format vtu -o p.pvtu
one_bisect_line_naming "--format with a .pvtu output"
[[ ! -e p.pvtu ]] || fail "a refused run wrote p.pvtu"
echo "options under mpirun: $n cases equal to the serial run"
