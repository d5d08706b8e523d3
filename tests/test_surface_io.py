# SPDX-License-Identifier: LGPL-2.1-or-later
"""Tests of FemBspTet.io.surface_io (OFF, STL, OBJ, PLY) and FemBspTet.io.atomic_file.

All data are made here; nothing is read from outside the test's tmp_path.
"""

import os
import stat
import struct

import meshio
import numpy as np
import pytest

from FemBspTet.io import surface_io
from FemBspTet.io.atomic_file import atomic_output, atomic_outputs
from FemBspTet.kernel.errors import InputError, InternalError
from FemBspTet.kernel.mesh_types import Surface
from FemBspTet.io.surface_io import read_surface, write_surface


# ------------------------------------------------------------------------------------------
# helpers
# ------------------------------------------------------------------------------------------


def cube_surface(xs=(0.1, 1.3), ys=(-0.2, 1.0 / 3.0), zs=(0.3, 2.7)):
    """Closed box surface: 8 vertices (index x + 2y + 4z), 12 outward triangles, 6 tags."""
    pts = np.array([[xs[i & 1], ys[(i >> 1) & 1], zs[(i >> 2) & 1]] for i in range(8)])
    quads = [(0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4),
             (1, 3, 7, 5)]
    center = pts.mean(axis=0)
    tris, tags = [], []
    for tag, (a, b, c, d) in enumerate(quads):
        for tri in ((a, b, c), (a, c, d)):
            p = pts[list(tri)]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            if np.dot(normal, p.mean(axis=0) - center) < 0:
                tri = (tri[0], tri[2], tri[1])
            tris.append(tri)
            tags.append(tag)
    return Surface(pts, np.array(tris), face_tags=np.array(tags))


def signed_volume(points, tris):
    p = points[tris]
    return np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0


def same_triangle_soup(a_points, a_tris, b_points, b_tris):
    """Same triangles, same corner order, same coordinates (any vertex numbering)."""
    return np.array_equal(a_points[a_tris], b_points[b_tris])


def expect_error(exc_info, path, *fragments):
    message = str(exc_info.value)
    assert os.path.basename(str(path)) in message, message
    for fragment in fragments:
        assert fragment in message, f"{fragment!r} not in {message!r}"


def write_text(path, text):
    path.write_text(text)
    return path


def ply_binary(points, tris, endian="<", count_type="uchar", index_type="int",
               list_name="vertex_indices", coord_type="float", with_extra=True):
    """A binary PLY made by hand (extra vertex colour, extra face flag, extra 'edge' element)."""
    ply_np = {"float": "f4", "double": "f8", "uchar": "u1", "int": "i4", "uint": "u4",
              "ushort": "u2", "short": "i2", "char": "i1"}
    fmt = "binary_little_endian" if endian == "<" else "binary_big_endian"
    header = ["ply", f"format {fmt} 1.0", "comment made by a test",
              f"element vertex {len(points)}", f"property {coord_type} x",
              f"property {coord_type} y", f"property {coord_type} z"]
    if with_extra:
        header.append("property uchar red")
    header += [f"element face {len(tris)}",
               f"property list {count_type} {index_type} {list_name}"]
    if with_extra:
        header.append("property short flag")
        header += ["element edge 2", "property int vertex1", "property int vertex2"]
    header.append("end_header")
    vfields = [(a, endian + ply_np[coord_type]) for a in "xyz"]
    if with_extra:
        vfields.append(("red", "u1"))
    varr = np.zeros(len(points), dtype=vfields)
    for j, a in enumerate("xyz"):
        varr[a] = points[:, j]
    ffields = [("n", endian + ply_np[count_type]), ("i", endian + ply_np[index_type], (3,))]
    if with_extra:
        ffields.append(("flag", endian + "i2"))
        varr["red"] = 200
    farr = np.zeros(len(tris), dtype=ffields)
    farr["n"] = 3
    farr["i"] = tris
    body = varr.tobytes() + farr.tobytes()
    if with_extra:
        body += np.array([[0, 1], [1, 2]], dtype=endian + "i4").tobytes()
    return ("\n".join(header) + "\n").encode("ascii") + body


