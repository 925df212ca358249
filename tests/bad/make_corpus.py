#!/usr/bin/env python3
"""Writes the hostile-input corpus of tests/bad/ (run it from anywhere).

Every bad file gets a row in cases.tsv:
    file <TAB> kind <TAB> expected substring of the one-line error
kind is `mesh` (refined with a good region), `region` (a region spec used
with data/square.msh, a 2D mesh) or `region3` (with good-tet.msh, 3D).
Files that look odd but are valid go to good.tsv (file <TAB> kind) and must
be accepted. tests/cli/bad_corpus.sh runs them all. The files are committed;
rerun this script after changing it.
"""
import base64
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
cases = []  # (file, kind, expected)
goods = []  # (file, kind)


def put(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


def bad(name, data, expected, kind="mesh"):
    put(name, data)
    cases.append((name, kind, expected))


def good(name, data, kind="mesh"):
    put(name, data)
    goods.append((name, kind))


# --------------------------------------------------------------- MSH 2.2 ASCII

def msh22(nodes, elements, header="2.2 0 8"):
    """nodes: [(tag, x, y, z)], elements: [(tag, type, [tags], [nodes])]."""
    s = "$MeshFormat\n%s\n$EndMeshFormat\n$Nodes\n%d\n" % (header, len(nodes))
    s += "".join("%s %s %s %s\n" % n for n in nodes)
    s += "$EndNodes\n$Elements\n%d\n" % len(elements)
    for tag, typ, tags, ns in elements:
        s += " ".join(str(v) for v in [tag, typ, len(tags)] + tags + ns) + "\n"
    return s + "$EndElements\n"


SQ_NODES = [(1, 0, 0, 0), (2, 1, 0, 0), (3, 1, 1, 0), (4, 0, 1, 0)]
SQ_TRIS = [(1, 2, [1, 1], [1, 2, 3]), (2, 2, [1, 1], [1, 3, 4])]
# Two tets sharing the face (2, 3, 4); 1 and 5 on opposite sides of it.
TET_NODES = [(1, 0, 0, 0), (2, 1, 0, 0), (3, 0, 1, 0), (4, 0, 0, 1), (5, 1, 1, 1)]
TET_ELEMS = [(1, 4, [1, 1], [1, 2, 3, 4]), (2, 4, [1, 1], [2, 3, 4, 5])]

good("good-square22.msh", msh22(SQ_NODES, SQ_TRIS))
good("good-tet.msh", msh22(TET_NODES, TET_ELEMS))
# One triangle given clockwise: reoriented, not rejected.
good("good-negative-triangle.msh",
     msh22(SQ_NODES, [(1, 2, [1, 1], [1, 3, 2]), (2, 2, [1, 1], [1, 3, 4])]))
# One tet negatively oriented (two ids swapped).
good("good-negative-tet.msh",
     msh22(TET_NODES, [(1, 4, [1, 1], [2, 1, 3, 4]), (2, 4, [1, 1], [2, 3, 4, 5])]))
# Boundary lines and a point element beside the triangles are ignored.
good("good-lines-ignored.msh",
     msh22(SQ_NODES, [(1, 15, [1, 1], [1]), (2, 1, [1, 1], [1, 2])] +
           [(3 + i, t, g, n) for i, (_, t, g, n) in enumerate(SQ_TRIS)]))
# Windows line endings, sparse node tags and an unused node.
good("good-crlf-sparse.msh",
     msh22([(10, 0, 0, 0), (20, 1, 0, 0), (30, 1, 1, 0), (40, 0, 1, 0), (99, 5, 5, 0)],
           [(1, 2, [1, 1], [10, 20, 30]), (2, 2, [1, 1], [10, 30, 40])]).replace("\n", "\r\n"))

base22 = msh22(SQ_NODES, SQ_TRIS)
bad("empty.msh", "", "empty file")
bad("blank.msh", "\n  \n", "file ends")
bad("garbage.msh", "hello world\n", "expected $MeshFormat")
bad("version1.msh", "$NOD\n3\n1 0 0 0\n$ENDNOD\n", "version 1")
bad("version3.msh", base22.replace("2.2 0 8", "3.0 0 8"), "unsupported MSH version")
bad("trunc22-ascii.msh", base22[: base22.index("1 3 4")], "file ends")
bad("nodes22-count-high.msh", base22.replace("$Nodes\n4\n", "$Nodes\n5\n"), "line 10")
bad("nodes22-count-low.msh", base22.replace("$Nodes\n4\n", "$Nodes\n3\n"), "expected $EndNodes")
bad("nodes22-count-text.msh", base22.replace("$Nodes\n4\n", "$Nodes\nfour\n"),
    "found 'four'")
bad("elements22-count-high.msh", base22.replace("$Elements\n2\n", "$Elements\n3\n"),
    "line 15")
bad("node22-out-of-range.msh", msh22(SQ_NODES, [SQ_TRIS[0], (2, 2, [1, 1], [1, 3, 9])]),
    "refers to node")
bad("node22-zero-id.msh", msh22(SQ_NODES, [SQ_TRIS[0], (2, 2, [1, 1], [1, 3, 0])]),
    "refers to node")
bad("node22-duplicate.msh", msh22(SQ_NODES + [(2, 5, 5, 0)], SQ_TRIS), "duplicate node tag 2")
bad("element22-duplicate.msh", msh22(SQ_NODES, [SQ_TRIS[0], (1, 2, [1, 1], [1, 3, 4])]),
    "duplicate element tag 1")
bad("only-quads.msh", msh22(SQ_NODES, [(1, 3, [1, 1], [1, 2, 3, 4])]),
    "no triangles or tetrahedra")
bad("only-lines.msh", msh22(SQ_NODES, [(1, 1, [1, 1], [1, 2]), (2, 1, [1, 1], [2, 3])]),
    "no triangles or tetrahedra")
bad("only-points.msh", msh22(SQ_NODES, [(1, 15, [1, 1], [1])]), "no triangles or tetrahedra")
bad("no-elements.msh", msh22(SQ_NODES, []), "no triangles or tetrahedra")
bad("quads-and-triangles.msh",
    msh22(SQ_NODES + [(5, 2, 0, 0), (6, 2, 1, 0)],
          SQ_TRIS + [(3, 3, [1, 1], [2, 5, 6, 3])]), "mixed non-simplex")
# A hexahedron above a triangle mesh: the hexahedra are the highest-dimension
# cells, so the file is not a triangle mesh.
bad("hex-and-triangles.msh",
    msh22(SQ_NODES + [(5, 0, 0, 1), (6, 1, 0, 1), (7, 1, 1, 1), (8, 0, 1, 1)],
          SQ_TRIS + [(3, 5, [1, 1], [1, 2, 3, 4, 5, 6, 7, 8])]), "hexahedron")
bad("hex-and-tets.msh",
    msh22(TET_NODES + [(6, 0, 0, 2), (7, 1, 0, 2), (8, 1, 1, 2), (9, 0, 1, 2)],
          TET_ELEMS + [(3, 5, [1, 1], [1, 2, 5, 3, 6, 7, 8, 9])]), "mixed non-simplex")
bad("quadratic-triangles.msh",
    msh22(SQ_NODES + [(5, .5, 0, 0), (6, .5, .5, 0), (7, 1, .5, 0)],
          [(1, 9, [1, 1], [1, 2, 3, 5, 7, 6])]), "higher-order")
bad("unknown-type.msh", msh22(SQ_NODES, [(1, 99, [1, 1], [1, 2, 3])]), "element type 99")
bad("nan-coordinate.msh", msh22(SQ_NODES[:2] + [(3, "nan", 1, 0), SQ_NODES[3]], SQ_TRIS),
    "non-finite")
bad("inf-coordinate.msh", msh22(SQ_NODES[:2] + [(3, 1, "inf", 0), SQ_NODES[3]], SQ_TRIS),
    "non-finite")
bad("huge-coordinate.msh", msh22(SQ_NODES[:2] + [(3, 1, "1e999", 0), SQ_NODES[3]], SQ_TRIS),
    "1e999")
bad("surface-in-3d.msh", msh22(SQ_NODES[:2] + [(3, 1, 1, 0.5), SQ_NODES[3]], SQ_TRIS),
    "not in one plane z = c")
bad("repeated-vertex.msh", msh22(SQ_NODES, [SQ_TRIS[0], (2, 2, [1, 1], [1, 3, 3])]),
    "repeats")
bad("zero-area-triangle.msh",
    msh22(SQ_NODES + [(5, 2, 2, 0)], SQ_TRIS + [(3, 2, [1, 1], [1, 3, 5])]), "zero volume")
bad("zero-volume-tet.msh",
    msh22(TET_NODES + [(6, 1, 1, 0)], [(1, 4, [1, 1], [1, 2, 3, 6])]), "zero volume")
# Both triangles of the edge (1, 3) on the same side of it: they overlap.
bad("tangled-triangles.msh",
    msh22(SQ_NODES + [(5, 0.9, 0.2, 0)], [SQ_TRIS[0], (2, 2, [1, 1], [1, 5, 3])]), "tangled")
bad("tangled-tets.msh",
    msh22(TET_NODES + [(6, 0.1, 0.1, 0.1)], [TET_ELEMS[0], (2, 4, [1, 1], [2, 3, 4, 6])]),
    "tangled")
# The face (2, 3, 4) shared by three tets.
# Two triangles that overlap without sharing an edge, and no vertex of one
# on an edge of the other: the facet test cannot see it.
bad("overlapping-triangles.msh",
    msh22([(1, 0, 0, 0), (2, 2, 0, 0), (3, 0, 2, 0), (4, .5, .5, 0), (5, 3, .5, 0), (6, .5, 3, 0)],
          [(1, 2, [1, 1], [1, 2, 3]), (2, 2, [1, 1], [4, 5, 6])]), "overlap")
# Found by fuzz_msh (kept as is, not generated): two_boxes_22b.msh with
# moved nodes; cells overlap away from shared facets, so refinement then
# fails its own check ("hanging node").
cases.append(("fuzz-overlapping-tets.msh", "mesh", "overlap"))
bad("nonmanifold-tets.msh",
    msh22(TET_NODES + [(6, 2, 2, 2)], TET_ELEMS + [(3, 4, [1, 1], [2, 3, 4, 6])]),
    "non-manifold")
bad("nonmanifold-triangles.msh",
    msh22(SQ_NODES + [(5, 2, 0, 0)], SQ_TRIS + [(3, 2, [1, 1], [1, 5, 3])]), "non-manifold")
# Node 5 lies on the edge (2, 3) of the big triangle but is no vertex of it.
bad("hanging-node.msh",
    msh22(SQ_NODES + [(5, 1, 0.5, 0), (6, 2, 0, 0), (7, 2, 1, 0)],
          SQ_TRIS + [(3, 2, [1, 1], [2, 6, 5]), (4, 2, [1, 1], [5, 6, 7]),
                     (5, 2, [1, 1], [5, 7, 3])]), "non-conforming")
bad("missing-endnodes.msh", base22.replace("$EndNodes\n", ""), "expected $EndNodes")
bad("elements-before-nodes.msh",
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n1\n1 2 0 1 2 3\n$EndElements\n",
    "$Elements comes before $Nodes")
bad("no-nodes-section.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", "no $Nodes")
bad("huge-node-count.msh", base22.replace("$Nodes\n4\n", "$Nodes\n99999999999999\n"),
    "line 10")

# --------------------------------------------------------------- MSH 4.1 ASCII

base41 = """$MeshFormat
4.1 0 8
$EndMeshFormat
$Nodes
1 4 1 4
2 1 0 4
1
2
3
4
0 0 0
1 0 0
1 1 0
0 1 0
$EndNodes
$Elements
1 2 1 2
2 1 2 2
1 1 2 3
2 1 3 4
$EndElements
"""
good("good-square41.msh", base41)
bad("trunc41-ascii.msh", base41[: base41.index("2 1 3 4")], "file ends")
bad("nodes41-header-mismatch.msh", base41.replace("1 4 1 4\n", "1 5 1 5\n"),
    "announces 5")
bad("elements41-header-mismatch.msh", base41.replace("1 2 1 2\n", "1 3 1 3\n"), "announces 3")
bad("node41-out-of-range.msh", base41.replace("2 1 3 4\n", "2 1 3 7\n"), "refers to node")
bad("node41-duplicate.msh", base41.replace("1\n2\n3\n4\n", "1\n2\n3\n3\n"),
    "duplicate node tag 3")
bad("entity41-bad-dim.msh", base41.replace("2 1 0 4\n", "7 1 0 4\n"), "entity dimension 7")


# -------------------------------------------------------------- MSH binary

def bin22(nodes, tris):
    s = b"$MeshFormat\n2.2 1 8\n" + struct.pack("<i", 1) + b"\n$EndMeshFormat\n"
    s += b"$Nodes\n%d\n" % len(nodes)
    for t, x, y, z in nodes:
        s += struct.pack("<iddd", t, x, y, z)
    s += b"\n$EndNodes\n$Elements\n%d\n" % len(tris)
    s += struct.pack("<iii", 2, len(tris), 2)
    for i, ns in enumerate(tris):
        s += struct.pack("<iii", i + 1, 1, 1) + struct.pack("<iii", *ns)
    return s + b"\n$EndElements\n"


def bin41(nodes, tris):
    s = b"$MeshFormat\n4.1 1 8\n" + struct.pack("<i", 1) + b"\n$EndMeshFormat\n$Nodes\n"
    n = len(nodes)
    s += struct.pack("<QQQQ", 1, n, 1, n) + struct.pack("<iiiQ", 2, 1, 0, n)
    s += b"".join(struct.pack("<Q", t) for t, *_ in nodes)
    s += b"".join(struct.pack("<ddd", x, y, z) for _, x, y, z in nodes)
    s += b"\n$EndNodes\n$Elements\n"
    s += struct.pack("<QQQQ", 1, len(tris), 1, len(tris)) + struct.pack("<iiiQ", 2, 1, 2, len(tris))
    for i, ns in enumerate(tris):
        s += struct.pack("<QQQQ", i + 1, *ns)
    return s + b"\n$EndElements\n"


SQ_TRI_IDS = [(1, 2, 3), (1, 3, 4)]
b22 = bin22(SQ_NODES, SQ_TRI_IDS)
b41 = bin41(SQ_NODES, SQ_TRI_IDS)
good("good-square22-binary.msh", b22)
good("good-square41-binary.msh", b41)
bad("trunc22-binary.msh", b22[: b22.index(b"$EndNodes") - 20], "file ends inside binary data")
bad("trunc41-binary.msh", b41[: b41.index(b"$EndNodes") - 20], "file ends inside binary data")
bad("trunc22-binary-elements.msh", b22[:-30], "file ends inside binary data")
bad("binary-bad-endianness.msh", b22.replace(struct.pack("<i", 1), struct.pack("<i", 7), 1),
    "endianness")
bad("binary41-node-out-of-range.msh", bin41(SQ_NODES, [(1, 2, 3), (1, 3, 1 << 40)]),
    "refers to node")
bad("binary41-huge-count.msh",
    b41.replace(struct.pack("<QQQQ", 1, 4, 1, 4), struct.pack("<QQQQ", 1, 1 << 62, 1, 4)),
    "byte offset")
bad("binary22-nan.msh", bin22(SQ_NODES[:2] + [(3, float("nan"), 1, 0), SQ_NODES[3]],
                              SQ_TRI_IDS), "non-finite")


# ------------------------------------- messages in the file's own numbering
# Errors about a .msh name Gmsh's node and element tags, never bisect's
# 0-based indices. These files tag nodes 101, 205, 309, ... (node i of the
# small meshes above becomes 101 + 104 (i - 1)) and elements 17, 23, 29, ...
# (element j becomes 17 + 6 (j - 1)), and list both in reverse order.

def node_tag(i):
    return 101 + 104 * (i - 1)


def elem_tag(j):
    return 17 + 6 * (j - 1)


def retag(nodes, elements):
    """Tagged as above, in reverse order; elements: [(tag, type, tags, nodes)]."""
    ns = [(node_tag(t), x, y, z) for t, x, y, z in nodes][::-1]
    es = [(elem_tag(t), typ, tags, [node_tag(n) for n in nn]) for t, typ, tags, nn in elements]
    return ns, es[::-1]


def msh41_ascii(nodes, elements):
    """One node block and one element block (all elements of one type)."""
    dim = {2: 2, 4: 3}[elements[0][1]]
    tags = [n[0] for n in nodes]
    s = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n"
    s += "1 %d %d %d\n%d 1 0 %d\n" % (len(nodes), min(tags), max(tags), dim, len(nodes))
    s += "".join("%d\n" % t for t in tags)
    s += "".join("%r %r %r\n" % (float(x), float(y), float(z)) for _, x, y, z in nodes)
    etags = [e[0] for e in elements]
    s += "$EndNodes\n$Elements\n1 %d %d %d\n%d 1 %d %d\n" % (
        len(elements), min(etags), max(etags), dim, elements[0][1], len(elements))
    s += "".join(" ".join(str(v) for v in [t] + nn) + "\n" for t, _, _, nn in elements)
    return s + "$EndElements\n"


def bin22_tagged(nodes, elements):
    s = b"$MeshFormat\n2.2 1 8\n" + struct.pack("<i", 1) + b"\n$EndMeshFormat\n"
    s += b"$Nodes\n%d\n" % len(nodes)
    for t, x, y, z in nodes:
        s += struct.pack("<iddd", t, x, y, z)
    s += b"\n$EndNodes\n$Elements\n%d\n" % len(elements)
    s += struct.pack("<iii", elements[0][1], len(elements), 2)
    for t, _, _, nn in elements:
        s += struct.pack("<iii", t, 1, 1) + struct.pack("<%di" % len(nn), *nn)
    return s + b"\n$EndElements\n"


def bin41_tagged(nodes, elements):
    dim = {2: 2, 4: 3}[elements[0][1]]
    tags = [n[0] for n in nodes]
    s = b"$MeshFormat\n4.1 1 8\n" + struct.pack("<i", 1) + b"\n$EndMeshFormat\n$Nodes\n"
    n = len(nodes)
    s += struct.pack("<QQQQ", 1, n, min(tags), max(tags)) + struct.pack("<iiiQ", dim, 1, 0, n)
    s += b"".join(struct.pack("<Q", t) for t in tags)
    s += b"".join(struct.pack("<ddd", x, y, z) for _, x, y, z in nodes)
    etags = [e[0] for e in elements]
    s += b"\n$EndNodes\n$Elements\n"
    s += struct.pack("<QQQQ", 1, len(elements), min(etags), max(etags))
    s += struct.pack("<iiiQ", dim, 1, elements[0][1], len(elements))
    for t, _, _, nn in elements:
        s += struct.pack("<%dQ" % (1 + len(nn)), t, *nn)
    return s + b"\n$EndElements\n"


def tagged(name, nodes, elements, expected, variants=("22",)):
    """The mesh retagged, as 2.2 ASCII and the other variants asked for."""
    ns, es = retag(nodes, elements)
    writers = {"22": msh22, "22b": bin22_tagged, "41": msh41_ascii, "41b": bin41_tagged}
    for v in variants:
        bad("tags%s-%s.msh" % (v, name), writers[v](ns, es), expected)


ALL = ("22", "22b", "41", "41b")
tagged("zero-area", SQ_NODES + [(5, 2, 2, 0)],
       SQ_TRIS + [(3, 2, [1, 1], [1, 3, 5])], "element 29 has zero volume", ALL)
tagged("repeated-vertex", SQ_NODES, [SQ_TRIS[0], (2, 2, [1, 1], [1, 3, 3])],
       "element 23 repeats node 309")
tagged("nonmanifold", SQ_NODES + [(5, 2, 0, 0)], SQ_TRIS + [(3, 2, [1, 1], [1, 5, 3])],
       "non-manifold: facet of nodes (101, 309) shared by 3 cells", ALL)
tagged("tangled", SQ_NODES + [(5, 0.9, 0.2, 0)], [SQ_TRIS[0], (2, 2, [1, 1], [1, 5, 3])],
       "tangled: elements 17 and 23 overlap across facet of nodes (101, 309)")
tagged("hanging-node", SQ_NODES + [(5, 1, 0.5, 0), (6, 2, 0, 0), (7, 2, 1, 0)],
       SQ_TRIS + [(3, 2, [1, 1], [2, 6, 5]), (4, 2, [1, 1], [5, 6, 7]),
                  (5, 2, [1, 1], [5, 7, 3])],
       "non-conforming input: node 517 lies on facet of nodes (205, 309) (hanging node)", ALL)
tagged("overlapping",
       [(1, 0, 0, 0), (2, 2, 0, 0), (3, 0, 2, 0), (4, .5, .5, 0), (5, 3, .5, 0), (6, .5, 3, 0)],
       [(1, 2, [1, 1], [1, 2, 3]), (2, 2, [1, 1], [4, 5, 6])],
       "tangled: elements 23 and 17 overlap (the centroid of element 17 lies inside element 23)")
# The fuzzer's wrong-overlap-2d.msh: a 3 x 3 grid of squares whose element
# 5 had node 1 changed into node 9; only the angles around a node show it.
GRID_NODES = [(1 + i + 4 * j, i / 3, j / 3, 0) for j in range(4) for i in range(4)]
GRID_TRIS = [[1, 2, 6], [5, 1, 6], [5, 6, 10], [9, 5, 2], [9, 10, 14], [13, 9, 14],
             [2, 3, 7], [6, 2, 7], [6, 7, 11], [10, 6, 11], [10, 11, 15], [14, 10, 15],
             [3, 4, 8], [7, 3, 8], [7, 8, 12], [11, 7, 12], [11, 12, 16], [15, 11, 16]]
tagged("fold", GRID_NODES, [(j + 2, 2, [7, 1], t) for j, t in enumerate(GRID_TRIS)],
       "tangled: the 4 cells around node 205 form fans (a pinch) that overlap")
# Coincident duplicate nodes (a mesh exported without merging them) are
# reported as duplicates whatever check trips over them first: a hanging node
# here (the square's two triangles do not share their diagonal) ...
tagged("duplicates", SQ_NODES + [(5, 0, 0, 0), (6, 1, 1, 0)],
       [SQ_TRIS[0], (2, 2, [1, 1], [5, 6, 4])],
       "duplicate nodes: 101 and 517 are both at (0, 0)", ALL)
# ... a zero-volume triangle (two of its nodes coincide) ...
tagged("duplicates-flat", SQ_NODES + [(5, 1, 0, 0)],
       SQ_TRIS + [(3, 2, [1, 1], [2, 5, 3])], "duplicate nodes: 205 and 517 are both at (1, 0)")
# ... and tetrahedra.
tagged("duplicates-tets", TET_NODES + [(6, 1, 0, 0), (7, 0, 1, 0), (8, 0, 0, 1)],
       [TET_ELEMS[0], (2, 4, [1, 1], [6, 7, 8, 5])],
       "duplicate nodes: 413 and 829 are both at (0, 0, 1) (and 2 more pairs)", ALL)
tagged("nonmanifold-tets", TET_NODES + [(6, 2, 2, 2)],
       TET_ELEMS + [(3, 4, [1, 1], [2, 3, 4, 6])],
       "non-manifold: facet of nodes (205, 309, 413) shared by 3 cells", ("22", "41b"))
tagged("zero-volume-tet", TET_NODES + [(6, 1, 1, 0)], [(1, 4, [1, 1], [1, 2, 3, 6])],
       "element 17 has zero volume", ("22", "41b"))


# --------------------------------------------------------------------- VTU

def vtu(points, conn, offsets, types, extra_piece="", points_xml=None, npoints=None,
        ncells=None, field=""):
    if points_xml is None:
        points_xml = ('<Points><DataArray type="Float64" NumberOfComponents="3" '
                      'format="ascii">%s</DataArray></Points>\n'
                      % " ".join(str(v) for p in points for v in p))
    return ('<?xml version="1.0"?>\n'
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64">\n<UnstructuredGrid>\n%s'
            '<Piece NumberOfPoints="%d" NumberOfCells="%d">\n%s%s'
            '<Cells>\n'
            '<DataArray type="Int64" Name="connectivity" format="ascii">%s</DataArray>\n'
            '<DataArray type="Int64" Name="offsets" format="ascii">%s</DataArray>\n'
            '<DataArray type="UInt8" Name="types" format="ascii">%s</DataArray>\n'
            '</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n'
            % (field, len(points) if npoints is None else npoints,
               len(types) if ncells is None else ncells, points_xml, extra_piece,
               " ".join(map(str, conn)), " ".join(map(str, offsets)), " ".join(map(str, types))))


SQ_PTS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
SQ_CONN, SQ_OFF, SQ_TYPES = [0, 1, 2, 0, 2, 3], [3, 6], [5, 5]
basevtu = vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES)
good("good-square.vtu", basevtu)
bad("empty.vtu", "", "empty file")
bad("not-xml.vtu", "this is not xml\n", "XML error at byte 0")
bad("trunc.vtu", basevtu[: basevtu.index("<Cells>") + 30], "the file ends inside")
bad("wrong-root.vtu", basevtu.replace("UnstructuredGrid", "PolyData"),
    "expected 'UnstructuredGrid'")
