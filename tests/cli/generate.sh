# generate makes meshes that refine and check.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
for d in 2 3 4; do
  expect_exit 0 "$BISECT" generate simplex --dim $d --shape random --seed 3 -o s$d.vtu
  expect_exit 0 "$BISECT" generate kuhn --dim $d --cells 2 -o k$d.vtu
  expect_exit 0 "$BISECT" check k$d.vtu
done
# check --against compares the invariants validation measured: a Kuhn cube
# against a larger one (exit 2, the first that differs), and a mesh against
# a copy refined from it.
expect_exit 0 "$BISECT" generate kuhn --dim 3 --cells 3 -o k3c3.vtu
expect_exit 2 "$BISECT" check k3.vtu --against s3.vtu --json
grep -q '"conforming":false' "$WORK/out" || fail "check --json: not conforming"
grep -q 'volume changed: ' "$WORK/out" || fail "check --against: no volume change named"
expect_exit 0 "$BISECT" check k3c3.vtu --against k3.vtu
grep -q "conforming (162 cells, volume, boundary and Euler characteristic match k3.vtu)" \
  "$WORK/out" || fail "check --against: $(cat "$WORK/out")"
expect_exit 0 "$BISECT" quality s3.vtu --classes
grep -q "^classes: 1$" "$WORK/out" || fail "one tet is one class"
# Forced mark types: the file carries them, refinement continues them, and the
# period-4 quality cycle of seed 000 §5.1 shows after Stage 1.
echo '{"type": "box", "min": [-9, -9, -9, -9], "max": [9, 9, 9, 9]}' >all4.json
for type in P_AA A_PO; do
  expect_exit 0 "$BISECT" generate simplex --dim 4 --type $type -o $type.vtu
  expect_exit 0 "$BISECT" info $type.vtu
  grep -q "marking explicit" "$WORK/out" || fail "$type.vtu does not carry the explicit marking"
  expect_exit 0 "$BISECT" refine $type.vtu --region all4.json -n 14 -o $type-14.vtu --quiet
  expect_exit 0 "$BISECT" check $type-14.vtu --against $type.vtu
  awk -F, 'NR > 1 {q[$1] = $6} END {for (k = 9; k <= 10; k++) if (q[k] != q[k + 4]) exit 1}' \
    $type-14.quality.csv || fail "$type: min quality not periodic with period 4"
done
# Refining in two runs equals one run (the edge ranks survive the file).
expect_exit 0 "$BISECT" refine A_PO.vtu --region all4.json -n 3 -o a3.vtu --quiet
expect_exit 0 "$BISECT" refine a3.vtu --region all4.json -n 3 -o a33.vtu --quiet
expect_exit 0 "$BISECT" refine A_PO.vtu --region all4.json -n 6 -o a6.vtu --quiet
[[ $(tail -n1 a33.quality.csv | cut -d, -f2,3,6,7) == $(tail -n1 a6.quality.csv | cut -d, -f2,3,6,7) ]] \
  || fail "3 + 3 iterations differ from 6"
expect_exit 1 "$BISECT" generate simplex --dim 4 --type P_AO -o bad.vtu
one_line_naming "does not arise"
expect_exit 1 "$BISECT" generate simplex --dim 2 --type P -o bad.vtu
one_line_naming "--type"
[[ ! -e bad.vtu ]] || fail "output left behind"
# Too many vertices for 32-bit ids: a usage error (exit 1), not an internal one.
expect_exit 1 "$BISECT" generate kuhn --dim 4 --cells 1000 -o too-many.vtu
one_line_naming "more than 32-bit ids allow"
echo "generate: ok"
