# SPDX-License-Identifier: LGPL-2.1-or-later
"""CalculiX acceptance cases of the FreeCAD mesher, headless: the same analysis solved
with our mesh and with FreeCAD's Gmsh mesh at the same size.

* ``cantilever``: steel box 8000 x 1000 x 1000 mm, Face1 (x = 0) fixed, 9e6 N in -z on Face2
  (x = L) (FreeCAD's own cantilever example; Gmsh tet10 at size 500: 88.15 mm).
* ``plate_with_hole``: steel plate 200 x 100 x 10 mm with a hole of radius 20 mm through its
  centre, Face1 (x = 0) fixed, 100 MPa pressure on the hole's cylindrical face.
* ``bracket``: the sample L-bracket (``resources/samples/bracket.step``, 80 x 40 x 50 mm, 8 mm
  legs, a fillet, four holes) at the size of the bounding-box diagonal / 20; the back of its
  upright leg (Face11, x = 0) fixed, 1 MPa pressure on the top of its horizontal leg (Face8,
  2540 mm^2): the leg bends.

    case = build_case(doc, "cantilever")          # part, analysis, solver, constraints
    mesh = add_bspt_mesh(case, max_size=500, order=2)    or    add_gmsh_mesh(case, 500, 2)
    figures = solve(case, workdir)                # {"max_displacement_mm", "min_uz_mm", ...}

Needs FreeCAD (Debian freecad-python3), ``ccx`` and ``gmsh`` on PATH.
"""

import math
import os

from ..kernel.errors import InternalError
from ..kernel.paths import RESOURCES_DIR
from .mesher_object import make_mesher, set_source
from .mesher_tools import run_mesher

#: The sample part of the ``bracket`` case.
BRACKET_STEP = os.path.join(RESOURCES_DIR, "samples", "bracket.step")

#: Steel, as in freecad.md §6.
YOUNGS_MODULUS = "210000 MPa"
POISSON_RATIO = "0.30"

CASES = {
    "cantilever": {"size": 500.0, "gmsh_reference_mm": 88.15, "fixed": "Face1"},
    "plate_with_hole": {"size": 10.0, "hole_radius": 20.0, "pressure_mpa": 100.0,
                        "fixed": "Face1"},
    # size: the diagonal of the 80 x 40 x 50 box / 20
    "bracket": {"size": math.sqrt(80.0 ** 2 + 40.0 ** 2 + 50.0 ** 2) / 20.0, "fixed": "Face11",
                "pressed": "Face8", "pressure_mpa": 1.0},
}


class Case:
    """A built analysis: ``doc``, ``part``, ``analysis``, ``solver``, ``loaded_face`` (the face
    name carrying the load), ``mesh`` (set by add_*_mesh)."""

    def __init__(self, name, doc, part, analysis, solver, loaded_face):
        self.name, self.doc, self.part = name, doc, part
        self.analysis, self.solver, self.loaded_face = analysis, solver, loaded_face
        self.mesh = None


def build_case(doc, name):
    """Part, analysis, CalculiX solver, steel, constraints of case ``name`` in ``doc``."""
    import FreeCAD
    import ObjectsFem
    import Part

    if name == "cantilever":
        part = doc.addObject("Part::Box", "Box")
        part.Length, part.Width, part.Height = 8000.0, 1000.0, 1000.0
    elif name == "plate_with_hole":
        r = CASES[name]["hole_radius"]
        part = doc.addObject("Part::Feature", "Plate")
        part.Shape = Part.makeBox(200.0, 100.0, 10.0).cut(
            Part.makeCylinder(r, 10.0, FreeCAD.Vector(100.0, 50.0, 0.0)))
    elif name == "bracket":
        part = doc.addObject("Part::Feature", "Bracket")
        part.Shape = Part.read(BRACKET_STEP)
    else:
        raise InternalError("unknown CalculiX case %r (known: %s)" % (name, ", ".join(CASES)))
    doc.recompute()

    analysis = ObjectsFem.makeAnalysis(doc, "Analysis")
    # FEM's ccxtools solver: makeSolverCalculiXCcxTools on FreeCAD 1.x, the old spelling on 0.20
    make_solver = getattr(ObjectsFem, "makeSolverCalculiXCcxTools", None) or \
        ObjectsFem.makeSolverCalculixCcxTools
    solver = make_solver(doc, "CalculiXccxTools")
    solver.AnalysisType = "static"
    solver.GeometricalNonlinearity = "linear"
    analysis.addObject(solver)
    mat = ObjectsFem.makeMaterialSolid(doc, "Steel")
    m = mat.Material
    m["Name"] = "Steel"
    m["YoungsModulus"] = YOUNGS_MODULUS
    m["PoissonRatio"] = POISSON_RATIO
    mat.Material = m
    analysis.addObject(mat)

    fix = ObjectsFem.makeConstraintFixed(doc, "Fixed")
    fix.References = [(part, CASES[name]["fixed"])]
    analysis.addObject(fix)
    if name == "cantilever":
        force = ObjectsFem.makeConstraintForce(doc, "Force")
        force.References = [(part, "Face2")]
        set_load(force, "Force", 9.0e6, "N")
        force.Direction = (part, ["Edge5"])
        force.Reversed = True
        analysis.addObject(force)
        loaded = "Face2"
    else:
        loaded = CASES[name].get("pressed") or hole_face_name(part.Shape)
        pressure = ObjectsFem.makeConstraintPressure(doc, "Pressure")
        pressure.References = [(part, loaded)]
        set_load(pressure, "Pressure", CASES[name]["pressure_mpa"], "MPa")
        analysis.addObject(pressure)
    return Case(name, doc, part, analysis, solver, loaded)


