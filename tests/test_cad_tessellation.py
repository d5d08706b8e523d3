# SPDX-License-Identifier: LGPL-2.1-or-later
"""Tests of FemBspTet.io.cad_tessellation (FreeCAD shapes and CAD files -> face-tagged surfaces).

Run with Debian's interpreter from the checkout: ``/usr/bin/python3 -m pytest -q tests``.
Skipped when FreeCAD (Debian package freecad-python3) is not available. The invariants are
checked with helpers written here, independent of the module's own checks.
"""

import math
import os
import shutil
from collections import Counter

import numpy as np
import pytest

from FemBspTet.kernel.errors import InputError
from FemBspTet.kernel.freecad_env import freecad_available

if not freecad_available():
    pytest.skip("FreeCAD (Debian package freecad-python3) is not available in this interpreter",
                allow_module_level=True)

from FemBspTet.io import cad_tessellation as ct  # noqa: E402
from FemBspTet.kernel.mesh_types import Surface  # noqa: E402

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "cad")
BOTTLE = os.path.join(DATA, "bottle.brep")
CUBE_CYLINDER = os.path.join(DATA, "red_cube_blue_cylinder.step")


@pytest.fixture(scope="module")
def fc():
    """(FreeCAD, Part), bootstrapped once per test process."""
    from FemBspTet.kernel.freecad_env import import_freecad

    freecad = import_freecad()
    import Part

    return freecad, Part


# ---------------------------------------------------------------------------------------------
# independent invariant helpers
# ---------------------------------------------------------------------------------------------

def edge_pairing_defects(triangles):
    """(directed edges occurring more than once, directed edges whose reverse is missing)."""
    directed = Counter()
    for a, b, c in np.asarray(triangles).tolist():
        for e in ((a, b), (b, c), (c, a)):
            directed[e] += 1
    duplicated = sum(1 for n in directed.values() if n > 1)
    unpaired = sum(1 for (a, b) in directed if (b, a) not in directed)
    return duplicated, unpaired


def enclosed_volume(points, triangles):
    """Sum over triangles of det[a, b, c] / 6 (divergence theorem), origin at zero."""
    p = np.asarray(points)[np.asarray(triangles)]
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)


def assert_closed_outward(surface, volume, rel):
    assert len(surface.triangles) > 0
    duplicated, unpaired = edge_pairing_defects(surface.triangles)
    assert duplicated == 0, "a directed edge is used twice (inconsistent orientation)"
    assert unpaired == 0, "a directed edge has no reverse (open or non-manifold surface)"
    v = enclosed_volume(surface.points, surface.triangles)
    assert v > 0
    assert abs(v - volume) <= rel * abs(volume), (v, volume)
    # every triangle is tagged, with a valid face index, and no unused / duplicate points
    assert surface.face_tags is not None and len(surface.face_tags) == len(surface.triangles)
    assert np.all(surface.face_tags >= 0) and np.all(surface.face_tags < len(surface.face_names))
    assert len(np.unique(surface.triangles)) == len(surface.points)
    assert len(np.unique(surface.points, axis=0)) == len(surface.points)
    return v


def vertex_face_distances(fc, shape, surface):
    """For every (vertex, face of one of its triangles): (face index, distance from the vertex
    to that CAD face, the vertex as a Part.Vertex)."""
    freecad, Part = fc
    tags_of_vertex = {}
    for tri, tag in zip(surface.triangles.tolist(), surface.face_tags.tolist()):
        for v in tri:
            tags_of_vertex.setdefault(v, set()).add(tag)
    out = []
    for v, tags in tags_of_vertex.items():
        p = Part.Vertex(freecad.Vector(*surface.points[v]))
        for k in tags:
            out.append((k, shape.Faces[k].distToShape(p)[0], p))
    return out


def assert_on_faces(fc, shape, surface, tol):
    dists = vertex_face_distances(fc, shape, surface)
    worst = max(d for _, d, _ in dists)
    assert worst <= tol, worst


def face_normal_at_triangle(fc, face, centroid):
    freecad, _ = fc
    u, v = face.Surface.parameter(freecad.Vector(*centroid))
    n = face.normalAt(u, v)   # accounts for the face's orientation
    return np.array([n.x, n.y, n.z])


