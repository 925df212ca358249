#!/usr/bin/env bash
# Installs what is missing, then configures and builds into build/ (Release).
# Usage: scripts/build.sh [extra cmake args...]; BUILD_DIR overrides build/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/install-deps.sh"
build=${BUILD_DIR:-$root/build}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build" -j "$(nproc)"
