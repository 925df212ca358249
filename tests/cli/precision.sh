# Refining past double precision: a tiny sphere refined for 200 iterations
# stops with exit 3 and one line before an edge too fine for doubles would be
# bisected; the mesh before that iteration is written and passes bisect check
# (every cell positive volume, conforming, the input's invariants).
source "$(dirname "$0")/lib.bash"
cd "$WORK"
for dim in 2 3; do
  "$BISECT" generate kuhn --dim "$dim" --cells 2 -o k.vtu --force >/dev/null
  if [[ $dim == 2 ]]; then c="0.3, 0.4"; else c="0.3, 0.4, 0.35"; fi
  echo "{\"type\": \"sphere\", \"center\": [$c], \"radius\": 1e-300}" >tiny.json
  expect_exit 3 "$BISECT" refine k.vtu --region tiny.json -n 200 -o out.vtu --force --json
  grep -v '^iteration' "$WORK/err" >"$WORK/err2"; mv "$WORK/err2" "$WORK/err"
  grep -c 'stopping before iteration' "$WORK/err" | grep -qx 1 || { cat "$WORK/err" >&2; fail "${dim}D: no stop line"; }
  grep -q 'finer than doubles resolve' "$WORK/err" || { cat "$WORK/err" >&2; fail "${dim}D: limit not named"; }
  grep -q '"limit_reached":true' "$WORK/out" || fail "${dim}D: JSON does not report the limit"
  iterations=$(sed -n 's/.*"iterations":\([0-9]*\).*/\1/p' "$WORK/out")
  (( iterations > 40 && iterations < 200 )) || fail "${dim}D: stopped after $iterations iterations"
  expect_exit 0 "$BISECT" check out.vtu --against k.vtu
  # The written mesh continues: one more iteration stops at once, changing nothing.
  expect_exit 3 "$BISECT" refine out.vtu --region tiny.json -n 1 -o again.vtu --force -q
  expect_exit 0 "$BISECT" check again.vtu --against k.vtu
done
echo "precision: ok"