# ---------------------------------------------------------------------------------------------
# native shapes
# ---------------------------------------------------------------------------------------------

def test_box_is_exact(fc):
    _, Part = fc
    box = Part.makeBox(10, 4, 2)
    surfaces = ct.tessellate_shape(box, 0.1)
    assert len(surfaces) == 1
    s = surfaces[0]
    assert isinstance(s, Surface)
    assert s.points.shape == (8, 3) and s.triangles.shape == (12, 3)
    assert enclosed_volume(s.points, s.triangles) == pytest.approx(80.0, rel=1e-14, abs=1e-12)
    assert_closed_outward(s, box.Volume, 1e-12)
    assert sorted(Counter(s.face_tags.tolist()).items()) == [(k, 2) for k in range(6)]
    assert s.face_names == ["Face%d" % (k + 1) for k in range(6)]
    assert_on_faces(fc, box, s, 1e-7)
    # every triangle's normal is the outward normal of its CAD face (Reversed faces flipped)
    assert {f.Orientation for f in box.Faces} == {"Forward", "Reversed"}
    for tri, tag in zip(s.triangles, s.face_tags):
        a, b, c = s.points[tri]
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n)
        ref = face_normal_at_triangle(fc, box.Faces[tag], (a + b + c) / 3)
        assert np.dot(n, ref) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("make, rel", [
    (lambda P, V: P.makeCylinder(2, 5), 0.03),
    (lambda P, V: P.makeSphere(3), 0.03),                      # two poles (degenerated edges)
    (lambda P, V: P.makeCone(2, 0, 4), 0.03),                  # apex
    (lambda P, V: P.makeTorus(5, 1), 0.03),                    # doubly periodic, seams
    (lambda P, V: P.makeCylinder(2, 5).fuse(P.makeBox(3, 3, 3)).removeSplitter(), 0.03),
], ids=["cylinder", "sphere", "cone", "torus", "cylinder_fused_box"])
def test_curved_solids_closed_outward_on_faces(fc, make, rel):
    freecad, Part = fc
    shape = make(Part, freecad.Vector)
    (s,) = ct.tessellate_shape(shape, 0.05)
    assert_closed_outward(s, shape.Volume, rel)
    assert set(s.face_tags.tolist()) == set(range(len(shape.Faces)))
    assert_on_faces(fc, shape, s, 1e-7)


def test_finer_deflection_converges(fc):
    _, Part = fc
    cyl = Part.makeCylinder(10, 30)
    errors, counts = [], []
    for lin, ang in ((0.5, 0.5), (0.05, 0.2), (0.005, 0.1)):
        (s,) = ct.tessellate_shape(cyl, lin, angular_deflection=ang)
        assert_closed_outward(s, cyl.Volume, 0.05)
        errors.append(abs(enclosed_volume(s.points, s.triangles) - cyl.Volume) / cyl.Volume)
        counts.append(len(s.triangles))
    assert counts[0] < counts[1] < counts[2]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-3


def test_angular_deflection_and_relative_mode(fc):
    _, Part = fc
    cyl = Part.makeCylinder(2, 5)
    (coarse,) = ct.tessellate_shape(cyl, 1.0, angular_deflection=0.5)
    (fine,) = ct.tessellate_shape(cyl, 1.0, angular_deflection=0.1)
    assert len(fine.triangles) > 2 * len(coarse.triangles)
    (rel,) = ct.tessellate_shape(cyl, 0.01, angular_deflection=0.5, relative=True)
    assert_closed_outward(rel, cyl.Volume, 0.05)
    assert_on_faces(fc, cyl, rel, 1e-7)


def test_hollow_solid_void_faces_point_into_the_void(fc):
    freecad, Part = fc
    shape = Part.makeBox(10, 10, 10).cut(Part.makeBox(2, 2, 2, freecad.Vector(4, 4, 4)))
    assert len(shape.Solids) == 1 and len(shape.Solids[0].Shells) == 2
    (s,) = ct.tessellate_shape(shape, 0.1)
    assert enclosed_volume(s.points, s.triangles) == pytest.approx(992.0, rel=1e-12)
    assert_closed_outward(s, 992.0, 1e-12)
    # the material is at x < 4 next to the void's face x = 4: its outward normal is +x
    inner = [t for t, tri in enumerate(s.triangles) if np.all(s.points[tri][:, 0] == 4.0)
             and np.all(s.points[tri][:, 1] >= 4.0)]
    assert len(inner) == 2
    for t in inner:
        a, b, c = s.points[s.triangles[t]]
        assert np.cross(b - a, c - a)[0] > 0


