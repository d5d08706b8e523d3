# SPDX-License-Identifier: LGPL-2.1-or-later
# FemBspTet: FreeCAD start-up (App side). FreeCAD exec()s this file inside a function, without
# __file__. The mesher object needs no registration (it is a Fem::FemMeshObjectPython with a
# Python proxy, FemBspTet.freecad.mesher_object); FreeCAD's test runner gets our App tests:
#     freecadcmd -t TestFemBspTetApp
import FreeCAD

FreeCAD.__unit_test__ += ["TestFemBspTetApp"]
