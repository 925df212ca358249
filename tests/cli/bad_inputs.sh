# Bad input: one line naming the file and the problem, exit 1, no output file.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
region="$ROOT/data/regions/circle.json"
check_bad() { # file, expected text
  expect_exit 1 "$BISECT" refine "$1" --region "$region" -o out.vtu
  one_line_naming "$1"
  grep -qiF -- "$2" "$WORK/err" || { cat "$WORK/err"; fail "message for $1 lacks '$2'"; }
  [[ ! -e out.vtu && ! -e out.quality.csv ]] || fail "output left behind for $1"
  ls -a | grep -q '\.tmp' && fail "temporary file left behind for $1" || true
}
: > empty.msh;                        check_bad empty.msh "empty"
mkdir dir.msh;                        check_bad dir.msh "directory"
check_bad missing.msh "cannot open"
echo hello > mesh.obj;                check_bad mesh.obj "unknown mesh format"
head -c 300 "$ROOT/data/square.msh" > trunc.msh; check_bad trunc.msh "trunc.msh"
# A bad region spec names the spec file.
echo '{"type": "cube"}' > bad.json
expect_exit 1 "$BISECT" refine "$ROOT/data/square.msh" --region bad.json -o out.vtu
one_line_naming bad.json
[[ ! -e out.vtu ]] || fail "output written for a bad spec"
echo '{"type": "sphere", "center": [0, 0, 0], "radius": 1}' > wrongdim.json
expect_exit 1 "$BISECT" refine "$ROOT/data/square.msh" --region wrongdim.json -o out.vtu
one_line_naming wrongdim.json
echo '{"type": "sphere", "center": [0, 0], "radius": -1}' > negative.json
expect_exit 1 "$BISECT" refine "$ROOT/data/square.msh" --region negative.json -o out.vtu
one_line_naming negative.json
# Usage errors.
expect_exit 1 "$BISECT" refine "$ROOT/data/square.msh" --region "$region" -n -4
expect_exit 1 "$BISECT" refine "$ROOT/data/square.msh" --region "$region" --marking shortest
expect_exit 1 "$BISECT" frobnicate
echo "bad_inputs: ok"
