#!/usr/bin/python3
"""A moving heat source: refine ahead, coarsen behind, with a bounded cell count.

A Gaussian bump f(x, t) = exp(-|x - c(t)|^2 / (2 sigma^2)) moves across the
unit square along a straight line in --steps steps. At each step the mesh is
adapted to the source at its new position:

  COARSEN  bisect coarsen --indicator eta --below TOL/8  (undo bisections where
           the source is resolved well enough, i.e. behind the front), then
  REFINE   bisect refine (the cells with eta > TOL) until no cell is above TOL
           or --max-refine iterations were made,

where eta_T is the P1 interpolation error of f on T measured at the edge
midpoints, max over the edges of |f(mid) - (f(a) + f(b))/2|. The factor 8
between the thresholds keeps a cell just bisected from being coarsened at
once. No PDE is solved: the example exercises refinement and coarsening with
a moving indicator. It prints the cell count per step and checks that it stays
within +-25% of its mean after the first steps.

    /usr/bin/python3 examples/afem/heat.py --steps 30 --out afem-out/

Exit 77 (skip) if this bisect has no `coarsen` command (with --indicator and
--below); --no-coarsen runs the refinement alone (the count then grows).
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bisect_cli import BisectCLI, BisectMissing, default_binary, write_vtu  # noqa: E402

SKIP = 77


def square_mesh(n):
    """The unit square, n x n squares of two triangles each."""
    x = np.linspace(0, 1, n + 1)
    X, Y = np.meshgrid(x, x, indexing="xy")
    points = np.column_stack([X.ravel(), Y.ravel()])
    vid = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b = vid[:-1, :-1].ravel(), vid[:-1, 1:].ravel()
    c, d = vid[1:, 1:].ravel(), vid[1:, :-1].ravel()
    cells = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return points, cells


class Source:
    def __init__(self, start, end, sigma):
        self.start, self.end, self.sigma = np.array(start), np.array(end), sigma

    def centre(self, t):
        return (1 - t) * self.start + t * self.end

    def __call__(self, pts, t):
        d2 = np.sum((pts - self.centre(t)) ** 2, axis=1)
        return np.exp(-d2 / (2 * self.sigma ** 2))


def interpolation_indicator(points, cells, f):
    """eta_T = max over the edges of T of |f(midpoint) - mean of f at the ends|."""
    fv = f(points)
    p = points[cells]
    eta = np.zeros(len(cells))
    for i, j in [(0, 1), (1, 2), (2, 0)]:
        mid = f(0.5 * (p[:, i] + p[:, j]))
        eta = np.maximum(eta, np.abs(mid - 0.5 * (fv[cells[:, i]] + fv[cells[:, j]])))
    return eta


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bisect", default=default_binary(),
                        help="the bisect binary (default: build/bisect of this repository)")
    parser.add_argument("--steps", type=int, default=30, help="time steps (30)")
    parser.add_argument("--tol", type=float, default=0.01,
                        help="refine cells with eta > TOL; coarsen below TOL/8 (0.01)")
    parser.add_argument("--sigma", type=float, default=0.05, help="width of the bump (0.05)")
    parser.add_argument("--initial", type=int, default=8,
                        help="initial mesh: n x n squares of two triangles (8)")
    parser.add_argument("--max-refine", type=int, default=10,
                        help="refine iterations per step at most (10)")
    parser.add_argument("--settle", type=int, default=5,
                        help="steps before the cell count is expected to be steady (5)")
    parser.add_argument("--small", action="store_true",
                        help="a quick run (for tests): 12 steps, TOL 0.03, sigma 0.08")
    parser.add_argument("--no-coarsen", action="store_true",
                        help="refine only (runs without bisect coarsen; the count grows)")
    parser.add_argument("--out", default="afem-out", help="output directory (afem-out)")
    args = parser.parse_args(argv)
    if args.small:
        args.steps, args.tol, args.sigma, args.settle = 12, 0.03, 0.08, 3

    try:
        bisect = BisectCLI(args.bisect)
    except FileNotFoundError as missing:
        print(f"error: {missing} (build it, or pass --bisect PATH)", file=sys.stderr)
        return 1
    if not args.no_coarsen and not bisect.has_coarsen():
        print(f"skipped: bisect coarsen (--indicator NAME --below X) is not available "
              f"in {bisect.binary}", file=sys.stderr)
        return SKIP
    os.makedirs(args.out, exist_ok=True)
    source = Source(start=(0.2, 0.25), end=(0.8, 0.75), sigma=args.sigma)
    below = args.tol / 8
    print(f"bisect: {bisect.binary}\nsource: Gaussian, sigma {args.sigma}, from "
          f"{tuple(source.start)} to {tuple(source.end)} in {args.steps} steps; "
          f"refine eta > {args.tol:g}, coarsen eta < {below:g}"
          + (" (coarsening off)" if args.no_coarsen else ""))
    points, cells = square_mesh(args.initial)
    cell_data = {}
    counts, other_seconds = [], 0.0
    print(f"{'step':>4} {'t':>6} {'after coarsen':>13} {'cells':>7} {'vertices':>8} "
          f"{'refines':>7} {'max eta':>9}")
    for step in range(args.steps):
        t = step / max(args.steps - 1, 1)
        f = lambda pts: source(pts, t)                       # noqa: E731
        after_coarsen = len(cells)
        if step > 0 and not args.no_coarsen:
            start = time.perf_counter()
            eta = interpolation_indicator(points, cells, f)
            other_seconds += time.perf_counter() - start
            points, cells, cell_data = bisect.coarsen(points, cells, cell_data, eta, below)
            after_coarsen = len(cells)
        refines = 0
        while True:
            start = time.perf_counter()
            eta = interpolation_indicator(points, cells, f)
            other_seconds += time.perf_counter() - start
            if eta.max() <= args.tol or refines == args.max_refine:
                break
            points, cells, cell_data = bisect.refine(points, cells, cell_data,
                                                     eta=eta, above=args.tol)
            refines += 1
        counts.append(len(cells))
        print(f"{step:4d} {t:6.3f} {after_coarsen:13d} {len(cells):7d} {len(points):8d} "
              f"{refines:7d} {eta.max():9.2e}")
        if step in (0, args.steps // 2, args.steps - 1):
            write_vtu(os.path.join(args.out, f"heat-step{step:02d}.vtu"), points, cells,
                      dict(cell_data, eta=eta, source=f(points[cells].mean(axis=1))))

    steady = np.array(counts[args.settle:], float)
    mean = steady.mean()
    spread = max(steady.max() / mean - 1, 1 - steady.min() / mean)
    bounded = spread <= 0.25
    print(f"cells over steps {args.settle}-{args.steps - 1}: min {int(steady.min())}, "
          f"max {int(steady.max())}, mean {mean:.0f}, largest deviation "
          f"{100 * spread:.1f}% of the mean: {'bounded' if bounded else 'NOT bounded'} "
          f"(within 25%)")
    print(f"time: bisect {bisect.seconds:.2f} s in {bisect.calls} calls, indicator "
          f"{other_seconds:.2f} s")
    return 0 if bounded or args.no_coarsen else 1


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BisectMissing as missing:
        print(f"skipped: {missing}", file=sys.stderr)
        sys.exit(SKIP)