def test_placement_gives_global_coordinates(fc):
    freecad, Part = fc
    box = Part.makeBox(1, 2, 3)
    box.Placement = freecad.Placement(freecad.Vector(5, -1, 2),
                                      freecad.Rotation(freecad.Vector(1, 1, 0), 30))
    (s,) = ct.tessellate_shape(box, 0.1)
    assert_closed_outward(s, 6.0, 1e-12)
    assert_on_faces(fc, box, s, 1e-7)
    bb = box.BoundBox
    assert s.points.min(axis=0) == pytest.approx([bb.XMin, bb.YMin, bb.ZMin], abs=1e-12)
    assert s.points.max(axis=0) == pytest.approx([bb.XMax, bb.YMax, bb.ZMax], abs=1e-12)


def test_compound_tags_index_the_original_faces(fc):
    freecad, Part = fc
    shape = Part.makeCompound([Part.makeSphere(1, freecad.Vector(5, 0, 0)),
                               Part.makeBox(1, 1, 1)])
    surfaces = ct.tessellate_shape(shape, 0.02, source="two solids")
    assert len(surfaces) == 2
    assert set(surfaces[0].face_tags.tolist()) == {0}
    assert set(surfaces[1].face_tags.tolist()) == set(range(1, 7))
    for s, solid in zip(surfaces, shape.Solids):
        assert s.face_names == ["Face%d" % (k + 1) for k in range(7)]
        assert_closed_outward(s, solid.Volume, 0.03)
        assert_on_faces(fc, shape, s, 1e-7)
    assert surfaces[1].source == "two solids, Solid2"


def test_callers_shape_keeps_no_triangulation(fc):
    _, Part = fc
    cyl = Part.makeCylinder(2, 5)
    (s,) = ct.tessellate_shape(cyl, 0.001)
    side = next(k for k, f in enumerate(cyl.Faces) if type(f.Surface).__name__ == "Cylinder")
    ours = int(np.sum(s.face_tags == side))
    # had the fine triangulation been stored on cyl, this call would reuse it
    _, tris = cyl.Faces[side].tessellate(100.0)
    assert len(tris) < ours / 10


# ---------------------------------------------------------------------------------------------
# shapes that are not solids, and other errors
# ---------------------------------------------------------------------------------------------

def test_closed_shell_is_refused_with_advice(fc):
    _, Part = fc
    with pytest.raises(InputError, match=r"shell \(6 faces\), not a solid.*Convert to solid"):
        ct.tessellate_shape(Part.makeBox(1, 1, 1).Shells[0], 0.1)


def test_open_shell_names_its_open_faces(fc):
    _, Part = fc
    faces = Part.makeBox(1, 1, 1).Faces
    shell = Part.Shell(faces[:5])          # Face6 (z = 1) missing
    with pytest.raises(InputError) as err:
        ct.tessellate_shape(shell, 0.1)
    msg = str(err.value)
    assert "not closed" in msg and "4 free edges" in msg
    # the four side faces touch the hole; Face5 (z = 0) does not
    assert "Face1 / Face2 / Face3 / Face4" in msg and "Face5" not in msg


def test_loose_faces_are_refused_naming_them(fc):
    _, Part = fc
    loose = Part.makeCompound(Part.makeBox(1, 1, 1).Faces[:3])
    with pytest.raises(InputError, match=r"compound of 3 faces, not a solid \(open boundary at "
                                         r"Face1 / Face2 / Face3"):
        ct.tessellate_shape(loose, 0.1)


def test_solid_with_extra_loose_face_names_the_face(fc):
    freecad, Part = fc
    shape = Part.makeCompound([Part.makeBox(1, 1, 1),
                               Part.makePlane(1, 1, freecad.Vector(5, 5, 5))])
    with pytest.raises(InputError, match=r"Face7 is not part of any solid"):
        ct.tessellate_shape(shape, 0.1)


