# SPDX-License-Identifier: LGPL-2.1-or-later
"""Tests of FemBspTet.io.volume_io (VTU, MSH, INP, TetGen, Medit).

Meshes are built here: a box split into 6 positively oriented Kuhn tets, and its tet10 version
with mid-edge nodes. Every written format is read back by our reader and by meshio. Tests that
run gmsh, tetgen or ccx are skipped where those programs are not installed.
"""

import base64
import itertools
import os
import shutil
import subprocess
import zlib

import meshio
import numpy as np
import pytest

from FemBspTet.io import volume_io
from FemBspTet.kernel.errors import InputError, InternalError
from FemBspTet.kernel.mesh_types import Surface, TetMesh
from FemBspTet.io.volume_io import (read_tet_mesh, read_tetgen, stored_points, surface_groups,
                                 tetgen_paths, write_tet_mesh)


# our mid-edge node 4 + k lies on the edge _EDGES[k] (0-based corners)
_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


# ------------------------------------------------------------------------------------------
# test meshes
# ------------------------------------------------------------------------------------------


def kuhn_box():
    """Box [0.1, 2.1] x [-0.2, 1.3] x [0.3, 1.3] in 6 positively oriented tets."""
    points = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float)
    points = points * [2.0, 1.5, 1.0] + [0.1, -0.2, 0.3]
    tets = []
    for axes in itertools.permutations(range(3)):
        corner, path = [0, 0, 0], [0]
        for axis in axes:
            corner[axis] = 1
            path.append(corner[0] + 2 * corner[1] + 4 * corner[2])
        a, b, c, d = points[path]
        if np.linalg.det(np.array([b - a, c - a, d - a])) < 0:
            path[0], path[1] = path[1], path[0]
        tets.append(path)
    return TetMesh(points, np.array(tets))


def quadratic(mesh):
    """tet10 version: mid-edge nodes appended after the corners, in our node order."""
    points = [tuple(p) for p in mesh.points]
    index = {}
    tets = []
    for tet in mesh.tets.tolist():
        row = list(tet)
        for a, b in _EDGES:
            key = tuple(sorted((tet[a], tet[b])))
            if key not in index:
                index[key] = len(points)
                points.append(tuple((mesh.points[tet[a]] + mesh.points[tet[b]]) / 2))
            row.append(index[key])
        tets.append(row)
    return TetMesh(np.array(points), np.array(tets))


def box_surface(mesh):
    """The 12 boundary triangles of the Kuhn box (outward), tagged by box side 0..5."""
    tets = mesh.tets[:, :4]
    faces = {}
    for t in tets.tolist():
        for skip in range(4):
            face = tuple(sorted(v for i, v in enumerate(t) if i != skip))
            faces.setdefault(face, []).append((t, skip))
    tris, tags = [], []
    lo, hi = mesh.points[:8].min(axis=0), mesh.points[:8].max(axis=0)
    for face, owners in sorted(faces.items()):
        if len(owners) != 1:
            continue
        tet, skip = owners[0]
        a, b, c = face
        p = mesh.points
        if np.dot(np.cross(p[b] - p[a], p[c] - p[a]), p[a] - p[tet[skip]]) < 0:
            b, c = c, b
        centroid = p[[a, b, c]].mean(axis=0)
        side = [np.isclose(centroid[j], lo[j]) for j in range(3)] + \
               [np.isclose(centroid[j], hi[j]) for j in range(3)]
        tris.append((a, b, c))
        tags.append(side.index(True))
    return Surface(mesh.points[:8], np.array(tris), face_tags=np.array(tags),
                   face_names=[f"Side{i}" for i in range(6)])


def volumes(mesh):
    c = mesh.points[mesh.tets[:, :4]]
    return np.linalg.det(np.stack([c[:, 1] - c[:, 0], c[:, 2] - c[:, 0], c[:, 3] - c[:, 0]], 1))


def assert_tet10_geometry(mesh):
    """Our order: node 4 + k is the midpoint of corners _EDGES[k]."""
    p = mesh.points
    for k, (a, b) in enumerate(_EDGES):
        assert np.allclose(p[mesh.tets[:, 4 + k]], (p[mesh.tets[:, a]] + p[mesh.tets[:, b]]) / 2)


def file_edge_order(points, rows):
    """For rows of 0-based node ids (10 per tet) give the corner pair of columns 4..9."""
    result = set()
    for row in rows:
        roles = []
        for m in row[4:]:
            pair = [(a, b) for a, b in itertools.combinations(range(4), 2)
                    if np.allclose(points[m], (points[row[a]] + points[row[b]]) / 2)]
            assert len(pair) == 1
            roles.append(pair[0])
        result.add(tuple(roles))
    assert len(result) == 1
    return list(result.pop())


MESHES = {"tet4": kuhn_box, "tet10": lambda: quadratic(kuhn_box())}
FORMATS = [".vtu", ".msh", ".inp", ".node", ".mesh"]


def expect_error(exc_info, path, *fragments):
    message = str(exc_info.value)
    assert os.path.basename(str(path)) in message, message
    for fragment in fragments:
        assert fragment in message, f"{fragment!r} not in {message!r}"


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def test_test_meshes_are_valid():
    mesh = kuhn_box()
    assert (volumes(mesh) > 0).all()
    assert np.isclose(volumes(mesh).sum() / 6, 2.0 * 1.5 * 1.0)
    quad = quadratic(mesh)
    assert quad.tets.shape == (6, 10) and len(quad.points) == 8 + 19
    assert_tet10_geometry(quad)
    surface = box_surface(mesh)
    assert len(surface.triangles) == 12 and sorted(set(surface.face_tags.tolist())) == list(
        range(6))


