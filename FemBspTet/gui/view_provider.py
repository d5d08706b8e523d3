# SPDX-License-Identifier: LGPL-2.1-or-later
"""View provider of the BspTet mesher object (on FreeCAD's ``FemGui::ViewProviderFemMeshPython``).

Double click or Edit opens the task panel (:mod:`FemBspTet.gui.task_panel`). Saved files store
``module="FemBspTet.gui.view_provider" class="VPMeshBspTet"`` in GuiDocument.xml: never rename
(files of earlier versions store ``FemBspTet.view_provider``, kept as a thin module).
Holds no state that is saved (both serialisation pairs return None).
"""

import os

from ..freecad.mesher_object import StatelessProxy
from ..kernel.paths import RESOURCES_DIR
from .task_panel import TaskPanelMeshBspTet

#: Icon of the mesher object and of its command.
ICON_PATH = os.path.join(RESOURCES_DIR, "icons", "FEM_MeshBspTetFromShape.svg")


class VPMeshBspTet(StatelessProxy):
    def __init__(self, vobj):
        vobj.Proxy = self
        self.ViewObject = vobj
        self.Object = vobj.Object
        self.task_panel = None

    def attach(self, vobj):
        self.ViewObject = vobj
        self.Object = vobj.Object
        self.task_panel = None

    def getIcon(self):
        return ICON_PATH

    def updateData(self, obj, prop):
        return

    def onChanged(self, vobj, prop):
        return

    def claimChildren(self):
        return []

    def setEdit(self, vobj, mode=0):
        """Open the task panel (edit mode 0 only; other modes, e.g. Transform, are FreeCAD's)."""
        if mode != 0:
            return None
        import FreeCADGui


        if FreeCADGui.Control.activeDialog():
            FreeCADGui.Control.closeDialog()
        # as FEM's own meshers: while editing, this mesh shows and the other meshes and results hide
        for other in vobj.Object.Document.Objects:
            if other is not vobj.Object and other.ViewObject is not None and (
                    other.isDerivedFrom("Fem::FemMeshObject")
                    or other.isDerivedFrom("Fem::FemPostObject")):
                other.ViewObject.hide()
        vobj.show()
        self.task_panel = TaskPanelMeshBspTet(vobj.Object)  # for scripts and tests; not saved
        FreeCADGui.Control.showDialog(self.task_panel)
        return True

    def unsetEdit(self, vobj, mode=0):
        if mode != 0:
            return None
        import FreeCADGui

        FreeCADGui.Control.closeDialog()
        self.task_panel = None
        return True

    def doubleClicked(self, vobj):
        import FreeCAD
        import FreeCADGui

        gui_doc = FreeCADGui.getDocument(vobj.Object.Document)
        if gui_doc.getInEdit():
            FreeCAD.Console.PrintWarning(
                "FemBspTet: another object is being edited; close its task panel first\n")
            return True
        gui_doc.setEdit(vobj.Object.Name)
        return True
