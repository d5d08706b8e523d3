# SPDX-License-Identifier: LGPL-2.1-or-later
"""A CAD part (STEP, BREP, IGES file or a BREP string) to an FEM mesh, without FreeCAD.

    result = mesh_cad_file("part.step", size=5.0, order=2)
    result.mesh          # TetMesh: points, tets (m, 4) or (m, 10)
    result.tet_solid     # (m,) 0-based CAD solid of each tet
    result.boundary      # Surface: the boundary triangles (corners), face_tags = 0-based CAD face
    result.stats         # dict (see the native mesh_cad_file)

The work is the native pipeline (``cpp_module/include/bsptet/fem/fem_mesh.h``): every CAD edge and
face meshed at the size field by our OpenCASCADE surface mesher, each solid tetrahedralized exactly
by the core on that surface, refined to the size with new surface points and tet10 mid-nodes put
on the CAD faces and edges, every tet10 certified valid. ``size`` is FreeCAD's
CharacteristicLengthMax (0: automatic, the bounding-box diagonal / 20, lowered by curvature)."""

import dataclasses

import numpy as np

from ..errors import InputError
from ..mesh_types import Surface, TetMesh


@dataclasses.dataclass
class CadMeshResult:
    mesh: TetMesh
    tet_solid: np.ndarray
    boundary: Surface
    #: (k, 3) tet10 mid-nodes of the boundary triangles' edges (a,b), (b,c), (c,a); (0, 3) for tet4
    boundary_midnodes: np.ndarray
    stats: dict


def _row_keys(triples):
    """One hashable value per row of sorted corner triples (a void view), for np.unique / isin."""
    rows = np.ascontiguousarray(np.sort(triples, axis=1).astype(np.int64))
    return rows.view(np.dtype((np.void, rows.dtype.itemsize * 3))).ravel()


def _boundary_rows(tets, triangles):
    """Rows of ``triangles`` (corner columns) that are faces of exactly one tet: the mesh's
    boundary (faces shared by two solids are inside it)."""
    corners = tets[:, :4]
    faces = np.concatenate([corners[:, [0, 1, 2]], corners[:, [0, 1, 3]], corners[:, [0, 2, 3]],
                            corners[:, [1, 2, 3]]])
    keys, counts = np.unique(_row_keys(faces), return_counts=True)
    return np.isin(_row_keys(triangles[:, :3]), keys[counts == 1])


def _run(native_call, source, size, min_size, order, progress, cancel, size_by_face):
    if order not in (1, 2):
        raise InputError(f"order must be 1 or 2, got {order}", where=source)
    for name, value in (("size", size), ("min_size", min_size)):
        if value is None:
            continue
        if not np.isfinite(value) or value < 0:
            raise InputError(f"{name} must be a finite number >= 0 (0: automatic), got {value}",
                             where=source)
    from ..core import _core_errors

    with _core_errors(Surface(points=np.zeros((0, 3)), triangles=np.zeros((0, 3), dtype=np.int64),
                              source=""), "FEM mesh"):
        points, tets, tet_solid, tri, tri_face, stats = native_call(
            size=float(size or 0.0), min_size=float(min_size or 0.0), order=int(order),
            size_by_face={int(k): float(v) for k, v in (size_by_face or {}).items()},
            progress=(lambda stage, fraction: progress(stage, fraction)) if progress else None,
            cancel=cancel)
    mesh = TetMesh(points=np.asarray(points), tets=np.asarray(tets, dtype=np.int64), source=source)
    tri = np.asarray(tri, dtype=np.int64)
    on_boundary = _boundary_rows(mesh.tets, tri) if len(tri) else np.zeros(0, dtype=bool)
    boundary = Surface(points=mesh.points, triangles=tri[on_boundary, :3],
                       face_tags=np.asarray(tri_face, dtype=np.int32)[on_boundary],
                       face_names=None, source=source)
    stats = dict(stats)
    # The corner mesh checked exactly against its own boundary (positive tets, conforming faces,
    # a closed boundary equal to the CAD faces' unshared triangles); corners come first.
    from ..core import check_mesh

    corners = int(stats["corner_nodes"])
    report = check_mesh(Surface(points=mesh.points[:corners], triangles=boundary.triangles,
                                face_tags=boundary.face_tags, source=source),
                        TetMesh(points=mesh.points[:corners], tets=mesh.tets[:, :4].copy()),
                        max_messages=5, compute_quality=False)
    if not report["valid"]:
        from ..errors import InternalError

        raise InternalError(f"{source}: the FEM mesh failed its own exact check ("
                            + "; ".join(report["messages"]) + "); this is a bug, please report it")
    stats.update(valid=True, points=int(stats.get("nodes", len(points))),
                 input_points=int(stats["surface_nodes"]),
                 input_triangles=int(stats["surface_triangles"]),
                 boundary_steiner_points=0, steiner_points=int(stats["core_steiner_points"]))
    midnodes = tri[on_boundary, 3:6] if tri.shape[1] == 6 else np.zeros((0, 3), dtype=np.int64)
    return CadMeshResult(mesh=mesh, tet_solid=np.asarray(tet_solid), boundary=boundary,
                         boundary_midnodes=midnodes, stats=stats)


def mesh_cad_file(path, size=0.0, min_size=0.0, order=2, progress=None, cancel=None,
                  size_by_face=None):
    """Meshes every solid of a STEP, BREP or IGES file (see the module doc). ``progress(stage,
    fraction)`` and ``cancel() -> bool`` are optional. Raises InputError (unreadable or
    unmeshable part, naming the CAD face or solid; bad option) or MeshingError."""
    from ..core import _native

    return _run(lambda **kw: _native().mesh_cad_file(str(path), **kw), str(path), size, min_size,
                order, progress, cancel, size_by_face)


def mesh_cad_brep(brep, size=0.0, min_size=0.0, order=2, progress=None, cancel=None,
                  size_by_face=None, source="BREP string"):
    """The same for a shape in OpenCASCADE's BREP text (FreeCAD's ``Shape.exportBrepToString()``)."""
    from ..core import _native

    return _run(lambda **kw: _native().mesh_cad_brep(brep, **kw), source, size, min_size, order,
                progress, cancel, size_by_face)