# ------------------------------------------------------------------------------------------
# round trips: ours and meshio
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", sorted(MESHES))
@pytest.mark.parametrize("ext", FORMATS)
def test_round_trip(tmp_path, ext, kind):
    mesh = MESHES[kind]()
    path = tmp_path / f"m{ext}"
    write_tet_mesh(path, mesh)
    back = read_tet_mesh(path)
    assert back.points.dtype == np.float64 and back.tets.dtype == np.int64
    assert np.array_equal(back.points, mesh.points)  # bit-identical
    assert np.array_equal(back.tets, mesh.tets)
    assert (volumes(back) > 0).all()
    assert leftovers(tmp_path) == []


def _meshio_read(path, ext):
    formats = {".vtu": "vtu", ".msh": "gmsh", ".inp": "abaqus", ".node": "tetgen",
               ".mesh": "medit"}
    return meshio.read(path, file_format=formats[ext])


@pytest.mark.parametrize("kind", sorted(MESHES))
@pytest.mark.parametrize("ext", FORMATS)
def test_meshio_reads_what_we_write(tmp_path, ext, kind):
    mesh = MESHES[kind]()
    path = tmp_path / f"m{ext}"
    write_tet_mesh(path, mesh)
    if kind == "tet10" and ext in (".node", ".mesh"):
        # meshio 5 reads only 4-node TetGen .ele files and knows no Medit P2 keyword;
        # the file's node order is checked directly in test_tetgen_order2_file_convention
        # and test_medit_p2_file_convention.
        with pytest.raises(BaseException):
            _meshio_read(path, ext)
        return
    other = _meshio_read(path, ext)
    cell_type = "tetra" if kind == "tet4" else "tetra10"
    assert [c.type for c in other.cells] == [cell_type]
    assert other.points.shape == mesh.points.shape
    assert np.allclose(other.points, mesh.points, rtol=0, atol=1e-15)
    # meshio converts every format to VTK node order, which is ours
    assert np.array_equal(other.cells[0].data, mesh.tets)


def test_tetgen_order2_file_convention(tmp_path):
    mesh = MESHES["tet10"]()
    write_tet_mesh(tmp_path / "q.ele", mesh)
    assert (tmp_path / "q.node").exists()
    lines = [ln for ln in (tmp_path / "q.ele").read_text().splitlines() if ln[:1] != "#"]
    assert lines[0].split() == ["6", "10", "0"]
    rows = np.array([ln.split() for ln in lines[1:]], dtype=int)[:, 1:] - 1
    # TetGen -o2 order: m34, m14, m12, m23, m24, m13 (0-based corner pairs below)
    assert file_edge_order(mesh.points, rows) == [(2, 3), (0, 3), (0, 1), (1, 2), (1, 3),
                                                  (0, 2)]


def test_medit_p2_file_convention(tmp_path):
    mesh = MESHES["tet10"]()
    write_tet_mesh(tmp_path / "q.mesh", mesh)
    lines = (tmp_path / "q.mesh").read_text().splitlines()
    k = lines.index("TetrahedraP2")
    count = int(lines[k + 1])
    rows = np.array([ln.split() for ln in lines[k + 2:k + 2 + count]], dtype=int)
    assert (rows[:, 10] == 1).all()  # reference
    assert file_edge_order(mesh.points, rows[:, :10] - 1) == [(0, 1), (1, 2), (0, 2), (0, 3),
                                                              (1, 3), (2, 3)]


def test_msh_and_inp_tet10_file_conventions(tmp_path):
    mesh = MESHES["tet10"]()
    write_tet_mesh(tmp_path / "q.msh", mesh)
    lines = (tmp_path / "q.msh").read_text().splitlines()
    assert lines[:3] == ["$MeshFormat", "2.2 0 8", "$EndMeshFormat"]
    rows = [ln.split() for ln in lines[lines.index("$Elements") + 2:lines.index("$EndElements")]]
    assert all(r[1] == "11" for r in rows)
    gmsh = np.array([r[5:] for r in rows], dtype=int) - 1
    # Gmsh: m01, m12, m20, m30, m32, m31 -> our last two swapped
    assert file_edge_order(mesh.points, gmsh) == [(0, 1), (1, 2), (0, 2), (0, 3), (2, 3),
                                                  (1, 3)]
    write_tet_mesh(tmp_path / "q.inp", mesh)
    text = (tmp_path / "q.inp").read_text().splitlines()
    k = text.index("*ELEMENT, TYPE=C3D10, ELSET=Eall")
    rows = np.array([ln.split(",") for ln in text[k + 1:k + 7]], dtype=int)
    assert rows.shape == (6, 11)  # one data line per element (11 <= 16 entries)
    assert file_edge_order(mesh.points, rows[:, 1:] - 1) == [(0, 1), (1, 2), (0, 2), (0, 3),
                                                             (1, 3), (2, 3)]


@pytest.mark.parametrize("kind", sorted(MESHES))
@pytest.mark.parametrize("ext", [".msh", ".mesh"])
def test_boundary_triangles_with_tags(tmp_path, ext, kind):
    mesh = MESHES[kind]()
    surface = box_surface(kuhn_box())
    path = tmp_path / f"s{ext}"
    write_tet_mesh(path, mesh, surface_groups(mesh, surface))
    back = read_tet_mesh(path)
    assert np.array_equal(back.tets, mesh.tets)
    tri = back.extra["triangles"]
    assert np.array_equal(tri[:, :3], surface.triangles)
    assert np.array_equal(back.extra["triangle_tags"], surface.face_tags)
    if kind == "tet10":
        assert tri.shape == (12, 6)
        p = mesh.points
        for k, (a, b) in enumerate([(0, 1), (1, 2), (2, 0)]):
            assert np.allclose(p[tri[:, 3 + k]], (p[tri[:, a]] + p[tri[:, b]]) / 2)
    if ext == ".msh":
        text = path.read_text()
        assert '2 1 "Side0"' in text and '3 1 "Solid1"' in text
    if kind == "tet4" or ext == ".msh":
        other = _meshio_read(path, ext)
        tri_type = "triangle" if kind == "tet4" else "triangle6"
        assert np.array_equal(other.get_cells_type(tri_type), tri)
        key = "gmsh:physical" if ext == ".msh" else "medit:ref"
        blocks = [c.type for c in other.cells]
        tags = other.cell_data[key][blocks.index(tri_type)]
        assert np.array_equal(tags, surface.face_tags + 1)


