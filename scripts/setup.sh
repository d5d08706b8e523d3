#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# Installs what is missing (Debian 12 packages only) and builds what is stale. Idempotent: a second
# run installs nothing and rebuilds only changed sources. Needs root or sudo for the install step.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${FEMBSPTET_BUILD_DIR:-$ROOT/build}

PACKAGES=(
  # build
  cmake g++ ninja-build pybind11-dev libgmp-dev python3-dev
  # tests
  libgtest-dev libgmock-dev python3-pytest
  # Python side
  python3-numpy python3-meshio python3-matplotlib python3-rich
  # FreeCAD FEM and the peers we compare with or solve with
  freecad-python3 gmsh python3-gmsh tetgen calculix-ccx python3-netgen
  # the CAD layer (cpp_module/src/cad): OpenCASCADE's headers and libraries
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev libocct-data-exchange-dev
  libtbb-dev  # named by OpenCASCADE's CMake targets
  # peak memory of each mesher's process in the comparison (GNU time)
  time
  # pieces meshed on a cluster (FemBspTet/fem/cluster.py): Dask distributed
  python3-distributed
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  if [ "$(id -u)" -eq 0 ]; then SUDO=(); elif command -v sudo >/dev/null; then SUDO=(sudo); else
    echo "setup: need root or sudo to install: ${missing[*]}" >&2; exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${SUDO[@]}" apt-get update -q
  "${SUDO[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
  cmake -S "$ROOT" -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
fi
cmake --build "$BUILD_DIR" --parallel "$(nproc)"
