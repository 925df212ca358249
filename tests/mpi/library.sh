# The library API of distributed refinement (<bisect/distributed.hpp>,
# bisect::mpi): the README's example, tests/mpi/example.cpp, compiled with
# mpicxx against the MPI build's headers and libraries, run on 3 ranks; its
# .pvtu has the cells of `bisect refine -n 3` run serially, and coarsened
# once (coarsen() across ranks) those of `-n 2`.
# $1: the bisect of a -DBISECT_MPI=ON build (its libraries beside it); $2: the source tree.
source "$(dirname "$0")/../cli/lib.bash"
cd "$WORK"
lib=$(dirname "$BISECT")
mpicxx -std=c++20 -O1 -I"$ROOT/include" "$ROOT/tests/mpi/example.cpp" -o example \
  -L"$lib" -lbisect_mpi -lbisect_io -lbisect_region -lbisect_engine -lbisect_measure \
  -Wl,-rpath,"$lib" || fail "the example does not compile"
R=$ROOT/data/regions
expect_exit 0 mpirun --allow-run-as-root --oversubscribe -np 3 ./example "$ROOT/data/ball.msh" \
  "$R/hemisphere.json" ball.pvtu ball-coarsened.pvtu
grep -q "iteration 3:" "$WORK/out" || fail "the example printed no third iteration"
grep -q "coarsened: [1-9]" "$WORK/out" || fail "the example's coarsening removed nothing"
# One pass of coarsen() undoes the third iteration: the cells of -n 2.
"$BISECT" refine "$ROOT/data/ball.msh" --region "$R/hemisphere.json" -n 2 -o serial2.vtu -q \
  --quality-csv none
/usr/bin/python3 "$ROOT/tests/mpi/same_cells.py" serial2.vtu ball-coarsened.pvtu >same.txt ||
  { cat same.txt >&2; fail "the example's coarsened mesh differs from the serial run's -n 2"; }
"$BISECT" refine "$ROOT/data/ball.msh" --region "$R/hemisphere.json" -n 3 -o serial.vtu -q \
  --quality-csv none
/usr/bin/python3 "$ROOT/tests/mpi/same_cells.py" serial.vtu ball.pvtu >same.txt ||
  { cat same.txt >&2; fail "the example's mesh differs from the serial run's"; }
echo "library (MPI): the README's example ran on 3 ranks and made the serial mesh"
