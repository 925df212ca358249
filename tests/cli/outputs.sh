# Outputs are one transaction and never lose a file: an output may not be an
# input or another output; FIFOs and devices are written into, symlinks
# written through; a full disk, a file size limit or a signal leaves the old
# mesh and CSV byte-identical and no temporary file; temporary names are
# unique and short; region inputs must be regular files.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
S=$ROOT/data/square.msh
cp "$ROOT/data/regions/circle.json" region.json
cp region.json region.orig
B() { "$BISECT" "$@"; }
no_temporaries() { # dir
  local left
  left=$(find "${1:-.}" -maxdepth 1 -name '.*.tmp' | head -3)
  [[ -z $left ]] || fail "temporary files left behind: $left"
}

# 1. No output may be an input or another output, even with --force.
expect_exit 1 B refine "$S" --region region.json -o out.vtu --quality-csv region.json --force
one_line_naming region.json
cmp -s region.json region.orig || fail "the region file was overwritten"
expect_exit 1 B refine "$S" --region region.json -o out.vtu --quality-csv out.vtu
one_line_naming out.vtu
[[ ! -e out.vtu ]] || fail "an output appeared"
ln -s region.json alias.json
expect_exit 1 B refine "$S" --region region.json -o out.vtu --quality-csv alias.json -f
cmp -s region.json region.orig || fail "the region file was overwritten through a link"
[[ -L alias.json ]] || fail "the link was replaced"

# 2. A FIFO is written into, not replaced.
mkfifo pipe.vtu
cat pipe.vtu >from-pipe.vtu &
reader=$!
expect_exit 0 B refine "$S" --region region.json -o pipe.vtu --quality-csv none -q
wait $reader
[[ -p pipe.vtu ]] || fail "the FIFO was replaced"
expect_exit 0 B check from-pipe.vtu --against "$S"
# Standard output, with --format.
B refine "$S" --region region.json -o - --format msh -q >stdout.msh || fail "-o - failed"
expect_exit 0 B check stdout.msh --against "$S"
expect_exit 1 B refine "$S" --region region.json -o - -q
grep -q -- "--format" "$WORK/err" || fail "-o - without --format should ask for it"
# Standard input ("-"), its format told by the content; a pipe both ways:
# .vtu into a pipe (compressed arrays are held, the header cannot be patched).
B refine - --region region.json -n 2 -o - --format vtu -q <"$S" >piped.vtu || fail "- in, - out"
expect_exit 0 B check piped.vtu --against "$S"
B refine - --region region.json -o - --format vtu -q <"$S" | B refine - --region region.json \
  -o - --format msh -q | B info - >piped-info.txt || fail "a pipeline of refine - -o -"
grep -q '^cells: ' piped-info.txt || fail "info - read nothing from the pipe"
B refine "$S" --region region.json -o piped2.vtu -q --quality-csv none
B coarsen - --all -n 1 -o - --format vtu -q <piped2.vtu | B info - >/dev/null || fail "coarsen -"
echo 'not a mesh' >junk.txt
expect_exit 1 B info - <junk.txt
one_line_naming "-: standard input is neither a .vtu (XML) nor a .msh file"
expect_exit 1 B info - </dev/null
one_line_naming "-: standard input is empty"
head -c 300 stdout.msh >truncated.msh
expect_exit 1 B refine - --region region.json -o x.vtu -q <truncated.msh
one_line_naming "-: "
[[ ! -e x.vtu ]] || fail "a failed read from standard input wrote x.vtu"
ls "${TMPDIR:-/tmp}"/bisect-stdin-* 2>/dev/null && fail "standard input's temporary copy was left"

# 3. A character device is written into; /dev/full says why it fails.
expect_exit 1 B refine "$S" --region region.json -o /dev/full --format vtu --quality-csv none -q
one_line_naming "/dev/full: cannot write: no space left on device"
[[ -c /dev/full ]] || fail "/dev/full is no longer a device"

