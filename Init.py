# FemBspTet: FreeCAD start-up (App side). FreeCAD exec()s this file inside a function, without
# __file__. Nothing is registered on the App side yet: the mesher document object and its unit
# tests arrive with the FreeCAD integration (issue 5). Keep this file: FreeCAD looks for it.
