#!/usr/bin/env bash
# Builds the Python module pybisect and installs it for /usr/bin/python3:
# the module into the interpreter's site directory (sysconfig platlib, on
# Debian /usr/local/lib/python3.X/dist-packages), the bisect libraries it
# links beside it in pybisect.libs/ (found through RPATH $ORIGIN, no
# ldconfig). Afterwards `/usr/bin/python3 -c 'import pybisect'` works from any
# directory. Installs the Debian packages first (scripts/install-deps.sh and
# the Python ones below). Runs as root (or with sudo).
# Usage: scripts/install-python.sh [extra cmake args...]; BUILD_DIR overrides
# build/, JOBS the parallel jobs (2), PYBISECT_INSTALL_DIR the destination.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
python=/usr/bin/python3
SUDO=""
[[ $(id -u) -ne 0 ]] && SUDO="sudo"

bash "$root/scripts/install-deps.sh"
packages=(pybind11-dev python3-pybind11 python3-dev python3-numpy python3-pytest python3-meshio)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "install-python: installing ${missing[*]}" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

dest=${PYBISECT_INSTALL_DIR:-$("$python" -c 'import sysconfig; print(sysconfig.get_path("platlib"))')}
build=${BUILD_DIR:-$root/build}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DBISECT_PYTHON=ON \
      -DPYTHON_EXECUTABLE="$python" -DPYBISECT_INSTALL_DIR="$dest" "$@" >/dev/null
cmake --build "$build" --target pybisect -j "${JOBS:-2}"
$SUDO cmake --install "$build" --component python

# The check: the installed module (not a build tree's), from another directory.
cd /
PYTHONPATH="$dest" "$python" - "$dest" <<'PY'
import os, sys, pybisect
where = os.path.realpath(pybisect.__file__)
assert where.startswith(os.path.realpath(sys.argv[1]) + os.sep), where
print("install-python: installed", where)
PY
