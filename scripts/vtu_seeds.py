#!/usr/bin/env python3
"""Writes small .vtu files with VTK's own writer (python3-vtk9) in every data
mode, compressor and header type, little and big endian, in 2D, 3D and 4D:
seeds for fuzz_vtu. Usage: /usr/bin/python3 scripts/vtu_seeds.py OUTDIR"""
import os
import sys

import vtk


def grid(dim):
    g = vtk.vtkUnstructuredGrid()
    p = vtk.vtkPoints()
    p.SetDataTypeToDouble()
    if dim == 2:
        pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]
        cells = [(5, [0, 1, 2]), (5, [2, 1, 3])]
    elif dim == 3:
        pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)]
        cells = [(10, [0, 1, 2, 3]), (10, [4, 3, 2, 1])]
    else:  # the 4D convention: poly-vertex pentatopes, point array t
        pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0), (1, 1, 1)]
        cells = [(2, [0, 1, 2, 3, 4]), (2, [5, 4, 3, 2, 1])]
    for x in pts:
        p.InsertNextPoint(x)
    g.SetPoints(p)
    for t, c in cells:
        g.InsertNextCell(t, len(c), c)
    m = vtk.vtkIntArray()
    m.SetName("m")
    for i in range(len(cells)):
        m.InsertNextValue(i)
    g.GetCellData().AddArray(m)
    u = vtk.vtkFloatArray()
    u.SetName("u")
    for i in range(len(pts)):
        u.InsertNextValue(i * 0.5)
    u.GetRange(-1)  # becomes an InformationKey element
    g.GetPointData().AddArray(u)
    if dim == 4:
        t = vtk.vtkDoubleArray()
        t.SetName("t")
        for v in (0, 0, 0, 0, 1, 0.3):
            t.InsertNextValue(v)
        g.GetPointData().AddArray(t)
        sd = vtk.vtkIntArray()
        sd.SetName("SpatialDimension")
        sd.InsertNextValue(4)
        g.GetFieldData().AddArray(sd)
    return g


out = sys.argv[1]
os.makedirs(out, exist_ok=True)
for dim in (2, 3, 4):
    for mode in ("ascii", "binary", "raw", "base64"):
        for comp in ("none", "zlib", "lz4", "lzma"):
            for header in (32, 64):
                if mode == "ascii" and comp != "none":
                    continue
                w = vtk.vtkXMLUnstructuredGridWriter()
                w.SetInputData(grid(dim))
                if mode == "ascii":
                    w.SetDataModeToAscii()
                elif mode == "binary":
                    w.SetDataModeToBinary()
                else:
                    w.SetDataModeToAppended()
                    w.SetEncodeAppendedData(mode == "base64")
                {"none": w.SetCompressorTypeToNone, "zlib": w.SetCompressorTypeToZLib,
                 "lz4": w.SetCompressorTypeToLZ4, "lzma": w.SetCompressorTypeToLZMA}[comp]()
                if header == 64:
                    w.SetHeaderTypeToUInt64()
                    w.SetByteOrderToBigEndian()
                else:
                    w.SetHeaderTypeToUInt32()
                w.SetFileName(os.path.join(out, "vtk-%dd-%s-%s-%d.vtu" % (dim, mode, comp, header)))
                w.Write()