bad("no-points.vtu", vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES, points_xml=""), "missing its Points")
bad("points-too-few.vtu",
    vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES,
        points_xml='<Points><DataArray type="Float64" NumberOfComponents="3" '
                   'format="ascii">0 0 0 1 0 0</DataArray></Points>\n'), "Points")
bad("connectivity-short.vtu", vtu(SQ_PTS, SQ_CONN[:4], SQ_OFF, SQ_TYPES), "connectivity")
bad("offsets-past-end.vtu", vtu(SQ_PTS, SQ_CONN, [3, 60], SQ_TYPES), "connectivity")
bad("offsets-decreasing.vtu", vtu(SQ_PTS, SQ_CONN, [6, 3], SQ_TYPES),
    "monotonically increasing")
bad("point-out-of-range.vtu", vtu(SQ_PTS, [0, 1, 2, 0, 2, 7], SQ_OFF, SQ_TYPES),
    "refers to point 7")
bad("negative-point-id.vtu", vtu(SQ_PTS, [0, 1, 2, 0, 2, -1], SQ_OFF, SQ_TYPES),
    "refers to point -1")
bad("nan-point.vtu", vtu([(0, 0, 0), (1, 0, 0), ("nan", 1, 0), (0, 1, 0)],
                         SQ_CONN, SQ_OFF, SQ_TYPES), "non-finite")
