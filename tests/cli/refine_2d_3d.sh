# End to end: refine the bundled meshes, check the result against the input,
# then refine the output again (continuing its bisection state) and check.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
for marking in index longest sorted; do
  expect_exit 0 "$BISECT" refine "$ROOT/data/square.msh" --region "$ROOT/data/regions/circle.json" \
    -n 6 -m $marking -o sq.vtu --quality-csv sq.csv --force --quiet
  [[ $(wc -l <sq.csv) == 8 ]] || fail "csv should have a header and 7 rows"
  head -1 sq.csv | grep -q '^iteration,cells,vertices,selected,bisections,min_quality,max_quality,mean_quality,seconds$' || fail "csv header"
  expect_exit 0 "$BISECT" check sq.vtu --against "$ROOT/data/square.msh"
  expect_exit 0 "$BISECT" refine sq.vtu --region "$ROOT/data/regions/circle.json" -n 3 -o sq2.msh --force --quiet
  expect_exit 0 "$BISECT" check sq2.msh --against "$ROOT/data/square.msh"
done
expect_exit 0 "$BISECT" refine "$ROOT/data/ball.msh" --region "$ROOT/data/regions/hemisphere.json" \
  -n 4 -m longest -o ball.msh --json --check
grep -q '"cells"' "$WORK/out" || fail "--json prints a summary"
grep -q "iteration 4/4" "$WORK/err" || fail "progress lines on stderr"
[[ -f ball.quality.csv ]] || fail "default CSV name beside the output"
expect_exit 0 "$BISECT" check ball.msh --against "$ROOT/data/ball.msh"
expect_exit 0 "$BISECT" refine ball.msh --region "$ROOT/data/regions/hemisphere.json" -n 2 -o ball2.vtu --quiet
expect_exit 0 "$BISECT" check ball2.vtu --against "$ROOT/data/ball.msh"
expect_exit 0 "$BISECT" info ball2.vtu
grep -q "bisection state: present (marking longest)" "$WORK/out" || fail "info shows the state"
echo "refine_2d_3d: ok"
