# SPDX-License-Identifier: LGPL-2.1-or-later
# FemBspTet: FreeCAD start-up (GUI side). exec()'d by FreeCAD inside a function: no __file__, and
# top-level names are locals, so everything the workbench needs is imported inside its methods.
# At start-up: the command FEM_MeshBspTetFromShape is registered, put into FEM's toolbar and menu
# (FemBspTet/gui/commands.py), and the preferences page is added (Edit > Preferences > FEM).
import FreeCADGui


class FemBspTetWorkbench(FreeCADGui.Workbench):
    """A small workbench holding the BspTet mesher command (also put into FEM's toolbar/menu)."""

    MenuText = "FEM BspTet"
    ToolTip = "BSP-assisted constrained tetrahedralization for FEM"

    def __init__(self):
        from FemBspTet.gui import commands

        self.__class__.Icon = commands.workbench_icon_path()
        self.keep_alive = []  # the FEM toolbar/menu helpers live as long as the workbench
        try:
            commands.install_in_fem_workbench(self.keep_alive)
        except Exception as e:  # the addon must never break FreeCAD's start-up
            import FreeCAD

            FreeCAD.Console.PrintWarning("FemBspTet: not added to FEM's toolbar: %s\n" % e)
        try:
            import os

            import FemBspTet

            ui = os.path.join(os.path.dirname(os.path.dirname(FemBspTet.__file__)),
                              "resources", "ui", "PreferencesBspTet.ui")
            FreeCADGui.addPreferencePage(ui, "FEM")
        except Exception as e:
            import FreeCAD

            FreeCAD.Console.PrintWarning("FemBspTet: no preferences page: %s\n" % e)

    def Initialize(self):
        from FemBspTet.gui import commands

        self.appendToolbar("BspTet", [commands.COMMAND_NAME])
        self.appendMenu("&BspTet", [commands.COMMAND_NAME])

    def Activated(self):
        pass

    def Deactivated(self):
        pass

    def GetClassName(self):
        return "Gui::PythonWorkbench"


FreeCADGui.addWorkbench(FemBspTetWorkbench())