bad("only-quads.vtu", vtu(SQ_PTS, [0, 1, 2, 3], [4], [9]), "no triangles or tetrahedra")
bad("quads-and-triangles.vtu",
    vtu(SQ_PTS + [(2, 0, 0), (2, 1, 0)], SQ_CONN + [1, 4, 5, 2], [3, 6, 10], [5, 5, 9]),
    "mixed non-simplex")
# A cell data array shorter than the cells, or with a token that is no
# number. (VTK 9.1 crashed on both: see the report of tests/bad.)
bad("cell-data-short.vtu",
    vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES,
        extra_piece='<CellData><DataArray type="Float64" Name="material" format="ascii">'
                    '1</DataArray></CellData>\n'), "material")
bad("cell-data-garbage.vtu",
    vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES,
        extra_piece='<CellData><DataArray type="Float64" Name="material" format="ascii">'
                    '1 x</DataArray></CellData>\n'), "material")
bad("point-data-short.vtu",
    vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES,
        extra_piece='<PointData><DataArray type="Float64" Name="temperature" format="ascii">'
                    '1 2</DataArray></PointData>\n'), "temperature")
bad("state-incomplete.vtu",
    vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES,
        extra_piece='<CellData><DataArray type="Float64" Name="bisect:stage" format="ascii">'
                    '1 1</DataArray></CellData>\n'), "bisection state is incomplete")
