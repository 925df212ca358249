# pytest suite for the pybisect module. CTest runs it with PYTHONPATH set to
# the build tree's module directory, BISECT_BIN to the bisect binary and
# BISECT_ROOT to the source tree (python/CMakeLists.txt); by hand:
#   PYTHONPATH=build/python BISECT_BIN=build/bisect /usr/bin/python3 -m pytest -q tests/python
import itertools
import os
import pathlib

import numpy as np
import pytest

ROOT = pathlib.Path(os.environ.get("BISECT_ROOT", pathlib.Path(__file__).resolve().parents[2]))
DATA = ROOT / "data"


def kuhn(dim, n):
    """The Freudenthal-Kuhn triangulation of [0,1]^dim with n^dim cubes, dim! simplices each."""
    axes = [np.linspace(0.0, 1.0, n + 1)] * dim
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    stride = [(n + 1) ** (dim - 1 - k) for k in range(dim)]
    cells = []
    for cube in itertools.product(range(n), repeat=dim):
        base = sum(c * s for c, s in zip(cube, stride))
        for perm in itertools.permutations(range(dim)):
            ids = [base]
            for k in perm:
                ids.append(ids[-1] + stride[k])
            cells.append(ids)
    return grid, np.array(cells, dtype=np.int64)


@pytest.fixture(scope="session")
def bisect_bin():
    path = os.environ.get("BISECT_BIN")
    if not path or not os.access(path, os.X_OK):
        pytest.skip("BISECT_BIN does not name the bisect binary")
    return path
