# SPDX-License-Identifier: LGPL-2.1-or-later
"""The path FreeCAD documents store for the mesher object's proxy (``module="FemBspTet.mesher_object"
class="MeshBspTet"``): kept so that saved files open. The code is FemBspTet.freecad.mesher_object."""

from .freecad.mesher_object import MeshBspTet  # noqa: F401
