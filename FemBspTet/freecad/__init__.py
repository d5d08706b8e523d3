# SPDX-License-Identifier: LGPL-2.1-or-later
"""FreeCAD's side without its GUI: the mesher document object and its factory, the worker process
that meshes outside FreeCAD's GUI thread, FemMesh building and FreeCAD's writers, the CalculiX
acceptance cases. FreeCAD is imported inside the functions that need it. Imports fem, compare and
below; the view provider is attached only when FreeCAD's GUI is up."""
