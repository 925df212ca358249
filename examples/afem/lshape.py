#!/usr/bin/python3
"""Adaptive P1 finite elements for the Laplace equation on the L-shaped domain
(-1,1)^2 minus [0,1)x(-1,0], with the exact solution u = r^(2/3) sin(2 theta/3)
(theta in [0, 3 pi/2], measured counter-clockwise from the positive x axis) as
Dirichlet data. The loop SOLVE -> ESTIMATE -> MARK -> REFINE runs through
files: bisect refines the mesh (Doerfler marking on the residual estimator),
and the same number of loops is run with uniform refinement for comparison.

    /usr/bin/python3 examples/afem/lshape.py --loops 16 --out afem-out/

prints a table per run (loop, free vertices, H1 error, estimator), the
fitted slopes of log(error) against log(free vertices) over the later half of
the loops, the time spent in bisect and in the solver, and writes
afem-out/lshape-convergence.png.
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import p1  # noqa: E402
from bisect_cli import BisectCLI, default_binary, write_vtu  # noqa: E402


def angle(x, y):
    """theta in [0, 2 pi): 0 on the positive x axis, 3 pi/2 on the negative y axis."""
    return np.mod(np.arctan2(y, x), 2 * np.pi)


def exact(pts):
    r = np.hypot(pts[:, 0], pts[:, 1])
    return r ** (2 / 3) * np.sin(2 / 3 * angle(pts[:, 0], pts[:, 1]))


def exact_gradient(pts):
    # grad u = 2/3 r^(-1/3) (-sin(theta/3), cos(theta/3))
    r = np.hypot(pts[:, 0], pts[:, 1])
    t = angle(pts[:, 0], pts[:, 1]) / 3
    return (2 / 3) * r[:, None] ** (-1 / 3) * np.column_stack([-np.sin(t), np.cos(t)])


def lshape_mesh(n=1):
    """The L-shape from three unit squares, each cut into n x n squares of two
    triangles (diagonals from lower left to upper right)."""
    k = 2 * n + 1
    x = np.linspace(-1, 1, k)
    X, Y = np.meshgrid(x, x, indexing="xy")
    points = np.column_stack([X.ravel(), Y.ravel()])
    vid = np.arange(k * k).reshape(k, k)               # vid[row j (y), column i (x)]
    cells = []
    for j in range(k - 1):
        for i in range(k - 1):
            if i >= n and j < n:                          # the removed lower-right square
                continue
            a, b, c, d = vid[j, i], vid[j, i + 1], vid[j + 1, i + 1], vid[j + 1, i]
            cells += [[a, b, c], [a, c, d]]
    cells = np.array(cells)
    used = np.unique(cells)
    renumber = np.full(k * k, -1)
    renumber[used] = np.arange(len(used))
    return points[used], renumber[cells]


def run(bisect, loops, adaptive, theta, n0, max_cells, out=None):
    """The AFEM loop; returns rows (loop, cells, free vertices, all vertices,
    H1 error, estimator) and the seconds spent solving/estimating."""
    points, cells = lshape_mesh(n0)
    cell_data = {}
    rows, solver_seconds = [], 0.0
    for loop in range(loops):
        start = time.perf_counter()
        u, free = p1.solve_dirichlet(points, cells, exact)              # SOLVE
        eta = p1.residual_estimator(points, cells, u)                  # ESTIMATE
        error = p1.h1_error(points, cells, u, exact_gradient)
        solver_seconds += time.perf_counter() - start
        rows.append((loop, len(cells), int(free.sum()), len(points), error,
                     np.sqrt(np.sum(eta ** 2))))
        capped = loop < loops - 1 and len(cells) * 3 > max_cells   # uniform: x2.1-2.6
        if capped:
            print(f"({'adaptive' if adaptive else 'uniform'} run stopped after loop "
                  f"{loop}: the next mesh could exceed --max-cells {max_cells})")
        if loop == loops - 1 or capped:
            if out:
                name = "adaptive" if adaptive else "uniform"
                write_vtu(os.path.join(out, f"lshape-{name}-final.vtu"), points, cells,
                          dict(cell_data, eta=eta))
            break
        # MARK and REFINE (bisect marks: Doerfler on eta; uniform: everything).
        points, cells, cell_data = bisect.refine(
            points, cells, cell_data, eta=eta if adaptive else None, theta=theta)
    return rows, solver_seconds


def report(title, rows):
    print(f"\n{title}")
    print(f"{'loop':>4} {'cells':>8} {'free v.':>8} {'all v.':>8} {'H1 error':>12} "
          f"{'estimator':>12} {'eff.':>6}")
    for loop, ncells, free, nverts, err, est in rows:
        print(f"{loop:4d} {ncells:8d} {free:8d} {nverts:8d} {err:12.4e} {est:12.4e} "
              f"{est / err:6.2f}")
    half = [r for r in rows[len(rows) // 2:] if r[2] > 0]
    free = np.array([r[2] for r in half], float)
    slope_err = p1.fitted_slope(free, [r[4] for r in half])
    slope_est = p1.fitted_slope(free, [r[5] for r in half])
    print(f"fitted slope over loops {half[0][0]}-{half[-1][0]} (log-log against free "
          f"vertices): H1 error {slope_err:+.3f}, estimator {slope_est:+.3f}")
    return slope_err


def plot(path, adaptive_rows, uniform_rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5))
    adaptive_rows = [r for r in adaptive_rows if r[2] > 0]   # log scale: no 0 unknowns
    uniform_rows = [r for r in uniform_rows if r[2] > 0]
    for rows, label, mark, colour in [(adaptive_rows, "adaptive (Dörfler)", "o", "C0"),
                                      (uniform_rows, "uniform", "s", "C3")]:
        n = np.array([r[2] for r in rows], float)
        ax.loglog(n, [r[4] for r in rows], mark + "-", color=colour,
                  label=f"{label}: H¹ error")
        ax.loglog(n, [r[5] for r in rows], mark + "--", color=colour, mfc="none",
                  alpha=0.6, label=f"{label}: estimator")
    n_all = np.array([r[2] for r in adaptive_rows + uniform_rows], float)
    e_all = np.array([r[4] for r in adaptive_rows + uniform_rows])
    lo, hi = n_all.min(), n_all.max()
    anchor = 0.5 * e_all.max()
    for slope, style, label in [(-0.5, "k-.", "slope -1/2"), (-1 / 3, "k:", "slope -1/3")]:
        ax.loglog([lo, hi], [anchor, anchor * (hi / lo) ** slope], style, lw=1,
                  label=label)
    ax.set_xlabel("free vertices (unknowns)")
    ax.set_ylabel("|u - u_h|_H¹ and estimator")
    ax.set_title("P1 on the L-shape, u = r^(2/3) sin(2θ/3)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bisect", default=default_binary(),
                        help="the bisect binary (default: build/bisect of this repository)")
    parser.add_argument("--loops", type=int, default=16, help="adaptive loops (default 16)")
    parser.add_argument("--uniform-loops", type=int, default=None,
                        help="uniform loops (default: as many as --loops, up to --max-cells)")
    parser.add_argument("--theta", type=float, default=0.5, help="Doerfler parameter (0.5)")
    parser.add_argument("--initial", type=int, default=2,
                        help="each unit square of the initial mesh is n x n squares "
                             "of two triangles (2: 24 triangles)")
    parser.add_argument("--max-cells", type=int, default=400000,
                        help="stop a run before a refinement would make more cells (4e5)")
    parser.add_argument("--small", action="store_true",
                        help="a quick run: 8 loops each (for tests)")
    parser.add_argument("--out", default="afem-out", help="output directory (afem-out)")
    parser.add_argument("--keep-files", action="store_true",
                        help="keep every mesh passed to and from bisect in OUT/files")
    args = parser.parse_args(argv)
    if args.small:
        args.loops = 8
    uniform_loops = args.uniform_loops or args.loops
    os.makedirs(args.out, exist_ok=True)
    workdir = os.path.join(args.out, "files") if args.keep_files else None
    try:
        bisect = BisectCLI(args.bisect, workdir=workdir, keep_files=args.keep_files)
    except FileNotFoundError as missing:
        print(f"error: {missing} (build it, or pass --bisect PATH)", file=sys.stderr)
        return 1
    how = ("bisect refine --indicator eta --dorfler" if bisect.has_indicator_refine()
           else "marked here, handed to bisect refine as a region (this bisect has "
                "no --indicator yet)")
    print(f"bisect: {bisect.binary}\nmarking: Doerfler theta = {args.theta}, {how}")
    print("unknowns = free (interior) vertices; estimator = sqrt(sum eta_T^2), "
          "jump terms only (f = 0, no Dirichlet oscillation term)")

    t0 = time.perf_counter()
    adaptive, solve_a = run(bisect, args.loops, True, args.theta, args.initial,
                            args.max_cells, args.out)
    bisect_a, calls_a = bisect.seconds, bisect.calls
    uniform, solve_u = run(bisect, uniform_loops, False, args.theta, args.initial,
                           args.max_cells, args.out)
    bisect_u, calls_u = bisect.seconds - bisect_a, bisect.calls - calls_a
    slope_a = report("adaptive", adaptive)
    slope_u = report("uniform", uniform)
    png = os.path.join(args.out, "lshape-convergence.png")
    plot(png, adaptive, uniform)
    print(f"\nslopes: adaptive {slope_a:+.3f} (expected about -0.5), "
          f"uniform {slope_u:+.3f} (expected about -0.33)")
    print(f"time: adaptive bisect {bisect_a:.2f} s in {calls_a} calls, solver "
          f"{solve_a:.2f} s; uniform bisect {bisect_u:.2f} s in {calls_u} calls, "
          f"solver {solve_u:.2f} s; total {time.perf_counter() - t0:.2f} s")
    print("(bisect time: writing the .vtu, running bisect, reading the result; "
          "solver time: assembly, solve, estimator and H1 error)")
    print(f"plot: {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