# 4. A symbolic link is written through: the target is replaced, the link kept.
echo old >target.vtu
ln -s target.vtu link.vtu
expect_exit 1 B refine "$S" --region region.json -o link.vtu -q
[[ $(cat target.vtu) == old ]] || fail "target overwritten without --force"
expect_exit 0 B refine "$S" --region region.json -o link.vtu -q -f
[[ -L link.vtu ]] || fail "the link was replaced by a file"
expect_exit 0 B check target.vtu --against "$S"
ln -s made-by-link.vtu dangling.vtu
expect_exit 0 B refine "$S" --region region.json -o dangling.vtu -q
[[ -L dangling.vtu && -f made-by-link.vtu ]] || fail "a dangling link should be written through"
no_temporaries

# 5. The longest legal name works (the temporary name is shortened).
long=$(printf 'm%.0s' $(seq 1 250)).vtu # 254 bytes
expect_exit 0 B refine "$S" --region region.json -o "$long" --quality-csv q.csv -q
[[ -f $long && -f q.csv ]] || fail "long output name"
no_temporaries
# Its default CSV name would be too long: refused before any work.
expect_exit 1 B refine "$S" --region region.json -o "$long" -f -q
one_line_naming "file name too long"

# 6. Runs writing the same output at once all succeed (unique temporaries).
for i in 1 2 3 4; do
  B refine "$S" --region region.json -n 2 -o same.vtu -f -q &
done
ok=0
for job in $(jobs -p); do wait "$job" && ok=$((ok + 1)); done
[[ $ok == 4 ]] || fail "only $ok of 4 concurrent runs succeeded"
expect_exit 0 B check same.vtu --against "$S"
no_temporaries

# 7. A file size limit: exit 1 naming the reason, old files intact.
echo old-mesh >big.vtu
echo old-csv >big.quality.csv
set +e
(ulimit -f 8 && exec "$BISECT" refine "$S" --region region.json -n 4 -o big.vtu -f -q) 2>"$WORK/err"
got=$?
set -e
[[ $got == 1 ]] || fail "file size limit: exit $got, expected 1"
one_line_naming "big.vtu: cannot write: file too large"
[[ $(cat big.vtu) == old-mesh && $(cat big.quality.csv) == old-csv ]] || fail "old outputs damaged"
no_temporaries

# 8. A full file system (a small tmpfs, when this machine lets us mount one).
if mkdir -p full && mount -t tmpfs -o size=12k tmpfs full 2>/dev/null; then
  echo old-mesh >full/o.vtu
  echo old-csv >full/o.quality.csv
  expect_exit 1 B refine "$S" --region region.json -n 3 -o full/o.vtu -f -q
  one_line_naming "no space left on device"
  [[ $(cat full/o.vtu) == old-mesh && $(cat full/o.quality.csv) == old-csv ]] ||
    { umount full; fail "a full disk damaged the old outputs"; }
  left=$(find full -name '.*.tmp')
  umount full
  [[ -z $left ]] || fail "temporaries left on the full file system: $left"
else
  echo "outputs: cannot mount a tmpfs here; the full-disk case is skipped" >&2
fi

# 9. Region inputs: regular files of sane size only (no hang, no endless read).
mkfifo region.fifo
expect_exit 1 timeout 5 "$BISECT" refine "$S" --region region.fifo -o r.vtu
one_line_naming "region.fifo: not a regular file"
expect_exit 1 timeout 5 "$BISECT" refine "$S" --region /dev/zero -o r.vtu
one_line_naming "/dev/zero: not a regular file"
# A mesh from a pipe: refused by name, with the way that works (-).
mkfifo mesh.fifo
expect_exit 1 timeout 5 "$BISECT" info mesh.fifo
one_line_naming "mesh.fifo: not a regular file (to read a mesh from a pipe, give - as the input"
truncate -s 65M huge.json
expect_exit 1 B refine "$S" --region huge.json -o r.vtu
one_line_naming "huge.json: larger than 64 MiB"
[[ ! -e r.vtu ]] || fail "an output appeared"

