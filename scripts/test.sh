#!/usr/bin/env bash
# The whole test suite on a fresh Debian 12 machine: installs the packages,
# builds, runs the unit tests under AddressSanitizer + UndefinedBehaviorSanitizer
# (skip with BISECT_NO_SANITIZE=1), then every test (unit and end-to-end CLI)
# on the release build with ctest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
BUILD_DIR=$root/build bash "$root/scripts/build.sh"
if [[ "${BISECT_NO_SANITIZE:-0}" != 1 ]]; then
  cmake -S "$root" -B "$root/build-sanitize" -DBISECT_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" >/dev/null
  cmake --build "$root/build-sanitize" -j "$(nproc)" --target bisect_tests
  echo "Unit tests under AddressSanitizer + UndefinedBehaviorSanitizer:"
  (cd "$root/build-sanitize" && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
     UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ./bisect_tests "~[slow]")
fi
cd "$root/build" && ctest --output-on-failure -j "$(nproc)"
