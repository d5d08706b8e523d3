"""The numpy API of FemBspTet: meshing and checking. Never imports FreeCAD.

    from FemBspTet import core
    report = core.check_mesh(surface, tetmesh)      # exact validity check, see below
    mesh, stats = core.tetrahedralize(surface)      # the BSP-assisted mesher

``check_mesh`` returns a dict: ``valid`` (bool), defect counts (``inverted_tets``,
``flat_tets``, ``overshared_faces``, ``same_orientation_faces``, ``boundary_faces_off_surface``,
``boundary_faces_inward``, ``unpaired_boundary_edges``, ``miscovered_triangles``,
``duplicate_points``, ``unreferenced_points``, ``inconsistent_midnodes``, ...), ``volume_equal``,
``tet_volume``, ``surface_volume``, ``steiner_points``, ``boundary_steiner_points``, ``messages``
(the first problems, with indices) and ``quality`` (dihedral angles, radius-edge ratios). The
conditions are listed in ``cpp_module/include/bsptet/mesh_check.h``.
"""

import numpy as np

from .errors import Cancelled, InputError, InternalError, SelfIntersectionError
from .mesh_types import Surface, TetMesh


def _native():
    """The compiled core, with a message that says how to build it when it is missing."""
    try:
        from . import _bsptet
    except ImportError as exc:  # pragma: no cover - depends on the build
        raise InternalError(
            "the C++ core FemBspTet._bsptet is not built or does not load "
            f"({exc}); run scripts/setup.sh (it installs what is missing and builds the core)"
        ) from exc
    return _bsptet


def check_mesh(surface: Surface, mesh: TetMesh, max_messages: int = 20, compute_quality=True):
    """Checks ``mesh`` against the closed surface it should fill, exactly. Returns a dict."""
    return _native().check_mesh(
        surface.points,
        surface.triangles,
        mesh.points,
        mesh.tets,
        max_messages=max_messages,
        compute_quality=compute_quality,
    )


def check_surface(surface: Surface, reorient=False, max_reported_pairs=1000):
    """Checks that ``surface`` bounds a solid the mesher can fill, exactly, before any meshing.

    The checks and their order are in ``cpp_module/include/bsptet/surface_check.h``: finite
    coordinates, indices, degenerate and duplicate triangles, open and non-manifold edges,
    consistent orientation, non-manifold vertices, self-intersections, shells facing the right
    way (outer shells outward, cavities inward). ``reorient=True`` flips triangles to make the
    orientation consistent and the shells face the right way instead of refusing.

    Returns ``(surface, info)``: the surface with flipped triangles reversed (the same object
    when nothing was flipped) and ``info`` (``flipped_triangles``, ``shells``,
    ``merged_points``). Raises :class:`InputError` (``code`` names the kind of problem; the
    message names the triangle, edge or vertex), :class:`SelfIntersectionError` with the pairs.
    """
    native = _native()
    where = surface.source or None
    try:
        tri, info = native.check_surface(surface.points, surface.triangles, reorient=bool(reorient),
                                         max_reported_pairs=int(max_reported_pairs))
    except native.InputError as exc:
        if getattr(exc, "code", "") == "self_intersection":
            raise SelfIntersectionError(str(exc), where=where, pairs=np.asarray(exc.pairs),
                                        complete=bool(exc.complete), surface=surface) from None
        raise InputError(str(exc), where=where, code=getattr(exc, "code", None)) from None
    except ValueError as exc:  # array shapes or indices beyond 32 bits (the binding's checks)
        raise InputError(str(exc), where=where, code="bad_argument") from None
    info = dict(info)
    if info["flipped_triangles"]:
        surface = Surface(surface.points, tri, surface.face_tags, surface.source)
    return surface, info


def tet_quality(mesh: TetMesh):
    """Dihedral angles (degrees) and radius-edge ratios of the linear tets of ``mesh``."""
    return _native().tet_quality(mesh.points, mesh.tets)


def orient3d(a, b, c, d) -> int:
    """Exact sign of det[b-a, c-a, d-a] (+1: d on the side of the right-hand normal of a, b, c)."""
    return _native().orient3d(tuple(map(float, a)), tuple(map(float, b)), tuple(map(float, c)),
                              tuple(map(float, d)))


_TET10_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))  # m12 m23 m31 m14 m24 m34


