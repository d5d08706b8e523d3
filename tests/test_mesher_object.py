# SPDX-License-Identifier: LGPL-2.1-or-later
"""The FreeCAD mesher object, headless: creation, properties, meshing through the FEM path (in
process and in the worker process), SMESH conventions, every boundary node found by
getNodesByFace (tet4 and tet10 with mid-nodes on curved faces), node groups per CAD face, tet10
certified valid, failures that keep the previous mesh, save/reload (and the upgrade of files
with the former tessellation parameters), export.
"""

import os

import numpy as np
import pytest

from FemBspTet.kernel.errors import InputError, MeshingCancelled
from FemBspTet.kernel.freecad_env import freecad_available

if not freecad_available():
    pytest.skip("FreeCAD (Debian package freecad-python3) is not available",
                allow_module_level=True)

import FemBspTet  # noqa: E402
from FemBspTet.kernel import core  # noqa: E402
from FemBspTet.fem import mesh_pipeline as mp  # noqa: E402
from FemBspTet.freecad.mesher_object import MeshBspTet, set_source, source_of  # noqa: E402
from FemBspTet.freecad.mesher_tools import comparison_line, comparison_rows  # noqa: E402

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "cad")


@pytest.fixture
def doc(fc):
    freecad = fc[0]
    d = freecad.newDocument("MesherTest")
    name = d.Name
    yield d
    if name in freecad.listDocuments():
        freecad.closeDocument(name)


def add_part(doc, fc, shape, name="Part"):
    obj = doc.addObject("Part::Feature", name)
    obj.Shape = shape
    doc.recompute()
    return obj


def block_with_hole(fc):
    freecad, Part, _ = fc
    return Part.makeBox(40, 20, 10).cut(Part.makeCylinder(5, 10, freecad.Vector(20, 10, 0)))


def smesh_signed_volumes(fem):
    """(p2-p1) x (p3-p1) . (p4-p1) of every volume of a FemMesh (SMESH: negative)."""
    nodes = fem.Nodes
    out = []
    for e in fem.Volumes:
        n = fem.getElementNodes(e)
        p = [np.array(nodes[i]) for i in n[:4]]
        out.append(float(np.dot(np.cross(p[1] - p[0], p[2] - p[0]), p[3] - p[0])))
    return np.array(out)


def assert_every_face_node_found(result, fem, shape):
    for k, face in enumerate(shape.Faces):
        want = set((result.face_nodes(k) + 1).tolist())
        found = set(fem.getNodesByFace(face))
        assert want, "Face%d has no boundary nodes" % (k + 1)
        assert want <= found, ("Face%d: %d boundary nodes not found, e.g. %s"
                               % (k + 1, len(want - found), sorted(want - found)[:5]))


# ------------------------------------------------------------------------------- the object

def test_make_mesher_creates_an_unmeshed_fem_mesh_object(doc, fc):
    part = add_part(doc, fc, block_with_hole(fc))
    obj = FemBspTet.make_mesher(doc, part, CharacteristicLengthMax=4, ElementOrder="1st",
                                CompareWithPeers=False)
    if "Fem::FemMeshShapeBaseObjectPython" in doc.supportedTypes():  # FreeCAD 1.x
        assert obj.TypeId == "Fem::FemMeshShapeBaseObjectPython"
        assert obj.Shape is part and "Part" not in obj.PropertiesList
    else:  # FreeCAD 0.20/0.21
        assert obj.TypeId == "Fem::FemMeshObjectPython"
        assert obj.Part is part
    assert source_of(obj) is part
    assert obj.isDerivedFrom("Fem::FemMeshObject")
    assert obj.Proxy.Type == "Fem::FemMeshBspTet"
    assert obj.CharacteristicLengthMax.Value == 4 and obj.ElementOrder == "1st"
    assert obj.ElementOrder in obj.getEnumerationsOfProperty("ElementOrder")
    assert obj.getEnumerationsOfProperty("ElementOrder") == ["1st", "2nd"]
    for name in ("Nodes", "Tetrahedra", "MinDihedralAngle", "Comparison", "MeshStatus"):
        assert "ReadOnly" in obj.getEditorMode(name)
    assert "Hidden" in obj.getEditorMode("ComparisonData")
    # faces and groups per CAD face by default; short group names the property editor shows
    assert obj.FaceGroups is True and obj.CompareWithPeers is False
    assert obj.getGroupOfProperty("CharacteristicLengthMax") == "Mesh Params"
    assert obj.getGroupOfProperty("Nodes") == "Mesh Results"
    doc.recompute()  # recompute never meshes
    assert obj.FemMesh.NodeCount == 0 and obj.Nodes == 0