# 10. Signals at any moment: either a complete new result (exit 0) or the
# old files untouched and no temporaries (exit 130), never a mix. The delays
# are fractions of an uninterrupted run, so they fall in reading, refining
# and writing alike.
hemi=$ROOT/data/regions/hemisphere.json
B refine "$ROOT/data/ball.msh" --region "$hemi" -n 7 -o sig.vtu -q
cp sig.vtu sig-orig.vtu
cp sig.quality.csv sig-orig.csv
t0=$(date +%s.%N)
B refine sig-orig.vtu --region "$hemi" -n 1 -o sig.vtu -f -q
run=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
cp sig-orig.vtu sig.vtu
cp sig-orig.csv sig.quality.csv
outcomes=""
latencies=""
for f in 0.02 0.15 0.3 0.45 0.6 0.75 0.85 0.95 1.1; do
  delay=$(awk -v r="$run" -v f="$f" 'BEGIN { print r * f }')
  "$BISECT" refine sig-orig.vtu --region "$hemi" -n 1 -o sig.vtu -f -q 2>"$WORK/err" &
  pid=$!
  sleep "$delay"
  kill -INT "$pid" 2>/dev/null || true
  killed=$(date +%s.%N)
  set +e
  wait "$pid"
  got=$?
  set -e
  latency=$(awk -v a="$killed" -v b="$(date +%s.%N)" 'BEGIN { printf "%.3f", b - a }')
  outcomes+=" $got"
  [[ $got == 130 ]] && latencies+=" ${latency}s"
  # The process stops at once (0.5 s is the promise; 1 s leaves room for a
  # loaded machine).
  awk -v l="$latency" 'BEGIN { exit !(l < 1.0) }' || fail "SIGINT took ${latency}s to act"
  no_temporaries
  if [[ $got == 130 ]]; then
    cmp -s sig.vtu sig-orig.vtu && cmp -s sig.quality.csv sig-orig.csv ||
      fail "interrupted after ${delay}s: the old outputs changed"
    grep -q "interrupted; no output written" "$WORK/err" || fail "no message on interruption"
  elif [[ $got == 0 ]]; then
    expect_exit 0 B check sig.vtu --against "$ROOT/data/ball.msh"
    cp sig-orig.vtu sig.vtu
    cp sig-orig.csv sig.quality.csv
  else
    fail "signal after ${delay}s: exit $got"
  fi
done
echo "outputs: a run takes ${run}s; exit codes under SIGINT at 2%..110% of it:$outcomes;" \
  "time from SIGINT to exit:$latencies" >&2
# The default build has no MPI: a .pvtu output, or mpirun starting several
# copies, is refused with the way to the MPI build (nothing written).
expect_exit 1 "$BISECT" refine "$ROOT/data/ball.msh" --region "$ROOT/data/regions/hemisphere.json" -n 1 -o no-mpi.pvtu
one_line_naming "no-mpi.pvtu: a .pvtu output is the distributed run's, and this bisect was built without MPI"
[[ ! -e no-mpi.pvtu ]] || fail "no-mpi.pvtu written"
if ! "$BISECT" --help | grep -q mpirun; then
  OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=0 expect_exit 1 "$BISECT" refine "$ROOT/data/ball.msh" \
    --region "$ROOT/data/regions/hemisphere.json" -n 1 -o two-copies.vtu
  one_line_naming "mpirun started 2 copies of a bisect built without MPI"
  [[ ! -e two-copies.vtu ]] || fail "two-copies.vtu written"
fi
# --format may not contradict the name's extension (a .vtu holding Gmsh data).
expect_exit 1 "$BISECT" refine "$ROOT/data/ball.msh" --region "$ROOT/data/regions/hemisphere.json" -n 1 --format msh -o said-vtu.vtu
one_line_naming "said-vtu.vtu: the format msh (--format) contradicts the name's .vtu"
[[ ! -e said-vtu.vtu ]] || fail "said-vtu.vtu written"
echo "outputs: ok"
