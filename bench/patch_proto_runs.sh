#!/bin/sh
# Alternated timing runs of patch_proto (issue 13): ours, proto, 3 times each.
# Usage: bench/patch_proto_runs.sh [K=30 or MESH.msh] [iterations=8] [radius=0.3] [band=0.002]
set -e
cd "$(dirname "$0")/.."
K=${1:-30}; IT=${2:-8}; R=${3:-0.3}; B=${4:-0.002}
export OMP_NUM_THREADS=1
for run in 1 2 3; do
  for impl in ours proto; do
    echo "=== run $run $impl  $(uptime)"
    nice -n 10 ./build/patch_proto $impl $K $IT $R $B
  done
done
