# SPDX-License-Identifier: LGPL-2.1-or-later
"""A CAD part (STEP, BREP, IGES file or a BREP string) to an FEM mesh, without FreeCAD.

    result = mesh_cad_file("part.step", size=5.0, order=2)
    result.mesh          # TetMesh: points, tets (m, 4) or (m, 10)
    result.tet_solid     # (m,) 0-based CAD solid of each tet
    result.boundary      # Surface: the boundary triangles (corners), face_tags = 0-based CAD face
    result.groups        # MeshGroups: every CAD face's triangles (Face1, ...), each tet's solid
    result.stats         # dict (see the native mesh_cad_file)

The work is the native pipeline (``cpp_module/include/bsptet/fem/fem_mesh.h``): every CAD edge and
face meshed at the size field by our OpenCASCADE surface mesher, each solid tetrahedralized exactly
by the core on that surface, refined to the size with new surface points and tet10 mid-nodes put
on the CAD faces and edges, every tet10 certified valid. ``size`` is FreeCAD's
CharacteristicLengthMax (0: automatic, the bounding-box diagonal / 20, lowered by curvature)."""

import dataclasses

import numpy as np

from ..kernel.core import core_errors, native_cad, boundary_surface, check_mesh
from ..kernel.errors import InputError, InternalError
from ..kernel.mesh_types import MeshGroups, Surface, TetMesh, triangle_keys


@dataclasses.dataclass
class CadMeshResult:
    mesh: TetMesh
    tet_solid: np.ndarray
    boundary: Surface
    #: (k, 3) tet10 mid-nodes of the boundary triangles' edges (a,b), (b,c), (c,a); (0, 3) for tet4
    boundary_midnodes: np.ndarray
    stats: dict
    #: named sets for the writers: the triangles of every CAD face (a face between two solids
    #: too), named ``Face<n>`` as FreeCAD names ``shape.Faces[n - 1]``; solids ``Solid<n>``
    groups: MeshGroups = None


def _boundary_rows(tets, triangles):
    """Rows of ``triangles`` (corner columns) that are faces of exactly one tet: the mesh's
    boundary (faces shared by two solids are inside it)."""
    corners = tets[:, :4]
    faces = np.concatenate([corners[:, [0, 1, 2]], corners[:, [0, 1, 3]], corners[:, [0, 2, 3]],
                            corners[:, [1, 2, 3]]])
    keys, counts = np.unique(triangle_keys(faces), return_counts=True)
    return np.isin(triangle_keys(triangles[:, :3]), keys[counts == 1])


def _check_each_solid(points, corner_tets, tet_solid, cad_triangles, source):
    """The exact check of every solid's corner tets against the faces of exactly one of its tets,
    and those faces equal to CAD triangles (``cad_triangles``, merged ids), every CAD triangle a
    face of a tet; InternalError naming the solid if one fails."""

    cad_keys = triangle_keys(cad_triangles)
    tet_faces = np.concatenate([corner_tets[:, [0, 1, 2]], corner_tets[:, [0, 1, 3]],
                                corner_tets[:, [0, 2, 3]], corner_tets[:, [1, 2, 3]]])
    unused = ~np.isin(cad_keys, triangle_keys(tet_faces))
    if unused.any():
        raise InternalError(f"{source}: {int(unused.sum())} CAD surface triangles are faces of no "
                            "tet of the FEM mesh; this is a bug, please report it")
    for solid in np.unique(tet_solid):
        tets = corner_tets[tet_solid == solid]
        used, local = np.unique(tets, return_inverse=True)
        pts = points[used]
        piece = TetMesh(points=pts, tets=local.reshape(tets.shape).astype(np.int64), source=source)
        boundary = boundary_surface(piece)
        off_cad = ~np.isin(triangle_keys(used[boundary.triangles]), cad_keys)
        if off_cad.any():
            raise InternalError(f"{source}: Solid{solid}: {int(off_cad.sum())} boundary faces of the "
                                "FEM mesh are not triangles of the CAD surface; this is a bug, "
                                "please report it")
        report = check_mesh(boundary, piece,
                            max_messages=5, compute_quality=False)
        if not report["valid"]:
            raise InternalError(f"{source}: Solid{solid}: the FEM mesh failed its own exact check ("
                                + "; ".join(report["messages"]) + "); this is a bug, please report it")


def _touching_solids(points, corner_tets, tet_solid):
    """Pairs [a, b] (a < b) of solids with distinct nodes at the same coordinates: they touch without
    sharing a CAD face, so their meshes are not connected there."""
    node_solid = np.full(len(points), -1, dtype=np.int64)
    node_solid[corner_tets.ravel()] = np.repeat(tet_solid, 4)
    used = np.flatnonzero(node_solid >= 0)
    if len(used) == 0:
        return []
    _, group, counts = np.unique(points[used], axis=0, return_inverse=True, return_counts=True)
    group = group.ravel()
    shared = counts[group] > 1
    if not shared.any():
        return []
    order = np.lexsort((node_solid[used][shared], group[shared]))
    g = group[shared][order]
    s = node_solid[used][shared][order]
    pairs = set()
    start = 0
    for end in range(1, len(g) + 1):
        if end == len(g) or g[end] != g[start]:
            solids = sorted(set(s[start:end].tolist()))
            pairs.update((a, b) for i, a in enumerate(solids) for b in solids[i + 1:])
            start = end
    return [list(p) for p in sorted(pairs)]


