#!/usr/bin/env bash
# The main job on the bundled sample: installs, builds, then refines the
# unstructured ball of radius 2 (data/ball.msh) around seed 002's hemisphere
# (data/regions/hemisphere.json) for ITERATIONS (default 10) iterations.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# The command alone: the tests, benchmarks and Python module are the test
# command's (scripts/test.sh) to build.
BUILD_DIR=$root/build TARGETS=${TARGETS:-bisect} bash "$root/scripts/build.sh"
out=${OUT_DIR:-$root/out/sample}
mkdir -p "$out"
"$root/build/bisect" refine "$root/data/ball.msh" --region "$root/data/regions/hemisphere.json" \
  --iterations "${ITERATIONS:-10}" -o "$out/ball-refined.vtu" --quality-csv "$out/quality.csv" --force
"$root/build/bisect" check "$out/ball-refined.vtu" --against "$root/data/ball.msh"
echo "output: $out/ball-refined.vtu (open it in ParaView), quality per iteration: $out/quality.csv"
