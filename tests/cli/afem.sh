# examples/afem: the L-shape AFEM loop (small) through bisect refine converges,
# the adaptive error decreasing at a rate steeper than uniform refinement's
# and below -0.4; the PNG is written. The moving heat source (small) keeps its
# cell count bounded; skipped while bisect has no coarsen command (heat.py
# exits 77). Needs /usr/bin/python3 with numpy, scipy, matplotlib and meshio.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
PY=/usr/bin/python3
$PY -c "import numpy, scipy, matplotlib, meshio" 2>/dev/null ||
  fail "afem: /usr/bin/python3 lacks numpy, scipy, matplotlib or meshio"

expect_exit 0 $PY "$ROOT/examples/afem/lshape.py" --bisect "$BISECT" --small --out lshape
out=$WORK/lshape.txt
cp "$WORK/out" "$out"
[[ -s lshape/lshape-convergence.png ]] || fail "no plot written"
[[ -z $(ls lshape | grep -v -e '\.png$' -e '\.vtu$') ]] || fail "stray files: $(ls lshape)"
# The adaptive table: H1 error (column 5) decreases from loop to loop.
awk '/^adaptive$/ {on = 1; next} /^fitted slope/ {on = 0}
     on && $1 ~ /^[0-9]+$/ {
       if (n++ && $5 >= last) { print "loop " $1 ": error " $5 " >= " last; bad = 1 }
       last = $5 }
     END { if (n < 8) { print "only " n " adaptive loops"; bad = 1 }; exit bad }' "$out" ||
  fail "adaptive H1 error does not decrease: $(cat "$out")"
slopes=$(sed -n 's/^slopes: adaptive \([-+0-9.]*\) .*uniform \([-+0-9.]*\) .*/\1 \2/p' "$out")
read -r adaptive uniform <<<"$slopes"
[[ -n $adaptive && -n $uniform ]] || fail "no slopes printed: $(cat "$out")"
awk -v a="$adaptive" -v u="$uniform" 'BEGIN { exit !(a < -0.4 && a < u) }' ||
  fail "adaptive slope $adaptive not below -0.4 and steeper than uniform $uniform"
echo "afem: lshape slopes adaptive $adaptive, uniform $uniform"

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
