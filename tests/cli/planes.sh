# Triangle meshes in a plane z = c (a Gmsh plane at z = 5, rounding noise in
# z) are refined and written back in their plane; a mesh that is not planar
# gets one line saying so; a z-section of a 3D mesh stays at its height, so
# it overlays the mesh in ParaView (read back with VTK's own reader).
source "$(dirname "$0")/lib.bash"
cd "$WORK"
cat >plane.msh <<'MSH'
$MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
4
1 0 0 5
2 1 0 5
3 1 1 5.00000000000001
4 0 1 4.99999999999999
$EndNodes
$Elements
2
1 2 2 1 1 1 2 3
2 2 2 1 1 1 3 4
$EndElements
MSH
echo '{"type": "sphere", "center": [0.3, 0.3], "radius": 0.2}' >c.json
expect_exit 0 "$BISECT" refine plane.msh --region c.json -n 5 -o plane.vtu -q
expect_exit 0 "$BISECT" refine plane.msh --region c.json -n 5 -o plane-out.msh -q
expect_exit 0 "$BISECT" check plane.vtu --against plane.msh
z_range() { /usr/bin/python3 -c "
import sys, vtk
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(sys.argv[1]); r.Update()
b = r.GetOutput().GetBounds(); print(round(b[4], 6), round(b[5], 6))" "$1"; }
[[ $(z_range plane.vtu) == "5.0 5.0" ]] || fail "plane.vtu is not at z = 5: $(z_range plane.vtu)"
expect_exit 0 "$BISECT" check plane-out.msh --against plane.msh
# Not planar: one line, saying so.
sed 's/^3 1 1 5.00000000000001/3 1 1 5.5/' plane.msh >tilted.msh
expect_exit 1 "$BISECT" refine tilted.msh --region c.json -o t.vtu
one_line_naming "tilted.msh: the triangles are not in one plane z = c"
# A z-section of a 3D mesh keeps its height.
"$BISECT" generate kuhn --dim 3 --cells 2 -o cube.vtu 2>/dev/null
expect_exit 0 "$BISECT" slice cube.vtu --t 0.25 -o section.vtu
[[ $(z_range section.vtu) == "0.25 0.25" ]] || fail "the section is not at z = 0.25"
echo "planes: ok"
