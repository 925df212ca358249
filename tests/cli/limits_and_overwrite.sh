# --max-elements stops with exit 3 and a valid mesh; nothing the user had is overwritten.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
expect_exit 3 "$BISECT" refine "$ROOT/data/ball.msh" --region "$ROOT/data/regions/hemisphere.json" \
  -n 40 --max-elements 20000 -o capped.vtu
grep -q "max-elements" "$WORK/err" || fail "the limit is named"
expect_exit 0 "$BISECT" check capped.vtu --against "$ROOT/data/ball.msh"
cells=$("$BISECT" info capped.vtu | sed -n 's/^cells: //p')
(( cells <= 20000 )) || fail "capped mesh has $cells cells"
# --max-memory: an iteration estimated not to fit is not started (exit 3).
expect_exit 3 "$BISECT" refine "$ROOT/data/ball.msh" --region "$ROOT/data/regions/hemisphere.json" \
  -n 40 --max-memory 0.01 -o mem.vtu
grep -q "GiB" "$WORK/err" || fail "the memory estimate is named"
expect_exit 0 "$BISECT" check mem.vtu --against "$ROOT/data/ball.msh"
# An existing output is left alone without --force.
echo "precious" > keep.vtu
expect_exit 1 "$BISECT" refine "$ROOT/data/square.msh" --region "$ROOT/data/regions/circle.json" -o keep.vtu
one_line_naming keep.vtu
[[ $(cat keep.vtu) == precious ]] || fail "existing output overwritten"
# The input is never overwritten, even with --force.
cp "$ROOT/data/square.msh" in.msh
expect_exit 1 "$BISECT" refine in.msh --region "$ROOT/data/regions/circle.json" -o in.msh --force
one_line_naming in.msh
cmp -s in.msh "$ROOT/data/square.msh" || fail "input changed"
# --help documents the exit codes.
"$BISECT" --help | grep -q "Exit codes" || fail "--help lacks exit codes"
"$BISECT" refine --help | grep -q -- "--max-elements" || fail "refine --help"
echo "limits_and_overwrite: ok"
