#!/usr/bin/python3
"""Whether two meshes have the same cells, as sets of vertex coordinates.

usage: same_cells.py A B [--array NAME]     (each a .vtu or a .pvtu)

Reads both with VTK's own readers (vtkXMLUnstructuredGridReader, and for a
.pvtu vtkXMLPUnstructuredGridReader, the one ParaView uses), takes every
cell of the highest dimension (4D: the VTK_POLY_VERTEX pentatopes, with the
point array t as the 4th coordinate), and compares the multisets of cells,
each the sorted tuple of its vertices' coordinates. Prints the counts and
exits 1 on any difference, naming how many cells each side has alone.
With --array NAME, each cell is paired with its value of the cell array
NAME, so the values must agree cell by cell too.
"""
import collections
import sys

import vtk

TOPOLOGICAL = {vtk.VTK_TRIANGLE: 2, vtk.VTK_TETRA: 3, vtk.VTK_POLY_VERTEX: 4}


def cells_of(path, array=None):
    reader = (vtk.vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu")
              else vtk.vtkXMLUnstructuredGridReader())
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        sys.exit(f"{path}: VTK's reader failed (error code {reader.GetErrorCode()})")
    grid = reader.GetOutput()
    t = grid.GetPointData().GetArray("t")
    values = grid.GetCellData().GetArray(array) if array else None
    if array and values is None:
        sys.exit(f"{path}: no cell array {array}")
    dims = collections.Counter(TOPOLOGICAL.get(grid.GetCellType(i), 0)
                               for i in range(grid.GetNumberOfCells()))
    top = max(dims)
    planar = top == 2
    cells = collections.Counter()
    ids = vtk.vtkIdList()
    for i in range(grid.GetNumberOfCells()):
        if TOPOLOGICAL.get(grid.GetCellType(i), 0) != top:
            continue
        grid.GetCellPoints(i, ids)
        verts = []
        for k in range(ids.GetNumberOfIds()):
            p = grid.GetPoint(ids.GetId(k))
            verts.append(p[:2] if planar else (p + (t.GetValue(ids.GetId(k)),) if top == 4 else p))
        key = tuple(sorted(verts))
        cells[(key, values.GetTuple1(i)) if values is not None else key] += 1
    return top, cells


def main():
    a, b = sys.argv[1], sys.argv[2]
    array = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == "--array" else None
    dim_a, cells_a = cells_of(a, array)
    dim_b, cells_b = cells_of(b, array)
    only_a = sum((cells_a - cells_b).values())
    only_b = sum((cells_b - cells_a).values())
    print(f"{a}: {sum(cells_a.values())} cells ({dim_a}D); {b}: {sum(cells_b.values())} cells "
          f"({dim_b}D); only in the first {only_a}, only in the second {only_b}")
    sys.exit(0 if dim_a == dim_b and only_a == 0 and only_b == 0 else 1)


if __name__ == "__main__":
    main()