# ------------------------------------------------------------------------------------------
# round trips
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("ext", [".off", ".obj", ".ply", ".OFF"])
def test_text_formats_round_trip_bit_exact(tmp_path, ext):
    surface = cube_surface()
    path = tmp_path / f"cube{ext}"
    write_surface(path, surface)
    back = read_surface(path)
    assert back.points.dtype == np.float64 and back.triangles.dtype == np.int64
    assert np.array_equal(back.points, surface.points)  # bit-identical (repr round trip)
    assert np.array_equal(back.triangles, surface.triangles)
    assert back.source == str(path)
    assert signed_volume(back.points, back.triangles) > 0
    if ext == ".ply":
        assert np.array_equal(back.face_tags, surface.face_tags)


@pytest.mark.parametrize("ascii_stl", [False, True])
def test_stl_round_trip_merges_vertices(tmp_path, ascii_stl):
    surface = cube_surface()
    path = tmp_path / "cube.stl"
    write_surface(path, surface, ascii=ascii_stl)
    data = path.read_bytes()
    if ascii_stl:
        assert data.startswith(b"solid")
        expected_points = surface.points
    else:
        assert len(data) == 84 + 50 * 12
        assert not data.startswith(b"solid")
        expected_points = surface.points.astype(np.float32).astype(np.float64)
    back = read_surface(path)
    assert len(back.points) == 8  # 36 corners merged into the 8 box corners
    assert len(back.triangles) == 12
    assert same_triangle_soup(back.points, back.triangles, expected_points, surface.triangles)
    # same topology: the vertex numbering is a bijection of the original one
    mapping = {}
    for ours, theirs in zip(back.triangles.ravel(), surface.triangles.ravel()):
        assert mapping.setdefault(int(ours), int(theirs)) == int(theirs)
    assert sorted(mapping.values()) == list(range(8))
    # first-occurrence numbering: the first triangle uses vertices 0, 1, 2
    assert back.triangles[0].tolist() == [0, 1, 2]


def test_stl_binary_normals_are_unit_outward(tmp_path):
    surface = cube_surface()
    path = tmp_path / "n.stl"
    write_surface(path, surface)
    records = np.frombuffer(path.read_bytes(), dtype=surface_io._STL_RECORD, offset=84)
    p = surface.points[surface.triangles]
    expected = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    assert np.allclose(records["normal"], expected, atol=1e-6)


def test_binary_stl_whose_header_starts_with_solid(tmp_path):
    surface = cube_surface(xs=(0.5, 1.25), ys=(-0.75, 2.0), zs=(0.0, 3.5))
    path = tmp_path / "tricky.stl"
    write_surface(path, surface)
    data = bytearray(path.read_bytes())
    data[:80] = b"solid but actually binary".ljust(80, b" ")
    path.write_bytes(bytes(data))
    back = read_surface(path)
    assert same_triangle_soup(back.points, back.triangles, surface.points, surface.triangles)


def test_stl_merge_is_exact_and_first_occurrence(tmp_path):
    text = """solid two
facet normal 0 0 1
 outer loop
  vertex 1 0 0
  vertex 0 1 0
  vertex 0 0 0
 endloop
endfacet
facet normal 0 0 1
 outer loop
  vertex 1 0 0
  vertex 1 1 0
  vertex 0 1 0
 endloop
endfacet
facet normal 0 0 1
 outer loop
  vertex 1.0000000000000002 0 0
  vertex 1 1 -0.0
  vertex 0 1 0
 endloop
endfacet
endsolid two
"""
    back = read_surface(write_text(tmp_path / "two.stl", text))
    assert back.points.tolist() == [[1, 0, 0], [0, 1, 0], [0, 0, 0], [1, 1, 0],
                                    [1.0000000000000002, 0, 0]]
    # -0.0 merged with 0.0, but a coordinate one ulp away is a different vertex
    assert back.triangles.tolist() == [[0, 1, 2], [0, 3, 1], [4, 3, 1]]


def test_stl_ascii_odd_layout_uses_slow_parser(tmp_path):
    surface = cube_surface()
    reference = tmp_path / "ref.stl"
    write_surface(reference, surface, ascii=True)
    text = reference.read_text().upper()  # upper-case keywords
    text = text.replace("ENDSOLID FEMBSPTET\n", "ENDSOLID\nsolid second\n") + "endsolid\n"
    text = text.replace("\n  VERTEX", "\n\tvertex\t")
    odd = write_text(tmp_path / "odd.stl", text)
    back = read_surface(odd)
    fast = read_surface(reference)
    assert np.array_equal(back.points, fast.points)
    assert np.array_equal(back.triangles, fast.triangles)


