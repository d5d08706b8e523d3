# SPDX-License-Identifier: LGPL-2.1-or-later
"""Tests of FemBspTet.freecad.femmesh (TetMesh <-> Fem.FemMesh, mesh files through FreeCAD).

Run with Debian's interpreter from the checkout: ``/usr/bin/python3 -m pytest -q tests``.
Skipped when FreeCAD (Debian package freecad-python3) is not available.
"""

import os
import re

import numpy as np
import pytest

from FemBspTet.kernel.errors import InputError, InternalError
from FemBspTet.kernel.freecad_env import freecad_available
from FemBspTet.kernel.mesh_types import TetMesh

if not freecad_available():
    pytest.skip("FreeCAD (Debian package freecad-python3) is not available in this interpreter",
                allow_module_level=True)

from FemBspTet.freecad import femmesh as fx  # noqa: E402

FORMATS = [".unv", ".med", ".z88", ".vtk", ".vtu", ".inp"]
# SMESH / CalculiX C3D10 mid-edge order: edge (i, j) of the corners for mid-node 4..9
TET10_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


@pytest.fixture(scope="module")
def Fem():
    """FreeCAD's Fem module, bootstrapped once per test process."""
    from FemBspTet.kernel.freecad_env import import_freecad

    import_freecad()
    import Fem as fem_module

    return fem_module


# ---------------------------------------------------------------------------------------------
# test meshes and independent helpers
# ---------------------------------------------------------------------------------------------

def det6(a, b, c, d):
    return float(np.dot(np.cross(np.subtract(b, a), np.subtract(c, a)), np.subtract(d, a)))


def cube_tet4(scale=(2.0, 3.0, 5.0), shift=(0.5, -1.25, 0.125)):
    """A box split into 6 positively oriented tets around the diagonal 0-6 (Kuhn split).
    Coordinates are short dyadic numbers, exactly representable in every file format."""
    unit = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                     (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)], dtype=float)
    pts = unit * scale + shift
    tets = np.array([(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6),
                     (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)])
    mesh = TetMesh(pts, tets, source="cube tet4")
    assert all(det6(*pts[t]) > 0 for t in tets)
    return mesh


def to_tet10(mesh4):
    """Add one mid-edge node per edge, order [n1..n4, m12, m23, m31, m14, m24, m34]."""
    pts = [tuple(p) for p in mesh4.points]
    mid = {}
    tets = []
    for t in mesh4.tets.tolist():
        row = list(t)
        for i, j in TET10_EDGES:
            key = (min(t[i], t[j]), max(t[i], t[j]))
            if key not in mid:
                mid[key] = len(pts)
                pts.append(tuple((mesh4.points[t[i]] + mesh4.points[t[j]]) / 2))
            row.append(mid[key])
        tets.append(row)
    return TetMesh(np.array(pts), np.array(tets), source="cube tet10")


def random_tet4(seed=7):
    """Positively oriented tets of the cube with generic (non-dyadic) coordinates."""
    rng = np.random.default_rng(seed)
    m = cube_tet4()
    pts = m.points * 10.0 + rng.uniform(-0.3, 0.3, m.points.shape) + np.pi
    assert all(det6(*pts[t]) > 0 for t in m.tets)
    return TetMesh(pts, m.tets)


def femmesh_arrays(femmesh):
    """(node ids, {id: xyz}, [(volume id, node ids)]) of a FemMesh, read through its API."""
    nodes = {i: np.array([v.x, v.y, v.z]) for i, v in femmesh.Nodes.items()}
    vols = [(e, list(femmesh.getElementNodes(e))) for e in femmesh.Volumes]
    return sorted(nodes), nodes, vols


