"""The OpenCASCADE projection hook on its own (FemBspTet.cad_projection): projected points lie on
the CAD face within its tolerance, so that FemMesh.getNodesByFace finds them; points between two
faces go onto their common CAD edge and are found by both faces and by the edge.

The shapes are moved by a non-trivial placement so that global coordinates are exercised.
"""

import math

import numpy as np
import pytest

from FemBspTet.errors import InputError
from FemBspTet.freecad_env import freecad_available

if not freecad_available():
    pytest.skip("FreeCAD (Debian package freecad-python3) is not available",
                allow_module_level=True)


def placed(fc, shape):
    freecad, _, _ = fc
    shape = shape.copy()
    shape.Placement = freecad.Placement(freecad.Vector(3.5, -7.25, 11.0),
                                        freecad.Rotation(freecad.Vector(1, 2, 3), 37.0))
    return shape


def plate_with_hole(fc):
    freecad, Part, _ = fc
    return placed(fc, Part.makeBox(60, 40, 8).cut(
        Part.makeCylinder(10, 8, freecad.Vector(30, 20, 0))))


def face_index(shape, kind):
    return [k for k, f in enumerate(shape.Faces) if type(f.Surface).__name__ == kind]


def nodes_found(fc, points, shape_part):
    """Ids (1-based) of ``points`` that FemMesh.getNodesBy{Face,Edge} returns for shape_part."""
    _, _, Fem = fc
    fem = Fem.FemMesh()
    for i, p in enumerate(points, start=1):
        fem.addNode(float(p[0]), float(p[1]), float(p[2]), i)
    if shape_part.ShapeType == "Face":
        return set(fem.getNodesByFace(shape_part))
    return set(fem.getNodesByEdge(shape_part))


def perturbed_points_near(face, n, offset, seed):
    """``n`` points of ``face`` (from its own parameter domain) moved ``offset`` mm off it along
    random directions."""
    rng = np.random.default_rng(seed)
    u0, u1, v0, v1 = face.ParameterRange
    pts = []
    while len(pts) < n:
        u, v = rng.uniform(u0, u1), rng.uniform(v0, v1)
        if not face.isPartOfDomain(u, v):
            continue
        p = face.Surface.value(u, v)
        d = rng.normal(size=3)
        d *= offset / np.linalg.norm(d)
        pts.append((p.x + d[0], p.y + d[1], p.z + d[2]))
    return pts


@pytest.mark.parametrize("kind", ["Cylinder", "Plane"])
def test_projected_points_are_found_by_get_nodes_by_face(fc, kind):
    from FemBspTet.cad_projection import CadProjection

    shape = plate_with_hole(fc)
    proj = CadProjection(shape)
    tag = face_index(shape, kind)[0]
    face = shape.Faces[tag]
    raw = perturbed_points_near(face, 40, 0.3, seed=tag)
    # the raw points are 0.3 mm off: getNodesByFace finds none of them
    assert nodes_found(fc, raw, face) == set()
    projected = [proj.to_face(p, tag) for p in raw]
    for q in projected:
        assert proj.distance_to_face(q, tag) < proj.face_tolerance(tag)
    assert nodes_found(fc, projected, face) == set(range(1, len(projected) + 1))
    # idempotent: a projected point stays where it is
    for q in projected:
        again = proj.to_face(q, tag)
        assert math.dist(again, q) <= 1e-9
    # the core's hook gives the same points where the surface's nearest point is inside the
    # trimmed face, and refuses (non-finite) the others
    for p, q in zip(raw, projected):
        h = proj(p, tag)
        if all(math.isfinite(c) for c in h):
            assert h == q
        else:
            assert all(math.isnan(c) for c in h)


def test_points_outside_the_trimmed_face_go_to_its_boundary(fc):
    """A point whose nearest point on the untrimmed plane lies in the hole: the nearest point of
    the bounded face is on the hole's edge, still on the face."""
    from FemBspTet.cad_projection import CadProjection

    freecad, Part, _ = fc
    shape = Part.makeBox(60, 40, 8).cut(Part.makeCylinder(10, 8, freecad.Vector(30, 20, 0)))
    proj = CadProjection(shape)
    top = [k for k in face_index(shape, "Plane") if abs(shape.Faces[k].CenterOfMass.z - 8) < 1e-9]
    assert len(top) == 1
    q = proj.to_face((33.0, 20.0, 9.0), top[0])  # above the hole, 3 mm from its axis
    assert proj.distance_to_face(q, top[0]) < proj.face_tolerance(top[0])
    assert abs(math.hypot(q[0] - 30, q[1] - 20) - 10) < 1e-9 and abs(q[2] - 8) < 1e-12
    # the core's hook refuses such a point (a mesh vertex inside the face put onto its edge
    # would make a flat fin triangle there), and takes one over the face's material
    assert all(math.isnan(c) for c in proj((33.0, 20.0, 9.0), top[0]))
    assert proj((45.0, 20.0, 9.0), top[0]) == (45.0, 20.0, 8.0)


