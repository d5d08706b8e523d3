# SPDX-License-Identifier: LGPL-2.1-or-later
"""Convert between :class:`~FemBspTet.kernel.mesh_types.TetMesh` and FreeCAD's ``Fem.FemMesh``, and write
or read mesh files through FreeCAD's own writers and readers.

Conventions (FreeCAD 0.20.2's FemMesh, SMESH underneath):

* Our tets are positively oriented, ``det[b - a, c - a, d - a] > 0``; SMESH (FreeCAD's FemMesh)
  uses the opposite sign, ``(p2 - p1) x (p3 - p1) . (p4 - p1) < 0``. Converting swaps corners 1
  and 2. For tet10 (both use ``[n1, n2, n3, n4, m12, m23, m31, m14, m24, m34]``) the mid-edge
  nodes follow the corners: with corners ``(n2, n1, n3, n4)`` the edges 1-2, 2-3, 3-1, 1-4,
  2-4, 3-4 are the old edges 2-1, 1-3, 3-2, 2-4, 1-4, 3-4, i.e. ``[m12, m31, m23, m24, m14,
  m34]``. The permutation (:data:`TET4_SWAP`, :data:`TET10_SWAP`) is its own inverse, so the
  same one converts back.
* FemMesh node ids are 1-based: ``TetMesh.points[i]`` becomes node ``i + 1``, ``TetMesh.tets[e]``
  becomes volume ``e + 1``. FemMesh coordinates are global, in mm; the FemMesh placement stays
  identity.
* Mesh files are written by ``FemMesh.write`` (format chosen by the file extension) under the
  target's name in a temporary directory next to it, then renamed over the target: a failure
  leaves no partial file and keeps an existing one.

Precision of the FreeCAD writers (0.20.2, measured by writing and reading back): ``.unv``,
``.med`` exact; ``.inp`` about 1e-13 relative; ``.vtu`` float32 (6e-8 relative); ``.vtk`` 6
significant digits (5e-6 relative); ``.z88`` 6 digits after the decimal point (5e-7 mm
absolute). The ``.vtk`` and ``.vtu`` writers need node ids 1..n without gaps (they emit garbage
points for missing ids), which :func:`tetmesh_to_femmesh` guarantees.
"""

import os
import shutil
import stat
import tempfile

import numpy as np

from ..io.volume_io import _checked_groups
from ..kernel.errors import InputError, InternalError
from ..kernel.freecad_env import import_freecad
from ..kernel.mesh_types import TetMesh

#: Our corner order -> SMESH corner order (swap n1, n2). Its own inverse.
TET4_SWAP = (1, 0, 2, 3)
#: Our tet10 order -> SMESH tet10 order (swap n1, n2; m23 <-> m31; m14 <-> m24). Its own inverse.
TET10_SWAP = (1, 0, 2, 3, 4, 6, 5, 8, 7, 9)

#: Extensions ``FemMesh.write`` / ``Fem.read`` handle for volume meshes, with format names.
FREECAD_MESH_FORMATS = {
    ".unv": "UNV (I-DEAS universal)",
    ".med": "MED (Salome)",
    ".z88": "Z88",
    ".vtk": "VTK legacy",
    ".vtu": "VTK XML unstructured grid",
    ".inp": "Abaqus/CalculiX INP",
}


def _swap_for(nodes_per_tet):
    return np.array(TET10_SWAP if nodes_per_tet == 10 else TET4_SWAP, dtype=np.int64)


