#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# Runs every test: sets up first (installs what is missing, builds what is stale), then the C++
# suite through CTest (labels `unit` and `corpus`), then the Python suite through pytest.
set -uo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD_DIR=${FEMBSPTET_BUILD_DIR:-$ROOT/build}
"$ROOT/scripts/setup.sh" || exit 1

status=0
echo "== C++ tests (CTest) =="
ctest --test-dir "$BUILD_DIR" --output-on-failure --timeout 1800 -j "$(nproc)" || status=1
echo "== Python tests (pytest) =="
cd "$ROOT" && /usr/bin/python3 -m pytest -q -p no:cacheprovider tests "$@" || status=1
exit $status