def same_mesh_up_to_numbering(a, b, atol=0.0):
    """True if TetMesh b equals a after renumbering nodes and reordering elements: each node of
    b is matched to the node of a at the same place (within atol), element node order must be
    kept exactly (orientation and mid-node order)."""
    if a.points.shape != b.points.shape or a.tets.shape != b.tets.shape:
        return False
    d = np.linalg.norm(b.points[:, None, :] - a.points[None, :, :], axis=2)
    match = d.argmin(axis=1)
    if np.any(d[np.arange(len(b.points)), match] > atol) or len(set(match)) != len(match):
        return False
    mapped = match[b.tets]
    return sorted(map(tuple, mapped.tolist())) == sorted(map(tuple, a.tets.tolist()))


# ---------------------------------------------------------------------------------------------
# TetMesh <-> FemMesh
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("order", [1, 2])
def test_tetmesh_to_femmesh_uses_smesh_conventions(Fem, order):
    mesh = cube_tet4() if order == 1 else to_tet10(cube_tet4())
    fem = fx.tetmesh_to_femmesh(mesh)
    ids, nodes, vols = femmesh_arrays(fem)
    assert ids == list(range(1, len(mesh.points) + 1))
    for i, p in enumerate(mesh.points):
        assert np.array_equal(nodes[i + 1], p)
    assert [e for e, _ in vols] == list(range(1, len(mesh.tets) + 1))
    assert fem.TetraCount == fem.VolumeCount == len(mesh.tets)
    for e, conn in vols:
        assert len(conn) == mesh.tets.shape[1]
        p = [nodes[n] for n in conn]
        assert det6(*p[:4]) < 0                    # SMESH: (p2-p1)x(p3-p1).(p4-p1) < 0
        assert sorted(conn[:4]) == sorted((mesh.tets[e - 1, :4] + 1).tolist())
        if order == 2:                             # each mid-node in its SMESH slot
            for slot, (i, j) in enumerate(TET10_EDGES, start=4):
                assert np.array_equal(p[slot], (p[i] + p[j]) / 2), (e, slot)


@pytest.mark.parametrize("order", [1, 2])
def test_femmesh_to_tetmesh_restores_positive_orientation(Fem, order):
    mesh = cube_tet4() if order == 1 else to_tet10(cube_tet4())
    back = fx.femmesh_to_tetmesh(fx.tetmesh_to_femmesh(mesh))
    assert np.array_equal(back.points, mesh.points)
    assert np.array_equal(back.tets, mesh.tets)
    assert all(det6(*back.points[t[:4]]) > 0 for t in back.tets)
    assert back.extra["node_ids"].tolist() == list(range(1, len(mesh.points) + 1))


def test_femmesh_with_own_ids_in_smesh_orientation(Fem):
    """A FemMesh made the way Gmsh results arrive: SMESH orientation, ids with gaps."""
    mesh = to_tet10(cube_tet4())
    fem = Fem.FemMesh()
    node_id = {i: 100 + 3 * i for i in range(len(mesh.points))}
    for i in reversed(range(len(mesh.points))):
        fem.addNode(*mesh.points[i].tolist(), node_id[i])
    for e, t in enumerate(mesh.tets.tolist()):
        n1, n2, n3, n4, m12, m23, m31, m14, m24, m34 = t
        smesh = [n2, n1, n3, n4, m12, m31, m23, m24, m14, m34]   # written out by hand
        fem.addVolume([node_id[n] for n in smesh], 50 + 2 * e)
    back = fx.femmesh_to_tetmesh(fem, source="by hand")
    assert back.extra["node_ids"].tolist() == sorted(node_id.values())
    assert back.extra["volume_ids"].tolist() == [50 + 2 * e for e in range(len(mesh.tets))]
    assert np.array_equal(back.points, mesh.points)   # ids grow with the index here
    assert np.array_equal(back.tets, mesh.tets)
    assert back.source == "by hand"


def test_femmesh_in_wrong_orientation_is_refused(Fem):
    mesh = cube_tet4()
    fem = Fem.FemMesh()
    for i, p in enumerate(mesh.points.tolist(), start=1):
        fem.addNode(*p, i)
    for e, t in enumerate(mesh.tets.tolist(), start=1):
        fem.addVolume([n + 1 for n in t], e)              # our order, i.e. positive: wrong
    with pytest.raises(InputError, match=r"6 of 6 tetrahedra are not negatively oriented"):
        fx.femmesh_to_tetmesh(fem)