def signed_volumes6(points, tets):
    """Six times the signed volume ``det[b - a, c - a, d - a]`` of each tet (corner nodes)."""
    p = np.asarray(points, dtype=np.float64)
    t = np.asarray(tets, dtype=np.int64)
    if len(t) == 0:
        return np.zeros(0)
    a, b, c, d = (p[t[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)


# --------------------------------------------------------------------------------------------
# TetMesh <-> FemMesh
# --------------------------------------------------------------------------------------------

def tetmesh_to_femmesh(mesh, groups=None, group_prefix=""):
    """Build a ``Fem.FemMesh`` (SMESH orientation, 1-based ids) from a positively oriented TetMesh.

    mesh:         :class:`TetMesh` with (m, 4) or (m, 10) tets, positively oriented.
    groups:       optional :class:`~FemBspTet.kernel.mesh_types.MeshGroups`: the CAD faces' triangles
                  become FemMesh faces (tria3, or tria6 for tet10; ids m + 1, m + 2, ...), and
                  each CAD face a "Face" group of them and a "Node" group of their nodes, each
                  solid (if ``groups.tet_solid`` is given) a "Volume" group, named
                  ``group_prefix + name`` (``Face3``, ``Solid1``).

    Nodes get ids 1..n in ``mesh.points`` order, volumes ids 1..m in ``mesh.tets`` order. Uses
    ``FemMesh.addVolumeList`` where FreeCAD has it (1.0+), else ``addVolume`` per tet (0.20).

    Raises InputError for non-finite coordinates, out-of-range node indices, or tets that are
    not positively oriented (zero or negative volume; the message names the first one).
    """

    import_freecad()
    import Fem

    _validate_tetmesh(mesh)
    fem = Fem.FemMesh()
    _fill_femmesh(fem, mesh, groups, group_prefix)
    return fem


def _validate_tetmesh(mesh):
    where = mesh.source or "mesh"
    pts, tets = mesh.points, mesh.tets
    if not np.all(np.isfinite(pts)):
        bad = int(np.nonzero(~np.isfinite(pts).all(axis=1))[0][0])
        raise InputError("point %d has a non-finite coordinate %s" % (bad, pts[bad]), where=where)
    if len(tets) == 0:
        raise InputError("the mesh has no tetrahedra", where=where)
    if tets.min() < 0 or tets.max() >= len(pts):
        e = int(np.nonzero((tets < 0).any(axis=1) | (tets >= len(pts)).any(axis=1))[0][0])
        raise InputError("tet %d refers to node indices %s outside 0..%d"
                         % (e, tets[e].tolist(), len(pts) - 1), where=where)
    det = signed_volumes6(pts, tets)
    bad = np.nonzero(~(det > 0))[0]
    if len(bad):
        e = int(bad[0])
        raise InputError(
            "%d tet(s) are not positively oriented (det[b-a, c-a, d-a] <= 0), first: tet %d "
            "with nodes %s, 6*volume %.6g" % (len(bad), e, tets[e, :4].tolist(), det[e]),
            where=where)


def _fill_femmesh(fem, mesh, groups=None, group_prefix=""):
    """Add the nodes and volumes of ``mesh``, and the faces and groups of ``groups``, to an
    empty FemMesh ``fem``."""
    pts, tets = mesh.points, mesh.tets
    add_node = fem.addNode
    for i, (x, y, z) in enumerate(pts.tolist(), start=1):
        add_node(x, y, z, i)

    conn = (tets[:, _swap_for(tets.shape[1])] + 1).tolist()
    if hasattr(fem, "addVolumeList"):  # FreeCAD 1.0+: (flat node ids, nodes per element)
        ids = fem.addVolumeList([n for row in conn for n in row], [tets.shape[1]] * len(conn))
        if list(ids) != list(range(1, len(conn) + 1)):
            raise InternalError("FemMesh.addVolumeList numbered the volumes %s..., expected 1..%d"
                                % (list(ids)[:3], len(conn)))
    else:  # FreeCAD 0.20/0.21
        add_volume = fem.addVolume
        for e, row in enumerate(conn, start=1):
            add_volume(row, e)

    if groups is not None:
        _add_groups(fem, mesh, groups, group_prefix)
    return fem


def _add_groups(fem, mesh, groups, prefix):
    """The faces and groups of :func:`tetmesh_to_femmesh`."""

    sets = _checked_groups(mesh.source or "mesh", groups, mesh.points, mesh.tets)
    _add_faces(fem, sets.tri, sets.tags, sets.face_names, len(mesh.tets) + 1, prefix)
    for t in sets.solids().tolist() if groups.tet_solid is not None else ():
        fem.addGroupElements(fem.addGroup(prefix + sets.solid_names[t], "Volume"),
                             (np.flatnonzero(sets.solid == t) + 1).tolist())


def _add_faces(fem, tri, tags, face_names, first_id, prefix):
    """The triangles ``tri`` (0-based nodes; tria3 or tria6) as faces with ids first_id, ...,
    and per CAD face (``tags``) a "Face" group of them and a "Node" group of their nodes."""
    face_ids = np.arange(first_id, first_id + len(tri))
    add_face = fem.addFace
    for e, row in zip(face_ids.tolist(), (tri + 1).tolist()):
        add_face(row, e)
    for t in np.unique(tags).tolist():
        rows = np.flatnonzero(tags == t)
        name = prefix + face_names[t]
        fem.addGroupElements(fem.addGroup(name, "Face"), face_ids[rows].tolist())
        fem.addGroupElements(fem.addGroup(name, "Node"), (np.unique(tri[rows]) + 1).tolist())


def triangles_to_femmesh(points, groups, group_prefix="", source=""):
    """A 2D ``Fem.FemMesh``: the nodes, the triangles of ``groups.face_triangles`` (tria3, or
    tria6 n1 n2 n3 m12 m23 m31, SMESH's order) as faces with ids 1, 2, ..., and per CAD face a
    "Face" group and a "Node" group named ``group_prefix + groups.face_names[tag]``.

    Raises InputError for non-finite coordinates, node indices out of range, or a triangle with
    a repeated corner (the message names the first one)."""

    import_freecad()
    import Fem

    where = source or "mesh"
    points = np.asarray(points, dtype=np.float64)
    tri = np.asarray(groups.face_triangles, dtype=np.int64)
    tags = np.asarray(groups.face_tags, dtype=np.int64)
    if not np.all(np.isfinite(points)):
        bad = int(np.nonzero(~np.isfinite(points).all(axis=1))[0][0])
        raise InputError("point %d has a non-finite coordinate %s" % (bad, points[bad]),
                         where=where)
    if len(tri) == 0:
        raise InputError("the mesh has no triangles", where=where)
    if tri.min() < 0 or tri.max() >= len(points):
        e = int(np.nonzero((tri < 0).any(axis=1) | (tri >= len(points)).any(axis=1))[0][0])
        raise InputError("triangle %d refers to node indices %s outside 0..%d"
                         % (e, tri[e].tolist(), len(points) - 1), where=where)
    c = tri[:, :3]
    repeated = (c[:, 0] == c[:, 1]) | (c[:, 1] == c[:, 2]) | (c[:, 0] == c[:, 2])
    if repeated.any():
        e = int(np.flatnonzero(repeated)[0])
        raise InputError("triangle %d has a repeated corner: %s" % (e, c[e].tolist()),
                         where=where)
    fem = Fem.FemMesh()
    add_node = fem.addNode
    for i, (x, y, z) in enumerate(points.tolist(), start=1):
        add_node(x, y, z, i)
    _add_faces(fem, tri, tags, list(groups.face_names), 1, group_prefix)
    return fem


def femmesh_to_tetmesh(femmesh, source=""):
    """Convert a ``Fem.FemMesh`` of tetrahedra (SMESH orientation) to a positive :class:`TetMesh`.

    Nodes are taken in increasing id order (``points[i]`` is the i-th smallest id); faces and
    edges of the FemMesh are ignored. ``extra["node_ids"]`` and ``extra["volume_ids"]`` hold the
    FemMesh ids of the points and tets.

    Raises InputError (``where`` = source or "FemMesh") if there are no volumes, a volume is
    not a 4- or 10-node tetrahedron, tet4 and tet10 are mixed, or a tet is not negatively
    oriented in SMESH's convention (it would come out zero or inverted).
    """
    where = source or "FemMesh"
    nodes = femmesh.Nodes
    vol_ids = list(femmesh.Volumes)
    if not vol_ids:
        raise InputError("the mesh has no volume elements (%d nodes, %d faces)"
                         % (len(nodes), femmesh.FaceCount), where=where)
    node_ids = np.array(sorted(nodes), dtype=np.int64)
    points = np.array([[v.x, v.y, v.z] for v in (nodes[i] for i in node_ids.tolist())],
                      dtype=np.float64).reshape(-1, 3)

    conn = [femmesh.getElementNodes(e) for e in vol_ids]
    sizes = {len(c) for c in conn}
    if not sizes <= {4, 10}:
        e = next(e for e, c in zip(vol_ids, conn) if len(c) not in (4, 10))
        raise InputError("volume %d has %d nodes: only 4- and 10-node tetrahedra are supported"
                         % (e, len(femmesh.getElementNodes(e))), where=where)
    if len(sizes) != 1:
        raise InputError("the mesh mixes 4- and 10-node tetrahedra", where=where)
    npe = sizes.pop()
    if femmesh.TetraCount != len(vol_ids):  # e.g. 4- or 10-node polyhedra
        raise InputError("%d of %d volumes are not tetrahedra"
                         % (len(vol_ids) - femmesh.TetraCount, len(vol_ids)), where=where)
    ids = np.array(conn, dtype=np.int64)
    idx = np.searchsorted(node_ids, ids)
    tets = idx[:, _swap_for(npe)]

    det = signed_volumes6(points, tets)
    bad = np.nonzero(~(det > 0))[0]
    if len(bad):
        e = int(bad[0])
        raise InputError(
            "%d of %d tetrahedra are not negatively oriented as SMESH requires "
            "((p2-p1)x(p3-p1).(p4-p1) < 0), first: volume %d with nodes %s"
            % (len(bad), len(tets), vol_ids[e], list(conn[e][:4])), where=where)
    return TetMesh(points, tets, source=source,
                   extra={"node_ids": node_ids, "volume_ids": np.array(vol_ids, dtype=np.int64)})


# --------------------------------------------------------------------------------------------
# files
# --------------------------------------------------------------------------------------------

def _format_of(path):
    ext = os.path.splitext(path)[1].lower()
    if ext not in FREECAD_MESH_FORMATS:
        raise InputError("unsupported mesh file extension %r; FreeCAD writes and reads %s"
                         % (os.path.splitext(path)[1] or "(none)",
                            ", ".join(sorted(FREECAD_MESH_FORMATS))), where=path)
    return ext


def write_via_freecad(path, mesh, groups=None):
    """Write ``mesh`` (a :class:`TetMesh`; with the faces and groups of ``groups``, a
    MeshGroups, when given) with FreeCAD's writer chosen by the extension of ``path``: the
    FemMesh of :func:`tetmesh_to_femmesh` (of :func:`triangles_to_femmesh` for a 2D mesh: no
    tets, the groups' triangles), written by :func:`write_femmesh`.

    Raises InputError for an unsupported extension, a missing or unwritable directory, or an
    invalid mesh; InternalError if FreeCAD's writer fails or writes nothing.
    """
    path = os.fspath(path)
    _check_target(path)
    if len(mesh.tets) == 0 and groups is not None:  # a 2D mesh: the faces' triangles
        return write_femmesh(path, triangles_to_femmesh(mesh.points, groups, source=path))
    return write_femmesh(path, tetmesh_to_femmesh(mesh, groups))


def _check_target(path):
    ext = _format_of(path)
    target = os.path.abspath(path)
    directory = os.path.dirname(target)
    if not os.path.isdir(directory):
        raise InputError("directory %s does not exist" % directory, where=path)
    if not os.access(directory, os.W_OK):
        raise InputError("directory %s is not writable" % directory, where=path)
    if os.path.isdir(target):
        raise InputError("is a directory", where=path)
    return ext, target, directory


def write_femmesh(path, fem):
    """Write the ``Fem.FemMesh`` ``fem`` with FreeCAD's writer chosen by the extension of ``path``.

    path: ``.unv``, ``.med``, ``.z88``, ``.vtk``, ``.vtu`` or ``.inp`` (any letter case).
    The mesh is written under the target's own file name into a private temporary directory
    ``.<name>.tmp<pid>_<random>`` next to the target (the writer picks the format from the
    extension, and the MED writer stores the file's stem as the mesh name that ``Fem.read``
    looks for), then renamed over ``path``; on failure the temporary directory is removed and an
    existing ``path`` is left untouched. Returns the absolute path.

    Raises InputError for an unsupported extension, a missing or unwritable directory;
    InternalError if FreeCAD's writer fails or writes nothing.
    """
    path = os.fspath(path)
    ext, target, directory = _check_target(path)
    # The temporary file keeps the target's base name: FemMesh.write picks the format from the
    # extension, and the MED writer names the mesh inside the file after the file's stem (which
    # Fem.read then looks up), so it lives in a private directory next to the target instead.
    try:
        tmp_dir = tempfile.mkdtemp(prefix=".%s.tmp%d_" % (os.path.basename(target),
                                                         os.getpid()), dir=directory)
    except OSError as e:
        raise InputError("cannot write the file: %s" % (e.strerror or e), where=path) from None
    tmp = os.path.join(tmp_dir, os.path.basename(target))
    try:
        try:
            fem.write(tmp)
        except Exception as e:
            raise InternalError("FreeCAD could not write %s (%s): %s"
                                % (path, FREECAD_MESH_FORMATS[ext], e)) from e
        if not os.path.isfile(tmp) or os.path.getsize(tmp) == 0:
            raise InternalError("FreeCAD's %s writer produced no file for %s"
                                % (FREECAD_MESH_FORMATS[ext], path))
        try:
            if os.path.exists(target):  # a replaced file keeps its permissions
                os.chmod(tmp, stat.S_IMODE(os.stat(target).st_mode))
            with open(tmp, "rb") as f:
                os.fsync(f.fileno())
            os.replace(tmp, target)
        except OSError as e:
            raise InputError("cannot write the file: %s" % (e.strerror or e),
                             where=path) from None
    finally:
        shutil.rmtree(tmp_dir, ignore_errors=True)
    return target


def read_via_freecad(path):
    """Read a volume mesh with ``Fem.read`` and convert it to a positive :class:`TetMesh`.

    path: ``.unv``, ``.med``, ``.z88``, ``.vtk``, ``.vtu`` or ``.inp``. Node order is by
    increasing FemMesh node id (see :func:`femmesh_to_tetmesh`; ``extra["node_ids"]``).

    Raises InputError for a missing file, an unsupported extension, a file FreeCAD cannot
    read, or a mesh that is not made of consistently oriented tetrahedra.
    """

    path = os.fspath(path)
    ext = _format_of(path)
    if not os.path.isfile(path):
        raise InputError("file not found", where=path)
    import_freecad()
    import Fem

    try:
        fem = Fem.read(path)
    except Exception as e:
        raise InputError("FreeCAD cannot read this file as %s: %s"
                         % (FREECAD_MESH_FORMATS[ext], e), where=path) from e
    if fem.NodeCount == 0:  # FreeCAD's readers return an empty mesh for garbage
        raise InputError("FreeCAD read no mesh from this file: it is empty or not a %s file"
                         % FREECAD_MESH_FORMATS[ext], where=path)
    return femmesh_to_tetmesh(fem, source=path)
