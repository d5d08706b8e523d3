#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# The FreeCAD tests with FreeCAD 1.0 (Debian 13, Python 3.13, OpenCASCADE 7.8), inside the chroot
# scripts/freecad1_chroot.sh makes or reuses (and where it builds the extension), with FreeCAD
# 1.0's Python: the FreeCAD object, export, named sets, the addon, CalculiX acceptance, the
# offscreen GUI, and the CAD layer on OpenCASCADE 7.8. Arguments go to pytest (e.g. -x, -k NAME, or test files instead of the default
# list). Needs root. The chroot script prints the seconds spent so far before each step.
set -uo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

TESTS=(
  tests/test_mesher_object.py
  tests/test_mesher_properties.py
  tests/test_freecad_export.py
  tests/test_named_sets.py
  tests/test_addon_install.py
  tests/test_calculix_acceptance.py
  tests/test_gui_offscreen.py
  # FreeCAD's tessellation and OpenCASCADE 7.8 under the CAD layer
  tests/test_cad_tessellation.py
  tests/test_tessellation_fins.py
  tests/test_calculix_cad_parts.py
  tests/test_fem_pipeline_binding.py
  tests/test_cad_check.py
)
args=("$@")
if ! printf '%s\n' "${args[@]}" | grep -q '^tests/'; then
  args=("${TESTS[@]}" "${args[@]}")
fi

echo "== FreeCAD 1.0 (Debian 13 chroot): FreeCAD tests =="
exec "$ROOT/scripts/freecad1_chroot.sh" -- \
  /usr/bin/python3 -m pytest -q -p no:cacheprovider -W "ignore:Type PySide2:DeprecationWarning" \
  "${args[@]}"