def test_femmesh_without_tets_is_refused(Fem):
    fem = Fem.FemMesh()
    for i, p in enumerate([(0, 0, 0), (1, 0, 0), (0, 1, 0)], start=1):
        fem.addNode(*p, i)
    fem.addFace([1, 2, 3], 1)
    with pytest.raises(InputError, match=r"no volume elements \(3 nodes, 1 faces\)"):
        fx.femmesh_to_tetmesh(fem)
    hexa = Fem.FemMesh()
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
               (0, 1, 1)]
    for i, p in enumerate(corners, start=1):
        hexa.addNode(*p, i)
    hexa.addVolume([1, 2, 3, 4, 5, 6, 7, 8], 1)
    with pytest.raises(InputError, match=r"volume 1 has 8 nodes"):
        fx.femmesh_to_tetmesh(hexa)


def test_mixed_tet4_tet10_is_refused(Fem):
    m10 = to_tet10(cube_tet4())
    fem = fx.tetmesh_to_femmesh(m10)
    n = [fem.getElementNodes(1)[k] for k in range(4)]
    fem.addVolume(n, 99)
    with pytest.raises(InputError, match="mixes 4- and 10-node"):
        fx.femmesh_to_tetmesh(fem)


@pytest.mark.parametrize("change, pattern", [
    (lambda p, t: (p, t[:, [1, 0, 2, 3]]), r"6 tet\(s\) are not positively oriented"),
    (lambda p, t: (np.vstack([p, p[0] + p[1] - p[0]]), np.vstack([t, [[0, 1, 8, 2]]])),
     r"1 tet\(s\) are not positively oriented .* first: tet 6 .* 6\*volume 0"),  # flat
    (lambda p, t: (p, np.vstack([t, [[0, 1, 2, 8]]])), r"tet 6 refers to node indices"),
    (lambda p, t: (np.vstack([p[:-1], [[np.nan, 0, 0]]]), t), r"point 7 has a non-finite"),
    (lambda p, t: (p, t[:0]), r"no tetrahedra"),
], ids=["inverted", "degenerate", "bad_index", "nan", "empty"])
def test_tetmesh_to_femmesh_rejects_bad_meshes(Fem, change, pattern):
    m = cube_tet4()
    pts, tets = change(m.points, m.tets)
    with pytest.raises(InputError, match=pattern):
        fx.tetmesh_to_femmesh(TetMesh(pts, tets, source="bad"))


def test_groups_become_faces_and_named_groups(Fem):
    from FemBspTet.kernel.core import boundary_surface
    from FemBspTet.kernel.mesh_types import MeshGroups

    mesh = cube_tet4()
    tri = boundary_surface(mesh).triangles
    x = mesh.points[tri][:, :, 0]
    tags = np.where((x == x.min()).all(axis=1), 0, 1)
    groups = MeshGroups(tri, tags, ["Face1", "Rest"], np.zeros(len(mesh.tets)), ["Solid1"])
    fem = fx.tetmesh_to_femmesh(mesh, groups, group_prefix="P_")
    assert fem.FaceCount == len(tri) and fem.VolumeCount == len(mesh.tets)
    named = {(fem.getGroupName(g), fem.getGroupElementType(g)): sorted(fem.getGroupElements(g))
             for g in fem.Groups}
    assert set(named) == {("P_Face1", "Node"), ("P_Face1", "Face"), ("P_Rest", "Node"),
                          ("P_Rest", "Face"), ("P_Solid1", "Volume")}
    x0 = np.flatnonzero(mesh.points[:, 0] == mesh.points[:, 0].min())
    assert named[("P_Face1", "Node")] == (x0 + 1).tolist()
    face_nodes = {tuple(sorted(fem.getElementNodes(e))) for e in named[("P_Face1", "Face")]}
    assert face_nodes == {tuple(sorted((t + 1).tolist())) for t in tri[tags == 0]}
    assert named[("P_Solid1", "Volume")] == list(range(1, len(mesh.tets) + 1))