def test_surface_matched_by_coordinates(tmp_path):
    mesh = kuhn_box()
    surface = box_surface(mesh)
    perm = np.array([5, 3, 7, 0, 1, 6, 2, 4])  # surface vertices in another order
    inverse = np.argsort(perm)
    shuffled = Surface(surface.points[perm], inverse[surface.triangles],
                       face_tags=surface.face_tags)
    write_tet_mesh(tmp_path / "s.msh", mesh, surface_groups(mesh, shuffled))
    back = read_tet_mesh(tmp_path / "s.msh")
    assert np.array_equal(back.extra["triangles"], surface.triangles)
    stranger = Surface(np.vstack([surface.points, [[9.0, 9.0, 9.0]]]),
                       np.vstack([surface.triangles, [[0, 1, 8]]]))
    with pytest.raises(InputError) as exc:
        surface_groups(mesh, stranger, where=str(tmp_path / "x.msh"))
    expect_error(exc, "x.msh", "surface vertex 8", "not a node of the mesh")
    assert not (tmp_path / "x.msh").exists()


def test_tetgen_path_forms(tmp_path):
    mesh = kuhn_box()
    assert tetgen_paths(tmp_path / "a.node") == (str(tmp_path / "a.node"),
                                                 str(tmp_path / "a.ele"))
    assert tetgen_paths(tmp_path / "a.ele") == tetgen_paths(tmp_path / "a")
    write_tet_mesh(tmp_path / "a.node", mesh)
    for name in ("a.node", "a.ele"):
        assert np.array_equal(read_tet_mesh(tmp_path / name).tets, mesh.tets)
    text = (tmp_path / "a.node").read_text()
    assert text.startswith("# Generated by FemBspTet\n")
    assert "\n8 3 0 0\n1 " in text  # 1-based
    # read_tetgen: TetGen output names X.1.node / X.1.ele, else X.node / X.ele
    shutil.copy(tmp_path / "a.node", tmp_path / "b.1.node")
    shutil.copy(tmp_path / "a.ele", tmp_path / "b.1.ele")
    assert np.array_equal(read_tetgen(tmp_path / "b").tets, mesh.tets)
    assert np.array_equal(read_tetgen(tmp_path / "a").tets, mesh.tets)


# ------------------------------------------------------------------------------------------
# reading other writers' files
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", sorted(MESHES))
@pytest.mark.parametrize("options", [dict(binary=False), dict(binary=True, compression=None),
                                     dict(binary=True, compression="zlib"),
                                     dict(binary=True, compression="lzma"),
                                     dict(binary=True, compression="zlib",
                                          header_type="UInt64")])
def test_vtu_written_by_meshio(tmp_path, kind, options):
    mesh = MESHES[kind]()
    cell_type = "tetra" if kind == "tet4" else "tetra10"
    path = tmp_path / "m.vtu"
    meshio.write(path, meshio.Mesh(mesh.points, [(cell_type, mesh.tets)]), **options)
    back = read_tet_mesh(path)
    assert np.array_equal(back.points, mesh.points)
    assert np.array_equal(back.tets, mesh.tets)


def test_vtu_ignores_other_cells(tmp_path):
    mesh = kuhn_box()
    surface = box_surface(mesh)
    path = tmp_path / "mixed.vtu"
    meshio.write(path, meshio.Mesh(mesh.points, [("vertex", [[0]]),
                                                 ("triangle", surface.triangles),
                                                 ("tetra", mesh.tets)]), binary=False)
    back = read_tet_mesh(path)
    assert np.array_equal(back.tets, mesh.tets)


def vtu_appended(mesh, encoding="raw", big_endian=False, header="UInt32", compress=False,
                 separate=False):
    """A VTU with <AppendedData> (made by hand).

    With base64 encoding, ``separate`` encodes each array's header on its own (as VTK does);
    otherwise header and data are encoded together (as meshio does).
    """
    e = ">" if big_endian else "<"
    hdtype = np.dtype(e + ("u4" if header == "UInt32" else "u8"))
    k = mesh.tets.shape[1]
    m = len(mesh.tets)
    arrays = [("Float64", None, 3, mesh.points.astype(e + "f8")),
              ("Int64", "connectivity", 1, mesh.tets.astype(e + "i8")),
              ("Int32", "offsets", 1, (np.arange(1, m + 1) * k).astype(e + "i4")),
              ("UInt8", "types", 1, np.full(m, 10 if k == 4 else 24, "u1"))]
    blobs, tags, offset = [], [], 0
    for type_name, name, ncomp, values in arrays:
        raw = values.tobytes()
        if compress:
            packed = zlib.compress(raw)
            head, data = np.array([1, len(raw), len(raw), len(packed)], hdtype).tobytes(), packed
        else:
            head, data = np.array([len(raw)], hdtype).tobytes(), raw
        if encoding == "base64" and separate:
            blob = base64.b64encode(head) + base64.b64encode(data)
        elif encoding == "base64":
            blob = base64.b64encode(head + data)
        else:
            blob = head + data
        name_attr = f' Name="{name}"' if name else ""
        tags.append(f'<DataArray type="{type_name}"{name_attr} NumberOfComponents="{ncomp}" '
                    f'format="appended" offset="{offset}"/>')
        blobs.append(blob)
        offset += len(blob)
    compressor = ' compressor="vtkZLibDataCompressor"' if compress else ""
    order = "BigEndian" if big_endian else "LittleEndian"
    head = (f'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
            f'byte_order="{order}" header_type="{header}"{compressor}>\n'
            f'<UnstructuredGrid><Piece NumberOfPoints="{len(mesh.points)}" '
            f'NumberOfCells="{m}">\n<Points>{tags[0]}</Points>\n'
            f'<Cells>{"".join(tags[1:])}</Cells>\n</Piece></UnstructuredGrid>\n'
            f'<AppendedData encoding="{encoding}">\n   _')
    return head.encode() + b"".join(blobs) + b"\n</AppendedData>\n</VTKFile>\n"


