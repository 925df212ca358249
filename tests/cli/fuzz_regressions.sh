# Every input a fuzzer ever crashed on (fuzz/crashes/) is now read cleanly:
# exit 0 (accepted) or 1 (one line naming the file), never a crash.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
n=0
for target in msh vtu; do
  for f in "$ROOT"/fuzz/crashes/fuzz_$target/*; do
    [[ -f $f ]] || continue
    cp "$f" case.$target
    set +e
    "$BISECT" info case.$target >/dev/null 2>"$WORK/err"
    rc=$?
    set -e
    [[ $rc == 0 || $rc == 1 ]] || { cat "$WORK/err"; fail "$(basename "$f"): exit $rc"; }
    [[ $rc == 0 ]] || one_line_naming case.$target
    n=$((n + 1))
  done
done
echo "fuzz_regressions: $n inputs ok"