def test_stl_written_by_meshio(tmp_path):
    surface = cube_surface()
    for binary in (True, False):
        path = tmp_path / f"meshio_{binary}.stl"
        meshio.write(path, meshio.Mesh(surface.points, [("triangle", surface.triangles)]),
                     binary=binary)
        back = read_surface(path)
        expected = surface.points.astype(np.float32).astype(np.float64) if binary else \
            surface.points
        assert len(back.points) == 8
        assert np.allclose(back.points[back.triangles], expected[surface.triangles],
                           rtol=0, atol=1e-12 if binary else 1e-6)


def test_off_variants(tmp_path):
    text = """# a comment before the keyword
COFF 4 4 0   # counts on the keyword line
0 0 0  255 0 0 255
1 0 0  0 255 0 255   # colour columns are ignored

0 1 0  0 0 255 255
0 0 1  9 9 9 9
3 0 2 1   1.0 0.5 0.5
3 0 1 3
3 0 3 2
  3 1 2 3   # trailing comment
"""
    back = read_surface(write_text(tmp_path / "c.off", text))
    assert back.points.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert back.triangles.tolist() == [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    noff = "NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n"
    back = read_surface(write_text(tmp_path / "n.off", noff))
    assert back.triangles.tolist() == [[0, 1, 2]]
    nokeyword = "3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    assert read_surface(write_text(tmp_path / "k.off", nokeyword)).points.shape == (3, 3)


def test_obj_variants(tmp_path):
    text = """# exported by something
mtllib x.mtl
o thing
v 0 0 0
v 1 0 0 1.0
v 0 1 0 1.0 0.5 0.5 0.5
vt 0 0
vn 0 0 1
g group
usemtl m
s off
f 1/1/1 3/1/1 2/1/1
v 0 0 1
f -4//1 -3//1 -1//1
f 1/1 4/1 3/1
f 2 3 4
l 1 2
"""
    back = read_surface(write_text(tmp_path / "v.obj", text))
    assert back.points.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert back.triangles.tolist() == [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


@pytest.mark.parametrize("endian", ["<", ">"])
@pytest.mark.parametrize("types", [("float", "uchar", "int", "vertex_indices"),
                                   ("double", "uint", "ushort", "vertex_index"),
                                   ("double", "uchar", "uint", "vertex_indices")])
def test_ply_binary(tmp_path, endian, types):
    coord, count, index, name = types
    surface = cube_surface(xs=(0.5, 1.25), ys=(-0.75, 2.0), zs=(0.0, 3.5))
    path = tmp_path / "b.ply"
    path.write_bytes(ply_binary(surface.points, surface.triangles, endian, count, index, name,
                                coord))
    back = read_surface(path)
    assert np.array_equal(back.points, surface.points)
    assert np.array_equal(back.triangles, surface.triangles)


def test_ply_binary_without_extras_and_ascii_with_extras(tmp_path):
    surface = cube_surface(xs=(0.5, 1.25), ys=(-0.75, 2.0), zs=(0.0, 3.5))
    path = tmp_path / "plain.ply"
    path.write_bytes(ply_binary(surface.points, surface.triangles, with_extra=False))
    back = read_surface(path)
    assert np.array_equal(back.triangles, surface.triangles)
    # ASCII with an extra vertex property, a face property before the list, an extra element
    lines = ["ply", "format ascii 1.0", "element vertex 8", "property float x",
             "property float y", "property uchar red", "property float z",
             "element face 12", "property uchar flag", "property list uchar int vertex_indices",
             "property int face_tag", "element edge 1", "property int a", "property int b",
             "end_header"]
    lines += [f"{x!r} {y!r} 7 {z!r}" for x, y, z in surface.points.tolist()]
    lines += [f"1 3 {a} {b} {c} {t}" for (a, b, c), t in zip(surface.triangles.tolist(),
                                                           surface.face_tags.tolist())]
    lines += ["0 1"]
    back = read_surface(write_text(tmp_path / "extra.ply", "\n".join(lines) + "\n"))
    assert np.array_equal(back.points, surface.points)
    assert np.array_equal(back.triangles, surface.triangles)
    assert np.array_equal(back.face_tags, surface.face_tags)


def test_ply_written_by_meshio(tmp_path):
    surface = cube_surface()
    for binary in (True, False):
        path = tmp_path / f"m{binary}.ply"
        meshio.write(path, meshio.Mesh(surface.points, [("triangle", surface.triangles)]),
                     binary=binary)
        back = read_surface(path)
        assert np.allclose(back.points, surface.points, atol=1e-12 if binary else 1e-6)
        assert np.array_equal(back.triangles, surface.triangles)


@pytest.mark.parametrize("ext", [".off", ".obj", ".ply", ".stl"])
def test_meshio_reads_what_we_write(tmp_path, ext):
    surface = cube_surface()
    path = tmp_path / f"w{ext}"
    write_surface(path, surface)
    mesh = meshio.read(path)
    cells = mesh.get_cells_type("triangle")
    assert len(cells) == 12
    if ext == ".stl":
        assert np.allclose(mesh.points[cells], surface.points[surface.triangles], atol=1e-6)
    else:
        assert np.array_equal(mesh.points, surface.points)
        assert np.array_equal(cells, surface.triangles)


def test_reading_is_deterministic(tmp_path):
    rng = np.random.default_rng(5)
    points = rng.random((200, 3))
    tris = rng.integers(0, 200, (500, 3))
    surface = Surface(points, tris)
    for ext in (".stl", ".off", ".ply", ".obj"):
        path = tmp_path / f"r{ext}"
        write_surface(path, surface)
        a, b = read_surface(path), read_surface(path)
        assert np.array_equal(a.points, b.points) and np.array_equal(a.triangles, b.triangles)


def test_big_off_reads_fast(tmp_path):
    """200k triangles: well within the budget of a few seconds for 1e6."""
    import time

    rng = np.random.default_rng(1)
    surface = Surface(rng.random((100_000, 3)), rng.integers(0, 100_000, (200_000, 3)))
    path = tmp_path / "big.off"
    write_surface(path, surface)
    start = time.perf_counter()
    back = read_surface(path)
    elapsed = time.perf_counter() - start
    assert np.array_equal(back.triangles, surface.triangles)
    assert elapsed < 5.0, elapsed


# ------------------------------------------------------------------------------------------
# errors
# ------------------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    path = tmp_path / "nope.off"
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, "file not found")
    assert exc.value.exit_code == 2


def test_unknown_extension_lists_supported(tmp_path):
    path = write_text(tmp_path / "thing.xyz", "1 2 3\n")
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, "'.xyz'", ".off", ".stl", ".obj", ".ply")
    with pytest.raises(InputError) as exc:
        write_surface(tmp_path / "out.dat", cube_surface())
    expect_error(exc, "out.dat", "'.dat'", ".ply")


