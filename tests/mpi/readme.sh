# The README's MPI examples (the ```sh mpi blocks of "MPI: distributed
# refinement") run as written, in order, in a scratch directory with the MPI
# build's bisect on PATH and the bundled data/ beside it, and exit 0; the
# gathered mesh they write has the serial run's cells.
# $1: the bisect of a -DBISECT_MPI=ON build; $2: the source tree.
source "$(dirname "$0")/../cli/lib.bash"
mkdir -p "$WORK/bin" "$WORK/run"
ln -s "$BISECT" "$WORK/bin/bisect"
ln -s "$ROOT/data" "$WORK/run/data"
cd "$WORK/run"
export PATH="$WORK/bin:$PATH"
commands=$(awk '/^```/ { if (inside) { inside = 0; next } if ($0 == "```sh mpi") { inside = 1; next } }
                inside { print }' "$ROOT/README.md")
[[ -n $commands ]] || fail "no \`\`\`sh mpi blocks in README.md"
count=0
while IFS= read -r line; do
  [[ -z $line || $line == \#* ]] && continue
  count=$((count + 1))
  set +e
  bash -c "$line" >"$WORK/out" 2>"$WORK/err" </dev/null
  got=$?
  set -e
  [[ $got == 0 ]] || { grep -Ev '^(--|  |$|Primary|a non|mpirun detected|the job)' "$WORK/err" >&2; fail "README example exits $got: $line"; }
done <<<"$commands"
((count >= 3)) || fail "only $count MPI examples found"
[[ -f ball-mpi.pvtu && -f ball-mpi_2.vtu ]] || fail "the .pvtu example wrote no pieces"
/usr/bin/python3 "$ROOT/tests/mpi/same_cells.py" ball-serial.vtu ball-gathered.vtu >/dev/null ||
  fail "the gathered example differs from the serial one"
/usr/bin/python3 "$ROOT/tests/mpi/same_cells.py" ball-serial.vtu ball-mpi.pvtu >/dev/null ||
  fail "the .pvtu example differs from the serial one"
echo "readme (MPI): $count examples ran"
