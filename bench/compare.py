#!/usr/bin/env python3
"""Compares two runs of bench/e2e.sh (JSON lines): per case, whole-run time,
seconds per million generated cells and peak bytes per cell, new / old."""
import json
import sys


def load(path):
    with open(path) as f:
        return {d["case"]: d for d in map(json.loads, filter(str.strip, f))}


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: compare.py OLD.jsonl NEW.jsonl")
    old, new = load(sys.argv[1]), load(sys.argv[2])
    keys = ["seconds", "seconds_per_million_generated", "peak_bytes_per_cell"]
    print(f"{'case':28s} " + " ".join(f"{k:>32s}" for k in keys))
    for case in sorted(set(old) & set(new)):
        cells = []
        for k in keys:
            a, b = old[case][k], new[case][k]
            cells.append(f"{a:>10.3f} -> {b:>10.3f} ({b / a:5.2f}x)")
        print(f"{case:28s} " + " ".join(f"{c:>32s}" for c in cells))
        stages = sorted(set(old[case]["stages"]) | set(new[case]["stages"]))
        print("  stages (s): " + ", ".join(
            f"{s} {old[case]['stages'].get(s, 0):.2f}->{new[case]['stages'].get(s, 0):.2f}"
            for s in stages))


if __name__ == "__main__":
    main()