bad("state-invalid.vtu",
    vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES,
        extra_piece='<CellData>'
                    '<DataArray type="Float64" Name="bisect:order" NumberOfComponents="3" '
                    'format="ascii">0 1 2 0 0 0</DataArray>'
                    '<DataArray type="Float64" Name="bisect:stage" format="ascii">1 1</DataArray>'
                    '<DataArray type="Float64" Name="bisect:tag" format="ascii">2 2</DataArray>'
                    '<DataArray type="Float64" Name="bisect:marking" format="ascii">0 0</DataArray>'
                    '</CellData>\n'), "invalid bisection state")
# 4D convention without the 4th coordinate array.
bad("4d-no-t.vtu",
    vtu([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0)], [0, 1, 2, 3, 4], [5], [2],
        field='<FieldData><DataArray type="Int32" Name="SpatialDimension" '
              'NumberOfTuples="1" format="ascii">4</DataArray></FieldData>\n'),
    "point data array 't'")


def vtu_zlib(payload_broken=False, truncate_b64=False, header=None):
    """The square with a zlib-compressed, base64-inlined Points array.
    header: (blocks, block size, last block size, compressed size)."""
    raw = struct.pack("<12d", *[v for p in SQ_PTS for v in p])
    comp = zlib.compress(raw)
    if payload_broken:
        comp = comp[:4] + bytes(b ^ 0x5A for b in comp[4:])
    header = struct.pack("<QQQQ", *(header or (1, len(raw), len(raw), len(comp))))
    text = base64.b64encode(header).decode() + base64.b64encode(comp).decode()
    if truncate_b64:
        text = text[: len(text) - 12]
    points = ('<Points><DataArray type="Float64" NumberOfComponents="3" format="binary">'
              '%s</DataArray></Points>\n' % text)
    return vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES, points_xml=points).replace(
        'header_type="UInt64"', 'header_type="UInt64" compressor="vtkZLibDataCompressor"')


