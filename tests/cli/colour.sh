# colour and extrude --method colouring: colour a Kuhn mesh, prove a mesh has
# no colouring, colour its barycentric subdivision, extrude by colour, refine
# the 4D result (continuing the state it carries) and check it.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
expect_exit 0 "$BISECT" generate kuhn --dim 3 --cells 2 -o cube.vtu
expect_exit 0 "$BISECT" colour cube.vtu -o cube-coloured.vtu
grep -q "4-colouring found by propagation (1 component)" "$WORK/out" || fail "no colouring reported"
grep -q "^colour 3 (D): [1-9]" "$WORK/out" || fail "no count for colour D"
expect_exit 0 "$BISECT" info cube-coloured.vtu
grep -q "^point array: colour" "$WORK/out" || fail "colour array not written"
# Reading the written colouring back checks it instead of recomputing it.
expect_exit 0 "$BISECT" colour cube-coloured.vtu
grep -q "given by the point array colour" "$WORK/out" || fail "given colouring not used"

# No 4-colouring (tets of ball.msh around an edge of odd degree), no 3-colouring
# (square.msh): exit 1, one line naming the file and the reason; no output.
expect_exit 1 "$BISECT" colour "$ROOT/data/ball.msh" -o ball-coloured.vtu
one_line_naming "ball.msh"
grep -q "odd number" "$WORK/err" || fail "no reason given"
[[ ! -e ball-coloured.vtu ]] || fail "output left behind"
expect_exit 1 "$BISECT" colour "$ROOT/data/square.msh"
one_line_naming "square.msh"
expect_exit 1 "$BISECT" extrude "$ROOT/data/square.msh" --slices 0:1:2 --method colouring -o bad.vtu
one_line_naming "square.msh"
[[ ! -e bad.vtu ]] || fail "output left behind"
# --barycentric always succeeds.
expect_exit 0 "$BISECT" colour "$ROOT/data/square.msh" --barycentric -o square-bary.vtu
grep -q "^cells: 2424$" "$WORK/out" || fail "square.msh: expected 6 x 404 triangles"
expect_exit 0 "$BISECT" check square-bary.vtu --against "$ROOT/data/square.msh"
expect_exit 0 "$BISECT" colour "$ROOT/data/ball.msh" --barycentric
grep -q "^cells: 144216$" "$WORK/out" || fail "ball.msh: expected 24 x 6009 tets"

# 3D + time: 4 pentatopes per tet and slab, uneven slices, state carried.
expect_exit 0 "$BISECT" extrude cube.vtu --slices 0,0.3,1 --method colouring -o st.vtu
grep -q "(384 pentatopes" "$WORK/err" || fail "expected 48 x 2 x 4 pentatopes"
expect_exit 0 "$BISECT" info st.vtu
grep -q "^dimension: 4$" "$WORK/out" || fail "not 4D"
grep -q "^volume: 1$" "$WORK/out" || fail "volume is not 1"
grep -q "^bisection state: present (marking sorted)$" "$WORK/out" || fail "no bisection state"
expect_exit 0 "$BISECT" check st.vtu
expect_exit 0 "$BISECT" refine st.vtu --region "$ROOT/data/regions/moving-sphere.json" -n 4 \
  --marking index -o st4.vtu --slices 0,0.5,1 --check
grep -q "continuing it" "$WORK/err" || fail "refine re-marked a mesh that carries state"
expect_exit 0 "$BISECT" check st4.vtu --against st.vtu
expect_exit 0 "$BISECT" check st4.t0.5.vtu
# Two runs of 2 iterations give the mesh of one run of 4.
expect_exit 0 "$BISECT" refine st.vtu --region "$ROOT/data/regions/moving-sphere.json" -n 2 -o st2.vtu -q
expect_exit 0 "$BISECT" refine st2.vtu --region "$ROOT/data/regions/moving-sphere.json" -n 2 -o st22.vtu -q
expect_exit 0 "$BISECT" info st22.vtu
cells22=$(grep "^cells:" "$WORK/out")
expect_exit 0 "$BISECT" info st4.vtu
[[ "$(grep "^cells:" "$WORK/out")" == "$cells22" ]] || fail "2 + 2 iterations differ from 4"

# 2D + time by the barycentric subdivision: tetrahedra, 3 per triangle and slab.
expect_exit 0 "$BISECT" extrude "$ROOT/data/square.msh" --slices 0:1:2 --method colouring --barycentric -o sq-st.vtu
grep -q "(14544 tetrahedra" "$WORK/err" || fail "expected 2424 x 2 x 3 tetrahedra"
expect_exit 0 "$BISECT" check sq-st.vtu
echo '{"type":"moving_sphere","center":[0.2,0.3],"velocity":[0.5,0.4],"radius":0.25}' >ms2.json
expect_exit 0 "$BISECT" refine sq-st.vtu --region ms2.json -n 3 -o sq-st3.vtu --check -q
expect_exit 0 "$BISECT" check sq-st3.vtu --against sq-st.vtu

# Usage errors are one line.
expect_exit 1 "$BISECT" extrude cube.vtu --slices 0,1 --barycentric -o bad.vtu
one_line_naming "--method colouring"
expect_exit 1 "$BISECT" extrude cube.vtu --slices 0,1 --method colouring -o bad.msh
one_line_naming "bad.msh"
expect_exit 0 "$BISECT" generate kuhn --dim 4 --cells 1 -o h.vtu
expect_exit 1 "$BISECT" colour h.vtu
one_line_naming "h.vtu"
[[ ! -e bad.vtu && ! -e bad.msh ]] || fail "output left behind"
# A coloured mesh refined: its colour array is -1 at the new vertices, so it
# is ignored and the mesh recoloured, and the extruded mesh carries the
# colouring used (its t = 0 section reads back as a proper given colouring).
echo '{"type":"box","min":[-1,-1,-1],"max":[2,2,2]}' >all.json
expect_exit 0 "$BISECT" refine cube-coloured.vtu --region all.json -n 3 --marking sorted -q -o cube-r.vtu
expect_exit 0 "$BISECT" colour cube-r.vtu
grep -q "found by propagation.*uncoloured (-1), so it was ignored" "$WORK/out" || fail "stale colour array not reported"
expect_exit 0 "$BISECT" extrude cube-r.vtu --slices 0,1 --method colouring -o cube-r4.vtu
expect_exit 0 "$BISECT" slice cube-r4.vtu --t 0 -o cube-r4-t0.vtu
expect_exit 0 "$BISECT" colour cube-r4-t0.vtu
grep -q "given by the point array colour" "$WORK/out" || fail "extruded mesh lacks the colouring it was cut by"

echo "colour: ok"
