#!/usr/bin/env bash
# The whole test suite on a fresh Debian 12 machine: installs the packages,
# builds, runs every test (unit, CLI end-to-end) with ctest; then the same
# unit tests again under AddressSanitizer + UndefinedBehaviorSanitizer
# (skip that second run with BISECT_NO_SANITIZE=1).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD_DIR=$root/build bash "$root/scripts/build.sh"
(cd "$root/build" && ctest --output-on-failure -j "$(nproc)")
if [[ "${BISECT_NO_SANITIZE:-0}" != 1 ]]; then
  BUILD_DIR=$root/build-sanitize bash "$root/scripts/build.sh" -DBISECT_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
  (cd "$root/build-sanitize" && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
     ctest --output-on-failure -j "$(nproc)" -L sanitize)
fi