def test_directory_and_empty_file(tmp_path):
    folder = tmp_path / "dir.stl"
    folder.mkdir()
    with pytest.raises(InputError) as exc:
        read_surface(folder)
    expect_error(exc, folder, "directory")
    empty = write_text(tmp_path / "empty.obj", "\n  \n")
    with pytest.raises(InputError) as exc:
        read_surface(empty)
    expect_error(exc, empty, "empty")


OFF_HEAD = "OFF\n4 4 0\n"
OFF_VERTS = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
OFF_FACES = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"


@pytest.mark.parametrize("text, fragments", [
    ("OFF\n8 12 0\n0 0 0\n1 0 0\n1 1 0\n",
     ["expected 8 vertices", "ends after 3", "line 5 (end of file)"]),
    (OFF_HEAD + OFF_VERTS + "3 0 2 1\n3 0 1 3\n",
     ["expected 4 faces", "ends after 2"]),
    (OFF_HEAD + "0 0 0\n1 0x 0\n0 1 0\n0 0 1\n" + OFF_FACES,
     ["vertex 1 (line 4)", "'0x'"]),
    (OFF_HEAD + "0 0 0\n1 0 0\n0 nan 0\n0 0 1\n" + OFF_FACES,
     ["vertex 2 (line 5)", "non-finite", "nan"]),
    (OFF_HEAD + "0 0 0\n1 0 0\n0 1 0\n0 0 inf\n" + OFF_FACES,
     ["vertex 3 (line 6)", "non-finite", "inf"]),
    (OFF_HEAD + OFF_VERTS + "3 0 2 1\n3 0 1 3\n3 0 7 2\n3 1 2 3\n",
     ["face 2 (line 9)", "index 7", "4 vertices", "0..3"]),
    (OFF_HEAD + OFF_VERTS + "3 0 2 1\n3 0 -1 3\n3 0 3 2\n3 1 2 3\n",
     ["face 1 (line 8)", "negative vertex index -1"]),
    (OFF_HEAD + OFF_VERTS + "3 0 2 1\n4 0 1 3 2\n3 0 3 2\n3 1 2 3\n",
     ["face 1 (line 8)", "4 vertices", "only triangles"]),
    (OFF_HEAD + OFF_VERTS + "3 0 2 1\n3 0 1\n3 0 3 2\n3 1 2 3\n",
     ["face 1 (line 8)", "found 2"]),
    (OFF_HEAD + OFF_VERTS + "3 0 2 1\n3 0 1.5 3\n3 0 3 2\n3 1 2 3\n",
     ["face 1 (line 8)", "'1.5'"]),
    (OFF_HEAD + OFF_VERTS + OFF_FACES + "3 0 1 2\n",
     ["line 11", "after the 4 faces"]),
    ("OFF\n4 0 0\n" + OFF_VERTS, ["0 faces"]),
    ("OFF\nfour 4 0\n", ["line 2", "'four'"]),
    ("PLY\n4 4 0\n", ["line 1", "expected 'OFF'"]),
    ("OFF BINARY\n4 4 0\n", ["binary OFF"]),
])
def test_off_errors(tmp_path, text, fragments):
    path = write_text(tmp_path / "bad.off", text)
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, *fragments)


