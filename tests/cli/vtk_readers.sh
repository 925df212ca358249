# Our .vtu output as ParaView reads it: VTK's own Python reader
# (vtkXMLUnstructuredGridReader, python3-vtk9) reads 2D, 3D, 4D and slice
# outputs in every --compression, with the cell and point counts `bisect
# info` reports, the right cell types, and every array with its name and type.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
if ! /usr/bin/python3 -c "import vtk" 2>/dev/null; then
  echo "vtk_readers: python3-vtk9 is not installed (scripts/install-deps.sh installs it)" >&2
  exit 1
fi
hemi=$ROOT/data/regions/hemisphere.json
"$BISECT" generate kuhn --dim 4 --cells 1 -o h.vtu 2>/dev/null
for c in zlib lz4 none; do
  expect_exit 0 "$BISECT" refine "$ROOT/data/square.msh" --region "$ROOT/data/regions/circle.json" -n 3 \
    -o 2d-$c.vtu --compression $c -q
  expect_exit 0 "$BISECT" refine "$ROOT/data/ball.msh" --region "$hemi" -n 2 -o 3d-$c.vtu --compression $c -q
  expect_exit 0 "$BISECT" refine h.vtu --region "$ROOT/data/regions/moving-sphere.json" -n 6 \
    -o 4d-$c.vtu --compression $c -q --slices 0,0.5
done
for f in 2d-*.vtu 3d-*.vtu 4d-*.vtu 4d-zlib.t0.5.vtu; do
  info=$("$BISECT" info "$f")
  cells=$(sed -n 's/^cells: //p' <<<"$info")
  dim=$(sed -n 's/^dimension: //p' <<<"$info")
  /usr/bin/python3 - "$f" "$cells" "$dim" <<'PY' || fail "$f: VTK's reader disagrees"
import sys, vtk
path, cells, dim = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(path)
r.Update()
if r.GetErrorCode() != 0:
    sys.exit(f"{path}: VTK error code {r.GetErrorCode()}")
g = r.GetOutput()
assert g.GetNumberOfCells() == cells, (g.GetNumberOfCells(), cells)
types = {g.GetCellType(i) for i in range(g.GetNumberOfCells())}
want = {2: {5}, 3: {10}, 4: {2}}[dim]
assert types == want, (types, want)
for i in range(g.GetNumberOfCells()):
    assert g.GetCell(i).GetNumberOfPoints() == dim + 1
cd = g.GetCellData()
names = {cd.GetArrayName(i): cd.GetArray(i) for i in range(cd.GetNumberOfArrays())}
if ".t" not in path:  # a refined mesh carries its bisection state as integers
    for n in ("bisect:state", "bisect:marking"):  # one component each
        assert n in names, (n, list(names))
        assert names[n].GetDataTypeAsString() == "int", (n, names[n].GetDataTypeAsString())
        assert names[n].GetNumberOfTuples() == cells
if dim == 4:
    t = g.GetPointData().GetArray("t")
    assert t is not None and t.GetNumberOfTuples() == g.GetNumberOfPoints()
    sd = g.GetFieldData().GetArray("SpatialDimension")
    assert sd is not None and sd.GetValue(0) == 4
# Every point is used and every coordinate finite.
import math
assert all(math.isfinite(c) for i in range(g.GetNumberOfPoints()) for c in g.GetPoint(i))
print(f"{path}: {cells} cells, types {sorted(types)}, {len(names)} cell arrays")
PY
done
echo "vtk_readers: ok"
