"""The REFINE (and COARSEN) step of the examples, two ways:

* BisectFiles: through files. The mesh goes to the bisect binary as .vtu
  (meshio), bisect marks and refines it (`refine --indicator eta --dorfler
  THETA` or `--above X`; uniform: a box region around the mesh), meshio reads
  the result back. The cell arrays "bisect:*" bisect writes (the bisection
  state) go back into the next call unchanged, so the bisection sequence
  continues across the calls.
* BisectModule: in process, through the Python module pybisect. The state
  lives in a pybisect.Mesh; the cells are marked here (Dorfler: the same rule
  as bisect's) and refined with mesh.refine(marked=mask). No files.

Both hold the current mesh and expose it as `points` (N, 2) float64 and
`cells` (M, 3) int64, and count the wall time spent in them in `seconds`
(files: writing the .vtu, running bisect, reading the result; module: the
marking, mesh.refine and copying the arrays out) and the calls in `calls`.
"""
import json
import os
import subprocess
import tempfile
import time

import meshio
import numpy as np


class BisectMissing(RuntimeError):
    """The bisect binary lacks a command an example needs."""


def repo_root():
    return os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def default_binary():
    return os.path.join(repo_root(), "build", "bisect")


def dorfler_marking(eta, theta):
    """Dorfler's bulk criterion, as `bisect refine --dorfler` computes it
    (src/engine/indicator.cpp): cells by decreasing eta, ties to the lower id;
    the fewest of them whose eta^2 sum to at least theta times the total.
    The total is summed in cell order and the running sum in the sorted order,
    left to right, as the C++ loop does, so both round alike."""
    eta = np.asarray(eta, dtype=np.float64)
    marked = np.zeros(len(eta), dtype=bool)
    eta2 = eta * eta
    total = np.cumsum(eta2)[-1] if len(eta) else 0.0       # sequential, not pairwise
    if total == 0:
        return marked
    order = np.lexsort((np.arange(len(eta)), -eta))        # by -eta, then by id
    running = np.cumsum(eta2[order])
    count = int(np.searchsorted(running, theta * total, side="left")) + 1
    marked[order[:min(count, len(eta))]] = True
    return marked


def write_vtu(path, points, cells, cell_data, point_data=None):
    xyz = np.column_stack([points, np.zeros(len(points))])
    meshio.write(path, meshio.Mesh(xyz, [("triangle", cells)],
                                   point_data=dict(point_data or {}),
                                   cell_data={k: [v] for k, v in cell_data.items()}))


def read_vtu(path):
    mesh = meshio.read(path)
    blocks = [b for b in mesh.cells if b.type == "triangle"]
    if len(blocks) != len(mesh.cells):
        raise RuntimeError(f"{path}: expected triangles only, got "
                           f"{[b.type for b in mesh.cells]}")
    cells = np.concatenate([b.data for b in blocks]).astype(np.int64)
    cell_data = {k: np.concatenate(v) for k, v in mesh.cell_data.items()}
    return mesh.points[:, :2].copy(), cells, cell_data, dict(mesh.point_data)


