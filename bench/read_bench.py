#!/usr/bin/python3
"""Benchmark (not a test): reading and validating a mesh with `bisect info`,
against a reference reader on the same file, in the same run.

    /usr/bin/python3 bench/read_bench.py FILE [REPEATS=3]
    BISECT=build/bisect /usr/bin/python3 bench/read_bench.py big.msh 5

`bisect info FILE` runs as a process (read, validate, restore the state,
then the invariants and quality it prints), timed by its wall clock and its
user + system CPU (wait4). The reference reads the file in this process:
for .vtu VTK's own vtkXMLUnstructuredGridReader (python3-vtk9), for .msh
meshio.read (the reference is named in the output). Each runs REPEATS
times, alternating, after one untimed warm-up read of the file (page
cache); the best time of each is compared. One JSON object on stdout, with
the machine's load before the run: on a shared machine compare ratios, not
seconds, and prefer cpu_ratio (CPU seconds of `bisect info` over those of
the reference read), which a busy machine disturbs least. A shared machine
also drifts in speed from one minute to the next (on 2026-12-04 VTK's read
of one file took 1.59 to 2.83 s within one run), so the best times of the
two may come from different moments: paired_ratios divides each `bisect
info` time by the reference read right after it, and paired_ratio_median
is their median.

VTK cannot read .msh. For FILE.msh with a FILE.vtu beside it (the same
mesh, e.g. written by `bisect refine ... -o FILE.vtu` and `-o FILE.msh`),
VTK's reader of that .vtu is timed too, in the same loop, and the JSON adds
vtu_twin, vtk_twin_seconds (best) and ratio_to_vtk_twin (bisect's best time
on the .msh over VTK's best on the .vtu).
"""
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run_bisect(bisect, path):
    t0 = time.perf_counter()
    proc = subprocess.Popen([bisect, "info", "-q", "--json", path], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    out, err = proc.communicate()
    wall = time.perf_counter() - t0
    # communicate() has reaped the child; its CPU is in RUSAGE_CHILDREN.
    if proc.returncode != 0:
        sys.exit("bisect info failed: " + err.decode(errors="replace").strip())
    return wall, json.loads(out)


def children_cpu():
    import resource
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def vtk_reader(path):
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

    def read():
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(path)
        reader.Update()
        return reader.GetOutput().GetNumberOfCells()

    return read


def reference_reader(path):
    if path.lower().endswith(".vtu"):
        from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

        def read():
            reader = vtkXMLUnstructuredGridReader()
            reader.SetFileName(path)
            reader.Update()
            return reader.GetOutput().GetNumberOfCells()

        return "vtkXMLUnstructuredGridReader (VTK %s)" % vtk_version(), read
    import meshio

    def read():
        m = meshio.read(path)
        rank = {"triangle": 2, "tetra": 3}  # count the cells bisect reads
        top = max((rank.get(b.type, 0) for b in m.cells), default=0)
        return sum(len(b.data) for b in m.cells if rank.get(b.type, 0) == top)

    return "meshio.read (meshio %s)" % meshio.__version__, read


def vtk_version():
    from vtkmodules.vtkCommonCore import vtkVersion
    return vtkVersion.GetVTKVersion()


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    path = sys.argv[1]
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    bisect = os.environ.get("BISECT", str(ROOT / "build" / "bisect"))
    load = open("/proc/loadavg").read().split()[:3]
    name, ref_read = reference_reader(path)
    Path(path).read_bytes()  # warm the page cache
    twin = None
    if path.lower().endswith(".msh") and Path(path[:-4] + ".vtu").is_file():
        twin = path[:-4] + ".vtu"
        twin_read = vtk_reader(twin)
        Path(twin).read_bytes()
    twin_times = []
    ours_wall, ours_cpu, ref, ref_cpu = [], [], [], []
    info = None
    for _ in range(repeats):
        if twin:
            t0 = time.perf_counter()
            twin_read()
            twin_times.append(time.perf_counter() - t0)
        cpu0 = children_cpu()
        wall, info = run_bisect(bisect, path)
        ours_wall.append(wall)
        ours_cpu.append(children_cpu() - cpu0)
        t0, c0 = time.perf_counter(), time.process_time()
        ref_cells = ref_read()
        ref.append(time.perf_counter() - t0)
        ref_cpu.append(time.process_time() - c0)
    cells = info["cells"]
    best_ours, best_ref = min(ours_wall), min(ref)
    extra = {}
    if twin:
        extra = {"vtu_twin": twin, "vtk_twin_seconds": round(min(twin_times), 3),
                 "all_vtk_twin_seconds": [round(t, 3) for t in twin_times],
                 "ratio_to_vtk_twin": round(best_ours / min(twin_times), 2)}
    print(json.dumps({
        "file": path, "bytes": os.path.getsize(path), "cells": cells,
        "reference": name, "reference_cells": ref_cells, "repeats": repeats,
        "bisect_info_seconds": round(best_ours, 3),
        "bisect_info_cpu_seconds": round(min(ours_cpu), 3),
        "reference_seconds": round(best_ref, 3),
        "reference_cpu_seconds": round(min(ref_cpu), 3),
        "ratio": round(best_ours / best_ref, 2),
        "paired_ratios": [round(o / r, 2) for o, r in zip(ours_wall, ref)],
        "paired_ratio_median": round(statistics.median(o / r for o, r in zip(ours_wall, ref)), 2),
        "cpu_ratio": round(min(ours_cpu) / min(ref_cpu), 2),
        "bisect_seconds_per_million_cells": round(best_ours / cells * 1e6, 3),
        "reference_seconds_per_million_cells": round(best_ref / cells * 1e6, 3),
        "all_bisect_seconds": [round(t, 3) for t in ours_wall],
        "all_reference_seconds": [round(t, 3) for t in ref],
        "load_before": " ".join(load), "cpus": os.cpu_count(), **extra,
    }))


if __name__ == "__main__":
    main()
