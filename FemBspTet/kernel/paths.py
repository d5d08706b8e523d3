# SPDX-License-Identifier: LGPL-2.1-or-later
"""Where the addon's files are: the addon folder (a checkout, or an installed
``PREFIX/share/fembsptet/FemBspTet``) holds Init.py, InitGui.py, package.xml, resources/, bin/,
the ``FemBspTet`` package and, in a checkout, build/."""

import os

#: The addon folder: the one that holds the FemBspTet package.
ADDON_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
#: Icons, the preferences page, the sample parts.
RESOURCES_DIR = os.path.join(ADDON_DIR, "resources")
