#!/usr/bin/env bash
# Installs what is missing, then configures and builds into build/ (Release).
# Usage: scripts/build.sh [extra cmake args...]; BUILD_DIR overrides build/,
# JOBS the parallel jobs (default: all cores), TARGETS the targets (default:
# all; e.g. TARGETS=bisect builds the command alone, about half the time).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
build=${BUILD_DIR:-$root/build}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
targets=()
for t in ${TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$build" -j "${JOBS:-$(nproc)}" "${targets[@]}"