def test_addvolumelist_path_when_freecad_has_it(Fem):
    """FreeCAD 1.0+ FemMesh.addVolumeList(flat node ids, nodes per element) -> new ids. 0.20.2
    lacks it; a stand-in with those semantics must give the same mesh as the addVolume path."""

    class WithVolumeList:
        def __init__(self, fem):
            self._fem = fem
            self.calls = 0

        def __getattr__(self, name):
            return getattr(self._fem, name)

        def addVolumeList(self, flat, sizes):
            assert isinstance(flat, list) and isinstance(sizes, list)
            self.calls += 1
            ids, k = [], 0
            for n in sizes:
                ids.append(self._fem.addVolume(flat[k:k + n]))
                k += n
            return ids

    for mesh in (cube_tet4(), to_tet10(cube_tet4())):
        shim = WithVolumeList(Fem.FemMesh())
        fx._fill_femmesh(shim, mesh)
        assert shim.calls == 1
        reference = fx.tetmesh_to_femmesh(mesh)
        assert femmesh_arrays(shim._fem)[2] == femmesh_arrays(reference)[2]


# ---------------------------------------------------------------------------------------------
# files
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("ext", FORMATS)
@pytest.mark.parametrize("order", [1, 2])
def test_write_read_round_trip(Fem, tmp_path, ext, order):
    mesh = cube_tet4() if order == 1 else to_tet10(cube_tet4())
    path = tmp_path / ("cube" + ext)
    written = fx.write_via_freecad(path, mesh)
    assert written == str(path) and path.stat().st_size > 0
    assert os.listdir(tmp_path) == [path.name]          # no temporary leftovers
    # FreeCAD's own reader sees SMESH-oriented tets with the right mid-nodes
    fem = Fem.read(str(path))
    _, nodes, vols = femmesh_arrays(fem)
    assert len(vols) == len(mesh.tets)
    for _, conn in vols:
        p = [nodes[n] for n in conn]
        assert det6(*p[:4]) < 0
        if order == 2:
            for slot, (i, j) in enumerate(TET10_EDGES, start=4):
                assert np.array_equal(p[slot], (p[i] + p[j]) / 2)
    back = fx.read_via_freecad(path)
    assert back.source == str(path)
    assert same_mesh_up_to_numbering(mesh, back)          # exact coordinates
    assert all(det6(*back.points[t[:4]]) > 0 for t in back.tets)


# Coordinate precision of FreeCAD 0.20.2's writers, as documented in freecad_export:
# (relative to each coordinate's magnitude, absolute).
PRECISION = {".unv": (0.0, 0.0), ".med": (0.0, 0.0), ".inp": (1e-12, 0.0),
             ".vtu": (1.2e-7, 0.0),       # float32
             ".vtk": (5.1e-6, 0.0),       # 6 significant digits
             ".z88": (0.0, 5.1e-7)}       # 6 digits after the decimal point


@pytest.mark.parametrize("ext", FORMATS)
def test_writer_precision(Fem, tmp_path, ext):
    mesh = random_tet4()
    path = tmp_path / ("r" + ext)
    fx.write_via_freecad(path, mesh)
    back = fx.read_via_freecad(path)
    rel, abs_ = PRECISION[ext]
    allowed = rel * np.abs(mesh.points) + abs_
    assert same_mesh_up_to_numbering(mesh, back, atol=np.linalg.norm(allowed, axis=1).max())
    assert np.all(np.abs(back.points - mesh.points) <= allowed)
    if ext in (".unv", ".med"):
        assert np.array_equal(back.points, mesh.points)


