#!/usr/bin/env bash
# End-to-end benchmark: `bisect refine` as a user runs it (one process: read,
# validate, select, refine, quality, final check, write .vtu), per stage,
# from its --json. Prints one JSON object per case and thread count on
# stdout, with the machine's load.
#
#   bash bench/e2e.sh                 # 3D ball 12 iterations (then 1 more from its file),
#                                     # 4D hypercube 25; 1 and all threads
#   ITER3D=14 ITER4D=25 bash bench/e2e.sh
#   BIG=1 bash bench/e2e.sh           # also issue 13's case: a 56,635-tet ball, 14 iterations (~3 GB)
#   SIZES=1 bash bench/e2e.sh         # also issue 13's own input (Gmsh's 49,090-tet ball, made by
#                                     # gmsh from data/ball.geo at size 0.148) at 12, 13, 14 and 15
#                                     # iterations (10.8, 18.3, 31.1 and 52.1 M tets; 2.5 GB at 15):
#                                     # seconds per million generated cells by size
#   THREADS="1 2" BISECT=build/bisect OUT=/tmp/bench bash bench/e2e.sh
#   REPEAT=3 SIZES=1 SIZE_ITERATIONS=14 bash bench/e2e.sh
#                                     # each case 3 times, the thread counts alternated;
#                                     # the run of median time is printed, with all the
#                                     # times ("seconds_all")
#
# The first line describes the machine (bench/machine.cpp; MACHINE=path to
# its binary, default beside BISECT).
#
# Figures: generated cells per second (cells made / whole run), seconds per
# million generated cells, and peak resident bytes per final cell; for a
# thread count other than 1, "speedup_over_1_thread" (one thread's median
# time over this one's) when 1 ran first. A
# baseline to compare with is kept in bench/baseline-e2e.jsonl (BIG=1, made
# 2026-12-02 16:35 UTC on a 2-core machine, load about 1.6 from the
# benchmark itself; bash bench/e2e.sh > new.jsonl, then /usr/bin/python3
# bench/compare.py bench/baseline-e2e.jsonl new.jsonl; the cases missing
# from one side are left out). The big case's input is data/ball.msh
# (6,009 tets, size 0.3) refined everywhere for 2 iterations (56,635 tets):
# close to issue 13's Gmsh ball of 49,090 tets (-clmax 0.148), without Gmsh.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BISECT=${BISECT:-$root/build/bisect}
OUT=${OUT:-$(mktemp -d)}
ITER3D=${ITER3D:-12}
ITER4D=${ITER4D:-25}
THREADS=${THREADS:-"1 $(nproc)"}
BIG=${BIG:-0}
SIZES=${SIZES:-0}
SIZE_ITERATIONS=${SIZE_ITERATIONS:-"12 13 14 15"}
REPEAT=${REPEAT:-1}
mkdir -p "$OUT"
load=$(cut -d' ' -f1-3 /proc/loadavg)
cpus=$(nproc)

