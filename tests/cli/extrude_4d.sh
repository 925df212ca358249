# extrude: a convex 3D mesh becomes a conforming 4D mesh that refines and slices.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
expect_exit 0 "$BISECT" generate kuhn --dim 3 --cells 2 -o cube.vtu
expect_exit 0 "$BISECT" extrude cube.vtu --slices 0:1:2 -o st.vtu
expect_exit 0 "$BISECT" info st.vtu
grep -q "^dimension: 4$" "$WORK/out" || fail "extruded mesh is not 4D"
grep -q "^volume: 1$" "$WORK/out" || fail "extruded volume is not 1"
expect_exit 0 "$BISECT" check st.vtu
expect_exit 0 "$BISECT" refine st.vtu --region "$ROOT/data/regions/moving-sphere.json" -n 4 -o st4.vtu --slices 0.5 --quiet
expect_exit 0 "$BISECT" check st4.vtu --against st.vtu
expect_exit 0 "$BISECT" check st4.t0.5.vtu
# Bad slices and a 2D mesh are one-line errors.
expect_exit 1 "$BISECT" extrude cube.vtu --slices 1,0 -o bad.vtu
one_line_naming "increase"
expect_exit 1 "$BISECT" extrude cube.vtu --slices 0:1:x -o bad.vtu
one_line_naming "not a number"
expect_exit 1 "$BISECT" extrude "$ROOT/data/square.msh" --slices 0,1 -o bad.vtu
one_line_naming "square.msh"
[[ ! -e bad.vtu ]] || fail "output left behind"
# The faceted octant is not convex: refused, unless --hull.
expect_exit 1 "$BISECT" extrude "$ROOT/data/octant.msh" --slices 0,1 -o oct.vtu
one_line_naming "--hull"
[[ ! -e oct.vtu ]] || fail "output left behind"
expect_exit 0 "$BISECT" extrude "$ROOT/data/octant.msh" --slices 0,1 --hull -o oct.vtu
expect_exit 0 "$BISECT" check oct.vtu
expect_exit 0 "$BISECT" refine oct.vtu --region "$ROOT/data/regions/hypersphere.json" -n 5 -o oct5.vtu --quiet --slices 0,0.5,1
expect_exit 0 "$BISECT" check oct5.vtu --against oct.vtu
for t in 0 0.5 1; do expect_exit 0 "$BISECT" check oct5.t$t.vtu; done
# A slab a million times thinner than the mesh is triangulated (Qhull
# without merging, src/tools/extrude.cpp) and passes the checks.
"$BISECT" generate kuhn --dim 3 --cells 2 -o k3.vtu -q
expect_exit 0 "$BISECT" extrude k3.vtu --slices 0,1e-6 -o thin6.vtu -q
expect_exit 0 "$BISECT" check thin6.vtu
# One 10^8 times thinner: Qhull's own report (dozens of lines) is not
# printed; the run ends on one line, nothing written (exit 2: the
# triangulation fails the validation every result gets).
set +e
"$BISECT" extrude k3.vtu --slices 0,1e-8 -o thin.vtu >"$WORK/out" 2>"$WORK/err"
rc=$?
set -e
[[ $rc == 2 || $rc == 1 ]] || { cat "$WORK/err" >&2; fail "thin slab: exit $rc"; }
one_line_naming "thin.vtu"
grep -q -- "--method colouring" "$WORK/err" || fail "thin slab: no hint of --method colouring"
[[ ! -e thin.vtu ]] || fail "thin slab: output left behind"
# The colouring extrusion writes each point's slab as the point array slice:
# an input array of that name is refused rather than written twice.
/usr/bin/python3 - <<'PY'
import meshio
m = meshio.read("k3.vtu")
m.point_data["slice"] = m.points[:, 0]
meshio.write("k3-slice.vtu", m)
PY
expect_exit 1 "$BISECT" extrude k3-slice.vtu --method colouring --slices 0,1 -o sl.vtu
one_line_naming "point array 'slice'"
[[ ! -e sl.vtu ]] || fail "slice clash: output left behind"
echo "extrude_4d: ok"