def test_point_between_two_faces_goes_onto_their_common_edge(fc):
    from FemBspTet.cad_projection import CadProjection

    shape = plate_with_hole(fc)
    proj = CadProjection(shape)
    cyl = face_index(shape, "Cylinder")[0]
    planes = [k for k in face_index(shape, "Plane") if proj.common_edges(cyl, k)]
    assert len(planes) == 2  # top and bottom share a circle with the hole
    for k in planes:
        edge = proj.common_edges(cyl, k)[0]
        t0, t1 = edge.ParameterRange
        raw = []
        centre = shape.Faces[cyl].CenterOfMass  # on the hole's axis, half-way up
        for j in range(12):
            p = edge.valueAt(t0 + (t1 - t0) * (j + 0.5) / 12)
            d = centre - p
            d.normalize()
            raw.append((p.x + 0.3 * d.x, p.y + 0.3 * d.y, p.z + 0.3 * d.z))  # off both faces
        projected = [proj.to_faces(p, {cyl, k}) for p in raw]
        ids = set(range(1, len(projected) + 1))
        assert nodes_found(fc, projected, shape.Faces[cyl]) == ids
        assert nodes_found(fc, projected, shape.Faces[k]) == ids
        assert nodes_found(fc, projected, edge) == ids
        # projecting onto one face only is not enough for the other face
        one_face = [proj.to_face(p, cyl) for p in raw]
        assert nodes_found(fc, one_face, shape.Faces[k]) != ids


def test_three_faces_meet_at_a_vertex(fc):
    from FemBspTet.cad_projection import CadProjection

    _, Part, _ = fc
    box = Part.makeBox(2, 3, 4)
    proj = CadProjection(box)
    corner_faces = [k for k, f in enumerate(box.Faces)
                    if any(v.Point.Length == 0 for v in f.Vertexes)]
    assert len(corner_faces) == 3
    assert proj.to_faces((0.1, -0.2, 0.05), corner_faces) == (0.0, 0.0, 0.0)


def test_bad_face_tag_is_an_input_error(fc):
    from FemBspTet.cad_projection import CadProjection

    _, Part, _ = fc
    proj = CadProjection(Part.makeBox(1, 1, 1))
    with pytest.raises(InputError, match="face tag 6 is not a face"):
        proj((0, 0, 0), 6)
    # Face1 (x=0) and Face2 (x=1) of a box are opposite: no point is on both; the nearest
    # point of the nearer face, recorded
    assert proj.to_faces((0.25, 0.5, 0.5), {0, 1}) == (0.0, 0.5, 0.5)
    assert proj.to_faces((0.75, 0.5, 0.5), {0, 1}) == (1.0, 0.5, 0.5)
    assert proj.disjoint_placements == [(0, 1), (0, 1)]


def test_touching_solids_keep_their_own_faces(fc):
    """Two boxes of a compound touching at x = 10: the coinciding contact faces are told apart
    by orientation, so every boundary triangle there takes its own solid's face and no node is
    put on a face of the other solid (before: "faces Face2, Face7 have no common CAD edge")."""
    freecad, Part, _ = fc
    from FemBspTet import mesh_pipeline as mp

    a = Part.makeBox(10, 10, 10)
    b = Part.makeBox(10, 10, 10, freecad.Vector(10, 0, 0))
    shape = Part.makeCompound([a, b])
    result = mp.mesh_cad_shape(shape, mp.MeshParameters(max_size=4, order=2))
    assert not result.notes, result.notes
    pts = result.mesh.points
    faces = result.boundary_faces
    on_contact = np.all(pts[faces][:, :, 0] == 10.0, axis=1)
    normals = np.cross(pts[faces[:, 1]] - pts[faces[:, 0]], pts[faces[:, 2]] - pts[faces[:, 0]])
    contact_tags = {+1: set(), -1: set()}
    for k in np.nonzero(on_contact)[0].tolist():
        contact_tags[int(np.sign(normals[k, 0]))].add(int(result.boundary_face_tags[k]))
    (plus,), (minus,) = contact_tags[+1], contact_tags[-1]
    of_solid = [{k for k, f in enumerate(shape.Faces) if any(f.isSame(g) for g in sol.Faces)}
                for sol in shape.Solids]
    # outward +x at x = 10 is the first box's face, outward -x the second box's
    assert plus in of_solid[0] and plus not in of_solid[1]
    assert minus in of_solid[1] and minus not in of_solid[0]
