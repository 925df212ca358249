# Round trips with meshio: to_meshio -> from_meshio, and .vtu written by the
# module -> meshio.read -> from_meshio -> refine continues the same sequence.
import meshio
import numpy as np
import pytest

import pybisect
from conftest import DATA, kuhn


def cell_sets(mesh):
    pts = mesh.points
    return sorted(tuple(sorted(map(tuple, pts[c]))) for c in mesh.cells)


@pytest.mark.parametrize("dim", [2, 3])
def test_to_meshio_from_meshio_keeps_cells_and_state(dim):
    points, cells = kuhn(dim, 2)
    mesh = pybisect.Mesh(points, cells, cell_data={"label": np.arange(len(cells))})
    mesh.refine(region={"type": "halfspace", "normal": [1] + [0] * (dim - 1), "offset": 0.6})
    m = mesh.to_meshio()
    assert m.cells[0].type == ("triangle" if dim == 2 else "tetra")
    assert {"bisect:state", "bisect:marking", "label"} <= set(m.cell_data)
    back = pybisect.from_meshio(m)
    assert back.marked and back.marking == mesh.marking
    assert np.array_equal(back.cells, mesh.cells)  # same tuples: the state came back
    assert np.array_equal(back.points, mesh.points)
    assert np.array_equal(back.cell_data["label"], mesh.cell_data["label"])
    # and both continue identically
    mesh.refine(region={"type": "halfspace", "normal": [1] + [0] * (dim - 1), "offset": 0.8})
    back.refine(region={"type": "halfspace", "normal": [1] + [0] * (dim - 1), "offset": 0.8})
    assert np.array_equal(back.cells, mesh.cells)


def test_vtu_through_meshio_continues_the_sequence(tmp_path):
    region = DATA / "regions" / "hemisphere.json"
    direct = pybisect.read(DATA / "ball.msh")
    direct.refine(region=region)
    path = tmp_path / "ball-1.vtu"
    direct.write(path)
    via = pybisect.from_meshio(meshio.read(path))
    assert via.marked
    assert cell_sets(via) == cell_sets(direct)
    direct.refine(region=region)
    via.refine(region=region)
    assert via.num_cells == direct.num_cells
    assert cell_sets(via) == cell_sets(direct)
    via.check()


def test_write_and_read_keep_the_state(tmp_path):
    mesh = pybisect.read(DATA / "square.msh")
    mesh.refine(region=DATA / "regions" / "circle.json")
    for name, compression in [("a.vtu", "zlib"), ("b.vtu", "none"), ("c.msh", "zlib")]:
        mesh.write(tmp_path / name, compression=compression)
        back = pybisect.read(tmp_path / name)
        assert back.marked and cell_sets(back) == cell_sets(mesh)


def test_from_meshio_reads_a_gmsh_file_with_lower_cells():
    m = meshio.read(DATA / "ball.msh")
    mesh = pybisect.from_meshio(m)
    assert mesh.dim == 3
    assert mesh.num_cells == pybisect.read(DATA / "ball.msh").num_cells
    assert "gmsh:physical" in mesh.cell_data
    mesh.refine([0, 1, 2])
    mesh.check()


def test_4d_has_no_meshio_form():
    points, cells = kuhn(4, 1)
    with pytest.raises(pybisect.Error, match="meshio has no cell type"):
        pybisect.Mesh(points, cells).to_meshio()


def test_from_meshio_reads_a_2d_gmsh_file():
    m = meshio.read(DATA / "square.msh")  # points (n, 3) with z = 0, lines and triangles
    mesh = pybisect.from_meshio(m)
    direct = pybisect.read(DATA / "square.msh")
    assert mesh.dim == 2 and mesh.points.shape[1] == 2
    assert cell_sets(mesh) == cell_sets(direct)
    mesh.refine(region=DATA / "regions" / "box2d.json", depth=2)
    mesh.check()
