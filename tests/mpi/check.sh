# The checks across ranks catch a non-conforming mesh under mpirun (README,
# "MPI"): the test binary bisect_mpi_hooked undoes one bisection in an
# iteration on every rank (tests/support/corrupt_hook.cpp). With --check the
# check after that iteration fails; without it the final check across
# ranks does (or the check before a rebalance): exit 2, one line, nothing
# written.
# $1: the bisect of a -DBISECT_MPI=ON build; $2: the source tree; $3: bisect_mpi_hooked.
source "$(dirname "$0")/../cli/lib.bash"
HOOKED=${3:?usage: check.sh BISECT ROOT BISECT_MPI_HOOKED}
cd "$WORK"
run_mpi() { # BINARY P ARGS...
  local binary=$1 p=$2
  shift 2
  mpirun --allow-run-as-root --oversubscribe -x BISECT_TEST_CORRUPT_ITERATION -np "$p" "$binary" "$@"
}
"$BISECT" generate kuhn --dim 3 --cells 2 -o cube.vtu -q
echo '{"type": "sphere", "center": [0.3, 0.4, 0.2], "radius": 0.25}' >sphere.json
"$BISECT" refine cube.vtu --region sphere.json -n 5 -o serial.vtu -q --quality-csv none
export BISECT_TEST_CORRUPT_ITERATION=0
# Honest runs pass --check after every iteration and give the serial mesh.
expect_exit 0 run_mpi "$BISECT" 3 refine cube.vtu --region sphere.json -n 5 --check -o ok.pvtu -q \
  --quality-csv none
/usr/bin/python3 "$ROOT/tests/mpi/same_cells.py" serial.vtu ok.pvtu >same.txt ||
  { cat same.txt >&2; fail "--check changed the mesh"; }
# The shipped binary has no hook: the variable does nothing there.
export BISECT_TEST_CORRUPT_ITERATION=3
expect_exit 0 run_mpi "$BISECT" 2 refine cube.vtu --region sphere.json -n 5 -o ok.pvtu -q -f \
  --quality-csv none
for p in 2 3; do
  # --check: the check after iteration 3 fails.
  rm -f out.pvtu out_*.vtu out.vtu
  expect_exit 2 run_mpi "$HOOKED" $p refine cube.vtu --region sphere.json -n 5 --check -o out.pvtu \
    -q --quality-csv none
  grep -q "^bisect: internal check failed after iteration 3: part [0-9]*: " "$WORK/err" ||
    { cat "$WORK/err" >&2; fail "P=$p --check: the failing iteration is not named"; }
  grep -qE 'hanging node|overlap|boundary measure changed|not matched' "$WORK/err" ||
    { cat "$WORK/err" >&2; fail "P=$p --check: the failure is not named"; }
  [[ $(grep -c '^bisect: ' "$WORK/err") == 1 ]] || { cat "$WORK/err" >&2; fail "P=$p: more than one line"; }
  ls out.pvtu out_*.vtu >/dev/null 2>&1 && fail "P=$p --check: output written despite exit 2"
  # Without --check: the final check (or the one before a rebalance) fails.
  for out in out.pvtu out.vtu; do
    expect_exit 2 run_mpi "$HOOKED" $p refine cube.vtu --region sphere.json -n 5 -o $out -q \
      --quality-csv none
    grep -qE '^bisect: internal check failed' "$WORK/err" ||
      { cat "$WORK/err" >&2; fail "P=$p $out: the final check does not say it failed"; }
    # Said once (mpirun ends the other ranks with a signal: they stay silent).
    [[ $(grep -c '^bisect: ' "$WORK/err") == 1 ]] || { cat "$WORK/err" >&2; fail "P=$p $out: more than one line"; }
    ls out.pvtu out_*.vtu out.vtu >/dev/null 2>&1 && fail "P=$p $out: output written despite exit 2"
  done
done
echo "mpi check: a corrupted iteration is caught by --check and by the final check across ranks"
