# Shared by the CLI tests: $1 is the bisect binary, $2 the source tree.
set -euo pipefail
BISECT=$1
ROOT=$2
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
# expect_exit CODE CMD...: runs CMD, checks its exit code, keeps stderr in $WORK/err
expect_exit() {
  local want=$1; shift
  set +e
  "$@" >"$WORK/out" 2>"$WORK/err"
  local got=$?
  set -e
  [[ $got == "$want" ]] || { cat "$WORK/err" >&2; fail "exit $got, expected $want: $*"; }
}
# stderr is exactly one line mentioning $1
one_line_naming() {
  [[ $(wc -l <"$WORK/err") == 1 ]] || { cat "$WORK/err" >&2; fail "expected one line on stderr"; }
  grep -qF -- "$1" "$WORK/err" || { cat "$WORK/err" >&2; fail "stderr does not name '$1'"; }
}
