#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# The main job: meshes the sample CAD part shipped in resources/samples, writes an FEM mesh as
# .inp and .vtu into out/, prints the statistics and the comparison with TetGen.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$ROOT/scripts/setup.sh"
mkdir -p "$ROOT/out"
"$ROOT/bin/fembsptet" mesh "$ROOT/resources/samples/bracket.step" \
  --order 2 -o "$ROOT/out/bracket.inp" -o "$ROOT/out/bracket.vtu" --stats-json "$ROOT/out/bracket.stats.json" \
  --compare-tetgen
