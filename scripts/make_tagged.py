#!/usr/bin/env python3
"""Writes small Gmsh meshes with tagged facets, curves and points (no Gmsh needed).

  make_tagged.py box  OUT.msh [N]   unit cube, N^3 cubes of 6 Kuhn tetrahedra,
                                    Gmsh 4.1 ASCII ($Entities, $PhysicalNames)
  make_tagged.py square OUT.msh [N] unit square, N^2 squares of 2 triangles,
                                    Gmsh 2.2 ASCII (physical tags on elements)

Physical groups (tag "name"): 1 "left" (x = 0), 2 "right" (x = 1),
3 "walls" (the other sides), 4 "mid" (the internal plane or line x = 1/2,
embedded: it bounds cells on both sides), 5 "edge" (the curve y = z = 0 in
3D; the point (0, 0) in 2D) and 10 "solid" (the cells). data/box-tagged.msh
is `make_tagged.py box data/box-tagged.msh 2`.
"""
import itertools
import sys


def grid(n, dim):
    ids = {}
    for ijk in itertools.product(range(n + 1), repeat=dim):
        ids[ijk] = len(ids) + 1
    return ids


def kuhn_cells(n, dim, ids):
    """Cells of the Kuhn (Freudenthal) subdivision: conforming, one pattern."""
    cells = []
    for base in itertools.product(range(n), repeat=dim):
        for perm in itertools.permutations(range(dim)):
            p = list(base)
            cell = [ids[tuple(p)]]
            for axis in perm:
                p[axis] += 1
                cell.append(ids[tuple(p)])
            cells.append(cell)
    return cells


def faces_on(cells, ids, n, dim, test, size):
    """The distinct faces with `size` vertices whose vertices all pass `test`."""
    where = {v: k for k, v in ids.items()}
    found = {}
    for cell in cells:
        for face in itertools.combinations(cell, size):
            if all(test([c / n for c in where[v]]) for v in face):
                found.setdefault(tuple(sorted(face)), face)
    return list(found.values())


def groups(cells, ids, n, dim):
    """[(dim, physical, elementary, [elements])] of the tagged entities."""
    side = dim - 1
    near = lambda a, b: abs(a - b) < 1e-12
    out = [
        (side, 1, 1, faces_on(cells, ids, n, dim, lambda x: near(x[0], 0), dim)),
        (side, 2, 2, faces_on(cells, ids, n, dim, lambda x: near(x[0], 1), dim)),
    ]
    walls = []
    for axis in range(1, dim):
        for value in (0, 1):
            walls += faces_on(cells, ids, n, dim, lambda x, a=axis, v=value: near(x[a], v), dim)
    out.append((side, 3, 3, walls))
    out.append((side, 4, 4, faces_on(cells, ids, n, dim, lambda x: near(x[0], 0.5), dim)))
    if dim == 3:
        edge = faces_on(cells, ids, n, dim, lambda x: near(x[1], 0) and near(x[2], 0), 2)
        out.append((1, 5, 1, edge))
    else:
        out.append((0, 5, 1, [(ids[(0, 0)],)]))
    return out


def write_names(f, names):
    f.write("$PhysicalNames\n%d\n" % len(names))
    for d, t, name in names:
        f.write('%d %d "%s"\n' % (d, t, name))
    f.write("$EndPhysicalNames\n")


def tagged_grid(n, d):
    """The Kuhn grid of the unit d-cube, its tagged groups and their names."""
    ids = grid(n, d)
    cells = kuhn_cells(n, d, ids)
    tagged = groups(cells, ids, n, d)
    names = [(d - 1, 1, "left"), (d - 1, 2, "right"), (d - 1, 3, "walls"), (d - 1, 4, "mid"),
             (d - 2, 5, "edge"), (d, 10, "solid")]
    return ids, cells, tagged, names


def write_box(path, n):
    ids, cells, tagged, names = tagged_grid(n, 3)
    with open(path, "w") as f:
        f.write("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
        write_names(f, names)
        f.write("$Entities\n0 1 4 1\n")
        f.write("1 0 0 0 1 0 0 1 5 0\n")  # curve 1: y = z = 0, physical 5
        for d, phys, tag, _ in tagged:
            if d == 2:
                f.write("%d 0 0 0 1 1 1 1 %d 0\n" % (tag, phys))
        f.write("1 0 0 0 1 1 1 1 10 0\n$EndEntities\n")
        f.write("$Nodes\n1 %d 1 %d\n3 1 0 %d\n" % (len(ids), len(ids), len(ids)))
        for v in ids.values():
            f.write("%d\n" % v)
        for ijk in ids:
            f.write("%.17g %.17g %.17g\n" % tuple(c / n for c in ijk))
        f.write("$EndNodes\n")
        blocks = [(d, tag, els) for d, _, tag, els in tagged] + [(3, 1, cells)]
        total = sum(len(els) for _, _, els in blocks)
        f.write("$Elements\n%d %d 1 %d\n" % (len(blocks), total, total))
        types = {1: 1, 2: 2, 3: 4}
        tag = 1
        for d, entity, els in blocks:
            f.write("%d %d %d %d\n" % (d, entity, types[d], len(els)))
            for e in els:
                f.write("%d %s\n" % (tag, " ".join(map(str, e))))
                tag += 1
        f.write("$EndElements\n")


def write_square(path, n):
    ids, cells, tagged, names = tagged_grid(n, 2)
    with open(path, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n")
        write_names(f, names)
        f.write("$Nodes\n%d\n" % len(ids))
        for ijk, v in ids.items():
            f.write("%d %.17g %.17g 0\n" % (v, ijk[0] / n, ijk[1] / n))
        f.write("$EndNodes\n")
        rows = []
        types = {0: 15, 1: 1, 2: 2}
        for d, phys, geom, els in tagged:
            rows += [(types[d], phys, geom, e) for e in els]
        rows += [(2, 10, 1, c) for c in cells]
        f.write("$Elements\n%d\n" % len(rows))
        for i, (t, phys, geom, e) in enumerate(rows, 1):
            f.write("%d %d 2 %d %d %s\n" % (i, t, phys, geom, " ".join(map(str, e))))
        f.write("$EndElements\n")


if __name__ == "__main__":
    kind, out = sys.argv[1], sys.argv[2]
    n = int(sys.argv[3]) if len(sys.argv) > 3 else 2
    (write_box if kind == "box" else write_square)(out, n)
