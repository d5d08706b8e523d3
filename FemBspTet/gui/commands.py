# SPDX-License-Identifier: LGPL-2.1-or-later
"""GUI command ``FEM_MeshBspTetFromShape`` and its places in FreeCAD's FEM workbench.

* The command (one selected shape) creates the mesher object through ``FreeCADGui.doCommand``
  (journaled: the macro recorder records ``FemBspTet.make_mesher(...)``), adds it to the active
  analysis if there is one, and opens its task panel. Importing this module registers it.
* FEM's toolbar and menu (:func:`install_in_fem_workbench`):
  - FreeCAD 1.x: a workbench manipulator puts the command among FEM's meshers: just before
    FEM's Gmsh command in FEM's Mesh toolbar (a manipulator inserts tool items before another),
    right after it in FEM's Mesh menu.
  - FreeCAD 0.20/0.21 (no manipulators; FEM is a C++ workbench): a custom toolbar "BspTet"
    defined by parameters, which FEM shows on activation (its workbench reads
    the toolbars stored under its parameter group), and an entry appended to FEM's "Mesh" menu each time FEM is activated.
"""

import os

from .view_provider import ICON_PATH

COMMAND_NAME = "FEM_MeshBspTetFromShape"
#: FEM's Gmsh command: our command goes beside it in FEM's toolbar and menu (1.x).
GMSH_COMMAND = "FEM_MeshGmshFromShape"
#: Parameter group of the custom toolbar FEM shows on 0.20/0.21.
FEM_TOOLBAR_PARAM = "User parameter:BaseApp/Workbench/FemWorkbench/Toolbar/FemBspTet"
FEM_TOOLBAR_NAME = "BspTet"
MENU_TEXT = "FEM mesh from shape by BspTet"
TOOL_TIP = ("Create a FEM mesh from a solid (tetrahedra, by the exact BSP-assisted "
            "tetrahedralizer) or a face or shell (triangles) with FemBspTet and open its task panel")


class CommandMeshBspTetFromShape:
    """Create a BspTet mesher object for the selected shape and open its task panel."""

    def GetResources(self):
        return {"Pixmap": ICON_PATH, "MenuText": MENU_TEXT, "ToolTip": TOOL_TIP}

    def IsActive(self):
        import FreeCAD
        import FreeCADGui

        if FreeCAD.ActiveDocument is None:
            return False
        sel = FreeCADGui.Selection.getSelection()
        return len(sel) == 1 and _has_faces(sel[0])

    def Activated(self):
        import FreeCAD
        import FreeCADGui

        sel = FreeCADGui.Selection.getSelection()
        if not self.IsActive():  # reached through a menu entry of ours (FreeCAD 0.20/0.21)
            FreeCAD.Console.PrintWarning(
                "FemBspTet: select one object with a solid, a shell or a face (a Part, Body or "
                "imported STEP) first, then %s\n" % MENU_TEXT)
            return
        part = sel[0]
        doc = FreeCAD.ActiveDocument
        doc.openTransaction("Create FEM mesh by BspTet")
        FreeCADGui.addModule("FemBspTet")
        FreeCADGui.doCommand(
            "_mesh = FemBspTet.make_mesher(FreeCAD.ActiveDocument, "
            "FreeCAD.ActiveDocument.getObject(%r))" % part.Name)
        import FemGui

        if FemGui.getActiveAnalysis() is not None:
            FreeCADGui.addModule("FemGui")
            FreeCADGui.doCommand("FemGui.getActiveAnalysis().addObject(_mesh)")
        doc.commitTransaction()
        FreeCADGui.doCommand("FreeCADGui.ActiveDocument.setEdit(_mesh.Name)")
        FreeCADGui.Selection.clearSelection()


def _has_faces(obj):
    """A solid (3D mesh) or a Face or Shell (2D mesh)."""
    shape = getattr(obj, "Shape", None)
    try:
        return shape is not None and not shape.isNull() and len(shape.Faces) > 0
    except Exception:  # a shape OCCT cannot explore: not a candidate
        return False


def register():
    """Register the command once (importing this module does it)."""
    import FreeCADGui

    if COMMAND_NAME not in FreeCADGui.listCommands():
        FreeCADGui.addCommand(COMMAND_NAME, CommandMeshBspTetFromShape())


