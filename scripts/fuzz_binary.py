#!/usr/bin/env python3
"""Mutation fuzzer for the real `bisect` binary (standard library only).

Each case takes a seed file from fuzz/seeds/, mutates it at byte or token
level, runs

    bisect refine IN --region R -n 2 -o OUT --quality-csv CSV -q

in a fresh temporary directory (10 s timeout, 4 GiB address space) and
classifies the outcome:

  ok           exit 0/3 and `bisect check OUT --against IN` passes
  wrong        exit 0/3 but the check fails or OUT/CSV is missing
  error        exit 1, one stderr line naming the input (mesh or region file)
  bad-message  exit 1 with several lines, a VTK dump, or no file named
  check-failed exit 2
  crash        killed by a signal
  hang         timeout
  leftover     files other than IN/R left behind (after a failure: any file;
               after success: anything besides OUT and CSV)
  other-exit   any other exit code

Cases that are not ok/error are saved under OUT_DIR/<class>/<format>-<n>.<ext>
with <...>.region.json and <...>.txt (command, exit code, stderr), one per
(class, first stderr line with digits normalised / signal) and format.

  scripts/fuzz_binary.py --cases 200                  # every format, 200 each
  scripts/fuzz_binary.py --formats vtu-zlib,json --cases 1000 --seed 7 --jobs 2
  scripts/fuzz_binary.py --cases 1000 --minimize      # shrink one input per finding
  scripts/fuzz_binary.py --make-seeds                 # rewrite fuzz/seeds/ (needs the binary)
  scripts/fuzz_binary.py --replay FILE --region R.json   # classify one file

Deterministic for a given --seed (the RNG of case i of format F is seeded
with "SEED:F:i"); only hang/no-hang can depend on the machine's load.
"""
import argparse
import base64
import json
import multiprocessing
import os
import random
import re
import resource
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SEEDS = os.path.join(ROOT, "fuzz", "seeds")
DEFAULT_BINARY = os.path.join(ROOT, "build", "bisect")
TIMEOUT = 10.0
MEM_LIMIT = 4 << 30

FORMATS = ["msh22a", "msh22b", "msh41a", "msh41b", "vtu-ascii", "vtu-binary",
           "vtu-raw", "vtu-b64", "vtu-zlib", "vtu4d", "state", "json"]
OUTCOMES = ["ok", "error", "bad-message", "wrong", "check-failed", "crash",
            "hang", "leftover", "other-exit"]

# ----------------------------------------------------------------- mesh codecs
VTK_TYPES = {"Int8": "b", "UInt8": "B", "Int16": "h", "UInt16": "H",
             "Int32": "i", "UInt32": "I", "Int64": "q", "UInt64": "Q",
             "Float32": "f", "Float64": "d"}


def kuhn(dim, k):
    """Freudenthal-Kuhn mesh of [0,1]^dim with k cubes per side."""
    import itertools
    n = k + 1
    pts = []
    for idx in itertools.product(range(n), repeat=dim):
        pts.append([i / k for i in reversed(idx)])

    def pid(c):
        r = 0
        for d in reversed(range(dim)):
            r = r * n + c[d]
        return r
    cells = []
    for cube in itertools.product(range(k), repeat=dim):
        for perm in itertools.permutations(range(dim)):
            c = list(cube)
            s = [pid(c)]
            for d in perm:
                c[d] += 1
                s.append(pid(c))
            cells.append(s)
    return pts, cells


def orient(pts, cells):
    """Positively oriented copies (bisect accepts both, but seeds stay clean)."""
    out = []
    for c in cells:
        dim = len(c) - 1
        m = [[pts[c[i + 1]][j] - pts[c[0]][j] for j in range(dim)] for i in range(dim)]
        det = _det(m)
        out.append(c if det > 0 else [c[1], c[0]] + c[2:])
    return out


def _det(m):
    n = len(m)
    if n == 1:
        return m[0][0]
    return sum((-1) ** j * m[0][j] * _det([r[:j] + r[j + 1:] for r in m[1:]]) for j in range(n))


