# 4D: refine a Kuhn hypercube around the moving sphere, write t-slices, and
# check each slice is a conforming 3D mesh with the section's volume.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
expect_exit 0 "$BISECT" generate kuhn --dim 4 --cells 2 -o cube.vtu
expect_exit 0 "$BISECT" refine cube.vtu --region "$ROOT/data/regions/moving-sphere.json" -n 6 \
  -m longest -o cube6.vtu --slices 0,0.5,1 --quiet
expect_exit 0 "$BISECT" check cube6.vtu --against cube.vtu
for t in 0 0.5 1; do
  [[ -f cube6.t$t.vtu ]] || fail "slice t=$t missing"
  expect_exit 0 "$BISECT" check cube6.t$t.vtu
  expect_exit 0 "$BISECT" info cube6.t$t.vtu
  grep -q "^volume: 1$" "$WORK/out" || fail "slice t=$t volume is not 1"
  grep -q "^boundary measure: 6$" "$WORK/out" || fail "slice t=$t boundary is not 6"
done
# Refining the 4D output continues its state; slicing by hand works too.
expect_exit 0 "$BISECT" refine cube6.vtu --region "$ROOT/data/regions/moving-sphere.json" -n 2 -o cube8.vtu --quiet
expect_exit 0 "$BISECT" check cube8.vtu --against cube.vtu
expect_exit 0 "$BISECT" slice cube8.vtu --axis x --value 0.3 -o x.vtu
expect_exit 0 "$BISECT" check x.vtu
# A 3D (2D+t) mesh slices into a conforming 2D triangle mesh; refine --slices too.
expect_exit 0 "$BISECT" generate kuhn --dim 3 --cells 2 -o k3.vtu
expect_exit 0 "$BISECT" slice k3.vtu --t 0.25 -o k3s.vtu
grep -q "triangles" "$WORK/err" || fail "no triangle count in the message"
expect_exit 0 "$BISECT" info k3s.vtu
grep -q "^dimension: 2$" "$WORK/out" || fail "slice of a 3D mesh is not 2D"
grep -q "^volume: 1$" "$WORK/out" || fail "slice of the unit cube is not the unit square"
expect_exit 0 "$BISECT" refine k3.vtu --region "$ROOT/data/regions/sphere.json" -n 3 -o k3r.vtu --slices 0,0.5,1 --quiet
for t in 0 0.5 1; do expect_exit 0 "$BISECT" check k3r.t$t.vtu; done
# slice --json: the section's size, as info reads it back.
expect_exit 0 "$BISECT" slice k3r.vtu --t 0.25 -o k3r-s.vtu --json -q
cp "$WORK/out" k3r-s.json
expect_exit 0 "$BISECT" info k3r-s.vtu --json
cp "$WORK/out" k3r-s-info.json
/usr/bin/python3 - <<'PY' || fail "slice --json: $(cat k3r-s.json)"
import json
s, i = json.load(open("k3r-s.json")), json.load(open("k3r-s-info.json"))
assert s["cells"] > 0 and s["vertices"] > 0, s
assert (s["dim"], s["cells"], s["vertices"]) == (i["dim"], i["cells"], i["vertices"]), (s, i)
assert (s["axis"], s["value"], s["output"]) == ("t", 0.25, "k3r-s.vtu"), s
PY
# refine --slices takes extrude's START:STOP:COUNT too (COUNT + 1 sections).
expect_exit 0 "$BISECT" refine k3.vtu --region "$ROOT/data/regions/sphere.json" -n 2 -o k3q.vtu --slices 0:1:4 --quiet
for t in 0 0.25 0.5 0.75 1; do expect_exit 0 "$BISECT" check k3q.t$t.vtu; done
[[ $(ls k3q.t*.vtu | wc -l) == 5 ]] || fail "--slices 0:1:4 wrote $(ls k3q.t*.vtu)"
expect_exit 0 "$BISECT" refine k3.vtu --region "$ROOT/data/regions/sphere.json" -n 1 -o k3one.vtu --slices 0.5 --quiet
[[ -f k3one.t0.5.vtu ]] || fail "--slices 0.5: no section written"
# Values that agree to 6 significant digits get names with more of them,
# not one name for two files.
expect_exit 0 "$BISECT" refine k3.vtu --region "$ROOT/data/regions/sphere.json" -n 1 -o k3near.vtu --slices 0.5,0.5000001
[[ -f k3near.t0.5.vtu && -f k3near.t0.5000001.vtu ]] || fail "--slices 0.5,0.5000001 wrote $(ls k3near.t*)"
grep -q "t = 0.5000001)" "$WORK/err" || fail "the section line does not show 0.5000001: $(cat "$WORK/err")"
for bad in 0:1 0:1:0 1,0.5 0.5,0.5 a,1; do
  expect_exit 1 "$BISECT" refine k3.vtu --region "$ROOT/data/regions/sphere.json" -o bad.vtu --slices $bad
  one_line_naming "--slices"
  [[ ! -e bad.vtu ]] || fail "--slices $bad wrote an output"