def fem_options(source="", **values):
    """The native FemOptions (the options schema, ``fem/fem_mesh.h`` for_each_fem_option) with
    ``values`` set: ``size``, ``min_size``, ``order``, ``size_by_face``, ``points_per_circle``,
    ``grading``, ``optimize_rounds``, ``face_rounds``, ``workers`` (None: the default). Raises InputError for
    an unknown name or a value out of range, naming ``source``."""
    options = native_cad().FemOptions()
    unknown = sorted(set(values) - set(native_cad().FemOptions.names))
    if unknown:
        raise InputError("unknown FEM option(s) %s; the options are %s"
                         % (", ".join(unknown), ", ".join(native_cad().FemOptions.names)), where=source)
    order = values.get("order")
    if order is not None and order not in (1, 2):
        raise InputError(f"order must be 1 or 2, got {order}", where=source)
    workers = values.get("workers")
    if workers is not None and (int(workers) != workers or workers < 0):
        raise InputError(f"workers must be a whole number >= 0 (0: every core), got {workers}",
                         where=source)
    for name in ("size", "min_size"):
        value = values.get(name)
        if value is not None and (not np.isfinite(value) or value < 0):
            raise InputError(f"{name} must be a finite number >= 0 (0: automatic), got {value}",
                             where=source)
    for name, value in values.items():
        if value is None:
            continue
        if name == "size_by_face":
            value = {int(k): float(v) for k, v in value.items()}
        try:
            setattr(options, name, value)
        except TypeError:
            raise InputError("FEM option %s: cannot use %r" % (name, value), where=source) from None
    return options


def _run(native_call, source, size, min_size, order, progress, cancel, size_by_face, workers):
    options = fem_options(source, size=size, min_size=min_size, order=order,
                          size_by_face=size_by_face, workers=workers)
    with core_errors(Surface(points=np.zeros((0, 3)), triangles=np.zeros((0, 3), dtype=np.int64),
                              source=""), "FEM mesh"):
        points, tets, tet_solid, tri, tri_face, stats, solid_names, face_names = native_call(
            options=options,
            progress=(lambda stage, fraction: progress(stage, fraction)) if progress else None,
            cancel=cancel)
    mesh = TetMesh(points=np.asarray(points), tets=np.asarray(tets, dtype=np.int64), source=source)
    tri = np.asarray(tri, dtype=np.int64)
    on_boundary = _boundary_rows(mesh.tets, tri) if len(tri) else np.zeros(0, dtype=bool)
    boundary = Surface(points=mesh.points, triangles=tri[on_boundary, :3],
                       face_tags=np.asarray(tri_face, dtype=np.int32)[on_boundary],
                       face_names=None, source=source)
    stats = dict(stats)
    # Each solid's corner mesh checked exactly against its own boundary (positive tets, conforming
    # faces, a closed boundary equal to the solid's CAD triangles); corners come first. Solids are
    # checked one by one because solids that touch without sharing a CAD face (an assembly that was
    # not fragmented) have coincident but distinct nodes there, which a check of the whole would
    # call non-conforming.
    corners = int(stats["corner_nodes"])
    tet_solid = np.asarray(tet_solid, dtype=np.int64)
    _check_each_solid(mesh.points[:corners], mesh.tets[:, :4], tet_solid, tri[:, :3], source)
    touching = _touching_solids(mesh.points[:corners], mesh.tets[:, :4], tet_solid)
    if touching:
        stats["unconnected_touching_solids"] = touching
        pairs = ", ".join(f"{solid_names[a]}-{solid_names[b]}" for a, b in touching[:6])
        more = f" and {len(touching) - 6} more" if len(touching) > 6 else ""
        stats.setdefault("notes", []).append(
            f"{len(touching)} pairs of solids touch without sharing a CAD face ({pairs}{more}): "
            "their meshes have separate nodes there and are not connected; to make them "
            "conforming, fuse them into one CompSolid first (FreeCAD: Part, Boolean Fragments "
            "in CompSolid mode) or tie them in the solver")
    stats.update(valid=True, points=int(stats.get("nodes", len(points))),
                 input_points=int(stats["surface_nodes"]),
                 input_triangles=int(stats["surface_triangles"]),
                 boundary_steiner_points=0, steiner_points=int(stats["core_steiner_points"]))
    midnodes = tri[on_boundary, 3:6] if tri.shape[1] == 6 else np.zeros((0, 3), dtype=np.int64)
    tri_face = np.asarray(tri_face, dtype=np.int64)
    groups = MeshGroups(face_triangles=tri, face_tags=tri_face, face_names=list(face_names),
                        tet_solid=tet_solid, solid_names=list(solid_names))
    return CadMeshResult(mesh=mesh, tet_solid=np.asarray(tet_solid), boundary=boundary,
                         boundary_midnodes=midnodes, stats=stats, groups=groups)


