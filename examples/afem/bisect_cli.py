"""The REFINE and COARSEN steps through files: the mesh goes to bisect as .vtu
(meshio), bisect refines or coarsens it, meshio reads the result back.

A mesh here is (points (N, 2), cells (M, 3), cell_data {name: (M, ...) array}).
cell_data carries bisect's bisection state (the cell arrays "bisect:*"), which
must go back into the next call unchanged so the bisection sequence continues;
refine() and coarsen() keep every array they are given and only add/replace the
indicator. The bisection tree coarsen needs also has point arrays
("bisect:parent_a", "bisect:parent_b"): the class keeps those of the last
result and writes them back with the same points. An in-process variant (a Python module pybisect with
mesh.refine(marked=...)) can replace this class with the same two methods.
"""
import json
import os
import subprocess
import tempfile
import time

import meshio
import numpy as np


class BisectMissing(RuntimeError):
    """The bisect binary lacks a command or option an example needs."""


def repo_root():
    return os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def default_binary():
    return os.path.join(repo_root(), "build", "bisect")


def dorfler_marking(eta, theta):
    """The fewest cells whose eta^2 sum to at least theta times the total."""
    eta2 = np.asarray(eta, dtype=float) ** 2
    order = np.argsort(-eta2, kind="stable")
    cumulative = np.cumsum(eta2[order])
    count = int(np.searchsorted(cumulative, theta * cumulative[-1]) + 1)
    marked = np.zeros(len(eta2), dtype=bool)
    marked[order[:min(count, len(eta2))]] = True
    return marked


def write_vtu(path, points, cells, cell_data, point_data=None):
    xyz = np.column_stack([points, np.zeros(len(points))])
    meshio.write(path, meshio.Mesh(xyz, [("triangle", cells)],
                                   cell_data={k: [v] for k, v in cell_data.items()},
                                   point_data=point_data or {}))


def read_vtu(path):
    mesh = meshio.read(path)
    blocks = [b for b in mesh.cells if b.type == "triangle"]
    if len(blocks) != len(mesh.cells):
        raise RuntimeError(f"{path}: expected triangles only, got "
                           f"{[b.type for b in mesh.cells]}")
    cells = np.concatenate([b.data for b in blocks]).astype(np.int64)
    cell_data = {k: np.concatenate(v) for k, v in mesh.cell_data.items()}
    return mesh.points[:, :2].copy(), cells, cell_data


