# coarsen: refine -> file -> bisect coarsen --all gives the input's cells back
# (2D, 3D, 4D from bisect extrude, forced simplex types); partial coarsening (region, indicator)
# passes the checks; the tree survives meshio (.vtu -> meshio -> .vtu, and
# Gmsh 2.2); usage and input errors exit 1 with one line.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
/usr/bin/python3 -c "import meshio" 2>/dev/null ||
  fail "coarsen: python3-meshio is not installed (scripts/install-deps.sh installs it)"

# same_cells A B: the two files hold the same cells (as sets of vertex
# coordinates) and the same vertices (meshio reads both; 2D and 3D).
same_cells() {
  /usr/bin/python3 - "$1" "$2" <<'PY' || fail "$1 and $2 hold different cells"
import sys, meshio
def shapes(name):
    m = meshio.read(name)
    blocks = [b for b in m.cells if b.type in ("triangle", "tetra")]
    top = "tetra" if any(b.type == "tetra" for b in blocks) else "triangle"
    pts = [tuple(round(float(c), 12) for c in p) for p in m.points]
    cells = sorted(tuple(sorted(pts[i] for i in c)) for b in blocks if b.type == top for c in b.data)
    used = sorted({pts[i] for b in blocks if b.type == top for c in b.data for i in c})
    return cells, used
a, b = shapes(sys.argv[1]), shapes(sys.argv[2])
assert a[0] == b[0], ("cells", len(a[0]), len(b[0]))
assert a[1] == b[1], ("vertices", len(a[1]), len(b[1]))
PY
}

json_field() { /usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }

# 2D and 3D, every marking: refine 4 times, coarsen 4 passes.
printf '%s\n' '{"type": "sphere", "center": [0.3, 0.3, 0.3], "radius": 0.3}' >s3.json
for marking in index longest sorted; do
  for input in "$ROOT/data/square.msh" "$ROOT/data/octant.msh"; do
    region=$ROOT/data/regions/circle.json
    [[ $input == *octant* ]] && region=s3.json
    name=$(basename "$input" .msh)-$marking
    expect_exit 0 "$BISECT" refine "$input" --region "$region" -n 4 --marking $marking -o $name.vtu -q \
      --quality-csv none
    expect_exit 0 "$BISECT" coarsen $name.vtu --all -n 4 -o $name.back.vtu --json -q
    cp "$WORK/out" $name.json
    [[ $(json_field $name.json cells) == $("$BISECT" info "$input" | sed -n 's/^cells: //p') ]] ||
      fail "$name: coarsened cell count: $(cat $name.json)"
    (($(json_field $name.json passes) <= 4)) || fail "$name: more passes than iterations"
    for key in input output passes cells vertices removed_vertices initial_cells; do
      grep -q "\"$key\"" $name.json || fail "--json has no key $key"
    done
    same_cells "$input" $name.back.vtu
    expect_exit 0 "$BISECT" check $name.back.vtu --against "$input"
    # Refining the coarsened file again continues the same sequence.
    expect_exit 0 "$BISECT" refine $name.back.vtu --region "$region" -n 4 -o $name.again.vtu -q \
      --quality-csv none
    same_cells $name.vtu $name.again.vtu
  done
done

# One pass undoes the last iteration: refine -n 4 then coarsen -n 1 gives
# refine -n 3; --origin: the first input cell merged into each output cell.
expect_exit 0 "$BISECT" refine "$ROOT/data/square.msh" --region "$ROOT/data/regions/circle.json" -n 3 \
  -o square-3.vtu -q --quality-csv none
expect_exit 0 "$BISECT" coarsen square-index.vtu --all -n 1 --origin -o square-back3.vtu -q
same_cells square-3.vtu square-back3.vtu
/usr/bin/python3 - <<'PY' || fail "--origin"
import meshio, numpy as np
fine, back = meshio.read("square-index.vtu"), meshio.read("square-back3.vtu")
o = back.cell_data["bisect:origin"][0]
assert o.dtype == np.int32, o.dtype
n = len(fine.cells_dict["triangle"])
assert 0 <= o.min() and o.max() < n and len(set(o.tolist())) == len(o), (o.min(), o.max(), n)
# each output cell's origin is an input cell that lies inside it
fp, bp = fine.points[:, :2], back.points[:, :2]
for c, src in zip(back.cells_dict["triangle"], o):
    a, b, d = bp[c]
    g = fp[fine.cells_dict["triangle"][src]].mean(axis=0)
    m = np.array([b - a, d - a]).T
    l = np.linalg.solve(m, g - a)
    assert l.min() > -1e-12 and l.sum() < 1 + 1e-12, (src, l)
