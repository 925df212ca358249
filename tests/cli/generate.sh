# generate makes meshes that refine and check.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
for d in 2 3 4; do
  expect_exit 0 "$BISECT" generate simplex --dim $d --shape random --seed 3 -o s$d.vtu
  expect_exit 0 "$BISECT" generate kuhn --dim $d --cells 2 -o k$d.vtu
  expect_exit 0 "$BISECT" check k$d.vtu
done
expect_exit 0 "$BISECT" quality s3.vtu --classes
grep -q "^classes: 1$" "$WORK/out" || fail "one tet is one class"
echo "generate: ok"