@pytest.mark.parametrize("kind", sorted(MESHES))
@pytest.mark.parametrize("variant", [dict(), dict(big_endian=True), dict(header="UInt64"),
                                     dict(compress=True), dict(encoding="base64"),
                                     dict(encoding="base64", separate=True),
                                     dict(encoding="base64", separate=True, compress=True,
                                          big_endian=True)])
def test_vtu_appended_data(tmp_path, kind, variant):
    mesh = MESHES[kind]()
    path = tmp_path / "app.vtu"
    path.write_bytes(vtu_appended(mesh, **variant))
    back = read_tet_mesh(path)
    assert np.array_equal(back.points, mesh.points)
    assert np.array_equal(back.tets, mesh.tets)
    # the hand-made file is genuine VTU: meshio agrees (it reads the same raw/base64 forms)
    other = meshio.read(path)
    assert np.array_equal(other.cells[0].data, mesh.tets)


@pytest.mark.parametrize("kind", sorted(MESHES))
@pytest.mark.parametrize("version", ["2.2", "4.1"])
def test_msh_written_by_meshio(tmp_path, kind, version):
    mesh = MESHES[kind]()
    cell_type = "tetra" if kind == "tet4" else "tetra10"
    path = tmp_path / "m.msh"
    file_format = "gmsh22" if version == "2.2" else "gmsh"  # meshio writes 4.1 by default
    meshio.write(path, meshio.Mesh(mesh.points, [(cell_type, mesh.tets)]),
                 file_format=file_format, binary=False)
    assert path.read_text().splitlines()[1].startswith(version)
    back = read_tet_mesh(path)
    assert np.array_equal(back.points, mesh.points)
    assert np.array_equal(back.tets, mesh.tets)


def test_msh22_arbitrary_node_tags_and_other_elements(tmp_path):
    mesh = kuhn_box()
    tags = (np.arange(8) + 1) * 10 + 3  # 13, 23, ...
    order = [3, 0, 7, 1, 6, 2, 5, 4]  # nodes listed out of order
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "1",
             '3 7 "Body"', "$EndPhysicalNames", "$Nodes", "8"]
    lines += [f"{tags[i]} {' '.join(repr(v) for v in mesh.points[i])}" for i in order]
    lines += ["$EndNodes", "$Elements", str(6 + 2)]
    lines.append(f"1 15 2 0 1 {tags[0]}")  # a point element
    lines.append(f"2 1 2 0 1 {tags[0]} {tags[1]}")  # a line element
    for j, tet in enumerate(mesh.tets):
        lines.append(f"{j + 3} 4 3 7 1 0 " + " ".join(str(tags[v]) for v in tet))
    lines += ["$EndElements", "$NodeData", "1", '"x"', "1", "0.0", "3", "0", "1", "8",
              "$EndNodeData"]
    path = tmp_path / "tags.msh"
    path.write_text("\n".join(lines) + "\n")
    back = read_tet_mesh(path)
    assert np.array_equal(back.points, mesh.points[order])
    position = np.argsort(order)  # node i of the mesh is back.points[position[i]]
    assert np.array_equal(back.tets, position[mesh.tets])
    assert (back.extra["region"] == 7).all()


def test_inp_freecad_style_with_include_and_continuation(tmp_path):
    mesh = quadratic(kuhn_box())
    ids = (np.arange(len(mesh.points)) + 1) * 10
    (tmp_path / "nodes.inp").write_text(
        "** nodes in an included file\n*Node, NSET=Nall\n"
        + "".join(f"{ids[i]}, {x!r}, {y!r}, {z!r}\n"
                  for i, (x, y, z) in enumerate(mesh.points.tolist())))
    lines = ["** written by a test", "*Heading", " model", "*INCLUDE, INPUT=nodes.inp",
             "*Element, TYPE=S3, ELSET=Faces", f"1, {ids[0]}, {ids[1]}, {ids[2]}",
             "*element, type=c3d10, elset=Evolumes"]
    for j, tet in enumerate(mesh.tets.tolist()):
        nodes = [str(ids[v]) for v in tet]
        lines.append(f"{j + 100}, " + ", ".join(nodes[:5]) + ",")  # continued
        lines.append("** a comment inside the data")
        lines.append("   " + ", ".join(nodes[5:]))
    lines += ["*ELSET, ELSET=Eall", "Evolumes", "*STEP", "*STATIC", "*NODE PRINT, NSET=Nall",
              "U", "*ELEMENT, TYPE=C3D4", "1, 1, 2, 3, 4", "*END STEP"]
    path = tmp_path / "fc.inp"
    path.write_text("\n".join(lines) + "\n")
    back = read_tet_mesh(path)
    assert np.array_equal(back.points, mesh.points)
    assert np.array_equal(back.tets, mesh.tets)