def _ascii_stl(facets):
    out = ["solid t"]
    for corners in facets:
        out += ["facet normal 0 0 0", "outer loop"]
        out += [f"vertex {c}" for c in corners]
        out += ["endloop", "endfacet"]
    out.append("endsolid t")
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("text, fragments", [
    (_ascii_stl([["0 0 0", "1 0 0", "0 1 0"], ["0 0 0", "1 0 0", "0 1 0", "0 0 1"]]),
     ["facet 1 (line 14)", "more than 3 vertices"]),
    (_ascii_stl([["0 0 0", "1 0 0", "0 1 0"], ["0 0 0", "1 O 0", "0 1 0"]]),
     ["facet 1 (line 12)", "'o'"]),
    (_ascii_stl([["0 0 0", "1 0 0", "0 1 0"], ["0 0 0", "1 0 0", "nan 1 0"]]),
     ["facet 1 (line 13)", "non-finite"]),
    (_ascii_stl([["0 0 0", "1 0 0"]]), ["facet 0 (line 6)", "2 vertices"]),
    ("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n",
     ["ends inside facet 0", "end of file"]),
    ("solid t\nendsolid t\n", ["no facets"]),
    ("hello world\n", ["does not start with 'solid'"]),
])
def test_stl_ascii_errors(tmp_path, text, fragments):
    path = write_text(tmp_path / "bad.stl", text)
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, *fragments)


