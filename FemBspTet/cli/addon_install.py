# SPDX-License-Identifier: LGPL-2.1-or-later
"""Links the addon into FreeCAD's user Mod folders (``fembsptet freecad-install``).

FreeCAD loads every folder of ``<user data>/Mod`` at start-up. The user data folder is
``$XDG_DATA_HOME/FreeCAD`` (``~/.local/share/FreeCAD``) for FreeCAD 0.20 to 1.0; FreeCAD 1.1
and later use a folder per version inside it (``v1-1``), made on that version's first start.
The link ``Mod/FemBspTet`` points at the addon folder: the checkout, or the installed
``PREFIX/share/fembsptet/FemBspTet`` (CMakeLists.txt's install rules), so FreeCAD runs the same
code as the ``fembsptet`` command.
"""

import glob
import os

from ..kernel.errors import InputError
from ..kernel.paths import ADDON_DIR

LINK_NAME = "FemBspTet"


def freecad_data_dir():
    base = os.environ.get("XDG_DATA_HOME") or os.path.join(os.path.expanduser("~"), ".local",
                                                           "share")
    return os.path.join(base, "FreeCAD")


def default_mod_dirs():
    """``<data>/Mod`` (FreeCAD 0.20 to 1.0) and ``<data>/v<X>-<Y>/Mod`` for every versioned
    folder FreeCAD 1.1+ has made."""
    data = freecad_data_dir()
    versioned = sorted(d for d in glob.glob(os.path.join(data, "v[0-9]*-[0-9]*"))
                       if os.path.isdir(d))
    return [os.path.join(data, "Mod")] + [os.path.join(d, "Mod") for d in versioned]


def install(mod_dirs=None, uninstall=False):
    """Makes (or with ``uninstall`` removes) ``<mod dir>/FemBspTet`` -> :data:`ADDON_DIR` in each
    folder. Returns one line per folder saying what was done. A ``FemBspTet`` there that is not
    a symbolic link (another copy of the addon) is left alone and named in an InputError."""
    if not os.path.isfile(os.path.join(ADDON_DIR, "InitGui.py")):
        raise InputError("this FemBspTet is not an addon folder (no InitGui.py next to the "
                         "package): install it with cmake --install, or run from a checkout",
                         where=ADDON_DIR)
    done = []
    for mod in mod_dirs or default_mod_dirs():
        link = os.path.join(mod, LINK_NAME)
        if os.path.lexists(link) and not os.path.islink(link):
            raise InputError("a FemBspTet folder that is not our link is already there; remove "
                             "or rename it first (FreeCAD would load both)", where=link)
        if uninstall:
            if os.path.islink(link):
                os.unlink(link)
                done.append(f"removed {link}")
            else:
                done.append(f"nothing to remove in {mod}")
            continue
        os.makedirs(mod, exist_ok=True)
        if os.path.islink(link):
            if os.path.realpath(link) == os.path.realpath(ADDON_DIR):
                done.append(f"{link} -> {ADDON_DIR} (already there)")
                continue
            os.unlink(link)
        os.symlink(ADDON_DIR, link)
        done.append(f"linked {link} -> {ADDON_DIR}")
    return done
