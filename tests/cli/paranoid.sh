# refine --check (always on in a BISECT_PARANOID build) checks conformity and
# the input's invariants after every iteration and exits 2 with one line naming
# the iteration and the failure, writing nothing. A real failure cannot be
# provoked from outside, so this uses the test hook of bisect_hooked
# BISECT_TEST_CORRUPT_ITERATION=k: after iteration k, refine merges one pair
# of sibling cells back into their parent, leaving the midpoint hanging.
# Without --check, the cheap final check that refine runs by default before
# writing must catch it too.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
# The hook lives in the test-only binary bisect_hooked (third argument).
HOOKED=${3:?usage: paranoid.sh BISECT ROOT BISECT_HOOKED}
paranoid=0
grep -q '^BISECT_PARANOID:BOOL=ON$' "$(dirname "$BISECT")/CMakeCache.txt" 2>/dev/null && paranoid=1

"$BISECT" generate kuhn --dim 4 --cells 1 -o cube4.vtu >/dev/null
# input, region, iterations, the iteration to corrupt
cases=(
  "$ROOT/data/square.msh|$ROOT/data/regions/circle.json|4|2"
  "$ROOT/data/ball.msh|$ROOT/data/regions/hemisphere.json|2|1"
  "cube4.vtu|$ROOT/data/regions/hypersphere.json|6|5"
)
for c in "${cases[@]}"; do
  IFS='|' read -r in region n k <<<"$c"
  name=$(basename "$in")
  # Honest runs pass the check after every iteration.
  expect_exit 0 "$BISECT" refine "$in" --region "$region" -n "$n" --check -q -o ok.vtu --force
  expect_exit 0 "$BISECT" check ok.vtu --against "$in"
  # A hook past the last iteration changes nothing.
  BISECT_TEST_CORRUPT_ITERATION=$((n + 1)) expect_exit 0 "$HOOKED" refine "$in" --region "$region" \
    -n "$n" --check -q -o ok.vtu --force
  # The shipped binary has no hook: the variable does nothing there.
  BISECT_TEST_CORRUPT_ITERATION=$k expect_exit 0 "$BISECT" refine "$in" --region "$region" \
    -n "$n" -q -o ok.vtu --force
  # The corrupted iteration trips the check: exit 2, one line, no output.
  rm -f out.vtu out.quality.csv
  BISECT_TEST_CORRUPT_ITERATION=$k expect_exit 2 "$HOOKED" refine "$in" --region "$region" \
    -n "$n" --check -q -o out.vtu
  one_line_naming "bisect: internal check failed after iteration $k: "
  grep -qE 'hanging node|overlap|boundary measure changed' "$WORK/err" ||
    { cat "$WORK/err" >&2; fail "$name: the failure is not named"; }
  [[ ! -e out.vtu && ! -e out.quality.csv ]] || fail "$name: output written despite exit 2"
  left=$(ls -A | grep -vxE 'ok\.vtu|ok\.quality\.csv|cube4\.vtu|err|out' || true)
  [[ -z $left ]] || fail "$name: files left behind: $left"
  # Without --check the final check, on by default, still refuses to write
  # the corrupted mesh: exit 2, one line, no output.
  rm -f out.vtu out.quality.csv
  BISECT_TEST_CORRUPT_ITERATION=$k expect_exit 2 "$HOOKED" refine "$in" --region "$region" \
    -n "$n" -q -o out.vtu
  if [[ $paranoid == 1 ]]; then
    one_line_naming "bisect: internal check failed after iteration $k: "
  else
    one_line_naming "bisect: internal check failed on the refined mesh: "
    grep -qE 'boundary measure changed|hanging node|overlap' "$WORK/err" ||
      { cat "$WORK/err" >&2; fail "$name: the final check does not name the failure"; }
  fi
  [[ ! -e out.vtu && ! -e out.quality.csv ]] || fail "$name: output written despite exit 2"
done
echo "paranoid: ok (paranoid build: $paranoid)"