def test_stl_binary_errors(tmp_path):
    surface = cube_surface()
    path = tmp_path / "b.stl"
    write_surface(path, surface)
    data = path.read_bytes()
    truncated = tmp_path / "truncated.stl"
    truncated.write_bytes(data[: 84 + 50 * 5 + 20])
    with pytest.raises(InputError) as exc:
        read_surface(truncated)
    expect_error(exc, truncated, "12 triangles", f"has {84 + 270} bytes",
                 "ends after 5 complete triangles")
    solid = tmp_path / "solid_truncated.stl"
    solid.write_bytes(b"solid binary header".ljust(80, b" ") + data[80: 84 + 50 * 5 + 20])
    with pytest.raises(InputError) as exc:
        read_surface(solid)
    expect_error(exc, solid, "truncated binary STL", "ends after 5 complete triangles")
    longer = tmp_path / "longer.stl"
    longer.write_bytes(data + b"xx")
    with pytest.raises(InputError) as exc:
        read_surface(longer)
    expect_error(exc, longer, "2 bytes of unexpected data")
    nan = bytearray(data)
    struct.pack_into("<f", nan, 84 + 50 * 7 + 12 + 12 * 2 + 4, float("nan"))
    bad = tmp_path / "nan.stl"
    bad.write_bytes(bytes(nan))
    with pytest.raises(InputError) as exc:
        read_surface(bad)
    expect_error(exc, bad, "corner 2 of triangle 7", "non-finite", f"byte {84 + 350 + 36}")
    empty = tmp_path / "zero.stl"
    empty.write_bytes(b"\x01" * 80 + struct.pack("<I", 0))
    with pytest.raises(InputError) as exc:
        read_surface(empty)
    expect_error(exc, empty, "no triangles")


OBJ_V = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"


@pytest.mark.parametrize("text, fragments", [
    (OBJ_V + "f 1 3 2\nf 1 2 4 3\n", ["face 1 (line 6)", "4 vertices", "only triangles"]),
    (OBJ_V + "f 1 3 2\nf 1 2 9\n", ["face 1 (line 6)", "vertex index 9", "1..4"]),
    (OBJ_V + "f 1 3 2\nf 1 0 3\n", ["face 1 (line 6)", "index 0"]),
    ("v 0 0 0\nf -1 -2 -3\n" + OBJ_V, ["face 0 (line 2)", "relative vertex index -2",
                                         "only 1 vertex is defined"]),
    (OBJ_V + "f 1 3 2\nf 1 two 3\n", ["face 1 (line 6)", "'two'"]),
    ("v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n", ["vertex 2 (line 2)", "'zero'"]),
    ("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", ["vertex 2 (line 2)", "found 2"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 -inf\nf 1 2 3\n", ["vertex 3 (line 3)", "non-finite"]),
    (OBJ_V + "l 1 2\n", ["no faces"]),
    ("f 1 2 3\n", ["no vertices"]),
])
def test_obj_errors(tmp_path, text, fragments):
    path = write_text(tmp_path / "bad.obj", text)
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, *fragments)


PLY_HEAD = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
            "end_header\n")


@pytest.mark.parametrize("text, fragments", [
    (PLY_HEAD + OFF_VERTS + "3 0 2 1\n4 0 1 3 2\n3 0 3 2\n3 1 2 3\n",
     ["face 1 (line 15)", "4 vertices", "only triangles"]),
    (PLY_HEAD + OFF_VERTS + "3 0 2 1\n3 0 1 3\n3 0 3 4\n3 1 2 3\n",
     ["face 2 (line 16)", "index 4", "out of range"]),
    (PLY_HEAD + "0 0 0\n1 0 0\n", ["expected 4 vertices", "ends after 2"]),
    (PLY_HEAD + "0 0 0\n1 0 0 5\n0 1 0\n0 0 1\n" + OFF_FACES,
     ["vertex 1 (line 11)", "expected 3 values, found 4"]),
    (PLY_HEAD + "0 0 0\n1 nan 0\n0 1 0\n0 0 1\n" + OFF_FACES,
     ["vertex 1 (line 11)", "non-finite"]),
    (PLY_HEAD.replace("ascii", "utf8"), ["line 2", "unknown PLY format"]),
    (PLY_HEAD.replace("end_header\n", ""), ["no 'end_header'"]),
    (PLY_HEAD.replace("vertex_indices", "corners"), ["line 7", "'vertex_indices'"]),
    (PLY_HEAD.replace("property float z\n", ""), ["line 3", "no property 'z'"]),
])
def test_ply_ascii_errors(tmp_path, text, fragments):
    path = write_text(tmp_path / "bad.ply", text)
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, *fragments)