def parse_vtu(data):
    """Reads a .vtu that bisect wrote (inline binary, zlib, UInt64 header) or
    any ASCII one: returns dict(points, cells, types, cell_arrays, point_arrays, field)."""
    import xml.etree.ElementTree as ET
    root = ET.fromstring(data)
    compressed = root.get("compressor") is not None
    hsize = 8 if root.get("header_type", "UInt32") == "UInt64" else 4

    def read(da):
        code = VTK_TYPES[da.get("type")]
        text = (da.text or "").strip()
        if da.get("format") == "ascii":
            vals = text.split()
            return [float(v) if code in "fd" else int(v) for v in vals]
        hc = "<Q" if hsize == 8 else "<I"
        if compressed:
            first = base64.b64decode(text[:((3 * hsize + 2) // 3) * 4])
            nb = struct.unpack_from(hc, first, 0)[0]
            hlen = ((hsize * (3 + nb) + 2) // 3) * 4
            head = base64.b64decode(text[:hlen])
            sizes = struct.unpack_from("<" + hc[1] * (3 + nb), head)
            blob = base64.b64decode(text[hlen:])
            raw, pos = b"", 0
            for s in sizes[3:]:
                raw += zlib.decompress(blob[pos:pos + s])
                pos += s
        else:
            blob = base64.b64decode(text)
            nbytes = struct.unpack_from(hc, blob)[0]
            raw = blob[hsize:hsize + nbytes]
        sz = struct.calcsize(code)
        return list(struct.unpack("<%d%s" % (len(raw) // sz, code), raw))

    piece = root.find("UnstructuredGrid/Piece")
    res = {"points": None, "cell_arrays": [], "point_arrays": [], "field": []}
    for da in root.findall("UnstructuredGrid/FieldData/DataArray"):
        res["field"].append((da.get("Name"), da.get("type"), int(da.get("NumberOfComponents", "1")), read(da)))
    for sec, key in (("PointData", "point_arrays"), ("CellData", "cell_arrays")):
        for da in piece.findall(sec + "/DataArray"):
            res[key].append((da.get("Name"), da.get("type"), int(da.get("NumberOfComponents", "1")), read(da)))
    p = read(piece.find("Points/DataArray"))
    res["points"] = [p[i:i + 3] for i in range(0, len(p), 3)]
    cells = {da.get("Name"): read(da) for da in piece.findall("Cells/DataArray")}
    conn, offs = cells["connectivity"], cells["offsets"]
    res["cells"], prev = [], 0
    for o in offs:
        res["cells"].append(conn[prev:o])
        prev = o
    res["types"] = cells["types"]
    return res


def _fmt_num(v, code):
    if code in "fd":
        return repr(float(v))
    return str(int(v))


def write_vtu(mesh, mode, header="UInt64"):
    """mode: ascii, binary, raw (appended), b64 (appended base64), zlib."""
    hc = "<Q" if header == "UInt64" else "<I"
    arrays = []  # (section, name, type, ncomp, values, extra attrs)
    for name, t, nc, vals in mesh.get("field", []):
        arrays.append(("FieldData", name, t, nc, vals, ' NumberOfTuples="%d"' % (len(vals) // nc)))
    for name, t, nc, vals in mesh.get("point_arrays", []):
        arrays.append(("PointData", name, t, nc, vals, ""))
    for name, t, nc, vals in mesh.get("cell_arrays", []):
        arrays.append(("CellData", name, t, nc, vals, ""))
    arrays.append(("Points", "Points", "Float64", 3, [x for p in mesh["points"] for x in p], ""))
    conn, offs = [], []
    for c in mesh["cells"]:
        conn += c
        offs.append(len(conn))
    arrays.append(("Cells", "connectivity", "Int64", 1, conn, ""))
    arrays.append(("Cells", "offsets", "Int64", 1, offs, ""))
    arrays.append(("Cells", "types", "UInt8", 1, mesh["types"], ""))
    appended = b""
    xml = {}
    for sec, name, t, nc, vals, extra in arrays:
        code = VTK_TYPES[t]
        raw = struct.pack("<%d%s" % (len(vals), code), *vals)
        attrs = 'type="%s" Name="%s"%s%s' % (t, name, ' NumberOfComponents="%d"' % nc if nc != 1 else "", extra)
        if mode == "ascii":
            body = " ".join(_fmt_num(v, code) for v in vals)
            el = '<DataArray %s format="ascii">\n%s\n</DataArray>' % (attrs, body)
        elif mode == "binary":
            body = base64.b64encode(struct.pack(hc, len(raw)) + raw).decode()
            el = '<DataArray %s format="binary">\n%s\n</DataArray>' % (attrs, body)
        elif mode == "zlib":
            comp = zlib.compress(raw)
            head = struct.pack("<" + hc[1] * 4, 1, 32768, len(raw), len(comp))
            body = base64.b64encode(head).decode() + base64.b64encode(comp).decode()
            el = '<DataArray %s format="binary">\n%s\n</DataArray>' % (attrs, body)
        elif mode == "raw":
            el = '<DataArray %s format="appended" offset="%d"/>' % (attrs, len(appended))
            appended += struct.pack(hc, len(raw)) + raw
        elif mode == "b64":
            el = '<DataArray %s format="appended" offset="%d"/>' % (attrs, len(appended))
            appended += base64.b64encode(struct.pack(hc, len(raw)) + raw)
        xml.setdefault(sec, []).append(el)
    out = ['<?xml version="1.0"?>',
           '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="%s"%s>'
           % (header, ' compressor="vtkZLibDataCompressor"' if mode == "zlib" else ""),
           "<UnstructuredGrid>"]
    if "FieldData" in xml:
        out += ["<FieldData>"] + xml["FieldData"] + ["</FieldData>"]
    out.append('<Piece NumberOfPoints="%d" NumberOfCells="%d">' % (len(mesh["points"]), len(mesh["cells"])))
    for sec in ("PointData", "CellData", "Points", "Cells"):
        if sec in xml:
            out += ["<%s>" % sec] + xml[sec] + ["</%s>" % sec]
    out += ["</Piece>", "</UnstructuredGrid>"]
    data = ("\n".join(out) + "\n").encode()
    if mode in ("raw", "b64"):
        data += ('<AppendedData encoding="%s">\n_' % ("raw" if mode == "raw" else "base64")).encode()
        data += appended + b"\n</AppendedData>\n"
    return data + b"</VTKFile>\n"


def write_msh(pts, cells, version, binary):
    dim = len(cells[0]) - 1
    etype = {2: 2, 3: 4}[dim]
    p3 = [list(p) + [0.0] * (3 - len(p)) for p in pts]
    out = b"$MeshFormat\n%s %d 8\n" % (version.encode(), 1 if binary else 0)
    if binary:
        out += struct.pack("<i", 1) + b"\n"
    out += b"$EndMeshFormat\n"
    if version == "2.2":
        out += b"$PhysicalNames\n1\n%d 7 \"domain\"\n$EndPhysicalNames\n" % dim
        out += b"$Nodes\n%d\n" % len(p3)
        if binary:
            out += b"".join(struct.pack("<i3d", i + 1, *p) for i, p in enumerate(p3)) + b"\n"
        else:
            out += b"".join(b"%d %r %r %r\n" % (i + 1, p[0], p[1], p[2]) for i, p in enumerate(p3))
        out += b"$EndNodes\n$Elements\n%d\n" % (len(cells) + 1)
        if binary:
            out += struct.pack("<3i", 15, 1, 2) + struct.pack("<4i", 1, 7, 1, 1)
            out += struct.pack("<3i", etype, len(cells), 2)
            out += b"".join(struct.pack("<%di" % (3 + len(c)), i + 2, 7, 1, *[v + 1 for v in c])
                            for i, c in enumerate(cells)) + b"\n"
        else:
            out += b"1 15 2 7 1 1\n"
            out += b"".join(b"%d %d 2 7 1 %s\n" % (i + 2, etype, b" ".join(b"%d" % (v + 1) for v in c))
                            for i, c in enumerate(cells))
        out += b"$EndElements\n"
        return out
    # 4.1
    lo = [min(p[j] for p in p3) for j in range(3)]
    hi = [max(p[j] for p in p3) for j in range(3)]
    counts = [1, 0, 1 if dim == 2 else 0, 1 if dim == 3 else 0]
    out += b"$Entities\n"
    if binary:
        out += struct.pack("<4Q", *counts)
        out += struct.pack("<i3dQ", 1, *p3[0], 0)
        out += struct.pack("<i6dQiQ", 1, *lo, *hi, 1, 7, 0) + b"\n"
    else:
        out += b"%d %d %d %d\n" % tuple(counts)
        out += b"1 %r %r %r 0\n" % tuple(p3[0])
        out += b"1 %r %r %r %r %r %r 1 7 0\n" % tuple(lo + hi)
    out += b"$EndEntities\n$Nodes\n"
    n = len(p3)
    if binary:
        out += struct.pack("<4Q", 1, n, 1, n) + struct.pack("<3iQ", dim, 1, 0, n)
        out += struct.pack("<%dQ" % n, *range(1, n + 1))
        out += b"".join(struct.pack("<3d", *p) for p in p3) + b"\n"
    else:
        out += b"1 %d 1 %d\n%d 1 0 %d\n" % (n, n, dim, n)
        out += b"".join(b"%d\n" % (i + 1) for i in range(n))
        out += b"".join(b"%r %r %r\n" % tuple(p) for p in p3)
    out += b"$EndNodes\n$Elements\n"
    m = len(cells)
    if binary:
        out += struct.pack("<4Q", 2, m + 1, 1, m + 1)
        out += struct.pack("<3iQ", 0, 1, 15, 1) + struct.pack("<2Q", 1, 1)
        out += struct.pack("<3iQ", dim, 1, etype, m)
        out += b"".join(struct.pack("<%dQ" % (1 + len(c)), i + 2, *[v + 1 for v in c])
                        for i, c in enumerate(cells)) + b"\n"
    else:
        out += b"2 %d 1 %d\n0 1 15 1\n1 1\n%d 1 %d %d\n" % (m + 1, m + 1, dim, etype, m)
        out += b"".join(b"%d %s\n" % (i + 2, b" ".join(b"%d" % (v + 1) for v in c)) for i, c in enumerate(cells))
    out += b"$EndElements\n"
    return out


# ------------------------------------------------------------------- seeds
REGIONS = {
    "json-2d-sphere": {"type": "sphere", "center": [0.5, 0.5], "radius": 0.3},
    "json-2d-box": {"type": "box", "min": [0.0, 0.0], "max": [0.5, 0.5]},
    "json-2d-halfspace": {"type": "halfspace", "normal": [1.0, 1.0], "offset": 1.2},
    "json-2d-intersection": {"type": "intersection", "regions": [
        {"type": "sphere", "center": [0.3, 0.3], "radius": 0.4, "solid": True},
        {"type": "halfspace", "normal": [0.0, 1.0], "offset": 0.2}]},
    "json-2d-levelset": {"type": "levelset", "expression": "x*x + y*y - r*r", "constants": {"r": 0.6},
                         "samples": 3, "indicator": {"type": "hessian", "fraction": 0.5}},
    "json-3d-sphere": {"name": "s", "comment": "solid ball", "type": "sphere",
                       "center": [0.5, 0.5, 0.5], "radius": 0.4, "solid": True},
    "json-3d-hemisphere": {"type": "hemisphere", "center": [0.5, 0.5, 0.5], "radius": 0.45,
                           "normal": [1.0, 0.0, 0.0], "offset": 0.5},
    "json-3d-box": {"type": "box", "min": [0.0, 0.0, 0.0], "max": [0.3, 0.6, 0.4]},
    "json-3d-union": {"type": "union", "regions": [
        {"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 0.5},
        {"type": "intersection", "regions": [
            {"type": "box", "min": [0.5, 0.5, 0.5], "max": [1.0, 1.0, 1.0]},
            {"type": "halfspace", "normal": [1.0, 1.0, 1.0], "offset": 2.5}]}]},
    "json-3d-levelset": {"type": "levelset", "variables": ["x", "y", "t"], "value": 0.1,
                         "expression": "sin(6*x) * cos(4*y) - t", "solid": False},
    "json-3d-moving_sphere": {"type": "moving_sphere", "center": [0.2, 0.2], "velocity": [0.5, 0.5],
                              "radius": 0.2},
    "json-4d-sphere": {"type": "sphere", "center": [0.0, 0.0, 0.0, 0.0], "radius": 0.5},
    "json-4d-moving_sphere": {"type": "moving_sphere", "center": [0.0, 0.0, 0.0],
                              "velocity": [0.0, 0.0, 1.0], "radius": 0.3, "solid": True},
    "json-4d-levelset": {"type": "levelset", "expression": "x + y + z + t - 1.3"},
}


def run_quiet(cmd, **kw):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)
    if r.returncode not in (0, 3):
        raise SystemExit("seed step failed: %s\n%s" % (" ".join(cmd), r.stderr.decode()))
    return r


def make_seeds(binary):
    os.makedirs(SEEDS, exist_ok=True)
    for f in os.listdir(SEEDS):
        os.unlink(os.path.join(SEEDS, f))

    def put(name, data):
        with open(os.path.join(SEEDS, name), "wb") as f:
            f.write(data if isinstance(data, bytes) else data.encode())
    for name, reg in REGIONS.items():
        put(name + ".json", json.dumps(reg, indent=1) + "\n")
    meshes = {}
    for dim, k in ((2, 3), (3, 2)):
        pts, cells = kuhn(dim, k)
        cells = orient(pts, cells)
        meshes[dim] = (pts, cells)
        for ver, b, fmt in (("2.2", 0, "msh22a"), ("2.2", 1, "msh22b"), ("4.1", 0, "msh41a"), ("4.1", 1, "msh41b")):
            put("%s-%dd.msh" % (fmt, dim), write_msh(pts, cells, ver, b))
        mesh = {"points": [p + [0.0] * (3 - dim) for p in pts], "cells": cells,
                "types": [5 if dim == 2 else 10] * len(cells),
                "cell_arrays": [("gmsh:physical", "Int32", 1, [7] * len(cells))],
                "point_arrays": [("temperature", "Float64", 1, [sum(p) for p in pts])]}
        for mode in ("ascii", "binary", "raw", "b64", "zlib"):
            put("vtu-%s-%dd.vtu" % (mode, dim), write_vtu(mesh, mode, "UInt64" if dim == 3 else "UInt32"))
    tmp = tempfile.mkdtemp(prefix="bisect-seeds-")
    try:
        def gen(args, out):
            run_quiet([binary, "generate"] + args + ["-o", os.path.join(tmp, out), "-f"])
            return os.path.join(tmp, out)

        def refine(src, region, n, out, extra=()):
            run_quiet([binary, "refine", src, "--region", os.path.join(SEEDS, region + ".json"), "-n", str(n),
                       "-o", os.path.join(tmp, out), "-q", "-f"] + list(extra), cwd=tmp)
            return os.path.join(tmp, out)
        # bisect's own writer: zlib inline binary .vtu and 4.1 binary .msh
        shutil.copy(gen(["kuhn", "--dim", "2", "--cells", "2"], "k2.vtu"), os.path.join(SEEDS, "vtu-zlib-2d-bisect.vtu"))
        shutil.copy(gen(["kuhn", "--dim", "3", "--cells", "1"], "k3.vtu"), os.path.join(SEEDS, "vtu-zlib-3d-bisect.vtu"))
        shutil.copy(refine(os.path.join(tmp, "k3.vtu"), "json-3d-sphere", 0, "k3.msh"), os.path.join(SEEDS, "msh41b-3d-bisect.msh"))
        k4 = gen(["kuhn", "--dim", "4", "--cells", "1"], "k4.vtu")
        shutil.copy(k4, os.path.join(SEEDS, "vtu4d-zlib-4d.vtu"))
        m4 = parse_vtu(open(k4, "rb").read())
        for mode in ("ascii", "raw"):
            put("vtu4d-%s-4d.vtu" % mode, write_vtu(m4, mode))
        m4c = dict(m4, types=[41] * len(m4["cells"]))  # VTK_CONVEX_POINT_SET
        put("vtu4d-binary-4d.vtu", write_vtu(m4c, "binary", "UInt32"))
        # bisection state (bisect:* cell arrays), 2D/3D/4D, plus ASCII copies
        states = {
            "state-2d": refine(os.path.join(tmp, "k2.vtu"), "json-2d-sphere", 2, "s2.vtu"),
            "state-3d": refine(os.path.join(tmp, "k3.vtu"), "json-3d-sphere", 2, "s3.vtu"),
            "state-4d": refine(k4, "json-4d-sphere", 1, "s4.vtu"),
            "state-4d-explicit": refine(gen(["simplex", "--dim", "4", "--type", "A_PO"], "apo.vtu"),
                                        "json-4d-sphere", 1, "apo1.vtu"),
            "state-3d-longest": refine(os.path.join(tmp, "k3.vtu"), "json-3d-hemisphere", 1, "l3.vtu",
                                       ["-m", "longest"]),
        }
        for name, path in states.items():
            shutil.copy(path, os.path.join(SEEDS, name + ".vtu"))
            put(name + "-ascii.vtu", write_vtu(parse_vtu(open(path, "rb").read()), "ascii"))
        shutil.copy(refine(os.path.join(tmp, "k3.vtu"), "json-3d-sphere", 1, "s3.msh"), os.path.join(SEEDS, "state-3d.msh"))
        shutil.copy(refine(os.path.join(tmp, "k2.vtu"), "json-2d-box", 1, "s2.msh"), os.path.join(SEEDS, "state-2d.msh"))
    finally:
        shutil.rmtree(tmp)
    # optional: the same 3D mesh written by VTK's own writer (python3-vtk9)
    try:
        import vtk  # noqa
        vtk_seeds()
    except ImportError:
        print("python3-vtk9 not installed: VTK-written seeds skipped")
    # every seed must refine and check cleanly
    for f in sorted(os.listdir(SEEDS)):
        if f.endswith(".json"):
            continue
        res = run_case(binary, os.path.join(SEEDS, f), open(os.path.join(SEEDS, f), "rb").read(),
                       None, seed_dim(f), "mesh")
        print("%-32s %6d bytes  %s" % (f, os.path.getsize(os.path.join(SEEDS, f)), res["class"]))
    for f in sorted(os.listdir(SEEDS)):
        if f.endswith(".json"):
            res = run_case(binary, os.path.join(SEEDS, f), open(os.path.join(SEEDS, f), "rb").read(),
                           None, seed_dim(f), "region")
            print("%-32s %6d bytes  %s" % (f, os.path.getsize(os.path.join(SEEDS, f)), res["class"]))


def vtk_seeds():
    import vtk
    pts, cells = kuhn(3, 2)
    cells = orient(pts, cells)
    ug = vtk.vtkUnstructuredGrid()
    vp = vtk.vtkPoints()
    vp.SetDataTypeToDouble()
    for p in pts:
        vp.InsertNextPoint(*p)
    ug.SetPoints(vp)
    for c in cells:
        ids = vtk.vtkIdList()
        for v in c:
            ids.InsertNextId(v)
        ug.InsertNextCell(vtk.VTK_TETRA, ids)
    arr = vtk.vtkIntArray()
    arr.SetName("gmsh:physical")
    for _ in cells:
        arr.InsertNextValue(7)
    ug.GetCellData().AddArray(arr)
    for name, mode, comp in (("vtu-ascii-3d-vtk", "ascii", None), ("vtu-binary-3d-vtk", "binary", None),
                             ("vtu-raw-3d-vtk", "raw", None), ("vtu-b64-3d-vtk", "b64", None),
                             ("vtu-zlib-3d-vtk-appended", "rawz", "zlib"), ("vtu-zlib-3d-vtk-lz4", "binz", "lz4")):
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetInputData(ug)
        w.SetFileName(os.path.join(SEEDS, name + ".vtu"))
        if mode == "ascii":
            w.SetDataModeToAscii()
        elif mode in ("binary", "binz"):
            w.SetDataModeToBinary()
        else:
            w.SetDataModeToAppended()
            w.SetEncodeAppendedData(mode == "b64")
        if comp is None:
            w.SetCompressorTypeToNone()
        elif comp == "zlib":
            w.SetCompressorTypeToZLib()
        else:
            w.SetCompressorTypeToLZ4()
        w.Write()


def seed_dim(name):
    m = re.search(r"-(\d)d", os.path.basename(name))
    return int(m.group(1)) if m else 3


def seed_format(name):
    base = os.path.basename(name)
    for f in sorted(FORMATS, key=len, reverse=True):
        if base.startswith(f + "-"):
            return f
    return None


# ---------------------------------------------------------------- mutators
INTERESTING_NUMS = [b"0", b"-1", b"1", b"2", b"-0", b"0.5", b"1.5", b"2147483647", b"2147483648",
                    b"4294967295", b"4294967296", b"-2147483649", b"9223372036854775807",
                    b"18446744073709551616", b"99999999999999999999999", b"1e999", b"-1e999",
                    b"1e308", b"1e-320", b"nan", b"NaN", b"inf", b"-inf", b"Infinity", b"0x10",
                    b"1e", b"--1", b"3.", b".", b"", b"65536", b"255", b"256", b"-128", b"1,5"]
INTERESTING_INTS = [0, 1, 2, 3, 4, 5, 6, 7, 8, 15, 16, 255, 256, 1023, 4096, 32767, 32768, 65535,
                    65536, 2 ** 31 - 1, 2 ** 31, 2 ** 32 - 1, 2 ** 32, 2 ** 63 - 1, 2 ** 63, 2 ** 64 - 1,
                    -1, -2, -(2 ** 31)]
NUM_RE = re.compile(rb"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")
B64_RE = re.compile(rb"[A-Za-z0-9+/]{16,}={0,2}")
ATTRS = {
    b"offset": [b"0", b"-1", b"1", b"7", b"99999999", b"18446744073709551615", b"x", b""],
    b"NumberOfComponents": [b"0", b"1", b"2", b"3", b"4", b"5", b"-1", b"1000000000", b"a"],
    b"NumberOfCells": [b"0", b"1", b"-1", b"2147483648", b"4294967296", b"1e3", b"999999999999"],
    b"NumberOfPoints": [b"0", b"1", b"-1", b"2147483648", b"4294967296", b"1e3", b"999999999999"],
    b"NumberOfTuples": [b"0", b"2", b"-1", b"4294967296"],
    b"type": [b"Int8", b"UInt8", b"Int16", b"Int32", b"UInt32", b"Int64", b"UInt64", b"Float32",
              b"Float64", b"String", b"Bit", b"Char", b"Foo", b"", b"PolyData", b"UnstructuredGrid"],
    b"format": [b"ascii", b"binary", b"appended", b"raw", b"base64", b""],
    b"header_type": [b"UInt32", b"UInt64", b"UInt8", b"Int64", b"Float64", b""],
    b"compressor": [b"vtkZLibDataCompressor", b"vtkLZ4DataCompressor", b"vtkLZMADataCompressor", b"", b"none"],
    b"byte_order": [b"BigEndian", b"LittleEndian", b"Middle"],
    b"encoding": [b"raw", b"base64", b"hex"],
    b"version": [b"0.1", b"1.0", b"2.2", b"99", b""],
    b"Name": [b"bisect:state", b"bisect:generation", b"bisect:parent_a", b"bisect:parent_b", b"bisect:order", b"bisect:stage", b"bisect:tag", b"bisect:marking", b"bisect:edge_rank", b"bisect:parent_rank", b"bisect:level",
              b"t", b"connectivity", b"offsets", b"types", b"Points", b"colour", b"SpatialDimension", b""],
}
ATTR_RE = re.compile(rb'\b(' + b"|".join(ATTRS) + rb')="([^"]*)"')
ELEM_NAMES = [b"DataArray", b"Piece", b"Points", b"Cells", b"CellData", b"PointData", b"FieldData",
              b"AppendedData", b"InformationKey", b"UnstructuredGrid"]
MSH_SECTIONS = [b"MeshFormat", b"Nodes", b"Elements", b"Entities", b"PhysicalNames", b"ElementData",
                b"NodeData"]


def m_bitflip(r, d, ctx):
    d = bytearray(d)
    for _ in range(r.randint(1, 8)):
        i = r.randrange(len(d))
        d[i] ^= 1 << r.randrange(8)
    return bytes(d)


def m_byteset(r, d, ctx):
    d = bytearray(d)
    for _ in range(r.randint(1, 4)):
        d[r.randrange(len(d))] = r.choice(b"\x00\xff\x7f\x80\x01 \n<>\"=-.0123456789e_$&")
    return bytes(d)


def m_truncate(r, d, ctx):
    if r.random() < 0.5:
        return d[:r.randrange(len(d))]
    return d[:max(0, len(d) - r.randint(1, 64))]


def m_insert(r, d, ctx):
    i = r.randrange(len(d) + 1)
    junk = bytes(r.randrange(256) for _ in range(r.randint(1, 64)))
    if r.random() < 0.3:
        junk = r.choice([b"\n", b" ", b"\r\n", b"\t", b"\x00", b" 0", b"<!-- x -->", b"&amp;", b"<![CDATA[x]]>"])
    return d[:i] + junk + d[i:]


def m_delchunk(r, d, ctx):
    i = r.randrange(len(d))
    return d[:i] + d[i + r.randint(1, 128):]


def m_dupchunk(r, d, ctx):
    i = r.randrange(len(d))
    j = min(len(d), i + r.randint(1, 256))
    k = r.randrange(len(d) + 1)
    return d[:k] + d[i:j] + d[k:]


def m_number(r, d, ctx):
    nums = list(NUM_RE.finditer(d))
    if not nums:
        return None
    for _ in range(r.randint(1, 3)):
        m = r.choice(nums)
        s, e = m.span()
        if s > len(d):
            break
        rep = r.choice(INTERESTING_NUMS) if r.random() < 0.8 else str(r.randint(-5, 200)).encode()
        d = d[:s] + rep + d[e:]
        nums = list(NUM_RE.finditer(d))
        if not nums:
            break
    return d


def m_swapnums(r, d, ctx):
    """Swap two numbers (ids) on one line, or two whole lines."""
    lines = d.split(b"\n")
    cand = [i for i, l in enumerate(lines) if len(NUM_RE.findall(l)) >= 2]
    if not cand:
        return None
    i = r.choice(cand)
    ms = list(NUM_RE.finditer(lines[i]))
    a, b = sorted(r.sample(range(len(ms)), 2))
    l = lines[i]
    sa, sb = ms[a].span(), ms[b].span()
    lines[i] = l[:sa[0]] + l[sb[0]:sb[1]] + l[sa[1]:sb[0]] + l[sa[0]:sa[1]] + l[sb[1]:]
    return b"\n".join(lines)


def m_lines(r, d, ctx):
    lines = d.split(b"\n")
    if len(lines) < 2:
        return None
    i = r.randrange(len(lines))
    op = r.randrange(4)
    if op == 0:
        del lines[i]
    elif op == 1:
        lines.insert(i, lines[i])
    elif op == 2:
        j = r.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    else:
        n = r.randint(2, 20)
        del lines[i:i + n]
    return b"\n".join(lines)


def m_xml_element(r, d, ctx):
    name = r.choice(ELEM_NAMES)
    pat = re.compile(rb"<" + name + rb"\b[^>]*?(?:/>|>.*?</" + name + rb">)", re.S)
    ms = list(pat.finditer(d))
    if not ms:
        return None
    m = r.choice(ms)
    s, e = m.span()
    op = r.randrange(4)
    if op == 0:
        return d[:s] + d[e:]
    if op == 1:
        return d[:e] + b"\n" + d[s:e] + d[e:]
    if op == 2:  # move it elsewhere (into another section)
        rest = d[:s] + d[e:]
        k = [x.end() for x in re.finditer(rb">", rest)]
        if not k:
            return None
        p = r.choice(k)
        return rest[:p] + d[s:e] + rest[p:]
    # empty its content
    inner = re.match(rb"(<[^>]*>)(.*)(</[^>]*>)", d[s:e], re.S)
    if not inner:
        return None
    return d[:s] + inner.group(1) + inner.group(3) + d[e:]


def m_attr(r, d, ctx):
    ms = list(ATTR_RE.finditer(d))
    if not ms:
        return None
    m = r.choice(ms)
    name = m.group(1)
    vals = ATTRS[name]
    if name in (b"offset",) and r.random() < 0.5:
        v = str(int(m.group(2) or b"0") + r.choice([-8, -4, -1, 1, 4, 8])).encode()
    else:
        v = r.choice(vals)
    op = r.random()
    if op < 0.8:
        return d[:m.start(2)] + v + d[m.end(2):]
    if op < 0.9:  # delete the attribute
        return d[:m.start()] + d[m.end():]
    return d[:m.end()] + b" " + m.group(0) + d[m.end():]  # duplicate it


def _hsize(d):
    return 8 if b'header_type="UInt64"' in d else 4


def _mutate_raw_values(r, raw, code):
    """Mutates decoded array bytes: values, tuples, length."""
    sz = struct.calcsize("<" + code)
    n = len(raw) // sz
    if n == 0:
        return raw + bytes(r.randint(1, 16))
    vals = list(struct.unpack("<%d%s" % (n, code), raw[:n * sz]))
    op = r.randrange(6)
    if op == 0:
        i = r.randrange(n)
        if code in "fd":
            vals[i] = r.choice([float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 0.0, 1e-310, 0.5])
        else:
            lim = 2 ** (8 * sz - (0 if code.isupper() else 1))
            cands = [v for v in INTERESTING_INTS if (0 if code.isupper() else -lim) <= v < lim]
            vals[i] = r.choice(cands)
    elif op == 1:  # swap two values
        i, j = r.randrange(n), r.randrange(n)
        vals[i], vals[j] = vals[j], vals[i]
    elif op == 2:  # permute a small window (a tuple)
        k = r.choice([2, 3, 4, 5])
        i = r.randrange(max(1, n - k + 1))
        w = vals[i:i + k]
        r.shuffle(w)
        vals[i:i + k] = w
    elif op == 3:  # drop some values
        i = r.randrange(n)
        del vals[i:i + r.randint(1, 5)]
    elif op == 4:  # duplicate some
        i = r.randrange(n)
        vals[i:i] = vals[i:i + r.randint(1, 5)]
    else:
        i = r.randrange(n)
        vals[i] = vals[r.randrange(n)] + (r.choice([-1, 1]) if code not in "fd" else 1e-9)
    try:
        return struct.pack("<%d%s" % (len(vals), code), *vals)
    except struct.error:
        return struct.pack("<%d%s" % (len(vals), code), *[0 if not isinstance(v, float) else v for v in vals])


def _pick_array(r, d, prefer=None):
    """A DataArray element with inline content: (start, end of content, attrs)."""
    ms = list(re.finditer(rb"<DataArray([^>]*?)>(.*?)</DataArray>", d, re.S))
    if not ms:
        return None
    if prefer:
        pm = [m for m in ms if prefer in m.group(1)]
        if pm and r.random() < 0.7:
            return r.choice(pm)
    return r.choice(ms)


def _attr(attrs, name, default=None):
    m = re.search(rb'\b' + name + rb'="([^"]*)"', attrs)
    return m.group(1).decode("latin1") if m else default


def m_b64_payload(r, d, ctx):
    """Decode an inline binary payload, mutate its block header or data, re-encode."""
    m = _pick_array(r, d, ctx.get("prefer"))
    if not m or b'format="binary"' not in m.group(1):
        return None
    text = re.sub(rb"\s+", b"", m.group(2).split(b"<")[0])
    tail = m.group(2)[len(m.group(2).split(b"<")[0]):]
    hs = _hsize(d)
    hc = "Q" if hs == 8 else "I"
    code = VTK_TYPES.get(_attr(m.group(1), b"type", "Int32"), "i")
    try:
        if b"compressor=" in d[:400]:
            first = base64.b64decode(text[:((3 * hs + 2) // 3) * 4])
            nb = struct.unpack_from("<" + hc, first)[0]
            if nb > 1000:
                return None
            hlen = ((hs * (3 + nb) + 2) // 3) * 4
            head = list(struct.unpack_from("<%d%s" % (3 + nb, hc), base64.b64decode(text[:hlen])))
            blob = base64.b64decode(text[hlen:])
            op = r.randrange(4)
            if op == 0:  # header integer
                i = r.randrange(len(head))
                head[i] = r.choice([v for v in INTERESTING_INTS if 0 <= v < 2 ** (8 * hs)] + [head[i] + 1, max(0, head[i] - 1)])
                newhead = struct.pack("<%d%s" % (len(head), hc), *head)
                return d[:m.start(2)] + base64.b64encode(newhead) + base64.b64encode(blob) + tail + d[m.end(2):]
            if op == 1:  # compressed bytes
                b = bytearray(blob)
                if b:
                    b[r.randrange(len(b))] ^= 1 << r.randrange(8)
                newhead = struct.pack("<%d%s" % (len(head), hc), *head)
                return d[:m.start(2)] + base64.b64encode(newhead) + base64.b64encode(bytes(b)) + tail + d[m.end(2):]
            # decompress, mutate values, recompress with a consistent header
            raw, pos = b"", 0
            for s in head[3:]:
                raw += zlib.decompress(blob[pos:pos + s])
                pos += s
            raw = _mutate_raw_values(r, raw, code)
            comp = zlib.compress(raw)
            newhead = struct.pack("<4" + hc, 1, 32768, len(raw), len(comp))
            if op == 3 and r.random() < 0.5:  # header says the old length
                newhead = struct.pack("<4" + hc, 1, 32768, head[2], len(comp))
            return d[:m.start(2)] + base64.b64encode(newhead) + base64.b64encode(comp) + tail + d[m.end(2):]
        blob = base64.b64decode(text)
        nbytes = struct.unpack_from("<" + hc, blob)[0]
        raw = blob[hs:hs + nbytes]
        if r.random() < 0.3:
            nb = r.choice([v for v in INTERESTING_INTS if 0 <= v < 2 ** (8 * hs)] + [nbytes + 1, max(0, nbytes - 1)])
            new = struct.pack("<" + hc, nb) + raw
        else:
            raw = _mutate_raw_values(r, raw, code)
            new = struct.pack("<" + hc, len(raw)) + raw
        return d[:m.start(2)] + base64.b64encode(new) + tail + d[m.end(2):]
    except Exception:
        return None


def m_appended(r, d, ctx):
    """Appended data: mutate a block header int or values of one array, raw or base64."""
    a = d.find(b"<AppendedData")
    if a < 0:
        return None
    u = d.find(b"_", a)
    end = d.rfind(b"</AppendedData>")
    if u < 0 or end < u:
        return None
    stream = d[u + 1:end]
    enc64 = b'encoding="base64"' in d[a:u]
    arrays = [(int(_attr(m.group(1), b"offset", "0") or 0), m.group(1))
              for m in re.finditer(rb"<DataArray([^>]*?)/?>", d[:a]) if b"offset=" in m.group(1)]
    if not arrays:
        return None
    try:
        offs = sorted(o for o, _ in arrays)
        o, attrs = r.choice(arrays)
        hs = _hsize(d)
        hc = "Q" if hs == 8 else "I"
        nxt = [x for x in offs if x > o]
        stop = nxt[0] if nxt else len(stream.rstrip())
        chunk = stream[o:stop]
        blob = base64.b64decode(chunk) if enc64 else chunk
        code = VTK_TYPES.get(_attr(attrs, b"type", "Int32"), "i")
        comp = b"compressor=" in d[:400]
        if comp or r.random() < 0.3:  # header ints
            nh = len(blob) // hs
            i = r.randrange(min(nh, 4)) if nh else 0
            b = bytearray(blob)
            val = r.choice([v for v in INTERESTING_INTS if 0 <= v < 2 ** (8 * hs)])
            b[i * hs:(i + 1) * hs] = struct.pack("<" + hc, val)
            blob = bytes(b)
        else:
            nbytes = struct.unpack_from("<" + hc, blob)[0]
            raw = _mutate_raw_values(r, blob[hs:hs + nbytes], code)
            blob = struct.pack("<" + hc, len(raw) if r.random() < 0.7 else nbytes) + raw
        new = base64.b64encode(blob) if enc64 else blob
        return d[:u + 1] + stream[:o] + new + stream[stop:] + d[end:]
    except Exception:
        return None


def m_ascii_array(r, d, ctx):
    """ASCII DataArray: permute a tuple (e.g. bisect:order), swap ids, drop/add values."""
    m = _pick_array(r, d, ctx.get("prefer"))
    if not m or b'format="ascii"' not in m.group(1):
        return None
    body = m.group(2)
    toks = body.split()
    if not toks:
        return None
    nc = int(_attr(m.group(1), b"NumberOfComponents", "1") or 1) if (_attr(m.group(1), b"NumberOfComponents", "1") or "1").isdigit() else 1
    nc = max(1, min(nc, 8))
    op = r.randrange(5)
    nt = max(1, len(toks) // nc)
    t = r.randrange(nt)
    if op == 0:  # permute one tuple
        w = toks[t * nc:(t + 1) * nc]
        r.shuffle(w)
        toks[t * nc:(t + 1) * nc] = w
    elif op == 1:  # swap two tuples
        u = r.randrange(nt)
        a, b = toks[t * nc:(t + 1) * nc], toks[u * nc:(u + 1) * nc]
        toks[t * nc:(t + 1) * nc], toks[u * nc:(u + 1) * nc] = b, a
    elif op == 2:
        del toks[t * nc:(t + 1) * nc]
    elif op == 3:
        toks[r.randrange(len(toks))] = r.choice(INTERESTING_NUMS)
    else:  # one value copied from another tuple's slot (repeated id)
        toks[r.randrange(len(toks))] = toks[r.randrange(len(toks))]
    return d[:m.start(2)] + b"\n" + b" ".join(toks) + b"\n" + d[m.end(2):]


def m_msh_section(r, d, ctx):
    """Delete, duplicate or reorder a whole $Section...$EndSection."""
    name = r.choice(MSH_SECTIONS)
    ms = list(re.finditer(rb"\$" + name + rb"\b.*?\$End" + name + rb"[^\n]*\n?", d, re.S))
    if not ms:
        return None
    m = r.choice(ms)
    op = r.randrange(3)
    if op == 0:
        return d[:m.start()] + d[m.end():]
    if op == 1:
        return d[:m.end()] + m.group(0) + d[m.end():]
    return m.group(0) + d[:m.start()] + d[m.end():]


def m_msh_binary_ints(r, d, ctx):
    """Binary .msh: overwrite an aligned int/size_t inside a section body."""
    ms = list(re.finditer(rb"\$(Nodes|Elements|Entities|ElementData)\n(.*?)\$End\1", d, re.S))
    if not ms:
        return None
    m = r.choice(ms)
    s, e = m.start(2), m.end(2)
    if e - s < 8:
        return None
    if m.group(1) == b"ElementData" and r.random() < 0.6:
        return _msh_elementdata(r, d, m)
    pos = s + r.randrange(e - s - 8)
    width = r.choice([4, 8])
    val = r.choice([v for v in INTERESTING_INTS if -(2 ** (8 * width - 1)) <= v < 2 ** (8 * width - 1)])
    return d[:pos] + struct.pack("<i" if width == 4 else "<q", val) + d[pos + width:]


def _msh_elementdata(r, d, m):
    """Permute the values of one entry of an $ElementData block (bisect:order tuples)."""
    body = m.group(2)
    lines = body.split(b"\n")
    try:
        ns = int(lines[0]); p = 1 + ns
        nr = int(lines[p]); p += 1 + nr
        ni = int(lines[p]); ints = [int(x) for x in lines[p + 1:p + 1 + ni]]; p += 1 + ni
        ncomp, n = ints[1], ints[2]
        head = b"\n".join(lines[:p]) + b"\n"
        data = body[len(head):]
        binary = b" 1 8" in d[:40]
        if not binary:
            rows = data.split(b"\n")
            i = r.randrange(min(n, len(rows)))
            toks = rows[i].split()
            w = toks[1:]
            r.shuffle(w)
            rows[i] = b" ".join(toks[:1] + w)
            data = b"\n".join(rows)
        else:
            size = 4 + 8 * ncomp
            i = r.randrange(max(1, min(n, len(data) // size)))
            vals = list(struct.unpack_from("<%dd" % ncomp, data, i * size + 4))
            if r.random() < 0.6:
                r.shuffle(vals)
            else:
                vals[r.randrange(ncomp)] = r.choice([-1.0, 5.0, 1e10, float("nan"), 0.5, 2.0 ** 40])
            data = data[:i * size + 4] + struct.pack("<%dd" % ncomp, *vals) + data[(i + 1) * size:]
        return d[:m.start(2)] + head + data + d[m.end(2):]
    except (ValueError, IndexError, struct.error):
        return None


BYTE_MUTATORS = [m_bitflip, m_byteset, m_truncate, m_insert, m_delchunk, m_dupchunk]
TEXT_MUTATORS = [m_number, m_swapnums, m_lines]
VTU_MUTATORS = [m_xml_element, m_attr, m_b64_payload, m_appended, m_ascii_array]
MSH_MUTATORS = [m_msh_section, m_msh_binary_ints]


def mutators_for(fmt, seedname):
    if fmt.startswith("msh") or seedname.endswith(".msh"):
        w = [(m, 2) for m in BYTE_MUTATORS] + [(m, 4) for m in TEXT_MUTATORS] + [(m, 3) for m in MSH_MUTATORS]
    else:
        w = [(m, 2) for m in BYTE_MUTATORS] + [(m, 3) for m in TEXT_MUTATORS] + [(m, 5) for m in VTU_MUTATORS]
    return w


def mutate_mesh(r, data, fmt, seedname):
    ws = mutators_for(fmt, seedname)
    if fmt == "state":  # mostly the bisect:* arrays
        ws = ws + [(m_b64_payload, 12), (m_ascii_array, 12), (m_msh_binary_ints, 6)]
    ctx = {"prefer": b"bisect:" if fmt == "state" else None}
    names = []
    for _ in range(r.choice([1] * 7 + [2] * 2 + [3])):
        for _try in range(10):
            m = r.choices([x for x, _ in ws], [w for _, w in ws])[0]
            if not data:
                return data, names + ["empty"]
            try:
                out = m(r, data, ctx)
            except (ValueError, IndexError, KeyError, struct.error, zlib.error, OverflowError):
                out = None  # a mutator that cannot apply to this input
            if out is not None and out != data:
                data = out
                names.append(m.__name__[2:])
                break
    return data, names


# JSON regions
class Raw:
    def __init__(self, text):
        self.text = text


def dumps(v):
    if isinstance(v, Raw):
        return v.text
    if isinstance(v, dict):
        return "{" + ", ".join(json.dumps(k) + ": " + dumps(x) for k, x in v.items()) + "}"
    if isinstance(v, list):
        return "[" + ", ".join(dumps(x) for x in v) + "]"
    return json.dumps(v)


JSON_VALUES = [Raw("1e999"), Raw("-1e999"), Raw("NaN"), Raw("Infinity"), Raw("-0"), Raw("2147483648"),
               Raw("1e-400"), Raw("18446744073709551616"), Raw("0.0"), Raw("-1"), Raw("1e308"),
               Raw("00"), Raw("1."), Raw(".5"), Raw("+1"), Raw("0x1"), None, True, False, "", "1", [], {},
               [1], [0, 0], [0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0, 0], [[0.5, 0.5]], "sphere", "\u0000", "\ud800"]
TYPES = ["sphere", "hemisphere", "box", "halfspace", "moving_sphere", "union", "intersection", "levelset",
         "Sphere", "", "levelset ", "plane"]
EXPRS = ["x", "1/0", "0/0", "sqrt(-1)", "x^1e9", "log(0)", "y*", "(((((x)))))", "q + 1", "x ? y : z",
         "max()", "sum(x,y,z,t)", "1e999*x", "x" + "+x" * 5000, "(" * 300 + "x" + ")" * 300, "\"x\"",
         "_pi*x - _e", "x = 1", "rint(x*1e20)", "x < 0.5 ? -1 : 1", ""]


def _containers(v, path=()):
    out = [(path, v)]
    if isinstance(v, dict):
        for k, x in v.items():
            out += _containers(x, path + (k,))
    elif isinstance(v, list):
        for i, x in enumerate(v):
            out += _containers(x, path + (i,))
    return out


def mutate_json(r, text):
    try:
        obj = json.loads(text)
    except ValueError:
        obj = None
    names = []
    for _ in range(r.choice([1, 1, 2, 3])):
        if obj is None or r.random() < 0.15:
            d, n = mutate_mesh(r, text.encode() if isinstance(text, str) else text, "json", ".json")
            return d, names + n
        nodes = _containers(obj)
        path, node = r.choice(nodes)
        op = r.randrange(9)

        def setp(val):
            nonlocal obj
            if not path:
                obj = val
                return
            cur = obj
            for k in path[:-1]:
                cur = cur[k]
            cur[path[-1]] = val
        if op == 0 and isinstance(node, dict) and node:
            del node[r.choice(list(node))]
            names.append("json-delete")
        elif op == 1:
            setp(r.choice(JSON_VALUES))
            names.append("json-value")
        elif op == 2 and isinstance(node, list):
            if node and r.random() < 0.5:
                del node[r.randrange(len(node))]
            else:
                node.append(r.choice([0.5, 1, Raw("1e999"), "a", None]))
            names.append("json-length")
        elif op == 3:  # deep nesting
            depth = r.choice([50, 500, 5000, 100000])
            if r.random() < 0.5:
                setp(Raw("[" * depth + "1" + "]" * depth))
            else:
                inner = dumps(node) if node is not None else '{"type": "sphere"}'
                for _ in range(min(depth, 20000)):
                    inner = '{"type": "union", "regions": [' + inner + ']}'
                setp(Raw(inner))
            names.append("json-nesting")
        elif op == 4 and isinstance(node, dict):
            if "type" in node and r.random() < 0.6:
                node["type"] = r.choice(TYPES)
            else:
                node[r.choice(["type", "center", "radius", "solid", "regions", "expression", "samples",
                               "variables", "constants", "indicator", "fraction", "value", "extra"])] = \
                    r.choice(JSON_VALUES + [r.choice(EXPRS)])
            names.append("json-field")
        elif op == 5 and isinstance(node, dict) and "regions" in node and isinstance(node["regions"], list):
            node["regions"] = node["regions"] * r.choice([0, 2, 100, 2000])
            names.append("json-regions")
        elif op == 6 and isinstance(node, dict) and node.get("type") == "levelset":
            k = r.choice(["expression", "samples", "variables", "constants", "indicator", "value"])
            node[k] = {"expression": r.choice(EXPRS), "samples": r.choice([0, 1, 16, 17, 10 ** 9, -1, 2.5]),
                       "variables": r.choice([["x"], ["x", "x"], ["a", "b", "c", "d", "e"], ["_pi", "y"], ["1x", "y"]]),
                       "constants": r.choice([{"x": 1}, {"sin": 2}, {"c": "a"}, {"": 1}, {"k": Raw("1e999")}]),
                       "indicator": r.choice([{"type": "hessian", "fraction": 0}, {"type": "hessian", "fraction": 2},
                                              {"type": "hessian", "fraction": 1e-300}, {"type": "other"},
                                              {"type": "hessian", "fraction": 0.5, "expression": r.choice(EXPRS)}]),
                       "value": r.choice([Raw("NaN"), Raw("1e999"), "x", 0])}[k]
            names.append("json-levelset")
        elif op == 7 and isinstance(node, (int, float)) and not isinstance(node, bool):
            setp(r.choice([0, -node, node * 1e12, 1e-300, Raw("1e999"), Raw("NaN"), node + 1e-12]))
            names.append("json-number")
        else:  # duplicate key at text level
            s = dumps(obj)
            if s.startswith("{") and len(s) > 2:
                k = r.choice(['"type": "box", ', '"radius": -1, ', '"center": [0.5, 0.5, 0.5], ', '"solid": true, '])
                obj = Raw("{" + k + s[1:])
            names.append("json-dupkey")
    return dumps(obj).encode(), names


# ----------------------------------------------------------------- runner
def _limits():
    os.setsid()
    resource.setrlimit(resource.RLIMIT_AS, (MEM_LIMIT, MEM_LIMIT))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    resource.setrlimit(resource.RLIMIT_FSIZE, (512 << 20, 512 << 20))
    os.nice(10)


def _run(cmd, cwd, timeout):
    p = subprocess.Popen(cmd, cwd=cwd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, preexec_fn=_limits)
    try:
        out, err = p.communicate(timeout=timeout)
        return p.returncode, out, err
    except subprocess.TimeoutExpired:
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        out, err = p.communicate()
        return None, out, err


VTK_DUMP = re.compile(r"Algorithm vtk|vtkXML|ERROR: In |Warning: In |vtkExecutive|\(0x[0-9a-f]+\)")


def default_region_text(dim):
    return dumps(REGIONS.get("json-%dd-sphere" % dim, REGIONS["json-3d-sphere"])).encode()


def run_case(binary, seedpath, data, region, dim, target, timeout=TIMEOUT, keep_dir=None):
    """target: mesh (data is the mesh) or region (data is the region JSON)."""
    d = tempfile.mkdtemp(prefix="bfz-")
    try:
        if target == "mesh":
            ext = os.path.splitext(seedpath)[1]
            inp = "case" + ext
            reg = "region.json"
            mesh_data, region_data = data, region if region is not None else default_region_text(dim)
        else:
            mesh_seed = {2: "vtu-zlib-2d.vtu", 3: "vtu-zlib-3d.vtu", 4: "vtu4d-zlib-4d.vtu"}[dim]
            ext = ".vtu"
            inp = "mesh.vtu"
            reg = "case.json"
            mesh_data = open(os.path.join(SEEDS, mesh_seed), "rb").read()
            region_data = data
        with open(os.path.join(d, inp), "wb") as f:
            f.write(mesh_data)
        with open(os.path.join(d, reg), "wb") as f:
            f.write(region_data)
        out = "out" + (".msh" if ext == ".msh" else ".vtu")
        cmd = [binary, "refine", inp, "--region", reg, "-n", "2", "-o", out, "--quality-csv", "out.csv", "-q"]
        t0 = time.time()
        rc, so, se = _run(cmd, d, timeout)
        el = time.time() - t0
        err = se.decode("utf-8", "replace")
        lines = [l for l in err.split("\n") if l.strip()]
        first = lines[0] if lines else ""
        files = sorted(set(os.listdir(d)) - {inp, reg})
        res = {"rc": rc, "stderr": err[:4000], "first": first[:300], "time": round(el, 3), "files": files,
               "cmd": cmd, "check": None}
        fuzzed = inp if target == "mesh" else reg
        if rc is None:
            cls = "hang"
        elif rc < 0:
            cls = "crash"
            res["signal"] = signal.Signals(-rc).name if -rc in signal.Signals._value2member_map_ else str(-rc)
            res["frame"] = crash_frame(cmd, d, timeout)
        elif rc == 2:
            cls = "check-failed"
        elif rc in (0, 3):
            if out not in files or "out.csv" not in files:
                cls = "wrong"
                res["check"] = "output missing"
            elif set(files) - {out, "out.csv"}:
                cls = "leftover"
            else:
                crc, cso, cse = _run([binary, "check", out, "--against", inp], d, 30)
                res["check"] = (cso + cse).decode("utf-8", "replace")[:1000]
                res["check_rc"] = crc
                if crc is None or crc < 0:  # the check itself hung or crashed
                    res["check"] = "check %s: %s" % ("timeout" if crc is None else "killed by signal %d" % -crc,
                                                     res["check"])
                cls = "ok" if crc == 0 else "wrong"
        elif rc == 1:
            if files:
                cls = "leftover"
            elif len(lines) != 1 or VTK_DUMP.search(err) or (inp not in first and reg not in first):
                cls = "bad-message"
            else:
                cls = "error"
        else:
            cls = "leftover" if files else "other-exit"
        res["class"] = cls
        res["key"] = dedup_key(cls, res, fuzzed)
        if keep_dir:
            shutil.copytree(d, keep_dir)
        return res
    finally:
        shutil.rmtree(d, ignore_errors=True)


def crash_frame(cmd, cwd, timeout):
    """The innermost named function of a crash, by re-running under gdb (when installed)."""
    if not shutil.which("gdb"):
        return ""
    rc, so, se = _run(["gdb", "-batch", "-nx", "-ex", "run", "-ex", "bt 8", "--args"] + cmd, cwd, 6 * timeout)
    for line in so.decode("utf-8", "replace").split("\n"):
        m = re.match(r"#\d+\s+(?:0x[0-9a-f]+ in )?([^\s(]+(?:\([^)]*\))?)", line)
        if m and "??" not in m.group(1) and not m.group(1).startswith(("std::", "__", "operator", "raise", "abort")):
            return re.sub(r"\(.*", "", m.group(1))[:120]
    return ""


def dedup_key(cls, res, fuzzed):
    if cls == "crash":
        return "%s|%s|%s|%s" % (cls, res.get("signal"), res.get("frame", ""), normalise(res["first"]))
    if cls == "hang":
        return cls
    if cls == "wrong":
        return "%s|%s" % (cls, normalise((res["check"] or "").split("\n")[0]))
    if cls == "leftover":
        return "%s|%s|%s" % (cls, res["rc"], ",".join(re.sub(r"\d+", "N", f) for f in res["files"]))
    return "%s|%s" % (cls, normalise(res["first"]))


def normalise(line):
    line = re.sub(r"(case|mesh|region)\.(vtu|msh|json)", "FILE", line)
    line = re.sub(r"0x[0-9a-fA-F]+", "HEX", line)
    line = re.sub(r"-?\d+(\.\d+)?(e[-+]?\d+)?", "N", line)
    return line[:160]


def load_seeds(fmt):
    fs = sorted(f for f in os.listdir(SEEDS) if seed_format(f) == fmt)
    return [(f, open(os.path.join(SEEDS, f), "rb").read()) for f in fs]


def make_case(seed, fmt, i, seeds, region_seeds):
    r = random.Random("%s:%s:%d" % (seed, fmt, i))
    name, data = r.choice(seeds)
    dim = seed_dim(name)
    if fmt == "json":
        try:
            mdata, muts = mutate_json(r, data.decode())
        except (ValueError, TypeError, KeyError, IndexError, RecursionError):
            mdata, muts = mutate_mesh(r, data, fmt, name)
        return {"fmt": fmt, "i": i, "seed": name, "dim": dim, "target": "region", "data": mdata,
                "region": None, "muts": muts}
    mdata, muts = mutate_mesh(r, data, fmt, name)
    regs = [d for n, d in region_seeds if seed_dim(n) == dim]
    region = r.choice(regs) if regs else default_region_text(dim)
    return {"fmt": fmt, "i": i, "seed": name, "dim": dim, "target": "mesh", "data": mdata,
            "region": region, "muts": muts}


_G = {}


def _worker_init(binary, seed, timeout):
    _G.update(binary=binary, seed=seed, timeout=timeout, seeds={}, region_seeds=load_seeds("json"))
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _work(job):
    fmt, i = job
    if fmt not in _G["seeds"]:
        _G["seeds"][fmt] = load_seeds(fmt)
    c = make_case(_G["seed"], fmt, i, _G["seeds"][fmt], _G["region_seeds"])
    res = run_case(_G["binary"], c["seed"], c["data"], c["region"], c["dim"], c["target"], _G["timeout"])
    keep = res["class"] not in ("ok", "error")
    return {"fmt": fmt, "i": i, "seed": c["seed"], "dim": c["dim"], "target": c["target"], "muts": c["muts"],
            "res": res, "data": c["data"] if keep else None, "region": c["region"] if keep else None}


def save_finding(outdir, case, cls, tag=None):
    res = case["res"]
    ext = ".json" if case["target"] == "region" else os.path.splitext(case["seed"])[1]
    d = os.path.join(outdir, cls)
    os.makedirs(d, exist_ok=True)
    stem = os.path.join(d, "%s-%d" % (case["fmt"], case["i"]) if tag is None else tag)
    with open(stem + ext, "wb") as f:
        f.write(case["data"])
    if case["target"] == "mesh":
        with open(stem + ".region.json", "wb") as f:
            f.write(case["region"])
    with open(stem + ".txt", "w") as f:
        f.write("seed file: fuzz/seeds/%s (dim %d), mutations: %s\n" % (case["seed"], case["dim"], " ".join(case["muts"])))
        f.write("fuzzed: %s\n" % ("the region (mesh: fuzz/seeds/%s)" % {2: "vtu-zlib-2d.vtu", 3: "vtu-zlib-3d.vtu", 4: "vtu4d-zlib-4d.vtu"}[case["dim"]]
                                  if case["target"] == "region" else "the mesh"))
        f.write("command (in a fresh directory, input copied as %s): %s\n" % (res["cmd"][2], " ".join(res["cmd"][1:])))
        f.write("class: %s  exit: %s  signal: %s  time: %ss  files left: %s\n" % (
            cls, res["rc"], res.get("signal"), res["time"], res["files"]))
        if res.get("frame"):
            f.write("crashed in: %s\n" % res["frame"])
        f.write("check: %s\n--- stderr ---\n%s" % (res["check"], res["stderr"]))
    return stem + ext


# ---------------------------------------------------------------- minimizer
def minimize(binary, case, budget_s=90, timeout=TIMEOUT):
    """Shrink case['data'] (lines, then byte chunks) while the dedup key stays the same."""
    key = case["res"]["key"]
    cls = case["res"]["class"]
    t_end = time.time() + budget_s
    tmo = timeout if cls == "hang" else min(timeout, max(2.0, 4 * case["res"]["time"] + 1))

    def same(data):
        if time.time() > t_end:
            return False
        res = run_case(binary, case["seed"], data, case["region"], case["dim"], case["target"], tmo)
        return res["key"] == key
    data = case["data"]
    for unit in ("line", "byte"):
        parts = data.split(b"\n") if unit == "line" else [data[i:i + 1] for i in range(len(data))]
        join = (lambda ps: b"\n".join(ps)) if unit == "line" else (lambda ps: b"".join(ps))
        n = max(1, len(parts) // 2)
        while n >= 1 and time.time() < t_end:
            i, changed = 0, False
            while i < len(parts) and time.time() < t_end:
                cand = parts[:i] + parts[i + n:]
                if cand and same(join(cand)):
                    parts, changed = cand, True
                else:
                    i += n
            if not changed:
                n //= 2
            if unit == "byte" and len(parts) > 4000:
                break
        data = join(parts)
    return data


def minimize_all(binary, firsts, mdir, a):
    """One minimized input per dedup key (per key and format for the rare classes)."""
    seen, done = set(), {}
    os.makedirs(mdir, exist_ok=True)
    for k in sorted(firsts, key=lambda k: (k[0], FORMATS.index(k[1]))):
        rare = firsts[k]["res"]["class"] in ("crash", "hang", "wrong", "check-failed")
        if (k[0] in seen and not rare) or (k[0] + "|" + k[1]) in seen:
            continue
        seen.add(k[0])
        seen.add(k[0] + "|" + k[1])
        c = dict(firsts[k])
        before = len(c["data"])
        c["data"] = minimize(binary, c, a.minimize_budget, a.timeout)
        c["res"] = run_case(binary, c["seed"], c["data"], c["region"], c["dim"], c["target"], a.timeout)
        if c["res"]["key"] != k[0]:
            print("minimized input of %s no longer reproduces (flaky?)" % k[0], file=sys.stderr)
            continue
        n = sum(1 for f in os.listdir(mdir) if f.endswith(".txt"))
        tag = "%s-%s-%d" % (c["res"]["class"], c["fmt"], n)
        path = save_finding(mdir, c, ".", tag)
        done[k] = path
        print("minimized %s: %d -> %d bytes  %s" % (os.path.relpath(path), before, len(c["data"]), k[0]),
              file=sys.stderr, flush=True)
    return done


def load_findings(dirs, binary, timeout):
    """Saved findings (<class>/<fmt>-<n>.<ext> + .txt) of earlier runs, re-run: {(key, fmt): case}."""
    firsts = {}
    for top in dirs:
        for cls in sorted(os.listdir(top)):
            d = os.path.join(top, cls)
            if cls == "minimized" or not os.path.isdir(d):
                continue
            for f in sorted(os.listdir(d)):
                if not f.endswith(".txt"):
                    continue
                stem = os.path.join(d, f[:-4])
                meta = open(stem + ".txt").read()
                m = re.match(r"seed file: fuzz/seeds/(\S+) \(dim (\d)\), mutations: (.*)", meta)
                target = "region" if "fuzzed: the region" in meta else "mesh"
                ext = ".json" if target == "region" else os.path.splitext(m.group(1))[1]
                fmt, i = f[:-4].rsplit("-", 1)
                c = {"fmt": fmt, "i": int(i), "seed": m.group(1), "dim": int(m.group(2)), "target": target,
                     "muts": m.group(3).split(), "data": open(stem + ext, "rb").read(),
                     "region": open(stem + ".region.json", "rb").read() if target == "mesh" else None}
                c["res"] = run_case(binary, c["seed"], c["data"], c["region"], c["dim"], target, timeout)
                if c["res"]["class"] in ("ok", "error"):
                    print("%s: now %s (flaky?)" % (stem, c["res"]["class"]), file=sys.stderr)
                    continue
                firsts.setdefault((c["res"]["key"], fmt), c)
    return firsts


# ------------------------------------------------------------------- main
def table(counts, fmts):
    cols = [o for o in OUTCOMES if any(counts[f].get(o) for f in fmts)] or ["ok"]
    w = max(8, max(len(f) for f in fmts))
    lines = ["%-*s" % (w, "format") + "".join("%13s" % c for c in cols) + "%8s" % "total"]
    tot = {}
    for f in fmts:
        row = counts[f]
        lines.append("%-*s" % (w, f) + "".join("%13d" % row.get(c, 0) for c in cols) + "%8d" % sum(row.values()))
        for c in cols:
            tot[c] = tot.get(c, 0) + row.get(c, 0)
    lines.append("%-*s" % (w, "total") + "".join("%13d" % tot.get(c, 0) for c in cols) + "%8d" % sum(tot.values()))
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", type=int, default=100, help="cases per format (default 100)")
    ap.add_argument("--formats", default=",".join(FORMATS), help="comma-separated: " + ",".join(FORMATS))
    ap.add_argument("--seed", default="1")
    ap.add_argument("--start", type=int, default=0, help="first case index (to continue a run)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--binary", default=DEFAULT_BINARY)
    ap.add_argument("--out", default=os.path.join(ROOT, "fuzz", "findings"))
    ap.add_argument("--timeout", type=float, default=TIMEOUT)
    ap.add_argument("--json", action="store_true", help="print the counts as JSON on stdout")
    ap.add_argument("--minimize", action="store_true", help="shrink one input per distinct finding into OUT/minimized/")
    ap.add_argument("--minimize-budget", type=float, default=90, help="seconds per finding")
    ap.add_argument("--make-seeds", action="store_true")
    ap.add_argument("--replay", help="classify one mesh (or .json region with --dim) file")
    ap.add_argument("--region", help="region for --replay")
    ap.add_argument("--dim", type=int, default=3)
    ap.add_argument("--minimize-from", nargs="+", metavar="DIR",
                    help="minimize the saved findings of earlier runs (their --out dirs) into OUT/minimized/")
    ap.add_argument("--merge", nargs="+", metavar="JSONL",
                    help="print the format x outcome table of earlier runs' cases-*.jsonl logs and exit")
    a = ap.parse_args()
    if a.merge:
        counts = {}
        for fn in a.merge:
            for line in open(fn):
                c = json.loads(line)
                counts.setdefault(c["fmt"], {})
                counts[c["fmt"]][c["class"]] = counts[c["fmt"]].get(c["class"], 0) + 1
        print(table(counts, [f for f in FORMATS if f in counts]))
        return
    binary = os.path.abspath(a.binary)
    if not os.access(binary, os.X_OK):
        sys.exit("no executable %s (--binary)" % binary)
    if a.make_seeds:
        make_seeds(binary)
        return
    if a.minimize_from:
        firsts = load_findings(a.minimize_from, binary, a.timeout)
        print("%d distinct findings to minimize" % len(firsts), file=sys.stderr)
        minimize_all(binary, firsts, os.path.join(a.out, "minimized"), a)
        return
    if a.replay:
        data = open(a.replay, "rb").read()
        if a.replay.endswith(".json"):
            res = run_case(binary, a.replay, data, None, a.dim, "region", a.timeout)
        else:
            reg = open(a.region, "rb").read() if a.region else None
            res = run_case(binary, a.replay, data, reg, a.dim, "mesh", a.timeout)
        print(json.dumps(res, indent=1))
        return
    fmts = [f for f in a.formats.split(",") if f]
    for f in fmts:
        if f not in FORMATS:
            sys.exit("unknown format %s (one of %s)" % (f, ", ".join(FORMATS)))
        if not load_seeds(f):
            sys.exit("no seeds for %s in %s (run --make-seeds)" % (f, SEEDS))
    jobs = [(f, i) for i in range(a.start, a.start + a.cases) for f in fmts]
    counts = {f: {} for f in fmts}
    firsts = {}  # dedup key -> case (first seen, in job order)
    keycount = {}
    t0 = time.time()
    done = 0
    os.makedirs(a.out, exist_ok=True)
    log = open(os.path.join(a.out, "cases-%s-%d-%d.jsonl" % (a.seed, a.start, a.cases)), "w")
    with multiprocessing.Pool(a.jobs, _worker_init, (binary, a.seed, a.timeout)) as pool:
        try:
            for c in pool.imap(_work, jobs, chunksize=4):
                done += 1
                log.write(json.dumps({"fmt": c["fmt"], "i": c["i"], "seed": c["seed"], "muts": c["muts"],
                                      "class": c["res"]["class"], "rc": c["res"]["rc"],
                                      "time": c["res"]["time"], "first": c["res"]["first"]}) + "\n")
                cls = c["res"]["class"]
                counts[c["fmt"]][cls] = counts[c["fmt"]].get(cls, 0) + 1
                if cls not in ("ok", "error"):
                    k = (c["res"]["key"], c["fmt"])
                    keycount[k] = keycount.get(k, 0) + 1
                    if k not in firsts:
                        firsts[k] = c
                        path = save_finding(a.out, c, cls)
                        print("[%6d/%d] %-12s %s  %s" % (done, len(jobs), cls, os.path.relpath(path),
                                                         c["res"].get("signal") or c["res"]["first"][:120]),
                              file=sys.stderr, flush=True)
                if done % 500 == 0:
                    print("[%6d/%d] %.0fs" % (done, len(jobs), time.time() - t0), file=sys.stderr, flush=True)
        except KeyboardInterrupt:
            pool.terminate()
            print("interrupted after %d cases" % done, file=sys.stderr)
    wall = time.time() - t0
    summary = {"command": " ".join(sys.argv), "seed": a.seed, "cases_per_format": a.cases, "start": a.start,
               "wall_seconds": round(wall, 1), "counts": counts,
               "findings": [{"key": k[0], "format": k[1], "count": keycount[k],
                             "class": firsts[k]["res"]["class"], "first_stderr": firsts[k]["res"]["first"],
                             "signal": firsts[k]["res"].get("signal"),
                             "example": "%s/%s-%d" % (firsts[k]["res"]["class"], k[1], firsts[k]["i"])}
                            for k in sorted(firsts)]}
    if a.minimize:
        done_min = minimize_all(binary, firsts, os.path.join(a.out, "minimized"), a)
        for f in summary["findings"]:
            if (f["key"], f["format"]) in done_min:
                f["minimized"] = os.path.relpath(done_min[(f["key"], f["format"])], a.out)
    with open(os.path.join(a.out, "summary-%s-%d-%d.json" % (a.seed, a.start, a.cases)), "w") as f:
        json.dump(summary, f, indent=1)
    if a.json:
        print(json.dumps(summary, indent=1))
    else:
        print(table(counts, fmts))
        print("%d cases in %.1f s (%s)" % (done, wall, " ".join(sys.argv)))
        print("distinct findings: %d (see %s)" % (len(firsts), os.path.relpath(a.out)))


if __name__ == "__main__":
    main()
