# Refinement through the module: conforming, volume and boundary unchanged,
# in 2D, 3D and 4D, by mask, by ids, by region and by depth.
import numpy as np
import pytest

import pybisect
from conftest import DATA, kuhn

REGIONS = {
    2: {"type": "sphere", "center": [0.5, 0.5], "radius": 0.3},
    3: {"type": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.3},
    4: {"type": "sphere", "center": [0.5, 0.5, 0.5, 0.5], "radius": 0.3},
}


def assert_conforming(mesh, volume):
    r = mesh.check()
    assert r["conforming"]
    assert r["volume"] == pytest.approx(volume, rel=1e-12)
    assert r["boundary_measure"] == pytest.approx(r["original_boundary_measure"], rel=1e-12)


@pytest.mark.parametrize("dim", [2, 3, 4])
def test_refine_by_mask_conforms_and_keeps_volume(dim):
    points, cells = kuhn(dim, 2)
    mesh = pybisect.Mesh(points, cells)
    assert mesh.dim == dim and mesh.num_cells == len(cells) and not mesh.marked
    mask = np.zeros(mesh.num_cells, dtype=bool)
    mask[0] = True
    r = mesh.refine(mask)
    assert r["selected"] == 1 and r["bisections"] >= 1 and r["cells"] == mesh.num_cells
    assert mesh.marked and mesh.marking == "index"
    assert_conforming(mesh, 1.0)


@pytest.mark.parametrize("dim", [2, 3, 4])
@pytest.mark.parametrize("depth", [2, 3])
def test_refine_depth_conforms_and_keeps_volume(dim, depth):
    points, cells = kuhn(dim, 2)
    mesh = pybisect.Mesh(points, cells)
    once = pybisect.Mesh(points, cells)
    once.refine(np.array([1, 0]))
    mesh.refine(np.array([1, 0]), depth=depth)
    assert mesh.num_cells > once.num_cells
    assert_conforming(mesh, 1.0)


@pytest.mark.parametrize("dim", [2, 3, 4])
def test_refine_by_region_iterations_conform(dim):
    points, cells = kuhn(dim, 2)
    mesh = pybisect.Mesh(points, cells)
    counts = []
    for _ in range(3):
        r = mesh.refine(region=REGIONS[dim])
        assert r["selected"] > 0
        counts.append(mesh.num_cells)
    assert counts == sorted(counts) and counts[0] > len(cells)
    assert_conforming(mesh, 1.0)
    q = mesh.quality()
    assert 0 < q["min"] <= q["mean"] <= q["max"] <= 1


def test_region_and_mask_select_their_union():
    points, cells = kuhn(3, 2)
    region = {"type": "box", "min": [0, 0, 0], "max": [0.1, 0.1, 0.1]}
    a = pybisect.Mesh(points, cells)
    only_region = a.refine(region=region)["selected"]
    b = pybisect.Mesh(points, cells)
    far = int(np.argmax(b.points[b.cells].mean(axis=1).sum(axis=1)))  # the cell nearest (1,1,1)
    r = b.refine(marked=[far], region=region)
    assert r["selected"] == only_region + 1
    assert_conforming(b, 1.0)


def test_region_dict_may_hold_numpy_values():
    points, cells = kuhn(3, 2)
    a, b = pybisect.Mesh(points, cells), pybisect.Mesh(points, cells)
    a.refine(region={"type": "sphere", "center": np.full(3, 0.5), "radius": np.float64(0.3)})
    b.refine(region=REGIONS[3])
    assert np.array_equal(a.cells, b.cells)


def test_region_as_json_text_and_as_file_give_the_same_mesh():
    spec = DATA / "regions" / "hemisphere.json"
    a = pybisect.read(DATA / "ball.msh")
    b = pybisect.read(str(DATA / "ball.msh"))
    a.refine(region=spec.read_text())
    b.refine(region=str(spec))
    assert np.array_equal(a.cells, b.cells) and np.array_equal(a.points, b.points)


def test_refine_on_a_file_mesh_keeps_volume_and_boundary():
    mesh = pybisect.read(DATA / "ball.msh")
    before = mesh.check()
    mesh.refine(region=DATA / "regions" / "hemisphere.json", depth=2)
    after = mesh.check()
    assert after["volume"] == pytest.approx(before["volume"], rel=1e-12)
    assert after["euler"] == before["euler"]


def test_triangles_in_a_plane_z_c_keep_their_z():
    points, cells = kuhn(2, 2)
    xyz = np.column_stack([points, np.full(len(points), 2.5)])
    mesh = pybisect.Mesh(xyz, cells)
    assert mesh.dim == 2 and mesh.points.shape == (len(points), 2)
    mesh.refine(np.arange(mesh.num_cells))
    assert np.all(mesh.point_data["bisect:z"] == 2.5)
    assert np.all(mesh.to_meshio().points[:, 2] == 2.5)


