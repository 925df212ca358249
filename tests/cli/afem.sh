# examples/afem: the L-shape AFEM loop (small) converges through bisect refine
# --indicator eta --dorfler 0.5 (--via files) and through the Python module
# pybisect (--via module): the adaptive error decreases every loop, its slope
# is below -0.4 and steeper than uniform refinement's, the PNG is written, and
# the two variants give the same meshes loop by loop (cell and vertex counts
# equal, H1 errors and estimators within 1e-12). The moving heat source
# (small) keeps its cell count bounded; skipped while bisect has no coarsen
# command (heat.py exits 77). Needs /usr/bin/python3 with numpy, scipy,
# matplotlib and meshio; pybisect is looked for in $(dirname BISECT)/python.
source "$(dirname "$0")/lib.bash"
BISECT=$(realpath "$BISECT")     # absolute: the runs below are in $WORK
ROOT=$(realpath "$ROOT")
cd "$WORK"
PY=/usr/bin/python3
$PY -c "import numpy, scipy, matplotlib, meshio" 2>/dev/null ||
  fail "afem: /usr/bin/python3 lacks numpy, scipy, matplotlib or meshio"
BUILD=$(cd "$(dirname "$BISECT")" && pwd)
export PYTHONPATH="$BUILD/python${PYTHONPATH:+:$PYTHONPATH}"
# The module variant runs when this build has pybisect (BISECT_PYTHON on:
# then it must import); a build without pybind11 runs the files variant only.
module=yes
if [[ -f $BUILD/CMakeCache.txt ]] && ! grep -q '^BISECT_PYTHON:BOOL=ON' "$BUILD/CMakeCache.txt"; then
  module=no
fi
if [[ $module == yes ]]; then
  $PY -c "import pybisect" 2>/dev/null ||
    fail "afem: pybisect not importable from $BUILD/python (build the target pybisect)"
fi

# lshape_checks VIA: the run's table and slopes.
lshape_checks() {
  local via=$1 out=$WORK/lshape-$1.txt
  expect_exit 0 $PY "$ROOT/examples/afem/lshape.py" --bisect "$BISECT" --small \
    --via "$via" --out "lshape-$via" --rows-json "rows-$via.json"
  cp "$WORK/out" "$out"
  grep -q "^via: $via" "$out" || fail "$via: the first line does not say via $via"
  [[ -s lshape-$via/lshape-convergence.png ]] || fail "$via: no plot written"
  [[ -z $(ls "lshape-$via" | grep -v -e '\.png$' -e '\.vtu$') ]] ||
    fail "$via: stray files: $(ls "lshape-$via")"
  # The adaptive table: H1 error (column 5) decreases from loop to loop.
  awk '/^adaptive$/ {on = 1; next} /^fitted slope/ {on = 0}
       on && $1 ~ /^[0-9]+$/ {
         if (n++ && $5 >= last) { print "loop " $1 ": error " $5 " >= " last; bad = 1 }
         last = $5 }
       END { if (n < 8) { print "only " n " adaptive loops"; bad = 1 }; exit bad }' "$out" ||
    fail "$via: adaptive H1 error does not decrease: $(cat "$out")"
  local slopes adaptive uniform
  slopes=$(sed -n 's/^slopes: adaptive \([-+0-9.]*\) .*uniform \([-+0-9.]*\) .*/\1 \2/p' "$out")
  read -r adaptive uniform <<<"$slopes"
  [[ -n $adaptive && -n $uniform ]] || fail "$via: no slopes printed: $(cat "$out")"
  awk -v a="$adaptive" -v u="$uniform" 'BEGIN { exit !(a < -0.4 && a < u) }' ||
    fail "$via: adaptive slope $adaptive not below -0.4 and steeper than uniform $uniform"
  grep -q "^time via $via: bisect [0-9.]* s, solver [0-9.]* s" "$out" ||
    fail "$via: no bisect/solver times printed"
  echo "afem: lshape via $via: slopes adaptive $adaptive, uniform $uniform"
}
lshape_checks files
if [[ $module == no ]]; then
  echo "afem: lshape via module skipped: this build has no pybisect (BISECT_PYTHON off)"
else
lshape_checks module

# The same meshes loop by loop.
$PY - rows-files.json rows-module.json <<'EOF' || fail "afem: --via files and --via module differ"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
bad = 0
for run in ("adaptive", "uniform"):
    if len(a[run]) != len(b[run]):
        print(f"{run}: {len(a[run])} loops via files, {len(b[run])} via module"); bad = 1
    for ra, rb in zip(a[run], b[run]):
        for key in ("cells", "free", "vertices"):
            if ra[key] != rb[key]:
                print(f"{run} loop {ra['loop']}: {key} {ra[key]} (files) != {rb[key]} (module)"); bad = 1
        for key in ("error", "estimator"):
            if abs(ra[key] - rb[key]) > 1e-12:
                print(f"{run} loop {ra['loop']}: {key} {ra[key]!r} (files) != {rb[key]!r} (module)"); bad = 1
sys.exit(bad)
EOF
echo "afem: lshape --via files and --via module agree loop by loop"
fi

set +e
$PY "$ROOT/examples/afem/heat.py" --bisect "$BISECT" --small --out heat >"$WORK/out" 2>"$WORK/err"
code=$?
set -e
case $code in
  0) grep -q "bounded (within 25%)" "$WORK/out" || fail "heat: no bound reported"
     echo "afem: heat $(grep '^cells over' "$WORK/out")" ;;
  77) echo "afem: heat skipped: bisect coarsen not available" ;;
  *) cat "$WORK/out" "$WORK/err" >&2; fail "heat.py exit $code" ;;
esac
echo "afem: ok"