def test_tetgen_zero_based_with_attributes_and_markers(tmp_path):
    mesh = kuhn_box()
    node = ["# TetGen-like output, 0-based", "8  3  1  1"]
    node += [f"  {i}  {x!r} {y!r} {z!r}  0.5  {i % 2}  # node {i}"
             for i, (x, y, z) in enumerate(mesh.points.tolist())]
    ele = ["6  4  1", "# comment between lines"]
    ele += [f"{j}  {' '.join(map(str, t))}  {j % 3 + 1}" for j, t in enumerate(mesh.tets.tolist())]
    (tmp_path / "z.1.node").write_text("\n".join(node) + "\n")
    (tmp_path / "z.1.ele").write_text("\n".join(ele) + "\n")
    back = read_tetgen(tmp_path / "z")
    assert np.array_equal(back.points, mesh.points)
    assert np.array_equal(back.tets, mesh.tets)
    assert back.extra["region"].tolist() == [1, 2, 3, 1, 2, 3]


def test_medit_ordering_section_and_unknown_sections(tmp_path):
    mesh = quadratic(kuhn_box())
    # file order: corners, then edges 12 13 14 23 24 34 (lexicographic), declared explicitly
    lexicographic = [0, 1, 2, 3, 4, 6, 7, 5, 8, 9]
    bary = [(2, 0, 0, 0), (0, 2, 0, 0), (0, 0, 2, 0), (0, 0, 0, 2), (1, 1, 0, 0),
            (1, 0, 1, 0), (1, 0, 0, 1), (0, 1, 1, 0), (0, 1, 0, 1), (0, 0, 1, 1)]
    lines = ["MeshVersionFormatted 1", "Dimension", "3", "Vertices", str(len(mesh.points))]
    lines += [f"{x!r} {y!r} {z!r} 0" for x, y, z in mesh.points.tolist()]
    lines += ["Corners", "2", "1", "2", "Edges", "1", "1 2 0", "TetrahedraP2Ordering", "10"]
    lines += [" ".join(map(str, b)) for b in bary]
    lines += ["TetrahedraP2", "6"]
    lines += [" ".join(str(v + 1) for v in tet[lexicographic]) + " 4" for tet in mesh.tets]
    lines += ["Ridges", "1", "1", "End"]
    path = tmp_path / "o.mesh"
    path.write_text("\n".join(lines) + "\n")
    back = read_tet_mesh(path)
    assert np.array_equal(back.tets, mesh.tets)
    assert back.extra["region"].tolist() == [4] * 6
    assert_tet10_geometry(back)


# ------------------------------------------------------------------------------------------
# real tools (skipped where not installed)
# ------------------------------------------------------------------------------------------

CUBE_POLY = """8 3 0 0
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 0 0 1
6 1 0 1
7 1 1 1
8 0 1 1
6 1
1 0 1
4 1 2 3 4
1 0 2
4 5 6 7 8
1 0 3
4 1 2 6 5
1 0 4
4 2 3 7 6
1 0 5
4 3 4 8 7
1 0 6
4 4 1 5 8
0
0
"""


@pytest.mark.skipif(shutil.which("tetgen") is None, reason="tetgen not installed")
@pytest.mark.parametrize("switches", ["-pqa0.05o2AQ", "-pqzQ"])
def test_reads_real_tetgen_output(tmp_path, switches):
    (tmp_path / "cube.poly").write_text(CUBE_POLY)
    subprocess.run(["tetgen", switches, "cube.poly"], cwd=tmp_path, check=True,
                   capture_output=True, timeout=60)
    mesh = read_tetgen(tmp_path / "cube")
    assert len(mesh.tets) >= 5
    assert (volumes(mesh) > 0).all()
    assert np.isclose(volumes(mesh).sum() / 6, 1.0)
    if "o2" in switches:
        assert mesh.order == 2
        assert_tet10_geometry(mesh)  # TetGen's -o2 order converted to ours
        assert "region" in mesh.extra


@pytest.mark.skipif(shutil.which("gmsh") is None, reason="gmsh not installed")
@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("fmt", ["msh22", "msh41"])
def test_reads_real_gmsh_output(tmp_path, order, fmt):
    (tmp_path / "box.geo").write_text('SetFactory("OpenCASCADE");\nBox(1) = {0,0,0,1,2,1};\n'
                                      "Mesh.CharacteristicLengthMax = 0.6;\n")
    subprocess.run(["gmsh", "-3", "-order", str(order), "-format", fmt, "box.geo", "-o",
                    "box.msh"], cwd=tmp_path, check=True, capture_output=True, timeout=120)
    mesh = read_tet_mesh(tmp_path / "box.msh")
    assert mesh.order == order
    assert (volumes(mesh) > 0).all()
    assert np.isclose(volumes(mesh).sum() / 6, 2.0)
    if order == 2:
        assert_tet10_geometry(mesh)
    tri = mesh.extra["triangles"]
    assert set(mesh.extra["triangle_tags"].tolist()) == set(range(6))  # the 6 box faces
    assert np.isin(tri, mesh.tets).all()