def test_views_share_memory_and_survive_refine():
    points, cells = kuhn(3, 1)
    mesh = pybisect.Mesh(points, cells, cell_data={"id": np.arange(len(cells), dtype=float)})
    p = mesh.points
    assert p.base is not None and not p.flags.writeable and not p.flags.owndata
    assert np.shares_memory(mesh.points, mesh.points)
    ids = mesh.cell_data["id"]
    ids[0] = 42.0  # data arrays are writable views
    assert mesh.cell_data["id"][0] == 42.0
    old_points = mesh.points.copy()
    old_view = mesh.points
    mesh.refine(np.arange(mesh.num_cells))
    assert np.array_equal(old_view, old_points)  # the old view still shows the old mesh
    assert mesh.points.shape[0] > old_points.shape[0]
    assert not np.shares_memory(old_view, mesh.points)
    children = mesh.cell_data["id"]
    assert len(children) == mesh.num_cells and 42.0 in children  # inherited by the children
    with pytest.raises(ValueError):
        mesh.points[0, 0] = 1.0


def test_arrays_added_replaced_and_removed_by_name(tmp_path):
    points, cells = kuhn(3, 1)
    mesh = pybisect.Mesh(points, cells)
    n = mesh.num_cells
    mesh.cell_data["eta"] = np.arange(n, dtype=float)
    mesh.cell_data["grad"] = np.ones((n, 3))
    mesh.point_data["u"] = np.zeros(len(points))
    assert set(mesh.cell_data) == {"eta", "grad"} and len(mesh.cell_data) == 2
    assert "u" in mesh.point_data and mesh.cell_data.get("nope") is None
    old = mesh.cell_data["eta"]
    mesh.cell_data["eta"] = np.full(n, 7.0)  # replaced; the old view keeps its values
    assert np.array_equal(old, np.arange(n)) and np.all(mesh.cell_data["eta"] == 7.0)
    mesh.refine(np.arange(n))
    assert mesh.cell_data["eta"].shape == (mesh.num_cells,)
    assert mesh.cell_data["grad"].shape == (mesh.num_cells, 3)
    del mesh.cell_data["grad"]
    assert set(mesh.cell_data) == {"eta"}
    with pytest.raises(KeyError):
        del mesh.cell_data["grad"]
    with pytest.raises(pybisect.Error, match="rows"):
        mesh.cell_data["short"] = np.zeros(3)
    with pytest.raises(pybisect.Error, match="bisect"):
        mesh.cell_data["bisect:state"] = np.zeros(mesh.num_cells)
    path = str(tmp_path / "arrays.vtu")
    mesh.write(path)
    back = pybisect.read(path)
    assert np.all(back.cell_data["eta"] == 7.0) and "u" in back.point_data


def test_copy_is_independent():
    points, cells = kuhn(2, 2)
    mesh = pybisect.Mesh(points, cells)
    mesh.refine([0])
    twin = mesh.copy()
    mesh.refine([1, 2])
    assert twin.num_cells < mesh.num_cells and twin.marked
    twin.refine([1, 2])
    assert np.array_equal(twin.cells, mesh.cells)
    twin.check()


def test_marking_choice_is_used_for_an_unmarked_mesh():
    points, cells = kuhn(3, 1)
    mesh = pybisect.Mesh(points, cells)
    mesh.refine([0], marking="longest")
    assert mesh.marking == "longest"


def test_refine_releases_the_gil_and_guards_the_mesh():
    # While one thread refines (GIL released), another runs Python and finds
    # the mesh busy instead of reading it half-refined.
    import threading

    mesh = pybisect.read(DATA / "ball.msh")
    worker = threading.Thread(target=lambda: mesh.refine(np.arange(mesh.num_cells), depth=3))
    seen_busy = False
    worker.start()
    while worker.is_alive():
        try:
            mesh.points  # holds the GIL: never makes the worker find the mesh busy
        except pybisect.Error as e:
            assert "in use" in str(e) and e.kind == "usage"
            seen_busy = True
    worker.join()
    assert seen_busy
    mesh.check(full=False)


@pytest.mark.parametrize("dim", [2, 3, 4])
def test_coarsen_undoes_refine(dim):
    """Refining by a region and coarsening every cell until nothing changes
    gives the original cells back (as sets of vertex coordinates)."""
    box = {"type": "box", "min": [0.0] * dim, "max": [0.3] * dim}
    def cell_set(m):
        pts = np.asarray(m.points)
        return {frozenset(tuple(pts[v]) for v in cell) for cell in np.asarray(m.cells)}

    mesh = pybisect.Mesh(*kuhn(dim, 2))
    before = cell_set(mesh)
    for _ in range(3):
        mesh.refine(region=box)
    assert mesh.num_cells > len(before)
    r = mesh.coarsen(passes=0)
    assert r["removed_vertices"] > 0 and r["cells"] == mesh.num_cells
    assert cell_set(mesh) == before
    mesh.check()
    # Partial coarsening stays conforming.
    mesh.refine(region=box)
    mesh.refine(region=box)
    mask = np.zeros(mesh.num_cells, dtype=bool)
    mask[: mesh.num_cells // 2] = True
    mesh.coarsen(mask)
    mesh.check()
