# SPDX-License-Identifier: LGPL-2.1-or-later
"""Makes bracket.step, the sample part of scripts/demo.sh (our own model, LGPL like the project).

An L-shaped steel bracket, 80 x 40 x 50 mm, 8 mm thick, with two bolt holes in each flange and a
filleted inner corner. Run with: freecadcmd resources/samples/make_bracket.py
"""

import os

import FreeCAD
import Part

HERE = os.path.dirname(os.path.abspath(__file__)) if "__file__" in dir() else os.getcwd()

base = Part.makeBox(80, 40, 8)
wall = Part.makeBox(8, 40, 50)
shape = base.fuse(wall).removeSplitter()
# Fillet the inner corner edge (the edge along y at x = 8, z = 8).
inner = [e for e in shape.Edges
         if abs(e.BoundBox.XMin - 8) < 1e-9 and abs(e.BoundBox.XMax - 8) < 1e-9
         and abs(e.BoundBox.ZMin - 8) < 1e-9 and abs(e.BoundBox.ZMax - 8) < 1e-9]
shape = shape.makeFillet(6, inner)
for x, y in ((35, 12), (65, 28)):
    shape = shape.cut(Part.makeCylinder(4, 10, FreeCAD.Vector(x, y, -1)))
for y, z in ((12, 35), (28, 20)):
    shape = shape.cut(Part.makeCylinder(4, 10, FreeCAD.Vector(-1, y, z), FreeCAD.Vector(1, 0, 0)))
shape = shape.removeSplitter()
assert shape.isValid() and len(shape.Solids) == 1
out = os.path.join(os.environ.get("BRACKET_DIR", HERE), "bracket.step")
shape.exportStep(out)
print(f"wrote {out}: volume {shape.Volume:.3f} mm^3, {len(shape.Faces)} faces")
