#!/usr/bin/env python3
"""Remakes data/square-eta.vtu: data/square.msh with a cell array `eta`, an
error indicator that is large near the corner (0, 0) (exp(-8 |centroid|)),
for the README's `refine --indicator` example. Needs the pybisect module
(scripts/install-python.sh, or PYTHONPATH=build/python)."""
import os
import numpy as np
import pybisect

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
m = pybisect.read(os.path.join(root, "data", "square.msh"))
points, cells = np.asarray(m.points), np.asarray(m.cells)
eta = np.exp(-8 * np.linalg.norm(points[cells].mean(axis=1), axis=1))
pybisect.Mesh(points, cells, cell_data={"eta": eta}).write(os.path.join(root, "data", "square-eta.vtu"))