@pytest.mark.skipif(shutil.which("gmsh") is None, reason="gmsh not installed")
@pytest.mark.parametrize("kind", sorted(MESHES))
def test_gmsh_reads_what_we_write(tmp_path, kind):
    mesh = MESHES[kind]()
    write_tet_mesh(tmp_path / "ours.msh", mesh, surface_groups(mesh, box_surface(kuhn_box())))
    subprocess.run(["gmsh", "ours.msh", "-0", "-format", "msh41", "-o", "theirs.msh"],
                   cwd=tmp_path, check=True, capture_output=True, timeout=120)
    back = read_tet_mesh(tmp_path / "theirs.msh")
    # gmsh renumbers the nodes: map them back by their (exact) coordinates
    ours = {tuple(p): i for i, p in enumerate(mesh.points.tolist())}
    to_ours = np.array([ours[tuple(p)] for p in back.points.tolist()])
    assert len(back.points) == len(mesh.points)
    assert np.array_equal(sort_rows(to_ours[back.tets]), sort_rows(mesh.tets))
    surface = box_surface(kuhn_box())
    tri = to_ours[back.extra["triangles"][:, :3]]
    assert np.array_equal(sort_rows(np.column_stack([tri, back.extra["triangle_tags"]])),
                          sort_rows(np.column_stack([surface.triangles, surface.face_tags])))


def sort_rows(rows):
    rows = np.asarray(rows)
    return rows[np.lexsort(rows.T[::-1])]


CCX_DECK = """*INCLUDE, INPUT=mesh.inp
*NSET, NSET=FIX
{fixed}
*MATERIAL, NAME=STEEL
*ELASTIC
210000, 0.3
*DENSITY
7.8e-9
*SOLID SECTION, ELSET=Eall, MATERIAL=STEEL
*STEP
*STATIC
*BOUNDARY
FIX, 1, 3
*DLOAD
Eall, GRAV, 9.81, 0., 0., -1.
*NODE PRINT, NSET=Nall
U
*END STEP
"""


@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) not installed")
@pytest.mark.parametrize("kind", sorted(MESHES))
def test_calculix_accepts_our_inp_and_rejects_flipped(tmp_path, kind):
    mesh = MESHES[kind]()
    fixed = np.flatnonzero(np.isclose(mesh.points[:, 2], mesh.points[:, 2].min())) + 1
    deck = CCX_DECK.format(fixed=", ".join(map(str, fixed.tolist())))
    (tmp_path / "job.inp").write_text(deck)

    def run():
        return subprocess.run(["ccx", "job"], cwd=tmp_path, capture_output=True, text=True,
                              timeout=120)

    write_tet_mesh(tmp_path / "mesh.inp", mesh)
    good = run()
    assert good.returncode == 0, good.stdout[-2000:]
    assert "nonpositive jacobian" not in good.stdout
    assert "displacements" in (tmp_path / "job.dat").read_text()
    # the check is meaningful: the same mesh with swapped n1/n2 is refused by ccx
    flipped = mesh.tets.copy()
    flipped[:, [0, 1]] = flipped[:, [1, 0]]
    if kind == "tet10":
        flipped[:, [5, 6]] = flipped[:, [6, 5]]
        flipped[:, [7, 8]] = flipped[:, [8, 7]]
    write_tet_mesh(tmp_path / "mesh.inp", TetMesh(mesh.points, flipped))
    bad = run()
    assert bad.returncode != 0 or "nonpositive jacobian" in bad.stdout


def test_inp_coordinates_fit_calculix_20_character_fields(tmp_path):
    """CalculiX reads every entry of a data line as a 20-character field: a coordinate whose
    round-trip repr is longer (-3.5090841499628797e-16, -0.00012345678901234567) made it stop
    with "*ERROR reading *NODE". Such values are rounded to what fits (14 significant digits at
    least); the others are written exactly."""
    pts = np.array([[0.0, 0.0, 0.0], [1.0, -3.5090841499628797e-16, 0.0],
                    [-0.00012345678901234567, 1.0, 0.0], [0.1, 0.2, 123.45678901234567]])
    mesh = TetMesh(pts, np.array([[0, 1, 2, 3]]))
    write_tet_mesh(tmp_path / "m.inp", mesh)
    lines = (tmp_path / "m.inp").read_text().splitlines()
    start = lines.index("*NODE, NSET=Nall") + 1
    rows = [ln.split(",") for ln in lines[start:start + 4]]
    assert all(len(f.strip()) <= 20 for row in rows for f in row)
    back = np.array([[float(f) for f in row[1:]] for row in rows])
    assert np.allclose(back, pts, rtol=1e-13, atol=0)
    assert back[3, 2] == 123.45678901234567 and back[3, 0] == 0.1  # short ones exact
    # stored_points is exactly what the file holds (the exact check rounds its reference so)
    assert np.array_equal(stored_points(tmp_path / "m.inp", pts), back)
    assert np.array_equal(read_tet_mesh(tmp_path / "m.inp").points, back)
    assert stored_points(tmp_path / "m.vtu", pts) is not None
    assert np.array_equal(stored_points(tmp_path / "m.vtu", pts), pts)


# ------------------------------------------------------------------------------------------
# errors
# ------------------------------------------------------------------------------------------


def test_missing_and_unknown(tmp_path):
    with pytest.raises(InputError) as exc:
        read_tet_mesh(tmp_path / "none.vtu")
    expect_error(exc, "none.vtu", "file not found")
    (tmp_path / "x.vtk").write_text("# vtk DataFile\n")
    with pytest.raises(InputError) as exc:
        read_tet_mesh(tmp_path / "x.vtk")
    expect_error(exc, "x.vtk", "'.vtk'", ".vtu", ".msh", ".inp", ".node", ".ele", ".mesh")
    with pytest.raises(InputError) as exc:
        write_tet_mesh(tmp_path / "y.stl", kuhn_box())
    expect_error(exc, "y.stl", "'.stl'", ".vtu")
    write_tet_mesh(tmp_path / "only.node", kuhn_box())
    os.remove(tmp_path / "only.ele")
    with pytest.raises(InputError) as exc:
        read_tet_mesh(tmp_path / "only.node")
    expect_error(exc, "only.ele", "file not found")


