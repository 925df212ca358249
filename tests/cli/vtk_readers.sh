# Our .vtu output as ParaView reads it: VTK's own Python reader
# (vtkXMLUnstructuredGridReader, python3-vtk9) reads 2D, 3D, 4D and slice
# outputs in every --compression, with the cell and point counts `bisect
# info` reports, the right cell types, and every array with its name and type;
# tagged facets and curves (data/ball.msh's boundary, data/box-tagged.msh's
# groups) as lower-dimensional cells after the volume cells, with their
# gmsh:physical, and the physical names as field data.
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
  expect_exit 0 "$BISECT" refine "$ROOT/data/box-tagged.msh" --region "$hemi" -n 2 \
    -o tagged-$c.vtu --compression $c -q
done
for f in 2d-*.vtu 3d-*.vtu 4d-*.vtu 4d-zlib.t0.5.vtu tagged-*.vtu; do
  info=$("$BISECT" info "$f")
  cells=$(sed -n 's/^cells: //p' <<<"$info")
  dim=$(sed -n 's/^dimension: //p' <<<"$info")
  entities=$(sed -n 's/^tagged entities: \([0-9]*\) .*/\1/p' <<<"$info" | awk '{s += $1} END {print s + 0}')
  case $f in 2d-* | 3d-* | tagged-*) ((entities > 0)) || fail "$f: no tagged entities" ;; esac
  /usr/bin/python3 - "$f" "$cells" "$dim" "$entities" <<'PY' || fail "$f: VTK's reader disagrees"
import sys, vtk
path, cells, dim, entities = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(path)
r.Update()
if r.GetErrorCode() != 0:
    sys.exit(f"{path}: VTK error code {r.GetErrorCode()}")
g = r.GetOutput()
assert g.GetNumberOfCells() == cells + entities, (g.GetNumberOfCells(), cells, entities)
volume = {2: 5, 3: 10, 4: 2}[dim]
points = {1: 1, 3: 2, 5: 3, 10: 4}  # vertex, line, triangle, tetra
types = [g.GetCellType(i) for i in range(g.GetNumberOfCells())]
assert set(types[:cells]) == {volume}, (set(types[:cells]), volume)
for i in range(cells):
    assert g.GetCell(i).GetNumberOfPoints() == dim + 1
for i in range(cells, cells + entities):  # tagged entities: lower-dimensional simplices
    assert types[i] != volume and types[i] in points, types[i]
    assert g.GetCell(i).GetNumberOfPoints() == points[types[i]]
types = set(types)
cd = g.GetCellData()
names = {cd.GetArrayName(i): cd.GetArray(i) for i in range(cd.GetNumberOfArrays())}
if ".t" not in path:  # a refined mesh carries its bisection state as small integers
    # bisect:state Int8 in 2D and 3D, Int16 in 4D
    small = (("bisect:state", "short" if dim == 4 else "signed char"),
             ("bisect:marking", "signed char"), ("bisect:generation", "unsigned short"))
    for n, kind in small:  # one component each
        assert n in names, (n, list(names))
        assert names[n].GetDataTypeAsString() == kind, (n, names[n].GetDataTypeAsString())
        assert names[n].GetNumberOfTuples() == cells + entities
if entities:
    phys = names["gmsh:physical"]
    assert all(phys.GetValue(i) != 0 for i in range(cells, cells + entities))