good("good-square-zlib.vtu", vtu_zlib())
bad("broken-zlib.vtu", vtu_zlib(payload_broken=True), "Points: zlib block 0 is corrupt")
bad("truncated-zlib.vtu", vtu_zlib(truncate_b64=True), "Points: compression header: block 0")
# Compression headers found by fuzz_vtu to break VTK 9.1 (see the report):
# block size 0 (division by zero), 2^40 blocks (std::length_error), a
# 2^40-byte block (huge allocation).
bad("zlib-block-size-zero.vtu", vtu_zlib(header=(1, 0, 0, 80)), "compression header")
bad("zlib-many-blocks.vtu", vtu_zlib(header=(1 << 40, 96, 96, 80)), "compress")
bad("zlib-huge-block.vtu", vtu_zlib(header=(1, 1 << 40, 1 << 40, 80)), "compress")
# Kept as found by fuzz_vtu (not generated): a division by zero (SIGFPE) in
# vtkXMLDataParser::ReadCompressedData, and a std::length_error from
# ReadCompressionHeader that bisect reports as "internal error" (exit 2).
cases.append(("fuzz-zlib-fpe.vtu", "mesh", "compress"))
cases.append(("fuzz-zlib-length-error.vtu", "mesh", "compress"))
# Field data array without a type: VTK 9.1 crashes in ReadXMLInformation.
bad("field-data-no-type.vtu",
    vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES,
        field='<FieldData><DataArray Name="x" NumberOfTuples="1" format="ascii">4'
              '</DataArray></FieldData>\n'), "type")


