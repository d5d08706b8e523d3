# SPDX-License-Identifier: LGPL-2.1-or-later
"""Makes tests/data/freecad/mesher_freecad_0_20.FCStd: a document saved by FreeCAD 0.20.2 (Debian
12's) with a block with a hole, an analysis and a BspTet mesher object meshed in tet10.

    PYTHONPATH=. /usr/bin/python3 tests/data/freecad/make_mesher_document.py OUT.FCStd

tests/test_mesher_object.py opens it on every FreeCAD version the tests run on (0.20.2 and 1.0):
the object, its link to the solid and its mesh must come back, and it must mesh again.
"""
import sys

from FemBspTet.kernel.freecad_env import import_freecad

FreeCAD = import_freecad()
import ObjectsFem  # noqa: E402
import Part  # noqa: E402

import FemBspTet  # noqa: E402

doc = FreeCAD.newDocument("Mesher020")
block = doc.addObject("Part::Feature", "Block")
block.Shape = Part.makeBox(40, 20, 10).cut(Part.makeCylinder(5, 10, FreeCAD.Vector(20, 10, 0)))
analysis = ObjectsFem.makeAnalysis(doc, "Analysis")
mesher = FemBspTet.make_mesher(doc, block, CharacteristicLengthMax=8, ElementOrder="2nd",
                               CompareWithPeers=False)
analysis.addObject(mesher)
doc.recompute()
FemBspTet.run_mesher(mesher)
doc.saveAs(sys.argv[1])
print("%s: FreeCAD %s, %d nodes, %d tets" % (sys.argv[1], ".".join(FreeCAD.Version()[:3]),
                                           mesher.Nodes, mesher.Tetrahedra))
