# FemBspTet: FreeCAD start-up (GUI side). exec()'d by FreeCAD inside a function: no __file__, and
# top-level names are locals, so everything the workbench needs is imported inside its methods.
import FreeCADGui


class FemBspTetWorkbench(FreeCADGui.Workbench):
    """A small workbench holding the BspTet mesher command (also injected into FEM's toolbar)."""

    MenuText = "FEM BspTet"
    ToolTip = "BSP-assisted constrained tetrahedralization for FEM"

    def __init__(self):
        import os

        import FemBspTet

        self.__class__.Icon = os.path.join(
            os.path.dirname(os.path.dirname(FemBspTet.__file__)), "resources", "icons", "FemBspTet.svg"
        )

    def Initialize(self):
        pass

    def GetClassName(self):
        return "Gui::PythonWorkbench"


FreeCADGui.addWorkbench(FemBspTetWorkbench())