def test_inp_file_has_calculix_elements(Fem, tmp_path):
    """Parse the C3D10 block FreeCAD wrote: CalculiX wants positive corners and mid-nodes in
    the order m12, m23, m31, m14, m24, m34."""
    mesh = to_tet10(cube_tet4())
    path = tmp_path / "cube.inp"
    fx.write_via_freecad(path, mesh)
    text = path.read_text()
    nodes, elems, block = {}, [], None
    for line in text.splitlines():
        if line.startswith("*"):
            block = line.upper()
            continue
        fields = [f for f in re.split(r"[,\s]+", line.strip()) if f]
        if not fields:
            continue
        if block.startswith("*NODE"):
            nodes[int(fields[0])] = np.array([float(f) for f in fields[1:4]])
        elif block.startswith("*ELEMENT") and "C3D10" in block:
            elems.append([int(f) for f in fields[1:]])
    assert len(elems) == len(mesh.tets) and all(len(e) == 10 for e in elems)
    for e in elems:
        p = [nodes[n] for n in e]
        assert det6(*p[:4]) > 0
        for slot, (i, j) in enumerate(TET10_EDGES, start=4):
            assert np.array_equal(p[slot], (p[i] + p[j]) / 2)


def test_write_replaces_existing_file(Fem, tmp_path):
    path = tmp_path / "m.unv"
    path.write_text("old content")
    os.chmod(path, 0o640)
    fx.write_via_freecad(path, to_tet10(cube_tet4()))
    assert fx.read_via_freecad(path).order == 2
    assert (path.stat().st_mode & 0o777) == 0o640          # the replaced file's permissions
    fx.write_via_freecad(path, cube_tet4())
    assert fx.read_via_freecad(path).order == 1
    assert os.listdir(tmp_path) == ["m.unv"]


def test_failed_write_keeps_existing_file_and_leaves_nothing(Fem, tmp_path, monkeypatch):
    path = tmp_path / "m.med"
    path.write_bytes(b"previous mesh")

    with pytest.raises(InputError):                              # invalid mesh
        fx.write_via_freecad(path, TetMesh(cube_tet4().points, cube_tet4().tets[:, [1, 0, 2, 3]]))
    assert path.read_bytes() == b"previous mesh"

    class HalfWriter:                                            # writer dies mid-way
        def write(self, name):
            with open(name, "wb") as f:
                f.write(b"partial")
            raise RuntimeError("disk full")

    monkeypatch.setattr(fx, "tetmesh_to_femmesh", lambda mesh, groups=None: HalfWriter())
    with pytest.raises(InternalError, match="disk full"):
        fx.write_via_freecad(path, cube_tet4())
    assert path.read_bytes() == b"previous mesh"
    assert os.listdir(tmp_path) == ["m.med"]

    class SilentWriter:                                          # writer writes nothing
        def write(self, name):
            pass

    monkeypatch.setattr(fx, "tetmesh_to_femmesh", lambda mesh, groups=None: SilentWriter())
    with pytest.raises(InternalError, match="produced no file"):
        fx.write_via_freecad(path, cube_tet4())
    assert path.read_bytes() == b"previous mesh"
    assert os.listdir(tmp_path) == ["m.med"]


def test_file_errors(Fem, tmp_path):
    with pytest.raises(InputError, match=r"unsupported mesh file extension '\.stl'"):
        fx.write_via_freecad(tmp_path / "m.stl", cube_tet4())
    with pytest.raises(InputError, match=r"directory .* does not exist"):
        fx.write_via_freecad(tmp_path / "nowhere" / "m.unv", cube_tet4())
    with pytest.raises(InputError, match=r"missing\.unv: file not found"):
        fx.read_via_freecad(tmp_path / "missing.unv")
    garbage = tmp_path / "garbage.unv"
    garbage.write_bytes(bytes(range(256)) * 8)
    with pytest.raises(InputError, match=r"garbage\.unv: FreeCAD read no mesh"):
        fx.read_via_freecad(garbage)
    with pytest.raises(InputError, match=r"unsupported mesh file extension"):
        fx.read_via_freecad(garbage.with_suffix(".xyz"))