@pytest.mark.parametrize("make, pattern", [
    (lambda P: P.Shape(), r"null shape"),
    (lambda P: P.makeCompound([]), r"empty compound"),
    (lambda P: P.Wire(P.makePolygon([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 0, 0)])),
     r"is a wire, without faces"),
    (lambda P: P.makeBox(1, 1, 1).reversed(), r"Solid1 is inverted"),
    (lambda P: P.Solid(P.Shell(P.makeBox(1, 1, 1).Faces[:5])), r"not a valid shape"),
], ids=["null", "empty_compound", "wire", "inverted_solid", "invalid_open_solid"])
def test_unusable_shapes_raise_input_error(fc, make, pattern):
    _, Part = fc
    with pytest.raises(InputError, match=pattern):
        ct.tessellate_shape(make(Part), 0.1)


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), "x"])
def test_bad_deflection_raises(fc, bad):
    _, Part = fc
    with pytest.raises(InputError, match="linear_deflection"):
        ct.tessellate_shape(Part.makeBox(1, 1, 1), bad)


def test_check_closed_names_faces_at_a_hole(fc):
    _, Part = fc
    (s,) = ct.tessellate_shape(Part.makeBox(1, 1, 1), 0.1)
    ct.check_closed(s)                                   # intact: no error
    drop = int(np.nonzero(s.face_tags == 0)[0][0])       # one triangle of Face1 (x = 0)
    keep = np.arange(len(s.triangles)) != drop
    holed = Surface(s.points, s.triangles[keep], s.face_tags[keep], s.face_names, "holed box")
    with pytest.raises(InputError) as err:
        ct.check_closed(holed)
    msg = str(err.value)
    assert msg.startswith("holed box: ")
    assert "3 edges shared by one triangle only" in msg and "Face1" in msg
    flipped = s.triangles.copy()
    flipped[drop] = flipped[drop][::-1]
    with pytest.raises(InputError, match="same direction"):
        ct.check_closed(Surface(s.points, flipped, s.face_tags, s.face_names))


def test_folded_triangle_pairs_of_one_face_are_dropped():
    # a tetrahedron surface plus, on face tag 0, a zero-volume fold (4, 5, 6) / (4, 6, 5)
    tris = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2], [4, 5, 6], [4, 6, 5],
                     [0, 1, 3]])
    tags = np.array([0, 1, 2, 3, 0, 0, 1])
    mask = ct._cancelling_pairs(tris, tags)
    assert mask.tolist() == [False] * 4 + [True, True, False]
    # the same fold split over two faces is not touched (it is reported as a defect instead)
    mask2 = ct._cancelling_pairs(tris, np.array([0, 1, 2, 3, 0, 1, 1]))
    assert not mask2.any()


def test_pole_fold_from_face_tessellation_is_removed(fc):
    """What BRepMesh gives on U_Joint_2.stp's B-spline faces with a pole (not in the test data:
    1.2 MB): two UV nodes of the pole become one 3D vertex and two triangles fold onto each
    other. The merged solid surface must come out closed, without the fold."""
    freecad, _ = fc
    V = freecad.Vector
    apex, a, b, c, d = V(0, 0, 1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0.2, 0.1, 0.5)

    class FakeFace:
        def __init__(self, index, verts, tris):
            self.index, self.verts, self.tris = index, verts, tris

        def tessellate(self, deflection):
            return self.verts, self.tris

    class FakeIndex:
        def find(self, face):
            return face.index

    class FakeSolid:
        # outward tetrahedron (a, b, c, apex): Face1 holds the three side triangles with the
        # pole twice (local nodes 0 and 4) plus a fold over (apex, a, d); Face2 is the bottom
        Faces = [FakeFace(0, [apex, a, b, c, apex, d],
                          [(1, 2, 0), (1, 4, 3), (2, 3, 0), (0, 1, 5), (4, 5, 1)]),
                 FakeFace(1, [a, c, b], [(0, 1, 2)])]

    surf, empty = ct._tessellate_solid(FakeSolid(), FakeIndex(), 1.0, ["Face1", "Face2"], "fake")
    assert empty == []
    assert len(surf.triangles) == 4 and surf.face_tags.tolist() == [0, 0, 0, 1]
    assert len(surf.points) == 4          # d, used only by the fold, is gone
    assert np.array_equal(surf.points[surf.triangles[3]], [[0, 0, 0], [0, 1, 0], [1, 0, 0]])
    ct.check_closed(surf)
    assert enclosed_volume(surf.points, surf.triangles) == pytest.approx(1 / 6)