class FemMeshManipulator:
    """FreeCAD 1.x workbench manipulator: our command before Gmsh's in FEM's Mesh toolbar (tool
    items go before the one named) and after it in FEM's Mesh menu. Gmsh's command exists only
    in FEM, so nothing else changes."""

    def modifyToolBars(self):
        return [{"insert": COMMAND_NAME, "toolItem": GMSH_COMMAND}]

    def modifyMenuBar(self):
        return [{"insert": COMMAND_NAME, "menuItem": GMSH_COMMAND, "after": ""}]


class _MenuInjector:
    """FreeCAD 0.20/0.21: on each activation of FEM, append our command to FEM's Mesh menu
    (FEM rebuilds its menus on activation, so this runs every time)."""

    def __init__(self):
        self.action = None

    def __call__(self, workbench_name):
        if workbench_name != "FemWorkbench":
            return
        from PySide import QtCore

        # The signal comes before FEM's menus are rebuilt: add the entry once they are.
        QtCore.QTimer.singleShot(0, self._add)

    def _add(self):
        try:
            add_to_fem_mesh_menu(self)
        except Exception as e:  # never break the workbench switch
            import FreeCAD

            FreeCAD.Console.PrintLog("FemBspTet: FEM menu entry not added: %s\n" % e)


def fem_mesh_menu():
    """FEM's top-level "Mesh" menu (object name ``M&esh``) in the main window, or None."""
    import FreeCADGui
    from PySide import QtGui

    mw = FreeCADGui.getMainWindow()
    for menu in mw.findChildren(QtGui.QMenu):
        try:
            if menu.objectName().replace("&", "") == "Mesh" and \
                    menu.parent() is mw.menuBar():
                return menu
        except RuntimeError:  # a menu of the previous workbench, being deleted
            continue
    return None


def add_to_fem_mesh_menu(holder):
    """Append an entry running our command to FEM's Mesh menu (if not there yet)."""
    import FreeCADGui
    from PySide import QtGui

    menu = fem_mesh_menu()
    if menu is None:
        return None
    for action in menu.actions():
        if action.objectName() == COMMAND_NAME:
            return action
    action = QtGui.QAction(QtGui.QIcon(ICON_PATH), MENU_TEXT, menu)
    action.setObjectName(COMMAND_NAME)
    action.setToolTip(TOOL_TIP)
    action.triggered.connect(lambda: FreeCADGui.runCommand(COMMAND_NAME))
    # enabled as FreeCAD enables commands: only with one solid selected
    menu.aboutToShow.connect(lambda: action.setEnabled(CommandMeshBspTetFromShape().IsActive()))
    action.setEnabled(CommandMeshBspTetFromShape().IsActive())
    actions = menu.actions()
    names = [a.objectName() for a in actions]
    if GMSH_COMMAND in names and names.index(GMSH_COMMAND) + 1 < len(actions):
        menu.insertAction(actions[names.index(GMSH_COMMAND) + 1], action)  # right after Gmsh
    else:
        menu.addAction(action)
    holder.action = action
    return action


def install_in_fem_workbench(keep):
    """Put the command into FEM's toolbar and menu (see the module docstring).

    keep: a list the caller keeps alive (the workbench object): the manipulator or the menu
          injector is appended to it, so that it lives as long as FreeCAD's GUI.
    """
    import FreeCAD
    import FreeCADGui

    if hasattr(FreeCADGui, "addWorkbenchManipulator"):  # FreeCAD 1.x
        manipulator = FemMeshManipulator()
        FreeCADGui.addWorkbenchManipulator(manipulator)
        keep.append(manipulator)
        return "manipulator"
    group = FreeCAD.ParamGet(FEM_TOOLBAR_PARAM)
    group.SetString("Name", FEM_TOOLBAR_NAME)
    group.SetBool("Active", True)
    group.SetString(COMMAND_NAME, __name__)  # module FreeCAD imports if the command is unknown
    injector = _MenuInjector()
    FreeCADGui.getMainWindow().workbenchActivated.connect(injector)
    keep.append(injector)
    return "custom toolbar"


def workbench_icon_path():
    return os.path.join(os.path.dirname(ICON_PATH), "FemBspTet.svg")


register()
