#!/usr/bin/env bash
# The whole test suite on a fresh Debian 12 machine: installs the packages,
# builds, runs the unit tests under AddressSanitizer + UndefinedBehaviorSanitizer
# (skip with BISECT_NO_SANITIZE=1), then every test (unit and end-to-end CLI)
# on the release build with ctest; then the MPI build (build-mpi/) and its
# tests under mpirun.
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
(cd "$root/build" && ctest --output-on-failure -j "$(nproc)")
# The MPI variant (README, "MPI"): bisect built with -DBISECT_MPI=ON in
# build-mpi/, and its tests under mpirun (tests/mpi/).
cmake -S "$root" -B "$root/build-mpi" -DCMAKE_BUILD_TYPE=Release -DBISECT_MPI=ON -DBISECT_TESTS=OFF \
  -DBISECT_PYTHON=OFF >/dev/null
cmake --build "$root/build-mpi" -j "$(nproc)" --target bisect bisect_mpi_hooked
cd "$root/build-mpi" && ctest --output-on-failure -R '^mpi\.'