run_case() { # name input region iterations extra...
  local name=$1 input=$2 region=$3 n=$4
  shift 4
  local runs="$OUT/.$name.runs.jsonl" threads r
  rm -f "$runs"
  # REPEAT rounds, each running every thread count once, so that a drift of
  # the machine's speed falls on all of them alike.
  for ((r = 1; r <= REPEAT; r++)); do
    for threads in $THREADS; do
      load=$(cut -d' ' -f1-3 /proc/loadavg)
      "$BISECT" refine "$input" --region "$region" -n "$n" -o "$OUT/$name.vtu" -f -q --json \
        --threads "$threads" "$@" |
        /usr/bin/python3 -c 'import json, sys; j = json.load(sys.stdin); j["threads"] = int(sys.argv[1]); j["load_before"] = sys.argv[2]; print(json.dumps(j))' \
          "$threads" "$load" >>"$runs"
    done
  done
  /usr/bin/python3 - "$name" "$cpus" "$runs" <<'EOF'
import json, sys
name, cpus = sys.argv[1], int(sys.argv[2])
runs = [json.loads(line) for line in open(sys.argv[3])]
by_threads = {}
for j in runs:
    by_threads.setdefault(j["threads"], []).append(j)
medians = {}
for threads, js in by_threads.items():
    # The run of median time (of an even count, the faster middle one)
    # stands for its thread count, with its stages and peak; with several
    # runs, all their times are given beside it.
    js.sort(key=lambda j: j["seconds"])
    j = js[(len(js) - 1) // 2]
    medians[threads] = j["seconds"]
    made = j["cells"] - j["initial_cells"]
    out = {
        "case": f"{name}-t{threads}", "threads": threads, "dim": j["dim"],
        "iterations": j["iterations"],
        "initial_cells": j["initial_cells"], "cells": j["cells"],
        "seconds": round(j["seconds"], 3),
        "stages": {k: round(v, 3) for k, v in j["stages"].items()},
        "generated_cells_per_second": round(made / j["seconds"]),
        "seconds_per_million_generated": round(j["seconds"] / made * 1e6, 3),
        "peak_bytes_per_cell": round(j["peak_rss_bytes"] / j["cells"], 1),
        "load_before": j["load_before"], "cpus": cpus,
    }
    if len(js) > 1:
        out["runs"] = len(js)
        out["seconds_all"] = [round(x["seconds"], 3) for x in js]
    if threads != 1 and 1 in medians:
        out["speedup_over_1_thread"] = round(medians[1] / j["seconds"], 3)
    print(json.dumps(out))
EOF
  rm -f "$runs"
}

# The machine first (bench/machine.cpp): its memory's first-touch rate,
# bandwidth and latency and its core's speed, for setting these figures
# beside those of another machine.
machine=${MACHINE:-$(dirname "$BISECT")/bisect_machine}
if [[ -x $machine ]]; then
  "$machine" | /usr/bin/python3 -c 'import json, sys; j = json.loads(sys.stdin.read()); j.pop("check"); j["load_before"] = sys.argv[1]; j["cpus"] = int(sys.argv[2]); print(json.dumps(j))' \
    "$(cut -d' ' -f1-3 /proc/loadavg)" "$cpus"
else
  echo "bench/e2e.sh: no $machine (cmake --build build --target bisect_machine): no machine figures" >&2
fi

run_case ball-hemisphere "$root/data/ball.msh" "$root/data/regions/hemisphere.json" "$ITER3D"
# An adaptive loop's next step: that refined file, with its bisection state,
# read, validated and refined one iteration more (its read and validate
# stages are those of a refined file of the size above).
run_case ball-hemisphere-continued "$OUT/ball-hemisphere.vtu" "$root/data/regions/hemisphere.json" 1
if [[ $BIG == 1 ]]; then
  "$BISECT" refine "$root/data/ball.msh" --region "$root/data/regions/everything3d.json" -n 2 \
    -o "$OUT/ball-57k.vtu" -f -q --quality-csv none
  run_case ball57k-hemisphere "$OUT/ball-57k.vtu" "$root/data/regions/hemisphere.json" 14
fi
if [[ $SIZES == 1 ]]; then
  command -v gmsh >/dev/null || {
    echo "bench/e2e.sh: SIZES=1 needs gmsh (scripts/install-deps.sh installs it)" >&2
    exit 2
  }
  sed 's/= 0\.3;/= 0.148;/' "$root/data/ball.geo" >"$OUT/ball148.geo"
  grep -q 'MeshSizeMax = 0.148;' "$OUT/ball148.geo" || {
    echo "bench/e2e.sh: data/ball.geo no longer sets its size as '= 0.3;'; SIZES=1 cannot make the 0.148 ball" >&2
    exit 2
  }
  gmsh "$OUT/ball148.geo" -3 -format msh41 -o "$OUT/ball148.msh" >/dev/null
  for n in $SIZE_ITERATIONS; do
    run_case "ball49k-hemisphere-n$n" "$OUT/ball148.msh" "$root/data/regions/hemisphere.json" "$n"
  done
fi
"$BISECT" generate kuhn --dim 4 --cells 1 -o "$OUT/hypercube.vtu" -f 2>/dev/null
run_case hypercube-moving-sphere "$OUT/hypercube.vtu" "$root/data/regions/moving-sphere.json" \
  "$ITER4D" -m longest
