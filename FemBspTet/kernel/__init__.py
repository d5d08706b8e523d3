# SPDX-License-Identifier: LGPL-2.1-or-later
"""The bottom layer: the compiled core (``core``: tetrahedralize, check, refine, certify), the mesh
types and their conventions, the errors, progress reporting, the memory budget, and how FreeCAD is
found (``freecad_env``; FreeCAD itself is imported only on demand). Imports nothing else of
FemBspTet."""