# ---------------------------------------------------------------------------------------------
# files
# ---------------------------------------------------------------------------------------------

def test_bottle_brep(fc):
    _, Part = fc
    shape = Part.read(BOTTLE)
    surfaces = ct.tessellate_file(BOTTLE)
    assert len(surfaces) == 1
    s = surfaces[0]
    assert s.source == BOTTLE
    assert len(s.face_names) == len(shape.Faces) == 71
    assert set(s.face_tags.tolist()) == set(range(71))
    assert_closed_outward(s, shape.Solids[0].Volume, 0.01)
    # Every vertex lies on its faces within the face tolerance, except a few near edges whose
    # 3D curves and pcurves disagree (tolerances up to 0.0155 mm in this file; it fails BOP
    # check): those lie on the underlying surface, but up to ~2 edge tolerances outside the
    # trimmed face as BRepExtrema measures it.
    pairs = vertex_face_distances(fc, shape, s)
    off_face = 0
    for k, d, vertex in pairs:
        face = shape.Faces[k]
        if d <= face.Tolerance:
            continue
        off_face += 1
        u, v = face.Surface.parameter(vertex.Point)
        assert (face.Surface.value(u, v) - vertex.Point).Length <= 1e-6, (k, d)
        assert d <= 2 * max(e.Tolerance for e in face.Edges), (k, d)
    assert off_face <= 0.01 * len(pairs)
    assert off_face > 0   # this file does have such tolerant edges


def test_default_deflections_follow_the_documented_rule(fc):
    _, Part = fc
    shape = Part.read(BOTTLE)
    bb = shape.BoundBox
    diag = math.sqrt(bb.XLength ** 2 + bb.YLength ** 2 + bb.ZLength ** 2)
    (auto,) = ct.tessellate_file(BOTTLE)
    (ref,) = ct.tessellate_shape(shape, diag / 500.0)
    assert np.array_equal(auto.triangles, ref.triangles)
    assert np.array_equal(auto.points, ref.points)
    for h in (1.0, 50.0):   # h / 10 wins, then the diag / 200 cap wins
        (sized,) = ct.tessellate_file(BOTTLE, size=h)
        (ref,) = ct.tessellate_shape(shape, min(h / 10.0, diag / 200.0))
        assert np.array_equal(sized.points, ref.points)
    (explicit,) = ct.tessellate_file(BOTTLE, size=1.0, linear_deflection=0.5)
    (ref,) = ct.tessellate_shape(shape, 0.5)
    assert np.array_equal(explicit.points, ref.points)


def test_step_compound_of_two_solids(fc):
    _, Part = fc
    shape = Part.read(CUBE_CYLINDER)
    surfaces = ct.tessellate_file(CUBE_CYLINDER, linear_deflection=0.05)
    assert len(surfaces) == len(shape.Solids) == 2
    expected_tags = []
    for solid in shape.Solids:
        expected_tags.append({next(k for k, f in enumerate(shape.Faces) if f.isSame(g))
                              for g in solid.Faces})
    for s, solid, tags in zip(surfaces, shape.Solids, expected_tags):
        assert set(s.face_tags.tolist()) == tags
        assert s.face_names == ["Face%d" % (k + 1) for k in range(9)]
        assert_closed_outward(s, solid.Volume, 0.01)
        assert_on_faces(fc, shape, s, 1e-7)
    assert expected_tags[0] | expected_tags[1] == set(range(9))

    one = ct.surfaces_to_single(surfaces)
    assert len(one.points) == sum(len(s.points) for s in surfaces)
    assert len(one.triangles) == sum(len(s.triangles) for s in surfaces)
    assert one.face_names == surfaces[0].face_names
    assert np.array_equal(one.face_tags, np.concatenate([s.face_tags for s in surfaces]))
    assert_closed_outward(one, shape.Volume, 0.01)
    for t in range(0, len(one.triangles), 7):   # same geometry, triangle by triangle
        j = 0 if t < len(surfaces[0].triangles) else 1
        tt = t - (0 if j == 0 else len(surfaces[0].triangles))
        assert np.array_equal(one.points[one.triangles[t]],
                              surfaces[j].points[surfaces[j].triangles[tt]])