if path.startswith("tagged"):
    assert types == {10, 5, 3}, types  # tetra, triangle (surfaces), line (the curve)
    fd = g.GetFieldData()
    fields = {fd.GetArrayName(i) for i in range(fd.GetNumberOfArrays())}
    assert {"left", "right", "walls", "mid", "edge", "solid"} <= fields, fields
    assert list(fd.GetArray("walls").GetTuple(0)) + list(fd.GetArray("walls").GetTuple(1)) == [3, 2]
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
# zlib's blocks as the writer codes them (deflate; stored; literals alone,
# one Huffman code each, where that comes within a quarter of deflate's
# size: a refined mesh's connectivity): VTK's reader gives the same arrays
# from the zlib file as from the uncompressed one, and the zlib file has
# blocks of each kind it should.
/usr/bin/python3 - 3d-zlib.vtu 3d-none.vtu <<'PY' || fail "3d-zlib.vtu: VTK reads it otherwise than 3d-none.vtu"
import sys, re, base64, struct, vtk
from vtk.util.numpy_support import vtk_to_numpy
def grid(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    assert r.GetErrorCode() == 0, path
    return r.GetOutput()
a, b = grid(sys.argv[1]), grid(sys.argv[2])
assert (vtk_to_numpy(a.GetPoints().GetData()) == vtk_to_numpy(b.GetPoints().GetData())).all()
assert (vtk_to_numpy(a.GetCells().GetConnectivityArray()) ==
        vtk_to_numpy(b.GetCells().GetConnectivityArray())).all()
for data in ("GetCellData", "GetPointData"):
    da, db = getattr(a, data)(), getattr(b, data)()
    assert da.GetNumberOfArrays() == db.GetNumberOfArrays()
    for i in range(da.GetNumberOfArrays()):
        name = da.GetArrayName(i)
        assert (vtk_to_numpy(da.GetArray(name)) == vtk_to_numpy(db.GetArray(name))).all(), name
# Each block of the connectivity: a literal-only block has zlib's header
# 78 01 and a dynamic-Huffman deflate block (type 2); libdeflate's level 3
# writes 78 5e, and its stored blocks (type 0) 78 01.
text = open(sys.argv[1], "rb").read()
m = re.search(rb'Name="connectivity"[^>]*>\s*([A-Za-z0-9+/=]+)', text)
body = m.group(1)
blocks = struct.unpack("<Q", base64.b64decode(body[:12])[:8])[0]
header_chars = ((3 + blocks) * 8 + 2) // 3 * 4
sizes = struct.unpack("<%dQ" % (3 + blocks), base64.b64decode(body[:header_chars]))[3:]
data = base64.b64decode(body[header_chars:])
kinds, at = [], 0
for size in sizes:
    head, block_type = data[at:at + 2], (data[at + 2] >> 1) & 3
    kinds.append("literal" if head == b"\x78\x01" and block_type == 2 else
                 "stored" if block_type == 0 else "deflate" if head == b"\x78\x5e" else "?")
    at += size
assert blocks >= 3, blocks
assert kinds[0] == "deflate", kinds  # the first block of a group decides
assert "literal" in kinds and "?" not in kinds, kinds
literal = kinds.count("literal")
print(f"3d-zlib.vtu: the same arrays as 3d-none.vtu; {literal} of {blocks} connectivity blocks literal-coded")
PY
# A refined file saved again by VTK's writer (what ParaView's "Save Data"
# does) in ASCII, inline binary, appended raw, LZ4-compressed appended and
# big-endian data continues its bisection sequence as our own file does: the state's
# arrays come back in the types VTK writes them in (read in their file
# types, StoredState) and the next iteration's output is the same file.
for f in 2d-zlib 3d-zlib 4d-zlib tagged-zlib; do
  case $f in
  2d-*) region=$ROOT/data/regions/circle.json ;;
  4d-*) region=$ROOT/data/regions/moving-sphere.json ;;
  *) region=$hemi ;;
  esac
  expect_exit 0 "$BISECT" refine $f.vtu --region "$region" -n 1 -o $f-next.vtu -q --quality-csv none
  /usr/bin/python3 - $f.vtu <<'PY' || fail "$f.vtu: VTK could not save it again"
import sys, vtk
r = vtk.vtkXMLUnstructuredGridReader()
r.SetFileName(sys.argv[1])
r.Update()
stem = sys.argv[1][:-4]
for mode in ("ascii", "binary", "raw", "lz4", "bigendian"):
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(r.GetOutput())
    w.SetFileName(f"{stem}-vtk-{mode}.vtu")
    if mode == "ascii":
        w.SetDataModeToAscii()
    elif mode == "binary":
        w.SetDataModeToBinary()
    else:
        w.SetDataModeToAppended()
        w.SetEncodeAppendedData(mode != "raw")
        if mode == "lz4":
            w.SetCompressorTypeToLZ4()
        if mode == "bigendian":
            w.SetByteOrderToBigEndian()
    assert w.Write() == 1, mode
PY
  for mode in ascii binary raw lz4 bigendian; do
    grep -q 'Name="bisect:state"' $f-vtk-$mode.vtu || fail "$f-vtk-$mode.vtu: VTK dropped bisect:state"
    expect_exit 0 "$BISECT" refine $f-vtk-$mode.vtu --region "$region" -n 1 -o $f-vtk-$mode-next.vtu \
      -q --quality-csv none
    cmp -s $f-next.vtu $f-vtk-$mode-next.vtu ||
      fail "$f-vtk-$mode.vtu (saved by VTK): the next iteration differs from $f.vtu's"
  done
done
echo "vtk_readers: ok"
# And a picture: VTK renders the 2D, 3D and section outputs offscreen
# (xvfb-run, as in a headless ParaView) into non-blank PNGs.
command -v xvfb-run >/dev/null || fail "xvfb-run is missing (scripts/install-deps.sh installs xvfb)"
for f in 2d-zlib.vtu 3d-zlib.vtu 4d-zlib.t0.5.vtu; do
  timeout 120 xvfb-run -a /usr/bin/python3 "$ROOT/tests/support/render_vtu.py" "$f" "${f%.vtu}.png" \
    >render.log 2>&1 || { cat render.log >&2; fail "$f: VTK could not render it"; }
  [[ -s ${f%.vtu}.png ]] || fail "$f: no PNG"
done
echo "vtk_readers: VTK reads every output and renders 2D, 3D and a section to PNG"
