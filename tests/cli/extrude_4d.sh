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
echo "extrude_4d: ok"
