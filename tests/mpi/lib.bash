# Shared by the MPI tests that run bisect under mpirun without standard
# input (options.sh, pieces.sh): the CLI tests' helpers, then:
source "$(dirname "${BASH_SOURCE[0]}")/../cli/lib.bash"
# run_mpi P ARGS...: bisect on P ranks (oversubscribed; as root).
run_mpi() {
  local p=$1; shift
  mpirun --allow-run-as-root --oversubscribe -np "$p" "$BISECT" "$@" </dev/null
}
# One line from bisect naming $1 (mpirun adds its own lines about the exit
# code).
one_bisect_line_naming() {
  [[ $(grep -c '^bisect:' "$WORK/err") == 1 ]] || { cat "$WORK/err" >&2; fail "expected one bisect line"; }
  grep -qF -- "$1" "$WORK/err" || { cat "$WORK/err" >&2; fail "stderr does not name '$1'"; }
}