def _msh(nodes, elements, version="2.2 0 8"):
    return "\n".join(["$MeshFormat", version, "$EndMeshFormat", "$Nodes", str(len(nodes))]
                     + nodes + ["$EndNodes", "$Elements", str(len(elements))] + elements
                     + ["$EndElements"]) + "\n"


_NODES = ["1 0 0 0", "2 1 0 0", "3 0 1 0", "4 0 0 1"]


@pytest.mark.parametrize("text, fragments", [
    (_msh(_NODES, ["1 4 2 1 1 1 2 3 9"]),
     ["tetrahedron 0 (line 13)", "node tag 9", "not in $Nodes"]),
    (_msh(_NODES, ["1 4 2 1 1 1 2 3"]), ["line 13", "type 4 needs 4 nodes", "has 3"]),
    (_msh(_NODES, ["1 4 2 1 1 1 2 3 x"]), ["tetrahedron 0 (line 13)", "'x'"]),
    (_msh(_NODES, ["1 4 2 1 1 1 2 3 4",
                   "2 11 2 1 1 1 2 3 4 1 2 3 4 1 2"]), ["line 14", "mixes"]),
    (_msh(_NODES[:3] + ["4 0 0 nan"], ["1 4 2 1 1 1 2 3 4"]), ["node 3 (line 9)", "non-finite"]),
    (_msh(_NODES[:2] + ["3 0 one 0", "4 0 0 1"], ["1 4 2 1 1 1 2 3 4"]),
     ["node 2 (line 8)", "'one'"]),
    (_msh(_NODES, ["1 2 2 1 1 1 2 3"]), ["no tetrahedra"]),
    (_msh(_NODES, ["1 4 2 1 1 1 2 3 4"], version="2.2 1 8"), ["binary MSH", "msh22"]),
    (_msh(_NODES, ["1 4 2 1 1 1 2 3 4"], version="3.0 0 8"), ["version 3.0"]),
    ("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n$EndNodes\n",
     ["expected 4 nodes", "after 2", "line 8"]),
    ("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n",
     ["$Nodes (line 4) is not closed"]),
])
def test_msh_errors(tmp_path, text, fragments):
    path = tmp_path / "bad.msh"
    path.write_text(text)
    with pytest.raises(InputError) as exc:
        read_tet_mesh(path)
    expect_error(exc, path, *fragments)


def ascii_vtu(mesh):
    """An ASCII VTU of a tet4 mesh, as other programs write it (we write binary)."""
    m = len(mesh.tets)
    rows = "".join(" ".join(map(str, t)) + "\n" for t in mesh.tets.tolist())
    pts = "".join(" ".join(map(repr, p)) + "\n" for p in mesh.points.tolist())
    return ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" '
            'byte_order="LittleEndian">\n  <UnstructuredGrid>\n'
            f'    <Piece NumberOfPoints="{len(mesh.points)}" NumberOfCells="{m}">\n'
            '      <Points>\n        <DataArray type="Float64" NumberOfComponents="3" '
            f'format="ascii">\n{pts}        </DataArray>\n      </Points>\n      <Cells>\n'
            '        <DataArray type="Int64" Name="connectivity" format="ascii">\n'
            f'{rows}        </DataArray>\n'
            '        <DataArray type="Int64" Name="offsets" format="ascii">\n'
            + "".join(f"{4 * (i + 1)}\n" for i in range(m)) + '        </DataArray>\n'
            '        <DataArray type="UInt8" Name="types" format="ascii">\n' + "10\n" * m
            + "        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n"
            "</VTKFile>\n")


def test_vtu_errors(tmp_path):
    mesh = kuhn_box()
    good = ascii_vtu(mesh)
    path = tmp_path / "good.vtu"
    path.write_text(good)
    assert np.array_equal(read_tet_mesh(path).tets, mesh.tets)
    cases = [
        (good.replace("</Points>", "", 1), ["not valid XML", "line"]),
        (good.replace('Name="connectivity"', 'Name="conn"'), ["no DataArray named"]),
        (good.replace('NumberOfPoints="8"', 'NumberOfPoints="9"'),
         ["DataArray 'Points'", "expected 27 values, found 24"]),
        (good.replace("\n10\n", "\n10 zz\n", 1), ["'types'", "value 1 'zz'"]),
        (good.replace('type="UnstructuredGrid"', 'type="PolyData"'), ["'PolyData'"]),
        (good.replace("0 1 3 7\n", "0 1 3 17\n", 1), ["'connectivity'", "cell 0",
                                                      "point index 17", "8 points"]),
    ]
    for text, fragments in cases:
        bad = tmp_path / "bad.vtu"
        bad.write_text(text)
        with pytest.raises(InputError) as exc:
            read_tet_mesh(bad)
        expect_error(exc, bad, *fragments)
    binary = vtu_appended(mesh, encoding="base64", compress=True)
    bad = tmp_path / "bad64.vtu"
    bad.write_bytes(binary.replace(b"   _", b"   _!!!!", 1))
    with pytest.raises(InputError) as exc:
        read_tet_mesh(bad)
    expect_error(exc, bad, "cannot decode the binary data")


