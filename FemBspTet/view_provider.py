# SPDX-License-Identifier: LGPL-2.1-or-later
"""The path FreeCAD documents store for the view provider's proxy (``module="FemBspTet.view_provider"
class="VPMeshBspTet"`` in GuiDocument.xml): kept so that saved files open. The code is
FemBspTet.gui.view_provider."""

from .gui.view_provider import VPMeshBspTet  # noqa: F401  # noqa: F401