def test_surfaces_to_single_offsets_tags_of_different_shapes(fc):
    _, Part = fc
    (a,) = ct.tessellate_shape(Part.makeBox(1, 1, 1), 0.1, source="a")
    (b,) = ct.tessellate_shape(Part.makeCylinder(1, 1), 0.1, source="b")
    one = ct.surfaces_to_single([a, b])
    assert one.face_names == a.face_names + b.face_names
    assert np.array_equal(one.face_tags[len(a.triangles):], b.face_tags + 6)
    assert one.source == "a + b"
    with pytest.raises(InputError):
        ct.surfaces_to_single([])


def test_shell_only_step_file_is_refused(fc, tmp_path):
    """An open shell (a box without its top) written as STEP is not a solid: named, with advice."""
    _, Part = fc
    shell_only = str(tmp_path / "open_box.step")
    Part.Shell(Part.makeBox(10, 10, 10).Faces[:5]).exportStep(shell_only)
    with pytest.raises(InputError) as err:
        ct.tessellate_file(shell_only)
    msg = str(err.value)
    assert msg.startswith(shell_only + ": ")
    assert "shell (5 faces)" in msg and "not a solid" in msg and "Convert to solid" in msg
    assert "open boundary at Face" in msg


def test_file_errors(fc, tmp_path):
    garbage = tmp_path / "garbage.step"
    garbage.write_bytes(bytes(range(256)) * 20)
    with pytest.raises(InputError, match=r"garbage\.step: FreeCAD cannot read this file as STEP"):
        ct.tessellate_file(garbage)

    text = tmp_path / "notes.stp"
    text.write_text("this is not ISO-10303-21\n")
    with pytest.raises(InputError, match=r"notes\.stp: FreeCAD cannot read"):
        ct.tessellate_file(text)

    empty = tmp_path / "empty.brep"
    empty.write_bytes(b"")
    with pytest.raises(InputError, match=r"empty\.brep: the BREP file contains no shape"):
        ct.tessellate_file(empty)

    with pytest.raises(InputError, match=r"missing\.step: file not found"):
        ct.tessellate_file(tmp_path / "missing.step")

    with pytest.raises(InputError, match=r"unsupported CAD file extension '\.stl'"):
        ct.tessellate_file(tmp_path / "part.stl")


def test_upper_case_extension_and_brep_round_trip(fc, tmp_path):
    _, Part = fc
    box = Part.makeBox(3, 2, 1)
    path = tmp_path / "BOX.BREP"
    box.exportBrep(str(path))
    (s,) = ct.tessellate_file(path)
    assert_closed_outward(s, 6.0, 1e-12)


def test_copied_file_reads_the_same(fc, tmp_path):
    # a file name with spaces and several dots works too
    target = tmp_path / "my part.v2.step"
    shutil.copy(CUBE_CYLINDER, target)
    a = ct.tessellate_file(target, linear_deflection=0.1)
    b = ct.tessellate_file(CUBE_CYLINDER, linear_deflection=0.1)
    assert [len(s.triangles) for s in a] == [len(s.triangles) for s in b]


# ---------------------------------------------------------------------------------------------
# FreeCAD bootstrap
# ---------------------------------------------------------------------------------------------

def test_import_freecad_is_idempotent_and_loads_fem(fc):
    from FemBspTet.kernel.freecad_env import import_freecad

    freecad, _ = fc
    assert import_freecad() is freecad
    assert import_freecad(console=True) is freecad
    import ObjectsFem  # noqa: F401  (needs Mod/Fem on sys.path: the bootstrap did that)

    doc = freecad.newDocument("FemBspTetBootstrap")
    try:
        analysis = ObjectsFem.makeAnalysis(doc, "Analysis")
        assert analysis.TypeId == "Fem::FemAnalysis"
    finally:
        freecad.closeDocument(doc.Name)