def uniform_box(points):
    """A box region around the whole mesh: every cell touches it."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 1.0 + (hi - lo).max()
    return {"type": "box", "min": (lo - pad).tolist(), "max": (hi + pad).tolist()}


class BisectFiles:
    """The bisect binary on scratch .vtu files."""

    via = "files"

    def __init__(self, points, cells, binary=None, workdir=None, keep_files=False):
        self.binary = os.path.abspath(binary or default_binary())
        if not os.access(self.binary, os.X_OK):
            raise FileNotFoundError(f"bisect binary not found: {self.binary}")
        self._tmp = None if workdir else tempfile.TemporaryDirectory(prefix="afem-")
        self.workdir = workdir or self._tmp.name
        os.makedirs(self.workdir, exist_ok=True)
        self.keep_files = keep_files
        self.points = np.asarray(points, dtype=np.float64)
        self.cells = np.asarray(cells, dtype=np.int64)
        # The bisect:* arrays bisect writes (the bisection state; with coarsen,
        # the tree: bisect:generation per cell, bisect:parent_a/b per vertex),
        # passed back unchanged with the next input.
        self.cell_data, self.point_data = {}, {}
        self.seconds = 0.0
        self.calls = 0
        self._step = 0
        self._has_coarsen = None

    def has_coarsen(self):
        """Whether this binary has a `coarsen` command at all (for an unknown
        command, `bisect CMD --help` prints the top-level usage, exit 0)."""
        if self._has_coarsen is None:
            run = subprocess.run([self.binary, "coarsen", "--help"], capture_output=True,
                                 text=True)
            usage = [line for line in run.stdout.splitlines() if line.startswith("Usage:")]
            self._has_coarsen = (run.returncode == 0 and bool(usage)
                                 and " coarsen " in usage[0] + " ")
        return self._has_coarsen

    def _call(self, what, args, indicator=None, region=None):
        start = time.perf_counter()
        self._step += 1
        stem = os.path.join(self.workdir, f"{what}-{self._step:03d}")
        src, dst, spec = stem + "-in.vtu", stem + "-out.vtu", stem + "-region.json"
        data = dict(self.cell_data)
        if indicator is not None:
            data["eta"] = np.asarray(indicator, dtype=np.float64)
        write_vtu(src, self.points, self.cells, data, self.point_data)
        if region is not None:
            with open(spec, "w") as f:
                json.dump(region, f)
            args = args + ["--region", spec]
        cmd = [self.binary, what, src] + args + ["-o", dst, "-q", "-f"]
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed (exit {run.returncode}): "
                               f"{run.stderr.strip()}")
        points, cells, cell_data, point_data = read_vtu(dst)
        if not self.keep_files:
            for path in (src, dst, spec):
                if os.path.exists(path):
                    os.remove(path)
        self.points, self.cells = points, cells
        self.cell_data = {k: v for k, v in cell_data.items() if k.startswith("bisect:")}
        self.point_data = {k: v for k, v in point_data.items() if k.startswith("bisect:")}
        self.calls += 1
        self.seconds += time.perf_counter() - start

    def refine_dorfler(self, eta, theta):
        self._call("refine", ["--indicator", "eta", "--dorfler", repr(float(theta)),
                              "--quality-csv", "none"], indicator=eta)

    def refine_above(self, eta, tol):
        self._call("refine", ["--indicator", "eta", "--above", repr(float(tol)),
                              "--quality-csv", "none"], indicator=eta)

    def refine_uniform(self):
        self._call("refine", ["--quality-csv", "none"], region=uniform_box(self.points))

    def coarsen_below(self, eta, below, passes=1):
        if not self.has_coarsen():
            raise BisectMissing(f"bisect coarsen is not available in {self.binary}")
        self._call("coarsen", ["--indicator", "eta", "--below", repr(float(below)),
                               "-n", str(int(passes))], indicator=eta)


class BisectModule:
    """pybisect in process: one pybisect.Mesh, refined in place."""

    via = "module"

    def __init__(self, points, cells):
        import pybisect
        self.pybisect = pybisect
        start = time.perf_counter()
        self.mesh = pybisect.Mesh(np.asarray(points, dtype=np.float64),
                                  np.asarray(cells, dtype=np.int64))
        self._fetch()
        self.seconds = time.perf_counter() - start
        self.calls = 0

    def _fetch(self):
        # Copies: the solver indexes with int64 and keeps the arrays while
        # the mesh is refined (views would then show the old mesh anyway).
        self.points = np.array(self.mesh.points, dtype=np.float64)
        self.cells = np.array(self.mesh.cells, dtype=np.int64)

    def _refine(self, **kwargs):
        start = time.perf_counter()
        marked = kwargs.pop("mask", None)
        if marked is not None:
            kwargs["marked"] = marked
        self.mesh.refine(**kwargs)
        self._fetch()
        self.calls += 1
        self.seconds += time.perf_counter() - start

    def refine_dorfler(self, eta, theta):
        start = time.perf_counter()
        mask = dorfler_marking(eta, theta)
        self.seconds += time.perf_counter() - start
        self._refine(mask=mask)

    def refine_above(self, eta, tol):
        self._refine(mask=np.asarray(eta) > tol)

    def refine_uniform(self):
        self._refine(mask=np.ones(self.mesh.num_cells, dtype=bool))