class BisectCLI:
    """Runs the bisect binary on scratch files. Accumulates the wall time spent
    in the calls (including meshio writing/reading) in `seconds`."""

    def __init__(self, binary=None, workdir=None, keep_files=False):
        self.binary = os.path.abspath(binary or default_binary())
        if not os.access(self.binary, os.X_OK):
            raise FileNotFoundError(f"bisect binary not found: {self.binary}")
        self._tmp = None if workdir else tempfile.TemporaryDirectory(prefix="afem-")
        self.workdir = workdir or self._tmp.name
        os.makedirs(self.workdir, exist_ok=True)
        self.keep_files = keep_files
        self.seconds = 0.0
        self.calls = 0
        self._step = 0
        self._help = {}

    # -- capability checks ------------------------------------------------
    def _help_text(self, command):
        if command not in self._help:
            run = subprocess.run([self.binary, command, "--help"],
                                 capture_output=True, text=True)
            self._help[command] = run.stdout if run.returncode == 0 else None
        return self._help[command]

    def has_indicator_refine(self):
        text = self._help_text("refine")
        return bool(text) and "--indicator" in text and "--dorfler" in text

    def has_coarsen(self):
        text = self._help_text("coarsen")
        return bool(text) and "--indicator" in text and "--below" in text

    # -- the steps ----------------------------------------------------------
    def _paths(self, what):
        self._step += 1
        stem = os.path.join(self.workdir, f"{what}-{self._step:03d}")
        return stem + "-in.vtu", stem + "-out.vtu"

    def _tree_for(self, points):
        """The tree's point arrays of the last result, if these are its points."""
        tree = getattr(self, "_tree", {})
        return tree if all(len(v) == len(points) for v in tree.values()) else {}

    def _run(self, args, src, dst):
        run = subprocess.run([self.binary] + args, capture_output=True, text=True)
        if run.returncode != 0:
            raise RuntimeError(f"bisect {' '.join(args)} failed (exit "
                               f"{run.returncode}): {run.stderr.strip()}")
        self.calls += 1
        result = read_vtu(dst)
        mesh = meshio.read(dst)
        self._tree = {k: v for k, v in mesh.point_data.items() if k.startswith("bisect:")}
        if not self.keep_files:
            for path in [src, dst, self._region_path()]:
                if os.path.exists(path):
                    os.remove(path)
        return result

    def has_refine_above(self):
        text = self._help_text("refine")
        return bool(text) and "--indicator" in text and "--above" in text

    def refine(self, points, cells, cell_data, eta=None, theta=0.5, above=None,
               name="eta"):
        """REFINE: returns the new (points, cells, cell_data).

        eta given: Doerfler marking with parameter theta on the indicator eta
        (one value per cell) by bisect itself (refine --indicator --dorfler);
        with `above`, the cells with eta > above instead (refine --indicator
        --above, if bisect has it). If this bisect lacks the option, the cells
        are marked here and handed over as a region: a union of tiny solid
        balls at the marked cells' centroids, each inside its cell only.
        eta None: uniform refinement (a box around the whole mesh)."""
        if eta is not None and above is not None and not np.any(np.asarray(eta) > above):
            return points, cells, cell_data                  # nothing to refine
        start = time.perf_counter()
        src, dst = self._paths("refine")
        data = dict(cell_data)
        if eta is not None:
            data[name] = np.asarray(eta, dtype=np.float64)
        write_vtu(src, points, cells, data, self._tree_for(points))
        args = ["refine", src, "-o", dst, "-q", "--quality-csv", "none", "-f"]
        if eta is None:
            lo, hi = points.min(axis=0), points.max(axis=0)
            pad = 1.0 + (hi - lo).max()
            region = {"type": "box", "min": (lo - pad).tolist(),
                      "max": (hi + pad).tolist()}
            args += ["--region", self._region_file(region)]
        elif above is not None and self.has_refine_above():
            args += ["--indicator", name, "--above", repr(float(above))]
        elif above is None and self.has_indicator_refine():
            args += ["--indicator", name, "--dorfler", repr(float(theta))]
        else:
            marked = (np.asarray(eta) > above if above is not None
                      else dorfler_marking(eta, theta))
            args += ["--region", self._marked_region(points, cells, marked)]
        result = self._run(args, src, dst)
        self.seconds += time.perf_counter() - start
        return result

    def coarsen(self, points, cells, cell_data, indicator, below, name="eta"):
        """COARSEN: bisect coarsen --indicator name --below X. Raises
        BisectMissing if this bisect has no coarsen command."""
        if not self.has_coarsen():
            raise BisectMissing("bisect coarsen (with --indicator and --below) "
                                f"is not available in {self.binary}")
        start = time.perf_counter()
        src, dst = self._paths("coarsen")
        data = dict(cell_data)
        data[name] = np.asarray(indicator, dtype=np.float64)
        write_vtu(src, points, cells, data, self._tree_for(points))
        args = ["coarsen", src, "--indicator", name, "--below", repr(float(below)),
                "-o", dst]
        # Options refine has; passed only if coarsen documents them too.
        text = self._help_text("coarsen")
        args += [opt for opt, flag in [("-q", "--quiet"), ("-f", "--force")]
                 if flag in text]
        if "--quality-csv" in text:
            args += ["--quality-csv", "none"]
        result = self._run(args, src, dst)
        self.seconds += time.perf_counter() - start
        return result

    # -- region files -----------------------------------------------------
    def _region_path(self):
        return os.path.join(self.workdir, f"region-{self._step:03d}.json")

    def _region_file(self, region):
        path = self._region_path()
        with open(path, "w") as f:
            json.dump(region, f)
        return path

    def _marked_region(self, points, cells, marked):
        """Fallback marking: a solid ball at each marked cell's centroid with a
        radius a thousandth of the cell's inradius touches that cell only."""
        p = points[cells[marked]]
        centroid = p.mean(axis=1)
        a = np.linalg.norm(p[:, 1] - p[:, 2], axis=1)
        b = np.linalg.norm(p[:, 2] - p[:, 0], axis=1)
        c = np.linalg.norm(p[:, 0] - p[:, 1], axis=1)
        s = 0.5 * (a + b + c)
        area = np.sqrt(np.maximum(s * (s - a) * (s - b) * (s - c), 0.0))
        radius = 1e-3 * area / s
        balls = [{"type": "sphere", "center": ctr.tolist(), "radius": float(r),
                  "solid": True} for ctr, r in zip(centroid, radius)]
        return self._region_file({"type": "union", "regions": balls})