def test_ply_binary_errors(tmp_path):
    surface = cube_surface()
    good = ply_binary(surface.points, surface.triangles, with_extra=False)
    body = good.index(b"end_header\n") + len(b"end_header\n")
    face_bytes = 1 + 12
    # a quad as face 3: set its count byte to 4
    quad = bytearray(good)
    quad[body + 8 * 12 + 3 * face_bytes] = 4
    path = tmp_path / "quad.ply"
    path.write_bytes(bytes(quad))
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, "face 3", "4 vertices", f"byte {body + 96 + 3 * face_bytes}")
    path = tmp_path / "short.ply"
    path.write_bytes(good[: body + 5 * 12 + 3])
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, "truncated", "expected 8 vertex elements", "ends after 5")
    path = tmp_path / "shortfaces.ply"
    path.write_bytes(good[: body + 96 + 7 * face_bytes])
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, "truncated", "expected 12 face elements", "ends after 7")
    bad_index = bytearray(good)
    struct.pack_into("<i", bad_index, body + 96 + 5 * face_bytes + 1 + 4, 99)
    path = tmp_path / "index.ply"
    path.write_bytes(bytes(bad_index))
    with pytest.raises(InputError) as exc:
        read_surface(path)
    expect_error(exc, path, "face 5", "index 99", "8 vertices")


# ------------------------------------------------------------------------------------------
# atomic output
# ------------------------------------------------------------------------------------------


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def test_atomic_output_writes_and_cleans_up(tmp_path):
    target = tmp_path / "a.txt"
    with atomic_output(target) as out:
        out.write("hello\n")
        assert not target.exists()  # nothing visible before the end
        assert len(leftovers(tmp_path)) == 1
        assert leftovers(tmp_path)[0].startswith(".a.txt.")
    assert target.read_text() == "hello\n"
    assert leftovers(tmp_path) == []
    umask = os.umask(0o022)
    os.umask(umask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~umask
    with atomic_output(target, "wb") as out:
        out.write(b"\x00\x01")
    assert target.read_bytes() == b"\x00\x01"


def test_atomic_output_failure_leaves_nothing_or_previous(tmp_path):
    target = tmp_path / "b.txt"
    with pytest.raises(RuntimeError):
        with atomic_output(target) as out:
            out.write("partial")
            raise RuntimeError("boom")
    assert not target.exists()
    assert leftovers(tmp_path) == []
    target.write_text("previous\n")
    with pytest.raises(KeyboardInterrupt):
        with atomic_output(target) as out:
            out.write("partial")
            raise KeyboardInterrupt
    assert target.read_text() == "previous\n"
    assert leftovers(tmp_path) == []


def test_writer_failure_keeps_previous_file(tmp_path, monkeypatch):
    target = tmp_path / "s.off"
    target.write_text("previous\n")
    calls = []

    def failing(fmt, arr):
        calls.append(fmt)
        raise OSError("disk full (simulated)")

    monkeypatch.setattr(surface_io, "_format_rows", failing)
    with pytest.raises(OSError):
        write_surface(target, cube_surface())
    assert calls  # the writer really ran and failed midway
    assert target.read_text() == "previous\n"
    assert leftovers(tmp_path) == []
    fresh = tmp_path / "fresh.ply"
    with pytest.raises(OSError):
        write_surface(fresh, cube_surface())
    assert not fresh.exists()
    assert leftovers(tmp_path) == []


def test_invalid_surface_is_refused_before_writing(tmp_path):
    bad = Surface(np.zeros((3, 3)), np.array([[0, 1, 5]]))
    target = tmp_path / "bad.stl"
    with pytest.raises(InternalError):
        write_surface(target, bad)
    assert not target.exists() and leftovers(tmp_path) == []


def test_atomic_outputs_all_or_nothing(tmp_path):
    a, b = tmp_path / "x.node", tmp_path / "x.ele"
    with atomic_outputs([a, b]) as (fa, fb):
        fa.write("A\n")
        fb.write("B\n")
        assert not a.exists() and not b.exists()
    assert a.read_text() == "A\n" and b.read_text() == "B\n"
    with pytest.raises(ValueError):
        with atomic_outputs([a, b]) as (fa, fb):
            fa.write("new A\n")
            raise ValueError("second file failed")
    assert a.read_text() == "A\n" and b.read_text() == "B\n"
    assert leftovers(tmp_path) == []


def test_atomic_output_missing_directory(tmp_path):
    target = tmp_path / "no" / "such" / "dir" / "f.off"
    with pytest.raises(InputError) as exc:
        write_surface(target, cube_surface())
    expect_error(exc, target, "does not exist")
