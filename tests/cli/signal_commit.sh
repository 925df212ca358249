# SIGINT around the moment the outputs are committed, 150 times: exit 130
# must leave the old mesh and CSV byte-identical, exit 0 give the new mesh.
# The signal may be taken by any of the process's threads; before the commit
# claimed its state once against the handler (src/io/output.cpp), a thread
# other than the committing one removed the temporaries mid-rename: 7 of
# 150 tries ended with exit 130 and a new mesh beside the old CSV.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
"$BISECT" generate kuhn --dim 3 --cells 8 -o in.vtu -q
echo '{"type": "sphere", "center": [0.3, 0.4, 0.2], "radius": 0.3}' >s.json
"$BISECT" refine in.vtu --region s.json -n 4 -o out.vtu -q -f
cp out.vtu old.vtu
cp out.quality.csv old.csv
"$BISECT" refine in.vtu --region s.json -n 5 -o new.vtu -q -f
t0=$(date +%s.%N)
"$BISECT" refine in.vtu --region s.json -n 5 -o timed.vtu -q -f
run=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
interrupted=0 finished=0
for i in $(seq 150); do
  cp old.vtu out.vtu
  cp old.csv out.quality.csv
  # Between 85% and 115% of a run: around the commit.
  delay=$(awk -v r="$run" -v i="$i" 'BEGIN { srand(i); print r * (0.85 + 0.3 * rand()) }')
  "$BISECT" refine in.vtu --region s.json -n 5 -o out.vtu -q -f 2>/dev/null &
  pid=$!
  sleep "$delay"
  kill -INT "$pid" 2>/dev/null || true
  set +e
  wait "$pid"
  got=$?
  set -e
  case $got in
  130)
    interrupted=$((interrupted + 1))
    cmp -s out.vtu old.vtu && cmp -s out.quality.csv old.csv ||
      fail "try $i: exit 130 after ${delay}s, but the old outputs changed"
    ;;
  0)
    finished=$((finished + 1))
    cmp -s out.vtu new.vtu || fail "try $i: exit 0 after ${delay}s, but not the new mesh"
    ;;
  *) fail "try $i: exit $got" ;;
  esac
  [[ -z $(find . -maxdepth 1 -name '.*.tmp' | head -1) ]] || fail "try $i: temporary files left"
done
echo "signal_commit: a run takes ${run}s; $interrupted interrupted, $finished finished" >&2
echo "signal_commit: ok"
