# SPDX-License-Identifier: LGPL-2.1-or-later
"""FreeCAD's GUI side: the view provider, the task panel, the command in FEM's menu and toolbar.
Nothing else of FemBspTet imports this package (FreeCAD does, through InitGui.py, and the
document object attaches the view provider when the GUI is up)."""