def mesh_cad_file(path, size=0.0, min_size=0.0, order=2, progress=None, cancel=None,
                  size_by_face=None, workers=None):
    """Meshes every solid of a STEP, BREP or IGES file (see the module doc). ``progress(stage,
    fraction)`` and ``cancel() -> bool`` are optional. ``workers``: solids meshed at the same
    time, one thread each (None or 0: the machine's cores); the mesh is the same for any value.
    Raises InputError (unreadable or unmeshable part, naming the CAD face or solid; bad option)
    or MeshingError."""

    return _run(lambda **kw: native_cad().mesh_cad_file(str(path), **kw), str(path), size, min_size,
                order, progress, cancel, size_by_face, workers)


def mesh_cad_brep(brep, size=0.0, min_size=0.0, order=2, progress=None, cancel=None,
                  size_by_face=None, source="BREP string", workers=None):
    """The same for a shape in OpenCASCADE's BREP text (FreeCAD's ``Shape.exportBrepToString()``)."""

    return _run(lambda **kw: native_cad().mesh_cad_brep(brep, **kw), source, size, min_size, order,
                progress, cancel, size_by_face, workers)


@dataclasses.dataclass
class CadFacesResult:
    """A 2D mesh of CAD faces (:func:`mesh_cad_faces_brep`)."""

    points: np.ndarray
    #: (k, 3) tria3 or (k, 6) tria6 (n1 n2 n3 m12 m23 m31), each face's triangles as the shape
    #: orients the face
    triangles: np.ndarray
    face_tags: np.ndarray  #: (k,) 0-based CAD face of each triangle
    stats: dict
    groups: MeshGroups = None


def mesh_cad_faces_brep(brep, size=0.0, min_size=0.0, order=2, progress=None, cancel=None,
                        size_by_face=None, source="BREP string", workers=None):
    """Every CAD face of a shape in BREP text (a Face, a Shell, or the faces of solids) as
    triangles at the size field, tria6 mid-nodes on the CAD (``cpp_module/include/bsptet/fem/
    fem_faces.h``): shell and plane analyses, on one thread (``workers`` is accepted for the
    3D path's sake and not used). Raises InputError (no face, bad option) or MeshingError."""
    return _faces(lambda **kw: native_cad().mesh_cad_brep(brep, dimension=2, **kw), source, size,
                  min_size, order, progress, cancel, size_by_face, workers)


def mesh_cad_faces_file(path, size=0.0, min_size=0.0, order=2, progress=None, cancel=None,
                        size_by_face=None, workers=None):
    """The same for the faces in a STEP, BREP or IGES file (the command line's
    ``--dimension 2``)."""
    return _faces(lambda **kw: native_cad().mesh_cad_file(str(path), dimension=2, **kw), str(path),
                  size, min_size, order, progress, cancel, size_by_face, workers)


def _faces(native_call, source, size, min_size, order, progress, cancel, size_by_face, workers):
    options = fem_options(source, size=size, min_size=min_size, order=order,
                          size_by_face=size_by_face, workers=workers)
    with core_errors(Surface(points=np.zeros((0, 3)), triangles=np.zeros((0, 3), dtype=np.int64),
                             source=""), "FEM surface mesh"):
        points, _tets, _solid, tri, tri_face, stats, _solid_names, face_names = native_call(
            options=options,
            progress=(lambda stage, fraction: progress(stage, fraction)) if progress else None,
            cancel=cancel)
    points = np.asarray(points)
    tri = np.asarray(tri, dtype=np.int64)
    tri_face = np.asarray(tri_face, dtype=np.int64)
    stats = dict(stats)
    angles = triangle_min_angles(points, tri[:, :3])
    stats.update(triangles=int(len(tri)), points=int(len(points)),
                 min_triangle_angle_deg=float(angles.min()) if len(angles) else 0.0,
                 median_triangle_min_angle_deg=float(np.median(angles)) if len(angles) else 0.0)
    groups = MeshGroups(face_triangles=tri, face_tags=tri_face, face_names=list(face_names))
    return CadFacesResult(points=points, triangles=tri, face_tags=tri_face, stats=stats,
                          groups=groups)


def triangle_min_angles(points, triangles):
    """Each triangle's smallest angle (degrees)."""
    p = np.asarray(points, dtype=float)[np.asarray(triangles)]
    out = np.full(len(p), 180.0)
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        cos = np.einsum("ij,ij->i", u, v) / np.maximum(
            np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), np.finfo(float).tiny)
        out = np.minimum(out, np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return out