# ------------------------------------------- VTU: the native reader's checks
# Inputs that crashed VTK 9.1's reader or that it silently cut holes into
# (bisect now reads .vtu itself; each must give one clear line).

def cell_data(array):
    return "<CellData>%s</CellData>\n" % array


# Int32 cell data whose ASCII text holds a value that is no Int32.
for tag, token, why in [("fraction", "1.5", "is not an integer of type Int32"),
                        ("exponent", "1e10", "is not an integer of type Int32"),
                        ("above", "2147483648", "is out of range for Int32"),
                        ("below", "-2147483649", "is out of range for Int32"),
                        ("overflow", "1e999", "is not an integer of type Int32")]:
    bad("cell-data-int32-%s.vtu" % tag,
        vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES,
            extra_piece=cell_data('<DataArray type="Int32" Name="material" format="ascii">'
                                  '1 %s</DataArray>' % token)),
        "cell data array 'material': value 1 ('%s') %s" % (token, why))


def appended_cells(offset_attr):
    """The square with an Int32 cell array in raw appended data (UInt64
    header); offset_attr is the array's offset attribute text."""
    raw = struct.pack("<Q2i", 8, 4, 5)
    arr = ('<DataArray type="Int32" Name="material" format="appended"%s/>' % offset_attr)
    return (vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES, extra_piece=cell_data(arr))
            .replace("</UnstructuredGrid>\n</VTKFile>\n", "</UnstructuredGrid>\n"
                     '<AppendedData encoding="raw">\n_').encode()
            + raw + b"\n</AppendedData>\n</VTKFile>\n")