lv = fine.point_data["bisect:level"]
assert lv.max() == 4 and lv.min() == 0, (lv.min(), lv.max())
PY

# One pass at a time, with a progress line per pass; -o default name.
expect_exit 0 "$BISECT" coarsen square-index.vtu --all -n 2
[[ -f square-index.coarsened.vtu ]] || fail "default output name"
[[ $(grep -c '^pass [12]/2: ' "$WORK/err") == 2 ]] || { cat "$WORK/err"; fail "progress lines"; }
expect_exit 1 "$BISECT" coarsen square-index.vtu --all -n 2
one_line_naming "square-index.coarsened.vtu"
expect_exit 0 "$BISECT" coarsen square-index.vtu --all -n 2 -f -q
[[ ! -s "$WORK/err" ]] || fail "-q printed something"
# -n 0 runs passes until one removes nothing: square-index.vtu was refined 4
# times, so 5 pass lines, the last saying it removed nothing; --json's
# "passes" counts the 4 that removed something, "passes_run" all 5.
expect_exit 0 "$BISECT" coarsen square-index.vtu --all -n 0 -o all0.vtu --json
cp "$WORK/out" all0.json
[[ $(grep -c '^pass [0-9]*: ' "$WORK/err") == 5 ]] || { cat "$WORK/err"; fail "-n 0: pass lines"; }
grep -q '^pass 5: .* 0 vertices removed, .*nothing left to remove' "$WORK/err" ||
  { cat "$WORK/err"; fail "-n 0: the last pass does not say it removed nothing"; }
[[ $(json_field all0.json passes) == 4 ]] || fail "-n 0: passes is not 4: $(cat all0.json)"
[[ $(json_field all0.json passes_run) == 5 ]] || fail "-n 0: passes_run is not 5: $(cat all0.json)"

# A region: only cells touching it, and the result passes bisect check.
printf '%s\n' '{"type": "box", "min": [0, 0], "max": [0.5, 0.5]}' >box.json
expect_exit 0 "$BISECT" coarsen square-index.vtu --region box.json -n 0 -o part.vtu --json -q
cp "$WORK/out" part.json
(($(json_field part.json removed_vertices) > 0)) || fail "the region removed nothing"
(($(json_field part.json cells) > 404)) || fail "the region removed everything"
expect_exit 0 "$BISECT" check part.vtu --against "$ROOT/data/square.msh"

# An indicator: a cell array (gmsh:physical is 1 everywhere in square.msh)
# and a point array (here made by meshio: x of each vertex).
expect_exit 0 "$BISECT" coarsen square-index.vtu --indicator gmsh:physical --below 2 -n 0 -o ind.vtu -q
same_cells "$ROOT/data/square.msh" ind.vtu
expect_exit 0 "$BISECT" coarsen square-index.vtu --indicator gmsh:physical --below 1 -n 0 -o none.vtu --json -q
cp "$WORK/out" none.json
[[ $(json_field none.json removed_vertices) == 0 ]] || fail "nothing is below 1"
/usr/bin/python3 - <<'PY' || fail "meshio round trip"
import meshio
m = meshio.read("square-index.vtu")
names = set(m.point_data) | set(m.cell_data)
for n in ["bisect:parent_a", "bisect:parent_b", "bisect:generation", "bisect:level"]:
    assert n in names, (n, sorted(names))
m.point_data["xcoord"] = m.points[:, 0].copy()
meshio.write("meshio.vtu", m)
# Gmsh 2.2 takes one-component fields only: the tree arrays are such.
meshio.write("meshio22.msh", m, file_format="gmsh22", binary=False)
PY
expect_exit 0 "$BISECT" coarsen meshio.vtu --all -n 0 -o meshio.back.vtu -q
same_cells "$ROOT/data/square.msh" meshio.back.vtu
expect_exit 0 "$BISECT" coarsen meshio.vtu --indicator xcoord --below 0.5 -n 0 -o left.vtu -q
expect_exit 0 "$BISECT" check left.vtu --against "$ROOT/data/square.msh"
expect_exit 0 "$BISECT" coarsen meshio22.msh --all -n 0 -o meshio22.back.vtu -q
same_cells "$ROOT/data/square.msh" meshio22.back.vtu

