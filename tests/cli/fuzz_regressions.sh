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
# Every finding of the binary fuzzer (scripts/fuzz_binary.py; crashes, hangs,
# wrong meshes written with exit 0, multi-line messages) now keeps the
# promise: exit 1 with one line naming the file, or exit 0/3 with a mesh that
# `bisect check --against` the input accepts; never a signal or 10 s.
m=0
for f in "$ROOT"/fuzz/findings/minimized/*.vtu "$ROOT"/fuzz/findings/minimized/*.msh; do
  [[ -f $f ]] || continue
  name=$(basename "$f")
  ext=${name##*.}
  rm -rf run && mkdir run
  cp "$f" run/case.$ext
  cp "${f%.*}.region.json" run/region.json
  set +e
  (cd run && timeout 10 "$BISECT" refine case.$ext --region region.json -n 2 -o out.$ext -q) \
    >/dev/null 2>"$WORK/err"
  rc=$?
  set -e
  case $rc in
    1) one_line_naming case.$ext
       [[ -z $(ls run | grep -v '^case\.\|^region\.json$') ]] || fail "$name: files left behind" ;;
    0|3) expect_exit 0 "$BISECT" check run/out.$ext --against run/case.$ext ;;
    *) cat "$WORK/err" >&2; fail "$name: exit $rc" ;;
  esac
  m=$((m + 1))
done
echo "fuzz_regressions: $n libFuzzer inputs and $m binary-fuzzer findings ok"