def to_second_order(mesh: TetMesh) -> TetMesh:
    """10-node tets with straight edges: one mid-node per edge, at the rounded midpoint.

    Node order n1..n4 m12 m23 m31 m14 m24 m34 (see mesh_types). Mid-nodes of surface edges lie on
    the input facets up to the rounding of the midpoint; curved CAD faces come with the projection
    hook of the quality stage (not built yet).
    """
    tets = mesh.tets[:, :4]
    pairs = np.concatenate([tets[:, [i, j]] for i, j in _TET10_EDGES])
    key = np.sort(pairs, axis=1)
    uniq, inverse = np.unique(key, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    mids = 0.5 * (mesh.points[uniq[:, 0]] + mesh.points[uniq[:, 1]])
    mid_ids = len(mesh.points) + inverse.reshape(len(_TET10_EDGES), len(tets)).T
    return TetMesh(np.vstack([mesh.points, mids]), np.hstack([tets, mid_ids]), mesh.source, dict(mesh.extra))


def tetrahedralize(surfaces, options=None, progress=None, cancel=None):
    """Tetrahedralizes the solid(s) bounded by ``surfaces`` (a Surface or a list, one per solid).

    BSP-assisted and exact (cpp_module/include/bsptet/mesher.h): the output boundary is the input
    triangulation (no Steiner point on it unless ``allow_boundary_steiner``); every tet is positive.

    ``options`` (dict): ``allow_boundary_steiner`` (bool, default False), ``order`` (1 or 2),
    ``size`` (maximum edge length: used for the tessellation of CAD input; volume sizing is not
    built yet and is reported in ``stats["notes"]``), ``reorient`` (bool, default False: flip
    inconsistently oriented or inward-facing shells instead of refusing them, see
    :func:`check_surface`), ``max_memory`` (bytes or None: refuse, before meshing, a run whose
    estimated peak memory exceeds it, :class:`MemoryBudgetError`; see :mod:`memory_budget`).
    ``progress(stage, fraction)`` is called now and then; ``cancel()`` returning True stops the run
    (:class:`Cancelled`); Ctrl-C raises ``KeyboardInterrupt``.

    Returns ``(TetMesh, stats)``. Every mesh is checked exactly against its surface before it is
    returned; ``stats`` holds the core's figures (see ``cli.STATS_KEYS``) and the checker's quality.
    Raises ``InputError`` (bad surface; the message names the triangle) or ``InternalError``.
    """
    from .errors import InputError

    options = dict(options or {})
    unknown = set(options) - {"allow_boundary_steiner", "order", "size", "reorient", "max_memory"}
    if unknown:
        raise InputError(f"unknown mesher option(s): {', '.join(sorted(unknown))}")
    order = int(options.get("order") or 1)
    if order not in (1, 2):
        raise InputError(f"order must be 1 or 2, got {order}")
    if isinstance(surfaces, Surface):
        surfaces = [surfaces]
    native = _native()
    checked, flipped = [], 0
    for surface in surfaces:
        surface, info = check_surface(surface, reorient=bool(options.get("reorient", False)))
        checked.append(surface)
        flipped += info["flipped_triangles"]
    surfaces = checked
    if options.get("max_memory") is not None:
        from .memory_budget import require_within_budget

        require_within_budget(surfaces, int(options["max_memory"]))
    meshes, all_stats = [], []
    for k, surface in enumerate(surfaces):
        label = f"solid {k + 1} of {len(surfaces)}: " if len(surfaces) > 1 else ""

        def report(stage, fraction, label=label):
            if progress is not None:
                progress(label + stage, fraction)

        try:
            points, tets, st = native.tetrahedralize(
                surface.points, surface.triangles,
                allow_boundary_steiner=bool(options.get("allow_boundary_steiner", False)),
                progress=report, cancel=cancel)
        except native.InputError as exc:
            raise InputError(str(exc), where=surface.source or None) from None
        except native.MeshingError as exc:
            if getattr(exc, "code", "") == "cancelled":
                raise Cancelled("cancelled: no mesh was made") from None
            raise InternalError(
                f"{surface.source or 'surface'}: the mesher failed ({exc}); this is a bug, "
                "please report it with the input") from None
        mesh = TetMesh(points, tets, surface.source)
        report_check = check_mesh(surface, mesh, max_messages=5)
        if not report_check["valid"]:
            raise InternalError(
                f"{surface.source or 'surface'}: the mesh failed its own exact check ("
                + "; ".join(report_check["messages"]) + "); this is a bug, please report it")
        st["quality"] = report_check["quality"]
        meshes.append(mesh)
        all_stats.append(st)
    mesh = _concatenate(meshes)
    if order == 2:
        mesh = to_second_order(mesh)
    stats = _merge_stats(all_stats)
    stats["order"] = order
    stats["nodes"] = int(len(mesh.points))
    stats["valid"] = True
    stats["flipped_triangles"] = flipped
    notes = []
    if flipped:
        notes.append(f"re-oriented {flipped} triangle(s) (--reorient)")
    if options.get("size") is not None:
        notes.append("volume size control is not built yet: tets use the surface's vertices only")
    stats["notes"] = notes
    return mesh, stats


def _concatenate(meshes):
    if len(meshes) == 1:
        return meshes[0]
    offsets = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
    return TetMesh(np.vstack([m.points for m in meshes]),
                   np.vstack([m.tets + off for m, off in zip(meshes, offsets)]),
                   " + ".join(m.source for m in meshes if m.source))


def _merge_stats(all_stats):
    out = {}
    for st in all_stats:
        for k, v in st.items():
            if k == "quality":
                continue
            if k == "seconds_by_stage":
                agg = out.setdefault(k, {})
                for stage, sec in v.items():
                    agg[stage] = agg.get(stage, 0.0) + sec
            else:
                out[k] = out.get(k, 0) + v
    qs = [st["quality"] for st in all_stats]
    out["min_dihedral_deg"] = min(q["min_dihedral_deg"] for q in qs)
    out["max_dihedral_deg"] = max(q["max_dihedral_deg"] for q in qs)
    out["max_radius_edge_ratio"] = max(q["max_radius_edge_ratio"] for q in qs)
    out["median_dihedral_deg"] = qs[0]["median_dihedral_deg"] if len(qs) == 1 else None
    out["p1_dihedral_deg"] = qs[0]["p1_dihedral_deg"] if len(qs) == 1 else None
    out["dihedral_histogram"] = [sum(h) for h in zip(*(q["dihedral_histogram"] for q in qs))]
    out["solids"] = len(all_stats)
    return out


def _version():
    from . import __version__

    return __version__


def signed_volume(surface: Surface) -> float:
    """Volume enclosed by ``surface`` (positive for outward orientation), in double precision."""
    p = surface.points
    t = surface.triangles
    if len(t) == 0:
        return 0.0
    o = p[t[0, 0]]
    a, b, c = p[t[:, 0]] - o, p[t[:, 1]] - o, p[t[:, 2]] - o
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)