def set_load(constraint, name, value, unit):
    """Set the load property ``name`` of a FEM constraint to ``value`` in ``unit`` (N or MPa):
    FreeCAD 0.20 stores a plain number in those units; FreeCAD 1.x stores a quantity (a plain
    number there would be read in mN or kPa)."""
    import FreeCAD

    if constraint.getTypeIdOfProperty(name) == "App::PropertyFloat":
        setattr(constraint, name, float(value))
    else:
        setattr(constraint, name, FreeCAD.Units.Quantity("%r %s" % (float(value), unit)))


def hole_face_name(shape):
    """Name of the (single) cylindrical face of ``shape``."""
    names = ["Face%d" % (k + 1) for k, f in enumerate(shape.Faces)
             if type(f.Surface).__name__ == "Cylinder"]
    if len(names) != 1:
        raise InternalError("expected one cylindrical face, found %d" % len(names))
    return names[0]


def add_bsptet_mesh(case, max_size, order, **properties):
    """Our mesher object for the case's part, meshed (run_mesher) and added to the analysis."""

    obj = make_mesher(case.doc, case.part, CharacteristicLengthMax=max_size,
                      ElementOrder="2nd" if order == 2 else "1st", CompareWithPeers=False,
                      **properties)
    run_mesher(obj)
    case.analysis.addObject(obj)
    case.mesh = obj
    return obj


def add_gmsh_mesh(case, max_size, order):
    """FreeCAD's Gmsh mesher object at ``CharacteristicLengthMax = max_size``, meshed."""
    import ObjectsFem
    from femmesh.gmshtools import GmshTools

    obj = ObjectsFem.makeMeshGmsh(case.doc, "MeshGmsh")
    set_source(obj, case.part)  # Gmsh's link: Shape on FreeCAD 1.x, Part on 0.20/0.21
    obj.CharacteristicLengthMax = max_size
    obj.ElementOrder = "2nd" if order == 2 else "1st"
    case.doc.recompute()
    # FreeCAD's GmshTools returns Gmsh's whole stderr, warnings included. Gmsh 4.8 sometimes
    # (not on every run of the same input: seen once in CI on the plate with a hole) ends with
    # "Warning : 1 ill-shaped tets are still in the mesh" and "0 errors": a mesh, usable. Only
    # an error line or an empty mesh is a failure.
    output = GmshTools(obj).create_mesh()
    errors = [line for line in (output or "").splitlines() if line.lstrip().startswith("Error")]
    if errors or obj.FemMesh.VolumeCount == 0:
        raise InternalError("Gmsh failed: %s" % (output or "no volume elements"))
    case.analysis.addObject(obj)
    case.mesh = obj
    return obj


def solve(case, workdir):
    """Run CalculiX on the case; returns the figures (displacements in mm)."""
    from femtools import ccxtools

    fea = ccxtools.FemToolsCcx(case.analysis, case.solver)
    fea.purge_results()
    fea.update_objects()
    fea.setup_working_dir(workdir)
    fea.setup_ccx()
    message = fea.check_prerequisites()
    if message:
        raise InternalError("CalculiX prerequisites: %s" % message)
    fea.write_inp_file()
    fea.ccx_run()
    fea.load_results()
    results = [o for o in case.analysis.Group if o.isDerivedFrom("Fem::FemResultObject")]
    if not results:
        raise InternalError("CalculiX gave no result (see %s)" % workdir)
    r = results[0]
    lengths = list(r.DisplacementLengths)
    fem = case.mesh.FemMesh
    return {
        "nodes": fem.NodeCount,
        "tets": fem.VolumeCount,
        "max_displacement_mm": max(lengths),
        "min_uz_mm": min(v.z for v in r.DisplacementVectors),
        "finite": all(math.isfinite(x) for x in lengths),
    }
