# Library errors arrive as pybisect.Error with the command line's message,
# its kind and the file it concerns.
import numpy as np
import pytest

import pybisect
from conftest import DATA, kuhn


def test_error_is_a_runtime_error():
    assert issubclass(pybisect.Error, RuntimeError)


def test_missing_file_names_the_file(tmp_path):
    path = str(tmp_path / "no-such.msh")
    with pytest.raises(pybisect.Error) as e:
        pybisect.read(path)
    assert path in str(e.value) and e.value.file == path and e.value.kind == "input"
    assert "\n" not in str(e.value)


def test_bad_region_json():
    mesh = pybisect.read(DATA / "ball.msh")
    with pytest.raises(pybisect.Error, match="invalid JSON") as e:
        mesh.refine(region='{"type": "sphere", "center": [0, 0, 0], ')
    assert e.value.kind == "input"
    with pytest.raises(pybisect.Error, match="radius"):
        mesh.refine(region={"type": "sphere", "center": [0, 0, 0]})
    with pytest.raises(pybisect.Error):
        mesh.refine(region={"type": "sphere", "center": [0, 0], "radius": 1})  # 2D centre in 3D
    assert not mesh.marked  # nothing happened


def test_out_of_range_cell_index():
    points, cells = kuhn(2, 1)
    mesh = pybisect.Mesh(points, cells)
    for bad in ([2], [-1]):
        with pytest.raises(pybisect.Error, match="out of range") as e:
            mesh.refine(bad)
        assert e.value.kind == "usage"
    with pytest.raises(pybisect.Error, match="one value per cell"):
        mesh.refine(np.ones(3, dtype=bool))


def test_bad_arrays():
    points, cells = kuhn(3, 1)
    with pytest.raises(pybisect.Error, match="vertex id"):
        pybisect.Mesh(points, cells + 100)
    with pytest.raises(pybisect.Error, match="integer"):
        pybisect.Mesh(points, cells.astype(float))
    with pytest.raises(pybisect.Error, match="no cells"):
        pybisect.Mesh(np.zeros((0, 3)), np.zeros((0, 4), dtype=int))
    flat = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], dtype=float)
    with pytest.raises(pybisect.Error, match="zero volume"):
        pybisect.Mesh(flat, [[0, 1, 2, 3]])
    tilted = np.array([[0, 0, 0], [1, 0, 1], [0, 1, 0]], dtype=float)
    with pytest.raises(pybisect.Error, match="not in one plane"):
        pybisect.Mesh(tilted, [[0, 1, 2]])


def test_bad_marking_and_compression(tmp_path):
    points, cells = kuhn(2, 1)
    mesh = pybisect.Mesh(points, cells)
    with pytest.raises(pybisect.Error, match="unknown marking"):
        mesh.refine([0], marking="random")
    with pytest.raises(pybisect.Error, match="unknown compression"):
        mesh.write(tmp_path / "x.vtu", compression="gzip")
    with pytest.raises(pybisect.Error, match="unknown mesh format"):
        mesh.write(tmp_path / "x.stl")


def test_cell_limit_leaves_the_mesh_unchanged():
    points, cells = kuhn(3, 2)
    mesh = pybisect.Mesh(points, cells)
    with pytest.raises(pybisect.Error, match="max_cells") as e:
        mesh.refine(np.arange(mesh.num_cells), max_cells=50)
    assert e.value.kind == "limit" and mesh.num_cells == len(cells)
