# --threads: every output is the same, byte for byte, for 1, 2 and 3 threads
# (README, "Threads"), on a mesh large enough for every parallel step (the
# final check's and the validation's walks split the cells above 131,072).
source "$(dirname "$0")/lib.bash"
cd "$WORK"
"$BISECT" refine "$ROOT/data/ball.msh" --region "$ROOT/data/regions/hemisphere.json" -n 7 \
  -o big.vtu -q
for t in 1 2 3; do
  # refine again from a large input (validation, selection, refinement,
  # quality, final check, compression), to .vtu and .msh
  "$BISECT" refine big.vtu --region "$ROOT/data/regions/hemisphere.json" -n 1 -o r$t.vtu \
    --quality-csv r$t.csv -q --threads $t
  "$BISECT" refine big.vtu --region "$ROOT/data/regions/hemisphere.json" -n 1 -o r$t.msh \
    --quality-csv none -q --threads $t
  "$BISECT" coarsen r$t.vtu --all -o c$t.vtu -q --threads $t
  "$BISECT" info big.vtu --json -q --threads $t >info$t.json
  "$BISECT" check r1.vtu --against big.vtu -q --threads $t >check$t.txt
done
cells=$(/usr/bin/python3 -c 'import json; print(json.load(open("info1.json"))["cells"])')
((cells > 150000)) || fail "the test mesh has only $cells cells"
# The CSV's last column is the time taken: drop it.
for t in 1 2 3; do cut -d, -f1-8 r$t.csv >q$t.csv; done
for t in 2 3; do
  for f in r.vtu r.msh q.csv c.vtu info.json check.txt; do
    a=${f%%.*}1.${f#*.} b=${f%%.*}$t.${f#*.}
    cmp -s "$a" "$b" || fail "$b differs from $a (--threads $t against --threads 1)"
  done
done
echo "threads: refine, coarsen, info and check give the same bytes for 1, 2 and 3 threads ($cells cells)"
