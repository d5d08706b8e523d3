# SPDX-License-Identifier: LGPL-2.1-or-later
"""The C++ FEM pipeline from CAD through the binding (_bsptet_cad.mesh_cad_file / mesh_cad_brep):
arrays of the documented shapes, every tet positive and checked exactly, every CAD face and solid
present, and (with FreeCAD) every node of a face's triangles found by FemMesh.getNodesByFace on a
moved and rotated part with a hole.
"""

import os
import re

import numpy as np
import pytest

from FemBspTet import _bsptet, _bsptet_cad
from FemBspTet.kernel.freecad_env import freecad_available

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "cad")


def boundary_faces(tets):
    """Faces of exactly one tet (first four nodes), outward (types.h), as an (f, 3) array."""
    t = np.asarray(tets)[:, :4]
    faces = np.concatenate([t[:, [0, 2, 1]], t[:, [0, 1, 3]], t[:, [0, 3, 2]], t[:, [1, 2, 3]]])
    key = np.sort(faces, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return faces[counts[inverse.ravel()] == 1]


def check(points, tets, tet_solid, triangles, triangle_face, stats, solid_names, face_names,
          order, solids, faces):
    npt, npf = (10, 6) if order == 2 else (4, 3)
    assert points.shape[1] == 3 and tets.shape[1] == npt and triangles.shape[1] == npf
    assert tet_solid.shape == (tets.shape[0],) and triangle_face.shape == (triangles.shape[0],)
    assert set(tet_solid.tolist()) == set(range(solids))
    assert set(triangle_face.tolist()) == set(range(faces))
    assert stats["tets"] == tets.shape[0] and stats["nodes"] == points.shape[0]
    assert len(solid_names) == solids and len(face_names) == faces
    # Exactly valid against its own boundary: positive, conforming, closed, one mid-node per edge.
    report = _bsptet.check_mesh(points, boundary_faces(tets), points, tets, compute_quality=False)
    assert report["valid"], report["messages"]
    assert report["inverted_tets"] == 0 and report["flat_tets"] == 0


def options(**values):
    o = _bsptet_cad.FemOptions()
    for name, value in values.items():
        setattr(o, name, value)
    return o


def test_the_options_schema_is_one_table():
    """FemOptions is bound from fem_mesh.h's for_each_fem_option; the Python layer, the CLI and
    the FreeCAD object map onto it and nothing else."""
    from FemBspTet.cli.main import FEM_OPTION_OF_FLAG
    from FemBspTet.fem.cad_mesh import fem_options
    from FemBspTet.fem.mesh_pipeline import FEM_OPTION_OF_PARAMETER, MeshParameters

    names = list(_bsptet_cad.FemOptions.names)
    assert names == ["size", "min_size", "size_by_face", "points_per_circle", "grading", "order",
                     "optimize_rounds", "face_rounds", "workers"]
    o = _bsptet_cad.FemOptions()
    assert (o.size, o.min_size, o.order, o.grading, o.points_per_circle, o.workers) == \
        (0, 0, 2, 0.3, 12, 0)
    with pytest.raises(AttributeError):
        o.no_such_option = 1
    # the Python builder refuses names outside the schema
    with pytest.raises(ValueError, match="unknown FEM option"):
        fem_options("x", sizee=1.0)
    assert fem_options("x", size=2.0, order=1).order == 1
    with pytest.raises(ValueError, match="workers"):
        fem_options("x", workers=-2)
    # the CLI's FEM flags and the FreeCAD object's parameters name schema options
    assert set(FEM_OPTION_OF_FLAG.values()) <= set(names)
    fields = {f for f in MeshParameters.__dataclass_fields__}
    assert set(FEM_OPTION_OF_PARAMETER) <= fields
    assert set(FEM_OPTION_OF_PARAMETER.values()) <= set(names)
    # the statistics keys are the FemStats fields
    stats = _bsptet_cad.FemStats()
    keys = set(stats.to_dict())
    assert {"solids", "faces", "size", "nodes", "tets", "min_dihedral_deg", "seconds_total",
            "median_tet_min_dihedral_deg", "refine_seconds_by_pass"} <= keys
    assert all(hasattr(stats, k) for k in keys)


@pytest.mark.parametrize("order", [1, 2])
def test_mesh_cad_file_red_cube_blue_cylinder(order):
    out = _bsptet_cad.mesh_cad_file(os.path.join(DATA, "red_cube_blue_cylinder.step"),
                                options=options(order=order))
    check(*out, order=order, solids=2, faces=9)
    stats, solid_names, face_names = out[5:]
    # The STEP file names its solids (MANIFOLD_SOLID_BREP), not its faces: FreeCAD's names then.
    # Each name is on its own solid: the 10 mm cube's tets fill 1000 mm^3.
    assert sorted(solid_names) == ["blue_cylinder", "red_cube"]
    assert face_names == [f"Face{k}" for k in range(1, 10)]
    points, tets, tet_solid = out[:3]
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    volume = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6
    assert volume[tet_solid == solid_names.index("red_cube")].sum() == pytest.approx(1000, rel=1e-9)
    assert stats["min_dihedral_deg"] > 0
    assert 0 <= stats["tets_below_10_deg"] <= 1
    for key in ("seconds_surface", "seconds_core", "seconds_refine", "seconds_merge", "seconds_total"):
        assert stats[key] >= 0


def test_bad_options_and_files_raise_value_errors():
    path = os.path.join(DATA, "red_cube_blue_cylinder.step")
    with pytest.raises(ValueError, match="order"):
        _bsptet_cad.mesh_cad_file(path, options=options(order=3))
    with pytest.raises(ValueError, match="size"):
        _bsptet_cad.mesh_cad_file(path, options=options(size=-1.0))
    with pytest.raises(ValueError):
        _bsptet_cad.mesh_cad_file(os.path.join(DATA, "no_such_part.step"))
    with pytest.raises(ValueError):
        _bsptet_cad.mesh_cad_brep("not a shape")


def test_cancel_raises_meshing_error():
    with pytest.raises(RuntimeError) as info:
        _bsptet_cad.mesh_cad_file(os.path.join(DATA, "red_cube_blue_cylinder.step"), cancel=lambda: True)
    assert info.value.code == "cancelled"


@pytest.mark.skipif(not freecad_available(), reason="FreeCAD (freecad-python3) is not available")
@pytest.mark.parametrize("order", [1, 2])
def test_mesh_cad_brep_nodes_found_by_face(order):
    from FemBspTet.kernel.freecad_env import import_freecad

    freecad = import_freecad()
    import Fem
    import Part

    shape = Part.makeBox(60, 40, 8).cut(Part.makeCylinder(10, 8, freecad.Vector(30, 20, 0)))
    shape.Placement = freecad.Placement(freecad.Vector(3.5, -7.25, 11.0),
                                        freecad.Rotation(freecad.Vector(1, 2, 3), 37.0))
    out = _bsptet_cad.mesh_cad_brep(shape.exportBrepToString(), options=options(order=order))
    points, tets, _, triangles, triangle_face = out[:5]
    assert out[7] == [f"Face{k}" for k in range(1, len(shape.Faces) + 1)]  # a BREP has no names
    check(*out, order=order, solids=1, faces=len(shape.Faces))
    fem = Fem.FemMesh()
    for i, p in enumerate(points, start=1):
        fem.addNode(float(p[0]), float(p[1]), float(p[2]), i)
    for k, face in enumerate(shape.Faces):
        wanted = set((triangles[triangle_face == k].ravel() + 1).tolist())
        found = set(fem.getNodesByFace(face))
        assert wanted <= found, "Face%d: %d of its nodes not found" % (k + 1, len(wanted - found))


def test_step_names_become_unique_set_names(tmp_path):
    """A STEP file's names of solids and faces name the sets: cleaned to letters, digits, '-' and
    '_', unique up to case (a shared name gets FreeCAD's name appended), FreeCAD's names where the
    file gives none or only "NONE" or no letter."""
    with open(os.path.join(DATA, "red_cube_blue_cylinder.step")) as f:
        text = f.read()
    text = text.replace("'red_cube'", "'Blue_Cylinder'")  # the two solids' names now clash
    faces = iter(["Top face!", "NONE", "#12", "Face1", "", "", "", "", ""])
    while "ADVANCED_FACE( ''" in text:
        text = text.replace("ADVANCED_FACE( ''", f"ADVANCED_FACE( '{next(faces)}@'", 1)
    text = text.replace("@'", "'")
    path = tmp_path / "renamed.step"
    path.write_text(text)
    _, _, _, _, tri_face, _, solid_names, face_names = _bsptet_cad.mesh_cad_file(
        str(path), dimension=2, options=options(order=1))
    assert solid_names == ["blue_cylinder_Solid1", "Blue_Cylinder_Solid2"]  # equal up to case
    assert len({n.upper() for n in solid_names + face_names}) == len(solid_names) + len(face_names)
    # "NONE", "#12" and "" are no names; a face named "Face1" that is not Face1 gets its own name
    # appended.
    assert face_names.count("Top_face") == 1
    assert all(re.fullmatch(r"Top_face|Face\d+|Face1_Face\d+", n) for n in face_names), face_names
    assert set(tri_face.tolist()) == set(range(9))


def test_solids_meshed_at_the_same_time_give_the_same_mesh():
    """FemOptions.workers solids at a time, each on its own thread: the arrays are identical for
    1 and 2 workers and for every core (0), and the mesh is valid."""
    path = os.path.join(DATA, "red_cube_blue_cylinder.step")
    runs = [_bsptet_cad.mesh_cad_file(path, options=options(order=2, workers=w)) for w in (1, 2, 0)]
    check(*runs[1], order=2, solids=2, faces=9)
    for other in runs[1:]:
        for a, b in zip(runs[0][:5], other[:5]):
            assert np.array_equal(a, b)
        assert other[6:] == runs[0][6:]
        assert other[5]["tets"] == runs[0][5]["tets"]
    with pytest.raises(ValueError, match="workers"):
        _bsptet_cad.mesh_cad_file(path, options=options(workers=-1))
