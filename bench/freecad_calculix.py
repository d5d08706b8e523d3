#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""The CalculiX acceptance cases of the FreeCAD mesher, with figures: each case solved with our
mesh and with FreeCAD's Gmsh mesh at the same CharacteristicLengthMax, tet4 and tet10, and the
ratio of the maximum displacements. Usage: bench/freecad_calculix.py [CASE ...]
(cases: cantilever, plate_with_hole; see FemBspTet/freecad/calculix_cases.py).
"""

import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from FemBspTet.freecad import calculix_cases as cc  # noqa: E402
from FemBspTet.kernel.errors import BspTetError  # noqa: E402
from FemBspTet.kernel.freecad_env import import_freecad  # noqa: E402


def main():
    freecad = import_freecad()
    names = sys.argv[1:] or list(cc.CASES)
    print("%-16s %-7s %-5s %7s %7s %14s %9s" % ("case", "mesher", "order", "nodes", "tets",
                                               "max |u| mm", "/ Gmsh"))
    for name in names:
        size = cc.CASES[name]["size"]
        gmsh = {}
        for order in (2, 1):
            for mesher in ("gmsh", "bsptet"):
                doc = freecad.newDocument("Bench")
                try:
                    case = cc.build_case(doc, name)
                    (cc.add_gmsh_mesh if mesher == "gmsh" else cc.add_bsptet_mesh)(
                        case, size, order)
                    f = cc.solve(case, tempfile.mkdtemp(prefix="fembsptet_ccx_"))
                    u = f["max_displacement_mm"]
                    if mesher == "gmsh":
                        gmsh[order] = u
                    ratio = "%.4f" % (u / gmsh[order]) if order in gmsh else ""
                    print("%-16s %-7s %-5d %7d %7d %14.6g %9s" % (name, mesher, order,
                                                                 f["nodes"], f["tets"], u, ratio))
                except BspTetError as e:
                    print("%-16s %-7s %-5d failed: %s" % (name, mesher, order, str(e)[:160]))
                finally:
                    freecad.closeDocument(doc.Name)
                sys.stdout.flush()
    print("(size: CharacteristicLengthMax of both meshers; cantilever %g mm, plate %g mm)"
          % (cc.CASES["cantilever"]["size"], cc.CASES["plate_with_hole"]["size"]))


if __name__ == "__main__":
    main()