def test_make_mesher_refuses_unknown_properties(doc, fc):
    part = add_part(doc, fc, block_with_hole(fc))
    with pytest.raises(InputError, match="unknown mesher property CharacteristicLength;"):
        FemBspTet.make_mesher(doc, part, CharacteristicLength=3)
    with pytest.raises(InputError, match="CompareWithTetGen is called CompareWithPeers"):
        FemBspTet.make_mesher(doc, part, CompareWithTetGen=False)
    assert [o.Name for o in doc.Objects] == [part.Name]


def test_femutils_sees_our_type_not_gmsh(doc, fc):
    from femtools import femutils

    obj = FemBspTet.make_mesher(doc, add_part(doc, fc, block_with_hole(fc)))
    assert femutils.type_of_obj(obj) == "Fem::FemMeshBspTet"
    assert not femutils.is_of_type(obj, "Fem::FemMeshGmsh")


# ------------------------------------------------------------------------------- meshing

def test_run_mesher_tet4_smesh_conventions_and_face_nodes(doc, fc):
    part = add_part(doc, fc, block_with_hole(fc))
    obj = FemBspTet.make_mesher(doc, part, ElementOrder="1st", CompareWithPeers=True)
    result = FemBspTet.run_mesher(obj)
    fem = obj.FemMesh
    assert fem.NodeCount == obj.Nodes == len(result.mesh.points)
    assert fem.VolumeCount == fem.TetraCount == obj.Tetrahedra == len(result.mesh.tets)
    assert np.all(smesh_signed_volumes(fem) < 0)
    # nodes are ours, in order, in global mm
    coords = np.array([fem.Nodes[i + 1] for i in range(fem.NodeCount)])
    assert np.array_equal(coords, result.mesh.points)
    assert_every_face_node_found(result, fem, part.Shape)
    # the tet volume is the solid's volume (up to the chords of the hole)
    assert abs(-smesh_signed_volumes(fem).sum() / 6 - part.Shape.Volume) < 0.01 * part.Shape.Volume
    assert obj.MeshStatus == "meshed: %d nodes, %d tet4" % (obj.Nodes, obj.Tetrahedra)
    # the comparison at the same size: ours, TetGen on our surface, Gmsh and Netgen on the part
    rows = {r["mesher"]: r for r in result.comparison}
    assert list(rows) == ["FemBspTet", "TetGen", "Gmsh", "Netgen"]
    assert all(r["status"] == "ok" for r in rows.values()), rows
    assert (rows["FemBspTet"]["nodes"], rows["FemBspTet"]["tets"]) == (obj.Nodes, obj.Tetrahedra)
    assert rows["FemBspTet"]["min_dihedral_deg"] == pytest.approx(obj.MinDihedralAngle)
    size = result.stats["size"]
    assert rows["TetGen"]["command"] == "tetgen -pq1.414a%.6g" % (size ** 3 / (6 * 2 ** 0.5))
    assert rows["Gmsh"]["command"] == "gmsh -3 -clmax %.4g -order 1" % size
    for name, row in rows.items():
        # the same part at the same size: counts of one order of magnitude, sane angles
        assert 0.2 < row["tets"] / obj.Tetrahedra < 5, (name, row, obj.Tetrahedra)
        assert 0 < row["min_dihedral_deg"] <= row["median_tet_min_dihedral_deg"] < 70.6
        assert row["seconds"] > 0
    assert len(obj.Comparison) == 4 and obj.Comparison[1].startswith("TetGen (tetgen -pq")
    assert comparison_rows(obj)[0].to_dict() == result.comparison[0]
    assert obj.MeshingTime > 0 and obj.MinDihedralAngle > 0 and obj.MaxRadiusEdgeRatio > 0


def test_comparison_row_of_a_missing_peer(monkeypatch, tmp_path):
    from FemBspTet.compare.at_size import gmsh_row, tetgen_row
    from FemBspTet.io.surface_io import read_surface
    from conftest import paper_path

    monkeypatch.setenv("PATH", str(tmp_path))  # no tetgen, no gmsh on it
    row = tetgen_row(read_surface(paper_path("schoenhardt")), 1.0, 1)
    assert row.status == "skipped" and "tetgen is not installed" in row.message
    row = gmsh_row(str(tmp_path / "part.brep"), 1.0, 2)
    assert row.status == "skipped" and "gmsh is not installed" in row.message
    assert comparison_line(row) == "Gmsh (gmsh -3 -clmax 1 -order 2): skipped, gmsh is not " \
        "installed"


# ------------------------------------------------------------------------------- 2D