good("good-appended-cell-data.vtu", appended_cells(' offset="0"'))
bad("appended-offset-missing.vtu", appended_cells(""), "'material' is appended but has no offset")
bad("appended-offset-empty.vtu", appended_cells(' offset=""'), "offset '' is not a non-negative")
bad("appended-offset-negative.vtu", appended_cells(' offset="-8"'), "offset '-8' is not a non-negative")
bad("appended-offset-huge.vtu", appended_cells(' offset="18446744073709551615"'),
    "is past the end of the appended data")
bad("appended-offset-too-big.vtu", appended_cells(' offset="99999999999999999999999"'),
    "is not a non-negative integer")
bad("appended-offset-inside.vtu", appended_cells(' offset="12"'), "runs past the end")


def zlib_array(vtk_type, fmt, values, name, header=None, extra=""):
    """A zlib-compressed inline binary DataArray (UInt64 header); header
    overrides (blocks, block size, last block size, compressed size or None
    for the real one)."""
    raw = struct.pack("<%d%s" % (len(values), fmt), *values)
    comp = zlib.compress(raw)
    header = header or (1, len(raw), len(raw), None)
    head = struct.pack("<QQQQ", *header[:3], len(comp) if header[3] is None else header[3])
    return ('<DataArray type="%s" Name="%s" format="binary"%s>%s%s</DataArray>'
            % (vtk_type, name, extra, base64.b64encode(head).decode(),
               base64.b64encode(comp).decode()))


def zlib_vtu(points=None, conn=None, cells=""):
    points = points or ('<Points>%s</Points>\n'
                        % zlib_array("Float64", "d", [v for p in SQ_PTS for v in p], "Points",
                                     extra=' NumberOfComponents="3"'))
    text = vtu(SQ_PTS, SQ_CONN, SQ_OFF, SQ_TYPES, points_xml=points, extra_piece=cells).replace(
        'header_type="UInt64"', 'header_type="UInt64" compressor="vtkZLibDataCompressor"')
    if conn:
        text = text.replace('<DataArray type="Int64" Name="connectivity" format="ascii">'
                            '0 1 2 0 2 3</DataArray>', conn)
    return text


good("good-zlib-cells.vtu",
     zlib_vtu(conn=zlib_array("Int64", "q", SQ_CONN, "connectivity"),
              cells=cell_data(zlib_array("Int32", "i", [4, 5], "material"))))
# A zlib header of 0 blocks where data is expected, for each kind of array.
bad("zlib-zero-blocks-points.vtu",
    zlib_vtu(points='<Points>%s</Points>\n'
             % zlib_array("Float64", "d", [0.0] * 12, "Points", header=(0, 96, 0, 0),
                          extra=' NumberOfComponents="3"')),
    "Points: holds 0 values (0 bytes), expected 12")
bad("zlib-zero-blocks-connectivity.vtu",
    zlib_vtu(conn=zlib_array("Int64", "q", SQ_CONN, "connectivity", header=(0, 48, 0, 0))),
    "past the end of the connectivity (0 ids)")
bad("zlib-zero-blocks-cell-data.vtu",
    zlib_vtu(cells=cell_data(zlib_array("Int32", "i", [4, 5], "material", header=(0, 8, 0, 0)))),
    "cell data array 'material': holds 0 values")
bad("zlib-size-mismatch.vtu",
    zlib_vtu(cells=cell_data(zlib_array("Int32", "i", [4, 5], "material", header=(1, 12, 12, None)))),
    "cell data array 'material': holds 3 values (12 bytes), expected 2")
bad("zlib-block-larger-than-header.vtu",
    zlib_vtu(cells=cell_data(zlib_array("Int32", "i", [4, 5, 6, 7], "material",
                                        header=(1, 8, 8, None)))),
    "holds more than the 8 bytes its header says")
bad("zlib-block-shorter-than-header.vtu",
    zlib_vtu(cells=cell_data(zlib_array("Int32", "i", [4], "material", header=(1, 8, 8, None)))),
    "cell data array 'material': zlib block 0 holds 4 bytes, its header says 8")

# Cells of unknown type, or with a number of ids their type does not have:
# VTK 9.1 dropped them without a word (or crashed, with a bad point id).
TET_PTS = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)]


def tets(conn, offsets, types, types_type="UInt8"):
    return vtu(TET_PTS, conn, offsets, types).replace(
        '<DataArray type="UInt8" Name="types"', '<DataArray type="%s" Name="types"' % types_type)