done

# Which coordinates a section has (README, bisect slice): a box of
# extents 1 (x), 2 (y), 3 (z) and, extruded, 4 (t).
/usr/bin/python3 - <<'PY' || fail "cannot make the box"
import meshio
m = meshio.read("k3.vtu")
m.points[:, 1] *= 2
m.points[:, 2] *= 3
meshio.write("box3.vtu", meshio.Mesh(m.points, [("tetra", m.cells_dict["tetra"])]))
PY
expect_exit 0 "$BISECT" extrude box3.vtu --slices 0:4:2 -o box4.vtu -q
# extent_is FILE X Y [Z]: the bounding box bisect info reads is [0, X] x [0, Y] (x [0, Z]).
extent_is() {
  local f=$1; shift
  expect_exit 0 "$BISECT" info "$f" --json
  /usr/bin/python3 - "$WORK/out" "$@" <<'PY' || fail "$f: bounding box is not [0, $*]: $(cat "$WORK/out")"
import json, sys
j = json.load(open(sys.argv[1]))
want = [float(v) for v in sys.argv[2:]]
assert j["dim"] == len(want), j["dim"]
assert all(abs(a) < 1e-12 for a in j["bounding_box"]["min"]), j["bounding_box"]
assert all(abs(a - b) < 1e-12 for a, b in zip(j["bounding_box"]["max"], want)), j["bounding_box"]
PY
}
expect_exit 0 "$BISECT" slice box4.vtu --t 1 -o b4t.vtu -q
extent_is b4t.vtu 1 2 3 # (x, y, z)
expect_exit 0 "$BISECT" slice box4.vtu --axis x --value 0.5 -o b4x.vtu -q
extent_is b4x.vtu 2 3 4 # (y, z, t) as x, y, z
expect_exit 0 "$BISECT" slice box4.vtu --axis y --value 0.5 -o b4y.vtu -q
extent_is b4y.vtu 1 3 4 # (x, z, t)
expect_exit 0 "$BISECT" slice box4.vtu --axis z --value 0.5 -o b4z.vtu -q
extent_is b4z.vtu 1 2 4 # (x, y, t)
expect_exit 0 "$BISECT" slice box3.vtu --t 1.5 -o b3t.vtu -q
extent_is b3t.vtu 1 2 # (x, y), written at z = 1.5
expect_exit 0 "$BISECT" slice box3.vtu --axis z --value 1.5 -o b3z.vtu -q
cmp -s b3t.vtu b3z.vtu || fail "a 3D mesh's --axis z is not its --t"
expect_exit 0 "$BISECT" slice box3.vtu --axis x --value 0.5 -o b3x.vtu -q
extent_is b3x.vtu 2 3 # (y, z) as x, y, written at z = 0
expect_exit 0 "$BISECT" slice box3.vtu --axis y --value 0.5 -o b3y.vtu -q
extent_is b3y.vtu 1 3 # (x, z) as x, y
# --t is --axis t --value: not with --axis, and a cut needs a value.
expect_exit 1 "$BISECT" slice box4.vtu --t 0.5 --axis x -o mixed.vtu
one_line_naming "--axis"
expect_exit 1 "$BISECT" slice box4.vtu --axis x -o novalue.vtu
one_line_naming "--value"
expect_exit 1 "$BISECT" slice box4.vtu -o novalue.vtu
one_line_naming "--t VALUE"
[[ ! -e mixed.vtu && ! -e novalue.vtu ]] || fail "a refused slice wrote its output"
/usr/bin/python3 - <<'PY' || fail "the third coordinate of a 3D mesh's sections"
import meshio
for name, z in (("b3t.vtu", 1.5), ("b3x.vtu", 0.0), ("b3y.vtu", 0.0)):
    p = meshio.read(name).points
    assert p.shape[1] == 3 and abs(p[:, 2] - z).max() == 0, (name, p[:, 2].min(), p[:, 2].max())
p = meshio.read("b4x.vtu").points
assert abs(p.max(axis=0) - [2, 3, 4]).max() < 1e-12, p.max(axis=0)
PY
expect_exit 1 "$BISECT" slice k3.vtu --axis t --value 0.5 -o /dev/null/x.vtu
expect_exit 1 "$BISECT" refine "$ROOT/data/square.msh" --region "$ROOT/data/regions/circle.json" --slices 0.5 -o sq.vtu
one_line_naming "square.msh"
echo "slice_4d: ok"