@pytest.mark.parametrize("order", ["1st", "2nd"])
def test_2d_mesh_of_a_face_and_a_shell(doc, fc, order):
    """A Face (a plate with a hole) and an open Shell mesh as triangles ("From Shape": no solid,
    so 2D): FemMesh faces only (tria3 / tria6), a face group and a node group per CAD face, every
    node on its CAD face (getNodesByFace finds them all), the plate's area covered."""
    freecad, Part, _ = fc
    plate = Part.makePlane(40, 20).cut(Part.makeCylinder(5, 1, freecad.Vector(20, 10, -0.5)))
    shell = Part.Shell(Part.makeBox(10, 10, 10).Faces[:5])
    for shape, name in ((plate.Faces[0], "Plate"), (shell, "OpenBox")):
        part = add_part(doc, fc, shape, name)
        obj = FemBspTet.make_mesher(doc, part, ElementOrder=order, CharacteristicLengthMax=2.5)
        assert obj.ElementDimension == "From Shape" and obj.FaceGroups is True
        result = FemBspTet.run_mesher(obj)
        fem = obj.FemMesh
        k = 3 if order == "1st" else 6
        assert fem.VolumeCount == 0 and obj.Tetrahedra == 0
        assert fem.FaceCount == fem.TriangleCount == obj.Triangles == len(result.boundary_faces)
        assert fem.NodeCount == obj.Nodes == len(result.mesh.points)
        assert {len(fem.getElementNodes(e)) for e in fem.Faces} == {k}
        assert obj.MeshStatus == "meshed: %d nodes, %d tria%d" % (obj.Nodes, obj.Triangles, k)
        assert fem.GroupCount == 2 * len(shape.Faces)
        assert_every_face_node_found(result, fem, part.Shape)
        # mid-nodes (tria6) and corners lie on the CAD
        pts = result.mesh.points
        for i in range(0, len(pts), max(1, len(pts) // 60)):
            assert shape.distToShape(Part.Vertex(freecad.Vector(*pts[i])))[0] < 1e-9
        if name == "Plate":
            tri = result.boundary_faces
            a, b, c = (pts[tri[:, j]] for j in range(3))
            area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
            # the hole's chords cut off a little of it: a little more than the CAD area
            assert shape.Area < area < 1.01 * shape.Area
    # a solid asked for 2D: its faces as triangles, no tets
    obj = FemBspTet.make_mesher(doc, add_part(doc, fc, block_with_hole(fc), "Block"),
                                ElementDimension="2D", ElementOrder=order,
                                CompareWithPeers=False)
    FemBspTet.run_mesher(obj)
    assert obj.FemMesh.VolumeCount == 0 and obj.FemMesh.FaceCount == obj.Triangles > 0


def test_2d_mesh_in_the_worker_process_equals_the_in_process_one(fc):
    """The task panel's worker meshes a Face as the in-process run does (same BREP text)."""
    from FemBspTet.freecad.mesh_worker import MeshJob

    freecad, Part, _ = fc
    face = Part.makePlane(40, 20).cut(Part.makeCylinder(5, 1, freecad.Vector(20, 10, -0.5)))
    face = face.Faces[0]
    params = mp.MeshParameters(max_size=3.0, order=2, dimension=2)
    job = MeshJob(face, params, python="/usr/bin/python3")
    job.start()
    assert job.wait(120)
    worker = job.result()
    here = mp.mesh_cad_shape(face, params)
    assert worker.mesh.tets.shape == (0, 4) and len(worker.boundary_faces) > 0
    assert np.array_equal(worker.mesh.points, here.mesh.points)
    assert np.array_equal(worker.boundary_faces, here.boundary_faces)
    assert np.array_equal(worker.boundary_midnodes, here.boundary_midnodes)
    assert worker.boundary_midnodes.shape == (len(worker.boundary_faces), 3)


def test_a_face_asked_for_3d_says_what_to_do(doc, fc):
    freecad, Part, _ = fc
    part = add_part(doc, fc, Part.makePlane(10, 10), "Plane")
    obj = FemBspTet.make_mesher(doc, part, ElementDimension="3D")
    with pytest.raises(InputError, match="holds no solid"):
        FemBspTet.run_mesher(obj)
    assert obj.MeshStatus.startswith("failed: ") and obj.FemMesh.NodeCount == 0


def assert_ccx_faces_are_the_boundary_faces(result, fem, shape, k):
    """FreeCAD's getccxVolumesByFace (what its CalculiX writer loads) gives, for CAD face k,
    exactly our boundary triangles tagged k: one (volume, CalculiX face) per triangle, each face
    being such a triangle. It decides by node membership only, so a tet with four corners on the
    face, or three that are not its face there, would be missed or loaded wrongly."""
    ccx_faces = {1: (0, 1, 2), 2: (0, 3, 1), 3: (1, 3, 2), 4: (2, 3, 0)}  # CalculiX, 1-based
    ccx_order = (1, 0, 2, 3)  # SMESH tet corner order -> CalculiX (FemMesh.cpp)
    want = {tuple(sorted(f)) for f in (result.boundary_faces[result.boundary_face_tags == k] + 1)
            .tolist()}
    got = set()
    for volume, face in fem.getccxVolumesByFace(shape.Faces[k]):
        corners = fem.getElementNodes(volume)[:4]
        ccx = [corners[i] for i in ccx_order]
        got.add(tuple(sorted(ccx[i] for i in ccx_faces[face])))
    assert got == want, (k, len(got), len(want), sorted(got ^ want)[:5])


def test_ccx_faces_of_a_block_with_a_hole_are_the_boundary_faces(doc, fc):
    part = add_part(doc, fc, block_with_hole(fc))
    for order in ("1st", "2nd"):
        obj = FemBspTet.make_mesher(doc, part, ElementOrder=order, CompareWithPeers=False)
        result = FemBspTet.run_mesher(obj)
        for k in range(len(part.Shape.Faces)):
            assert_ccx_faces_are_the_boundary_faces(result, obj.FemMesh, part.Shape, k)


def test_tet10_midnodes_on_a_cylinder_are_found_by_get_nodes_by_face(doc, fc):
    """Curved face, tet10: every boundary node of every face, mid-nodes included, is found;
    CalculiX's face search finds one element face per boundary triangle; every element is
    certified valid."""
    _, Part, _ = fc
    part = add_part(doc, fc, Part.makeCylinder(10, 30))
    obj = FemBspTet.make_mesher(doc, part, ElementOrder="2nd", CompareWithPeers=False)
    result = FemBspTet.run_mesher(obj)
    fem = obj.FemMesh
    assert result.mesh.tets.shape[1] == 10 and result.stats["midnodes_projected"] > 0
    assert_every_face_node_found(result, fem, part.Shape)
    side = [k for k, f in enumerate(part.Shape.Faces) if type(f.Surface).__name__ == "Cylinder"]
    k = side[0]
    for j in range(len(part.Shape.Faces)):
        assert_ccx_faces_are_the_boundary_faces(result, fem, part.Shape, j)
    assert core.certify_tet10(result.mesh)["certified"] == len(result.mesh.tets)
    # the mid-nodes on the side are on the cylinder, not on the chords
    mids = np.unique(result.boundary_midnodes[result.boundary_face_tags == k])
    r = np.hypot(result.mesh.points[mids, 0], result.mesh.points[mids, 1])
    assert np.max(np.abs(r - 10)) < 1e-9
    assert result.notes == []


def assert_nodes_on_their_cad_faces(result, shape):
    """Every boundary node (corners and tet10 mid-nodes) of every CAD face's triangles lies within
    that face's tolerance of the bounded face, as FemMesh.getNodesByFace measures."""
    import FreeCAD
    import Part

    for k, face in enumerate(shape.Faces):
        nodes = result.face_nodes(k)
        assert len(nodes), "Face%d has no boundary nodes" % (k + 1)
        worst = max(face.distToShape(Part.Vertex(FreeCAD.Vector(*p)))[0]
                    for p in result.mesh.points[nodes].tolist())
        assert worst <= face.Tolerance, ("Face%d" % (k + 1), worst, face.Tolerance)


@pytest.mark.parametrize("name, solids", [("bracket.step", 1), ("red_cube_blue_cylinder.step", 2)])
def test_cad_parts_tet10_on_the_cad_certified_with_face_groups(doc, fc, name, solids):
    """CAD files through the object (tet10, face groups): every boundary node on its CAD face,
    every element certified valid, one node group per CAD face holding exactly that face's
    boundary nodes, each found by getNodesByFace; one or two solids."""
    _, Part, _ = fc
    part = add_part(doc, fc, Part.read(os.path.join(DATA, name)), "Cad")
    assert len(part.Shape.Solids) == solids
    obj = FemBspTet.make_mesher(doc, part, ElementOrder="2nd", FaceGroups=True,
                                CompareWithPeers=False)
    result = FemBspTet.run_mesher(obj)
    mesh = result.mesh
    assert mesh.tets.shape[1] == 10
    assert core.certify_tet10(mesh)["certified"] == len(mesh.tets)
    assert_nodes_on_their_cad_faces(result, part.Shape)
    fem = obj.FemMesh
    assert_every_face_node_found(result, fem, part.Shape)
    groups = {fem.getGroupName(g): g for g in fem.Groups}
    assert sorted(groups) == sorted("BspTet_Face%d" % (k + 1)
                                    for k in range(len(part.Shape.Faces)))
    for k in range(len(part.Shape.Faces)):
        got = set(fem.getGroupElements(groups["BspTet_Face%d" % (k + 1)]))
        assert got == set((result.face_nodes(k) + 1).tolist())
    # the boundary triangles are closed and outward: they enclose the tets' volume
    p = mesh.points
    f = result.boundary_faces
    enclosed = np.einsum("ij,ij->i", p[f[:, 0]], np.cross(p[f[:, 1]], p[f[:, 2]])).sum() / 6
    assert enclosed == pytest.approx(-smesh_signed_volumes(fem).sum() / 6, rel=1e-9)


def test_face_groups(doc, fc):
    part = add_part(doc, fc, block_with_hole(fc))
    obj = FemBspTet.make_mesher(doc, part, ElementOrder="1st", FaceGroups=True,
                                CompareWithPeers=False)
    result = FemBspTet.run_mesher(obj)
    fem = obj.FemMesh
    groups = {fem.getGroupName(g): g for g in fem.Groups}
    assert sorted(groups) == sorted("BspTet_Face%d" % (k + 1)
                                    for k in range(len(part.Shape.Faces)))
    for k in range(len(part.Shape.Faces)):
        g = groups["BspTet_Face%d" % (k + 1)]
        assert fem.getGroupElementType(g) == "Node"
        assert set(fem.getGroupElements(g)) == set((result.face_nodes(k) + 1).tolist())


def test_failure_keeps_the_previous_mesh(doc, fc):
    _, Part, _ = fc
    part = add_part(doc, fc, block_with_hole(fc))
    obj = FemBspTet.make_mesher(doc, part, ElementOrder="1st", CompareWithPeers=False,
                                ElementDimension="3D")  # an open shell cannot be 3D
    FemBspTet.run_mesher(obj)
    before = (obj.FemMesh.NodeCount, obj.FemMesh.VolumeCount, obj.Nodes)
    shell = add_part(doc, fc, Part.Shell(Part.makeBox(1, 1, 1).Faces[:5]), "OpenShell")
    set_source(obj, shell)
    with pytest.raises(InputError, match=r"holds no solid \(1 shell\(s\), 5 face\(s\)\)"):
        FemBspTet.run_mesher(obj)
    assert (obj.FemMesh.NodeCount, obj.FemMesh.VolumeCount, obj.Nodes) == before
    assert obj.MeshStatus.startswith("failed: ") and "holds no solid" in obj.MeshStatus
    set_source(obj, None)
    with pytest.raises(InputError, match="no solid is set"):
        FemBspTet.run_mesher(obj)
    assert obj.FemMesh.NodeCount == before[0]


def test_cancel_keeps_the_previous_mesh(doc, fc):
    part = add_part(doc, fc, block_with_hole(fc))
    obj = FemBspTet.make_mesher(doc, part, ElementOrder="1st", CompareWithPeers=False)
    FemBspTet.run_mesher(obj)
    nodes = obj.FemMesh.NodeCount
    with pytest.raises(MeshingCancelled):
        FemBspTet.run_mesher(obj, cancel=lambda: True)
    assert obj.FemMesh.NodeCount == nodes and obj.MeshStatus.startswith("failed: cancelled")


def test_sizes_are_honoured(doc, fc):
    """CharacteristicLengthMax/Min act on the mesh: a smaller size gives more tets, and no edge
    is longer than twice the size (the refinement splits longer ones)."""
    part = add_part(doc, fc, block_with_hole(fc))
    counts = {}
    for h in (8.0, 4.0):
        obj = FemBspTet.make_mesher(doc, part, ElementOrder="1st", CompareWithPeers=False,
                                    CharacteristicLengthMax=h, CharacteristicLengthMin=0.5)
        result = FemBspTet.run_mesher(obj)
        p, t = result.mesh.points, result.mesh.tets
        edges = np.unique(np.sort(np.concatenate(
            [t[:, [i, j]] for i in range(4) for j in range(i + 1, 4)]), axis=1), axis=0)
        lengths = np.linalg.norm(p[edges[:, 0]] - p[edges[:, 1]], axis=1)
        assert lengths.max() <= 2.0 * h
        assert result.stats["size"] == h and result.stats["min_size"] == 0.5
        counts[h] = len(t)
    assert counts[4.0] > 1.2 * counts[8.0], counts  # 840 -> 1193 when written


def test_former_parameters_are_refused_with_the_reason(doc, fc):
    """The tessellation pipeline's parameters are gone: make_mesher, mesh_shape and
    MeshParameters refuse them, saying why; new objects do not have them."""
    _, Part, _ = fc
    part = add_part(doc, fc, block_with_hole(fc))
    with pytest.raises(InputError, match="LinearDeflection no longer exists: the mesher meshes "
                                         "the CAD faces itself"):
        FemBspTet.make_mesher(doc, part, LinearDeflection=0.1)
    with pytest.raises(InputError, match="parameters RemeshSurface, StraightenMidNodes no longer "
                                         "exist"):
        FemBspTet.mesh_shape(Part.makeBox(1, 1, 1), RemeshSurface=True, StraightenMidNodes=False)
    with pytest.raises(InputError, match="quality_bound no longer exists"):
        mp.MeshParameters.from_dict({"quality_bound": 1.5})
    obj = FemBspTet.make_mesher(doc, part)
    for name in mp.REMOVED_PARAMETERS.values():
        assert name not in obj.PropertiesList
    assert [o.Name for o in doc.Objects] == [part.Name, obj.Name]


def test_parameters_are_validated_with_property_names():
    with pytest.raises(InputError, match="CharacteristicLengthMax must be a finite number"):
        mp.MeshParameters(max_size=-1).validate()
    with pytest.raises(InputError, match="CharacteristicLengthMin .* is larger than"):
        mp.MeshParameters(max_size=1, min_size=2).validate()
    with pytest.raises(InputError, match="ElementOrder must be 1st or 2nd"):
        mp.MeshParameters(order=3).validate()
    with pytest.raises(InputError, match="unknown mesh parameter"):
        mp.MeshParameters.from_dict({"size": 3})
    p = mp.MeshParameters(max_size=5, order=1)
    assert mp.MeshParameters.from_dict(p.to_dict()) == p


def test_mesh_shape_returns_a_femmesh(fc):
    _, Part, Fem = fc
    fem = FemBspTet.mesh_shape(Part.makeBox(3, 4, 5), ElementOrder="2nd")
    assert isinstance(fem, Fem.FemMesh)
    assert fem.VolumeCount > 0 and len(fem.getElementNodes(fem.Volumes[0])) == 10
    assert np.all(smesh_signed_volumes(fem) < 0)
    fem1 = FemBspTet.mesh_shape(Part.makeBox(3, 4, 5), order=1, face_groups=True,
                                CharacteristicLengthMax=2)
    assert len(fem1.getElementNodes(fem1.Volumes[0])) == 4 and fem1.GroupCount == 12
    kinds = sorted(fem1.getGroupElementType(g) for g in fem1.Groups)
    assert kinds == ["Face"] * 6 + ["Node"] * 6 and fem1.FaceCount > 0
    nodes = fem1.Nodes
    longest = max((nodes[a] - nodes[b]).Length for e in fem1.Volumes
                  for a in fem1.getElementNodes(e) for b in fem1.getElementNodes(e))
    assert longest <= 4.0  # no edge longer than twice CharacteristicLengthMax


# ------------------------------------------------------------------------------- worker

def test_worker_process_gives_the_same_mesh_as_in_process(fc):
    from FemBspTet.freecad.mesh_worker import MeshJob

    shape = block_with_hole(fc)
    params = mp.MeshParameters(order=1, compare_peers=False)
    local = mp.mesh_cad_shape(shape, params)
    job = MeshJob(shape, params, python="/usr/bin/python3")
    job.start()
    assert job.wait(120)
    events = job.poll()
    assert events and events[-1] == ("done", 1.0)
    remote = job.result()
    assert np.array_equal(remote.mesh.points, local.mesh.points)
    assert np.array_equal(remote.mesh.tets, local.mesh.tets)
    assert np.array_equal(remote.boundary_face_tags, local.boundary_face_tags)


def test_worker_reports_input_errors_and_can_be_cancelled(fc):
    from FemBspTet.freecad.mesh_worker import MeshJob

    _, Part, _ = fc
    job = MeshJob(Part.Shell(Part.makeBox(1, 1, 1).Faces[:5]), mp.MeshParameters(),
                  python="/usr/bin/python3")
    job.start()
    job.wait(120)
    with pytest.raises(InputError, match="holds no solid"):
        job.result()
    job = MeshJob(block_with_hole(fc), mp.MeshParameters(order=1), python="/usr/bin/python3")
    job.start()
    job.cancel()
    assert not job.running
    with pytest.raises(MeshingCancelled):
        job.result()
    with pytest.raises(InputError, match="does not exist"):
        MeshJob(block_with_hole(fc), mp.MeshParameters(), python="/nonexistent/python").start()


# ------------------------------------------------------------------------------- files

def test_save_and_reload(doc, fc, tmp_path):
    freecad = fc[0]
    part = add_part(doc, fc, block_with_hole(fc))
    part_name = part.Name
    obj = FemBspTet.make_mesher(doc, part, ElementOrder="2nd", FaceGroups=True,
                                CharacteristicLengthMax=7.5, CompareWithPeers=False)
    FemBspTet.run_mesher(obj)
    # as in a file of an older version: the former tessellation parameters saved with it
    obj.addProperty("App::PropertyBool", "RemeshSurface", "BspTet Mesh Params", "former")
    obj.addProperty("App::PropertyLength", "LinearDeflection", "BspTet Mesh Params", "former")
    obj.RemeshSurface, obj.LinearDeflection = True, 0.25
    # ... the former comparison's parameter (its value carries over) and results, former groups
    obj.removeProperty("CompareWithPeers")
    obj.addProperty("App::PropertyBool", "CompareWithTetGen", "BspTet Mesh Params", "former")
    obj.addProperty("App::PropertyInteger", "TetGenTetrahedra", "BspTet Mesh Results", "former")
    obj.CompareWithTetGen, obj.TetGenTetrahedra = False, 99
    obj.setGroupOfProperty("ElementOrder", "BspTet Mesh Params")
    obj.setGroupOfProperty("Nodes", "BspTet Mesh Results")
    fem = obj.FemMesh
    nodes = {i: tuple(v) for i, v in fem.Nodes.items()}
    vols = [fem.getElementNodes(e) for e in fem.Volumes]
    name, faces = obj.Name, len(part.Shape.Faces)
    path = str(tmp_path / "mesher.FCStd")
    doc.saveAs(path)
    freecad.closeDocument(doc.Name)
    d2 = freecad.openDocument(path)
    try:
        o2 = d2.getObject(name)
        assert o2.Proxy.Type == "Fem::FemMeshBspTet" and source_of(o2).Name == part_name
        assert o2.CharacteristicLengthMax.Value == 7.5 and o2.FaceGroups is True
        f2 = o2.FemMesh
        assert {i: tuple(v) for i, v in f2.Nodes.items()} == nodes
        assert [f2.getElementNodes(e) for e in f2.Volumes] == vols
        assert f2.GroupCount == 2 * faces  # a face group and a node group per CAD face
        assert f2.FaceCount == fem.FaceCount > 0
        assert o2.Nodes == len(nodes) and o2.MeshStatus.startswith("meshed")
        # the former parameters went on opening; the object meshes as before
        assert "RemeshSurface" not in o2.PropertiesList
        assert "LinearDeflection" not in o2.PropertiesList
        assert "CompareWithTetGen" not in o2.PropertiesList and o2.CompareWithPeers is False
        assert "TetGenTetrahedra" not in o2.PropertiesList
        assert o2.getGroupOfProperty("ElementOrder") == "Mesh Params"
        assert o2.getGroupOfProperty("Nodes") == "Mesh Results"
        FemBspTet.run_mesher(o2)
        assert o2.FemMesh.NodeCount == len(nodes)
        # a restored object upgrades itself: a property missing in an old file comes back
        o2.removeProperty("CompareWithPeers")
        o2.Proxy.onDocumentRestored(o2)
        assert o2.CompareWithPeers is True
    finally:
        freecad.closeDocument(d2.Name)


def test_a_document_saved_by_freecad_0_20_opens_with_its_mesher_and_mesh(fc, tmp_path):
    """tests/data/freecad/mesher_freecad_0_20.FCStd was saved by FreeCAD 0.20.2
    (make_mesher_document.py beside it). On every FreeCAD the tests run on (0.20.2 and 1.0) it
    opens with the mesher object, its link to the block, its tet10 mesh and the analysis holding
    it, and meshes again."""
    import shutil

    freecad = fc[0]
    path = str(tmp_path / "mesher_freecad_0_20.FCStd")
    shutil.copy(os.path.join(os.path.dirname(DATA), "freecad", "mesher_freecad_0_20.FCStd"),
                path)
    d = freecad.openDocument(path)
    try:
        o = d.getObject("MeshBspTet")
        assert o.Proxy.Type == "Fem::FemMeshBspTet"
        assert source_of(o).Name == "Block"
        if "Fem::FemMeshShapeBaseObjectPython" in d.supportedTypes():  # FreeCAD 1.x
            assert "Shape" in o.PropertiesList and "Part" not in o.PropertiesList
        fem = o.FemMesh
        assert fem.NodeCount == o.Nodes > 0 and fem.VolumeCount == o.Tetrahedra > 0
        assert {len(fem.getElementNodes(e)) for e in fem.Volumes} == {10}
        assert o in d.getObject("Analysis").Group
        assert o.ElementDimension == "From Shape" and o.CompareWithPeers is False
        nodes = o.Nodes
        FemBspTet.run_mesher(o)
        assert o.FemMesh.NodeCount == o.Nodes > 0 and o.MeshStatus.startswith("meshed")
        assert abs(o.Nodes - nodes) <= 0.2 * nodes  # the same part at the same size
    finally:
        freecad.closeDocument(d.Name)


def test_object_of_0_20_files_opens_and_meshes(doc, fc, tmp_path):
    """A mesher object as FreeCAD 0.20/0.21 make it (Fem::FemMeshObjectPython with our Part link)
    opens and meshes; on FreeCAD 1.x its Part link becomes a global Shape link on restore."""
    freecad = fc[0]
    part = add_part(doc, fc, block_with_hole(fc))
    obj = doc.addObject("Fem::FemMeshObjectPython", "MeshBspTet")
    MeshBspTet(obj)
    obj.Part = part
    obj.ElementOrder, obj.CompareWithPeers = "1st", False
    name, part_name = obj.Name, part.Name
    path = str(tmp_path / "old_mesher.FCStd")
    doc.saveAs(path)
    freecad.closeDocument(doc.Name)
    d2 = freecad.openDocument(path)
    try:
        o2 = d2.getObject(name)
        assert o2.TypeId == "Fem::FemMeshObjectPython"
        assert source_of(o2).Name == part_name
        if "Fem::FemMeshShapeBaseObjectPython" in d2.supportedTypes():  # FreeCAD 1.x
            assert "Part" not in o2.PropertiesList
            assert o2.getTypeIdOfProperty("Shape") == "App::PropertyLinkGlobal"
        else:
            assert "Shape" not in o2.PropertiesList and o2.Part.Name == part_name
        FemBspTet.run_mesher(o2)
        assert o2.FemMesh.VolumeCount > 0
    finally:
        freecad.closeDocument(d2.Name)


@pytest.mark.parametrize("ext", [".inp", ".unv", ".vtk", ".vtu", ".med", ".z88"])
def test_export(doc, fc, tmp_path, ext):
    from FemBspTet.freecad.femmesh import read_via_freecad

    _, Part, _ = fc
    part = add_part(doc, fc, Part.makeCylinder(3, 7))
    obj = FemBspTet.make_mesher(doc, part, ElementOrder="2nd", CompareWithPeers=False)
    result = FemBspTet.run_mesher(obj)
    path = FemBspTet.export_mesh(obj, str(tmp_path / ("mesh" + ext)))
    back = read_via_freecad(path)
    assert back.tets.shape == result.mesh.tets.shape
    assert len(back.points) == len(result.mesh.points)
    scale = np.abs(result.mesh.points).max()
    tol = {".vtk": 1e-5, ".z88": 1e-6 / scale, ".vtu": 1e-7}.get(ext, 1e-12) * scale
    assert np.allclose(np.sort(back.points, axis=0), np.sort(result.mesh.points, axis=0),
                       atol=tol, rtol=0)


def test_export_refuses_other_formats_and_empty_meshes(doc, fc, tmp_path):
    _, Part, _ = fc
    obj = FemBspTet.make_mesher(doc, add_part(doc, fc, Part.makeBox(1, 1, 1)))
    with pytest.raises(InputError, match="has no volume mesh"):
        FemBspTet.export_mesh(obj, str(tmp_path / "a.inp"))
    with pytest.raises(InputError, match="cannot export a mesh as '.stl'"):
        FemBspTet.export_mesh(obj, str(tmp_path / "a.stl"))
    assert not os.listdir(tmp_path)


# ------------------------------------------------------------------------------- pieces

def test_boundary_faces_of_two_tets_are_outward():
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], dtype=float)
    tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    tets[1] = tets[1][[1, 0, 2, 3]] if np.linalg.det(pts[tets[1][1:]] - pts[tets[1][0]]) < 0 \
        else tets[1]
    faces = mp.boundary_faces_of(tets)
    assert len(faces) == 6  # the shared face (1, 2, 3) is inside
    centre = pts.mean(axis=0)
    for a, b, c in faces:
        n = np.cross(pts[b] - pts[a], pts[c] - pts[a])
        assert np.dot(n, pts[a] - centre) > 0
