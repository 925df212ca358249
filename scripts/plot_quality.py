#!/usr/bin/python3
"""Plots minimum (blue) and maximum (red) element quality per refinement
iteration from the CSV files `bisect refine --quality-csv` writes, one subplot
per CSV, in the style of the papers' quality figures.

Usage: plot_quality.py A.csv [B.csv ...] -o quality.png [--title T]
                       [--labels a,b,...]

Each CSV needs the columns iteration, min_quality and max_quality (the full
header is iteration,cells,vertices,selected,bisections,min_quality,
max_quality,mean_quality,seconds; row iteration 0 is the input mesh).
Run it with /usr/bin/python3 (Debian's python3-matplotlib).
"""
import argparse
import csv
import os
import sys

REQUIRED = ("iteration", "min_quality", "max_quality")


class CsvError(Exception):
    pass


def read_quality(path):
    """Returns (iterations, min_q, max_q) lists from one quality CSV."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise CsvError(f"{path}: cannot read: {e.strerror}")
    if not rows:
        raise CsvError(f"{path}: empty file (expected a header line)")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        raise CsvError(f"{path}:1: header lacks column(s) {', '.join(missing)}; "
                       f"found: {','.join(header)}")
    col = {c: header.index(c) for c in REQUIRED}
    its, lo, hi = [], [], []
    for line, row in enumerate(rows[1:], start=2):
        if not row or all(not x.strip() for x in row):
            continue
        try:
            its.append(int(row[col["iteration"]]))
            lo.append(float(row[col["min_quality"]]))
            hi.append(float(row[col["max_quality"]]))
        except (IndexError, ValueError):
            raise CsvError(f"{path}:{line}: bad row: {','.join(row)}")
    if not its:
        raise CsvError(f"{path}: no data rows after the header")
    return its, lo, hi


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv", nargs="+", help="quality CSV file(s)")
    ap.add_argument("-o", "--output", required=True, help="PNG file to write")
    ap.add_argument("--title", default=None, help="figure title")
    ap.add_argument("--labels", default=None,
                    help="comma-separated subplot titles (default: file names)")
    args = ap.parse_args()

    labels = [os.path.splitext(os.path.basename(p))[0] for p in args.csv]
    if args.labels is not None:
        given = args.labels.split(",")
        if len(given) != len(args.csv):
            sys.exit(f"plot_quality: --labels has {len(given)} names for "
                     f"{len(args.csv)} CSV files")
        labels = given

    try:
        data = [read_quality(p) for p in args.csv]
    except CsvError as e:
        sys.exit(f"plot_quality: {e}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    n = len(data)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.6), squeeze=False)
    for ax, (its, lo, hi), label in zip(axes[0], data, labels):
        ax.plot(its, hi, "r.-", label="max quality")
        ax.plot(its, lo, "b.-", label="min quality")
        ax.set_title(label)
        ax.set_xlabel("iteration")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_ylabel("quality")
        ax.set_ylim(0.0, 1.05)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize="small")
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    try:
        fig.savefig(args.output, dpi=120)
    except OSError as e:
        sys.exit(f"plot_quality: {args.output}: cannot write: {e.strerror}")
    print(f"plot_quality: wrote {args.output}")


if __name__ == "__main__":
    main()