bad("cell-type-0.vtu", tets([0, 1, 2, 3, 4, 3, 2, 1], [4, 8], [10, 0]),
    "cell 1 has VTK type 0 (an empty cell)")
bad("cell-triangle-4-ids.vtu", tets([0, 1, 2, 3, 4, 3, 2, 1], [4, 8], [10, 5]),
    "cell 1 (VTK type 5, triangle) has 4 point ids, expected 3")
for t in (64, 152, 255):
    bad("cell-type-%d.vtu" % t, tets([0, 1, 2, 3, 4, 3, 2, 1], [4, 8], [10, t]),
        "cell 1 has VTK type %d, which is not a known linear cell type" % t)
bad("cell-type-300.vtu", tets([0, 1, 2, 3, 4, 3, 2, 1], [4, 8], [10, 300], "Int32"),
    "cell 1 has VTK type 300, which is not a known linear cell type")
bad("cell-type-300-uint8.vtu", tets([0, 1, 2, 3, 4, 3, 2, 1], [4, 8], [10, 300]),
    "value 1 ('300') is out of range for UInt8")
for t in (64, 255):
    bad("cell-type-%d-bad-point.vtu" % t, tets([0, 1, 2, 3, 4, 3, 2, 99], [4, 8], [10, t]),
        "cell 1 refers to point 99, but there are 5 points")

bad("mesh.obj", "v 0 0 0\n", "unknown mesh format")

# ----------------------------------------------------------- region specs

bad("syntax-error.json", '{"type": "sphere", "center": [0.5, 0.5], "radius": 0.3,}\n',
    "invalid JSON", "region")
bad("unterminated.json", '{"type": "sphere", "center": [0.5, 0.5\n', "invalid JSON", "region")
bad("empty.json", "", "empty region spec", "region")
bad("not-object.json", "[1, 2, 3]\n", "must be a JSON object", "region")
bad("trailing-garbage.json", '{"type": "halfspace", "normal": [1, 0], "offset": 0} x\n',
    "invalid JSON", "region")
bad("unknown-type.json", '{"type": "cube", "center": [0, 0]}\n', "unknown region type",
    "region")
bad("missing-type.json", '{"center": [0, 0], "radius": 1}\n', "missing \"type\"", "region")
bad("type-not-string.json", '{"type": 3}\n', "must be a string", "region")
bad("wrong-length-center.json", '{"type": "sphere", "center": [0.5, 0.5, 0.5], "radius": 1}\n',
    "the mesh is 2D", "region")
bad("wrong-length-center-3d.json", '{"type": "sphere", "center": [0.5, 0.5], "radius": 1}\n',
    "the mesh is 3D", "region3")
bad("negative-radius.json", '{"type": "sphere", "center": [0.5, 0.5], "radius": -0.3}\n',
    "positive", "region")
bad("zero-radius.json", '{"type": "sphere", "center": [0.5, 0.5], "radius": 0}\n',
    "positive", "region")
bad("huge-radius.json", '{"type": "sphere", "center": [0.5, 0.5], "radius": 1e999}\n',
    "radius", "region")
bad("string-radius.json", '{"type": "sphere", "center": [0.5, 0.5], "radius": "1"}\n',
    "positive", "region")
bad("missing-radius.json", '{"type": "sphere", "center": [0.5, 0.5]}\n', "missing \"radius\"",
    "region")
bad("center-not-numbers.json", '{"type": "sphere", "center": ["a", 0.5], "radius": 1}\n',
    "entry 0", "region")
bad("unknown-field.json", '{"type": "sphere", "center": [0.5, 0.5], "radius": 1, "radios": 2}\n',
    "unknown field", "region")
bad("box-min-above-max.json", '{"type": "box", "min": [0, 1], "max": [1, 0]}\n', "exceeds",
    "region")
bad("zero-normal.json", '{"type": "halfspace", "normal": [0, 0], "offset": 0}\n',
    "must not be zero", "region")
bad("moving-sphere-2d.json",
    '{"type": "moving_sphere", "center": [0], "velocity": [1], "radius": 1}\n',
    "space-time", "region")
bad("solid-not-bool.json", '{"type": "sphere", "center": [0.5, 0.5], "radius": 1, "solid": 1}\n',
    "true or false", "region")
bad("empty-union.json", '{"type": "union", "regions": []}\n', "non-empty array", "region")
bad("union-bad-member.json",
    '{"type": "union", "regions": [{"type": "sphere", "center": [0, 0], "radius": 1}, '
    '{"type": "box", "min": [0], "max": [1, 1]}]}\n', "regions[1]", "region")
deep = '{"type": "union", "regions": [' * 100 + \
    '{"type": "sphere", "center": [0, 0], "radius": 1}' + ']}' * 100
bad("deep-nesting.json", deep + "\n", "nested more than", "region")
very_deep = "[" * 200000 + "]" * 200000
bad("very-deep-arrays.json", very_deep, "must be a JSON object", "region")
bad("binary.json", bytes(range(256)), "invalid JSON", "region")

with open(os.path.join(HERE, "cases.tsv"), "w") as f:
    f.write("# file\tkind\texpected substring (generated by make_corpus.py)\n")
    for row in cases:
        f.write("\t".join(row) + "\n")
with open(os.path.join(HERE, "good.tsv"), "w") as f:
    f.write("# file\tkind (generated by make_corpus.py): odd but valid, must be accepted\n")
    for row in goods:
        f.write("\t".join(row) + "\n")
print("%d bad cases, %d good files" % (len(cases), len(goods)))
