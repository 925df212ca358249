# Writes small meshes with meshio (tests/cli/meshio_vtu.sh): a 2D square of
# triangles with boundary lines, and a cube of tetrahedra, as .vtu in ascii,
# binary, zlib, lzma and zlib with UInt64 headers, into the current directory.
import numpy as np
import meshio

# A 2D square of 4 x 4 x 2 triangles, with boundary lines (tagged entities in bisect),
# and the unit cube of 6 tetrahedra.
n = 4
xs = np.linspace(0.0, 1.0, n + 1)
pts = np.array([[x, y, 0.0] for y in xs for x in xs])
tris, lines = [], []
for j in range(n):
    for i in range(n):
        a = j * (n + 1) + i
        b, c, d = a + 1, a + n + 2, a + n + 1
        tris += [[a, b, c], [a, c, d]]
for i in range(n):
    lines.append([i, i + 1])
tri = meshio.Mesh(pts, [("line", np.array(lines)), ("triangle", np.array(tris))],
                  point_data={"temperature": pts[:, 0] * 2.0},
                  cell_data={"material": [np.full(len(lines), 7, dtype=np.int32),
                                          np.arange(len(tris), dtype=np.int32)]})
cube = np.array([[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)])
tets = [[0, 1, 3, 7], [0, 1, 7, 5], [0, 5, 7, 4], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7]]
tet = meshio.Mesh(cube, [("tetra", np.array(tets))],
                  point_data={"u": np.arange(8, dtype=np.float32)},
                  cell_data={"region": [np.arange(6, dtype=np.int64)]})
for name, mesh in (("tri", tri), ("tet", tet)):
    meshio.vtu.write("%s-ascii.vtu" % name, mesh, binary=False)
    meshio.vtu.write("%s-binary.vtu" % name, mesh, binary=True, compression=None)
    meshio.vtu.write("%s-zlib.vtu" % name, mesh, binary=True, compression="zlib")
    meshio.vtu.write("%s-lzma.vtu" % name, mesh, binary=True, compression="lzma")
    meshio.vtu.write("%s-zlib64.vtu" % name, mesh, binary=True, compression="zlib",
                     header_type="UInt64")