# 4D: a mesh made by bisect extrude, refined, coarsened back.
expect_exit 0 "$BISECT" generate kuhn --dim 3 --cells 2 -o cube.vtu
expect_exit 0 "$BISECT" extrude cube.vtu --slices 0:1:2 -o st.vtu
printf '%s\n' '{"type": "sphere", "center": [0.3, 0.3, 0.3, 0.3], "radius": 0.3}' >s4.json
expect_exit 0 "$BISECT" refine st.vtu --region s4.json -n 3 -o st-fine.vtu -q --quality-csv none
expect_exit 0 "$BISECT" coarsen st-fine.vtu --all -n 3 -o st-back.vtu --json -q
cp "$WORK/out" st.json
expect_exit 0 "$BISECT" info st.vtu --json
cp "$WORK/out" st-info.json
[[ $(json_field st.json cells) == $(json_field st-info.json cells) ]] || fail "4D cells: $(cat st.json)"
[[ $(json_field st.json vertices) == $(json_field st-info.json vertices) ]] || fail "4D vertices"
expect_exit 0 "$BISECT" check st-back.vtu --against st.vtu

# Forced types (generate simplex --type): the explicit edge order survives
# the refined file (bisect:parent_rank: the split edges' ranks, which no cell
# holds any more), so coarsening rebuilds the Stage 1 parents.
for dt in 3:P 3:A 3:O 3:M 4:A_PO 4:O_OO 4:M_MM; do
  dim=${dt%%:*} type=${dt#*:}
  expect_exit 0 "$BISECT" generate simplex --dim $dim --type $type --shape random -o forced-$type.vtu -q
  expect_exit 0 "$BISECT" refine forced-$type.vtu --region "$ROOT/data/regions/everything${dim}d.json" -n 3 \
    -o forced-$type-3.vtu -q --quality-csv none
  expect_exit 0 "$BISECT" coarsen forced-$type-3.vtu --all -n 3 -o forced-$type-0.vtu --json -q
  cp "$WORK/out" forced-$type.json
  [[ $(json_field forced-$type.json cells) == 1 ]] || fail "forced $type: $(cat forced-$type.json)"
  [[ $(json_field forced-$type.json vertices) == $((dim + 1)) ]] || fail "forced $type: vertices"
  expect_exit 0 "$BISECT" check forced-$type-0.vtu --against forced-$type.vtu
done

# Errors: one line, exit 1.
expect_exit 1 "$BISECT" coarsen square-index.vtu -o x.vtu
one_line_naming "--all"
expect_exit 1 "$BISECT" coarsen square-index.vtu --indicator nothing --below 1 -o x.vtu
one_line_naming "nothing"
expect_exit 1 "$BISECT" coarsen square-index.vtu --indicator gmsh:physical -o x.vtu
one_line_naming "--below"
expect_exit 1 "$BISECT" coarsen square-index.vtu --all --region box.json -o x.vtu
/usr/bin/python3 - <<'PY'
import meshio
m = meshio.read("square-index.vtu")
a = m.point_data["bisect:parent_a"]
a[len(a) - 1] = len(a) + 5
meshio.write("bad-tree.vtu", m)
PY
expect_exit 1 "$BISECT" coarsen bad-tree.vtu --all -o x.vtu
one_line_naming "bisect:parent_a"
# A misspelt --sum array is an input error naming the file, not ignored.
expect_exit 0 "$BISECT" refine "$ROOT/data/square-eta.vtu" --region "$ROOT/data/regions/circle.json" -n 2 -o eta-fine.vtu -q --quality-csv none
expect_exit 1 "$BISECT" coarsen eta-fine.vtu --all --sum etaa -o eta-back.vtu
one_line_naming "eta-fine.vtu: --sum etaa: no cell array of that name"
[[ ! -e eta-back.vtu ]] || fail "coarsen --sum etaa wrote eta-back.vtu"
expect_exit 0 "$BISECT" coarsen eta-fine.vtu --all --sum eta -o eta-back.vtu -q
echo "coarsen: ok"
