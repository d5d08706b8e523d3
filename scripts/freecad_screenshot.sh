#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# The README's picture of FemBspTet in FreeCAD: a CAD part meshed from the task panel, the mesh
# in the 3D view beside the panel, taken in FreeCAD's real GUI under Xvfb (a throw-away HOME
# with this checkout as a Mod, so no user configuration is touched or used).
#
#   scripts/freecad_screenshot.sh [PART] [OUT.png]
#
# Defaults: resources/samples/bracket.step, docs/images/freecad_bracket.png. Needs FreeCAD
# (scripts/setup.sh) and Xvfb (Debian package xvfb; installed here when missing, as root).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
PART=$(realpath "${1:-$ROOT/resources/samples/bracket.step}")
OUT=$(realpath -m "${2:-$ROOT/docs/images/freecad_bracket.png}")

if ! command -v xvfb-run >/dev/null; then
  if [ "$(id -u)" -eq 0 ]; then SUDO=(); elif command -v sudo >/dev/null; then SUDO=(sudo); else
    echo "freecad_screenshot: needs xvfb-run (Debian package xvfb)" >&2; exit 1
  fi
  DEBIAN_FRONTEND=noninteractive "${SUDO[@]}" apt-get install -y -q --no-install-recommends xvfb xauth
fi

HOME_DIR=$(mktemp -d)
trap 'rm -rf "$HOME_DIR"' EXIT
mkdir -p "$HOME_DIR/.local/share/FreeCAD/Mod"
ln -s "$ROOT" "$HOME_DIR/.local/share/FreeCAD/Mod/FemBspTet"
# Start in the Part workbench (the Start page's web view is not wanted), no notifications.
HOME=$HOME_DIR freecadcmd -c "import FreeCAD
FreeCAD.ParamGet('User parameter:BaseApp/Preferences/General').SetString('AutoloadModule', 'PartWorkbench')
g = FreeCAD.ParamGet('User parameter:BaseApp/Preferences/NotificationArea')
g.SetBool('NotificationAreaEnabled', False)
g.SetBool('NonIntrusiveNotificationsEnabled', False)" >/dev/null
mkdir -p "$(dirname "$OUT")"
TMP_OUT="$OUT.tmp.png"
HOME=$HOME_DIR FEMBSPTET_SHOT_PART=$PART FEMBSPTET_SHOT_OUT=$TMP_OUT \
  xvfb-run -a -s "-screen 0 1440x900x24" freecad "$ROOT/scripts/freecad_screenshot_session.py"
[ -s "$TMP_OUT" ] || { echo "freecad_screenshot: no picture was made" >&2; exit 1; }
mv "$TMP_OUT" "$OUT"
echo "freecad_screenshot: $OUT"