def test_inp_errors(tmp_path):
    head = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n*ELEMENT, TYPE=C3D4\n"
    cases = [
        (head + "1, 1, 2, 3, 5\n", ["element 1 (line 7)", "node 5", "no *NODE defines"]),
        (head + "1, 1, 2, 3, 4\n2, 1, 2,\n*STEP\n", ["line 8", "element 1 is incomplete"]),
        (head + "1, 1, 2, 3, 4\n2, 1, x, 3, 4\n", ["line 8", "'x'"]),
        ("*NODE\n1, 0, 0, 0\n2, 1, zero, 0\n", ["node 1 (line 3)", "'zero'"]),
        ("*NODE\n1, 0, 0\n", ["node 0 (line 2)", "expected 4 values, found 3"]),
        ("*NODE\n1, 0, 0, 0\n*ELEMENT, TYPE=S3\n1, 1, 1, 1\n", ["no C3D4 or C3D10"]),
        ("*NODE\n1, 0, 0, 0\n*INCLUDE, INPUT=missing.inp\n", ["line 3", "missing.inp",
                                                              "not found"]),
        ("1, 0, 0, 0\n", ["line 1", "data before the first keyword"]),
        (head + "1, 1, 2, 3, 4\n*ELEMENT, TYPE=C3D10\n"
         "2, 1, 2, 3, 4, 1, 2, 3, 4, 1, 2\n", ["mixes C3D4 and C3D10"]),
    ]
    for text, fragments in cases:
        path = tmp_path / "bad.inp"
        path.write_text(text)
        with pytest.raises(InputError) as exc:
            read_tet_mesh(path)
        expect_error(exc, path, *fragments)


def test_tetgen_errors(tmp_path):
    node = "# c\n4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
    ele = "2 4 0\n1 1 2 3 4\n2 1 2 4 3\n"
    cases = [
        (node, "2 4 0\n1 1 2 3 4\n2 1 2 4 5\n", "bad.ele",
         ["tetrahedron 1 (line 3)", "node index 5", "4 nodes", "valid indices 1..4"]),
        (node, "3 4 0\n1 1 2 3 4\n2 1 2 4 3\n", "bad.ele",
         ["expected 3 tetrahedra", "ends after 2"]),
        (node.replace("3 0 1 0", "4 0 1 0"), ele, "bad.node",
         ["node 2 (line 5)", "node index 4 where 3 was expected"]),
        (node.replace("3 0 1 0", "3 0 1 nan"), ele, "bad.node",
         ["node 2 (line 5)", "non-finite"]),
        (node.replace("4 3 0 0", "4 2 0 0"), ele, "bad.node", ["line 2", "dimension 2"]),
        (node, "2 8 0\n", "bad.ele", ["8 nodes per tetrahedron"]),
        (node, ele + "3 1 2 3 4\n", "bad.ele", ["line 4", "after the 2 tetrahedra"]),
        (node, "2 4 0\n1 1 2 3 4\n2 1 2 4 3.5\n", "bad.ele",
         ["tetrahedron 1 (line 3)", "3.5", "not an integer"]),
    ]
    for node_text, ele_text, name, fragments in cases:
        (tmp_path / "bad.node").write_text(node_text)
        (tmp_path / "bad.ele").write_text(ele_text)
        with pytest.raises(InputError) as exc:
            read_tet_mesh(tmp_path / "bad.node")
        expect_error(exc, name, *fragments)


def test_medit_errors(tmp_path):
    head = "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n"
    cases = [
        (head + "Tetrahedra\n2\n1 2 3 4 1\n", ["expected 2 Tetrahedra", "ends after 1"]),
        (head + "Tetrahedra\n1\n1 2 3 5 1\n", ["tetrahedron 1 (line 11)", "index 5",
                                                "valid indices 1..4"]),
        (head + "Tetrahedra\n1\n1 2 3 4\n", ["tetrahedron 1 (line 11)", "found 4"]),
        (head + "Tetrahedra\n1\n1 2 3 4 1\nTetrahedraP2\n1\n" + "1 " * 10 + "1\n",
         ["both Tetrahedra and TetrahedraP2"]),
        (head.replace("Dimension 3", "Dimension 2"), ["line 2", "Dimension 2"]),
        (head, ["no Tetrahedra"]),
        ("MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 x 0\n", ["vertex 1 (line 5)",
                                                                         "'x'"]),
        (head + "12\n", ["line 9", "expected a keyword"]),
    ]
    for text, fragments in cases:
        path = tmp_path / "bad.mesh"
        path.write_text(text)
        with pytest.raises(InputError) as exc:
            read_tet_mesh(path)
        expect_error(exc, path, *fragments)


# ------------------------------------------------------------------------------------------
# writers: refusal and atomicity
# ------------------------------------------------------------------------------------------


def test_invalid_mesh_is_refused(tmp_path):
    bad = TetMesh(np.zeros((4, 3)), np.array([[0, 1, 2, 4]]))
    for ext in FORMATS:
        with pytest.raises(InternalError):
            write_tet_mesh(tmp_path / f"bad{ext}", bad)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("ext", FORMATS)
def test_failed_write_keeps_previous_files(tmp_path, monkeypatch, ext):
    old = kuhn_box()
    target = tmp_path / f"m{ext}"
    write_tet_mesh(target, old)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    calls = []
    # the function that formats each block of data (VTU: each binary array)
    name = "_vtu_binary" if ext == ".vtu" else "_format_rows"
    real = getattr(volume_io, name)

    def fail_late(*args):
        calls.append(args[0])
        if len(calls) == 2:  # the first block is already written when this fails
            raise OSError("disk full (simulated)")
        return real(*args)

    monkeypatch.setattr(volume_io, name, fail_late)
    with pytest.raises(OSError):
        write_tet_mesh(target, quadratic(old))
    assert len(calls) == 2
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    fresh = tmp_path / "sub"
    fresh.mkdir()
    calls.clear()
    with pytest.raises(OSError):
        write_tet_mesh(fresh / f"new{ext}", old)
    assert list(fresh.iterdir()) == []  # neither the file(s) nor temporaries
