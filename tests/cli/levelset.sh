# End to end: levelset regions. A circle as a level set refines the square as
# the exact circle region does; seed 002 §5.3's two-body spec refines the
# space-time cylinder conformingly, its indicator keeps 10% of the crossed
# cells, and refining the output continues; bad specs give one line naming the
# file, exit 1 and no output.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
sq=$ROOT/data/square.msh
cyl=$ROOT/data/cylinder.msh
body=$ROOT/data/regions/two-body.json

# A circle: the sampled test finds the same cells as the exact one here.
echo '{"type": "levelset", "expression": "(x-0.5)^2 + (y-0.5)^2", "value": 0.09}' > circle.json
expect_exit 0 "$BISECT" refine "$sq" --region circle.json -n 5 -o level.vtu --json --quiet
level_cells=$(grep -o '"cells":[0-9]*' "$WORK/out" | cut -d: -f2)
expect_exit 0 "$BISECT" refine "$sq" --region "$ROOT/data/regions/circle.json" -n 5 -o exact.vtu --json --quiet
exact_cells=$(grep -o '"cells":[0-9]*' "$WORK/out" | cut -d: -f2)
[[ -n $level_cells && $level_cells == "$exact_cells" ]] || fail "levelset circle $level_cells cells, exact circle $exact_cells"
expect_exit 0 "$BISECT" check level.vtu --against "$sq"

# The two-body iso-surface with the Hessian indicator (2D+t: variables x, y, t).
expect_exit 0 "$BISECT" refine "$cyl" --region "$body" -n 6 -m longest -o body.vtu \
  --quality-csv body.csv --check --quiet
expect_exit 0 "$BISECT" check body.vtu --against "$cyl"
# Iteration 1 keeps round(0.1 * F) of the F cells the iso-surface crosses.
sed 's/"fraction": 0.1}/"fraction": 1}/' "$body" > crossed.json # keeps every crossed cell
grep -q '"fraction": 1}' crossed.json || fail "could not set the fraction to 1"
expect_exit 0 "$BISECT" refine "$cyl" --region crossed.json -n 1 -o crossed.vtu --quality-csv crossed.csv --quiet
crossed=$(awk -F, 'NR == 3 {print $4}' crossed.csv)
kept=$(awk -F, 'NR == 3 {print $4}' body.csv)
want=$(awk -v n="$crossed" 'BEGIN {k = int(0.1 * n + 0.5); if (k < 1) k = 1; print k}')
[[ $crossed -gt 20 && $kept == "$want" ]] || fail "indicator kept $kept of $crossed cells, expected $want"
# Continuing from the output (its bisection state) stays conforming.
expect_exit 0 "$BISECT" refine body.vtu --region "$body" -n 2 -o body8.vtu --quiet
expect_exit 0 "$BISECT" check body8.vtu --against "$cyl"

# Bad specs: one line naming the spec file, exit 1, no output written.
bad() { # bad NAME 'JSON' MESH 'TEXT IN THE MESSAGE'
  printf '%s\n' "$2" > "$1.json"
  expect_exit 1 "$BISECT" refine "$3" --region "$1.json" -o "$1.vtu"
  one_line_naming "$1.json"
  grep -qF -- "$4" "$WORK/err" || { cat "$WORK/err" >&2; fail "$1: message lacks '$4'"; }
  [[ ! -e $1.vtu && ! -e $1.quality.csv ]] || fail "$1: output written"
}
bad syntax '{"type": "levelset", "expression": "x + * y"}' "$sq" 'Unexpected operator "*"'
bad unknown '{"type": "levelset", "expression": "x + z"}' "$sq" 'unknown variable "z"'
bad function '{"type": "levelset", "expression": "bessel(x)"}' "$sq" 'unknown function "bessel"'
bad missing '{"type": "levelset", "value": 1}' "$sq" 'missing "expression"'
bad fraction '{"type": "levelset", "expression": "x", "indicator": {"type": "hessian"}}' "$sq" 'missing "fraction"'
cp "$body" two-body.json # 2D+t spec on a 2D mesh: the variable list is too long
expect_exit 1 "$BISECT" refine "$sq" --region two-body.json -o wrong.vtu
one_line_naming "two-body.json"
grep -qF '"variables" has 3 names, the mesh is 2D' "$WORK/err" || fail "wrong dimension message"
[[ ! -e wrong.vtu ]] || fail "output written for a wrong dimension"
echo "levelset: ok"
