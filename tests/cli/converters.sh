# The bisection state is one-component integer arrays (bisect:state,
# bisect:marking), so converters carry it: bisect's .vtu through meshio to
# XDMF and back, and to Gmsh 2.2, refines on exactly as bisect's own file
# does. Also: files with the older 4-component bisect:order still read.
source "$(dirname "$0")/lib.bash"
cd "$WORK"
region="$ROOT/data/regions/hemisphere.json"
expect_exit 0 "$BISECT" refine "$ROOT/data/ball.msh" --region "$region" -n 2 -o a.vtu -q
/usr/bin/python3 - <<'PY'
import meshio
m = meshio.read("a.vtu")
for key in ("bisect:state", "bisect:marking"):
    arrays = m.cell_data[key]
    assert all(a.ndim == 1 and a.dtype.kind == "i" for a in arrays), (key, [a.shape for a in arrays])
meshio.write("a.xdmf", m)
x = meshio.read("a.xdmf")
assert "bisect:state" in x.cell_data, list(x.cell_data)
meshio.write("from-xdmf.vtu", x)
meshio.write("a22.msh", m, file_format="gmsh22", binary=False)
PY
for f in a.vtu from-xdmf.vtu a22.msh; do
  expect_exit 0 "$BISECT" info "$f"
  grep -q "bisection state: present (marking index)" "$WORK/out" || fail "$f lost its state"
  expect_exit 0 "$BISECT" refine "$f" --region "$region" -n 2 -o "next-$f.vtu" -q
done
/usr/bin/python3 - <<'PY'
import meshio
def cells(name):
    m = meshio.read(name)
    pts = m.points
    return {frozenset(tuple(round(c, 12) for c in pts[i]) for i in cell)
            for block in m.cells if block.type == "tetra" for cell in block.data}
want = cells("next-a.vtu.vtu")
for other in ("next-from-xdmf.vtu.vtu", "next-a22.msh.vtu"):
    got = cells(other)
    assert got == want, (other, len(got), len(want), len(got ^ want))
print("converters: XDMF and Gmsh 2.2 round trips refine on identically,", len(want), "tets")
PY
