#!/usr/bin/env bash
# Installs the Debian packages bisect builds and tests with. Idempotent: a
# no-op when everything is present. Runs as root (or through sudo).
set -euo pipefail
packages=(cmake g++ make libvtk9-dev libcli11-dev nlohmann-json3-dev catch2 libqhull-dev libmuparser-dev
          zlib1g-dev liblz4-dev liblzma-dev libdeflate-dev python3-meshio python3-vtk9
          python3-h5py xvfb xauth clang-format pybind11-dev python3-pybind11 python3-dev python3-numpy python3-pytest
          python3-scipy python3-matplotlib libopenmpi-dev openmpi-bin gmsh)
# gmsh: the tests read back what Gmsh writes of our .msh output (ASCII and
# binary 4.1, binary 2.2), and scripts/make_data.sh remakes data/ with it.
# scipy and matplotlib: examples/afem (tests/cli/afem.sh).
# libopenmpi-dev, openmpi-bin: the MPI build (-DBISECT_MPI=ON) and its tests (tests/mpi/).
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}" >&2
  SUDO=""
  [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
