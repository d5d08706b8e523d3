# SPDX-License-Identifier: LGPL-2.1-or-later
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
conditions are listed in ``cpp_module/include/bsptet/mesh/mesh_check.h``.
"""

import contextlib
import importlib

import numpy as np

from .. import __version__
from .errors import Cancelled, ErrorCode, InputError, InternalError, SelfIntersectionError
from .memory_budget import require_within_budget
from .mesh_types import Surface, TetMesh


#: End of the note on tet10 mid-nodes the core left on their chords (after the count).
MIDNODES_STRAIGHTENED_NOTE = ("curved mid-nodes were put back on their chord (the curved tet would "
                              "not have been valid)")


@contextlib.contextmanager
def core_errors(surface, stage):
    """The core's errors as the package's: InputError (naming the input), Cancelled, and
    InternalError for anything else (a bug of ours: the message asks for a report)."""
    lib = native()
    try:
        yield
    except lib.InputError as exc:
        raise InputError(str(exc), where=surface.source or None) from None
    except lib.MeshingError as exc:
        if getattr(exc, "code", "") == "cancelled":
            raise Cancelled("cancelled: no mesh was made") from None
        raise InternalError(
            f"{surface.source or 'surface'}: the {stage} failed ({exc}); this is a bug, "
            "please report it with the input") from None


def _checked(reference, mesh, what, source=None):
    """The exact check of ``mesh`` against ``reference``; InternalError if it fails."""
    report = check_mesh(reference, mesh, max_messages=5)
    if not report["valid"]:
        raise InternalError(
            f"{source or reference.source or 'surface'}: the {what} failed its own exact check ("
            + "; ".join(report["messages"]) + "); this is a bug, please report it")
    return report


def _extension(name, what):
    """The compiled module FemBspTet.<name>, with a message that says how to build it when it is
    missing."""
    try:
        return importlib.import_module(f"..{name}", __package__)
    except ImportError as exc:  # pragma: no cover - depends on the build
        raise InternalError(
            f"{what} FemBspTet.{name} is not built or does not load "
            f"({exc}); run scripts/setup.sh (it installs what is missing and builds the core)"
        ) from exc


def native():
    """The compiled core (no OpenCASCADE)."""
    return _extension("_bsptet", "the C++ core")


def native_cad():
    """The compiled FEM pipeline from CAD, the extension that loads OpenCASCADE (only the CAD
    paths import it, so a triangle surface meshes without it)."""
    return _extension("_bsptet_cad", "the C++ FEM pipeline")


def check_mesh(surface: Surface, mesh: TetMesh, max_messages: int = 20, compute_quality=True):
    """Checks ``mesh`` against the closed surface it should fill, exactly. Returns a dict."""
    return native().check_mesh(
        surface.points,
        surface.triangles,
        mesh.points,
        mesh.tets,
        max_messages=max_messages,
        compute_quality=compute_quality,
    )


def check_surface(surface: Surface, reorient=False, max_reported_pairs=1000, self_intersections=True):
    """Checks that ``surface`` bounds a solid the mesher can fill, exactly, before any meshing.

    The checks and their order are in ``cpp_module/include/bsptet/input/surface_check.h``: finite
    coordinates, indices, degenerate and duplicate triangles, open and non-manifold edges,
    consistent orientation, non-manifold vertices, self-intersections, shells facing the right
    way (outer shells outward, cavities inward). ``reorient=True`` flips triangles to make the
    orientation consistent and the shells face the right way instead of refusing.

    Returns ``(surface, info)``: the surface with flipped triangles reversed (the same object
    when nothing was flipped) and ``info`` (``flipped_triangles``, ``shells``,
    ``merged_points``). Raises :class:`InputError` (``code`` names the kind of problem; the
    message names the triangle, edge or vertex), :class:`SelfIntersectionError` with the pairs.
    """
    lib = native()
    where = surface.source or None
    try:
        with _self_intersection_errors(surface):
            tri, info = lib.check_surface(surface.points, surface.triangles, reorient=bool(reorient),
                                             self_intersections=bool(self_intersections),
                                             max_reported_pairs=int(max_reported_pairs))
    except SelfIntersectionError:
        raise
    except lib.InputError as exc:
        raise InputError(str(exc), where=where, code=getattr(exc, "code", None)) from None
    except ValueError as exc:  # array shapes or indices beyond 32 bits (the binding's checks)
        raise InputError(str(exc), where=where, code=ErrorCode.BAD_ARGUMENT) from None
    info = dict(info)
    if info["flipped_triangles"]:
        surface = Surface(surface.points, tri, surface.face_tags, surface.source)
    return surface, info


@contextlib.contextmanager
def _self_intersection_errors(surface: Surface):
    """The native self-intersection error (an InputError with ``pairs``) as SelfIntersectionError."""
    lib = native()
    try:
        yield
    except lib.InputError as exc:
        if getattr(exc, "code", "") != "self_intersection":
            raise
        raise SelfIntersectionError(str(exc), where=surface.source or None, pairs=np.asarray(exc.pairs),
                                    complete=bool(exc.complete), surface=surface) from None


def tet_quality(mesh: TetMesh):
    """Dihedral angles (degrees) and radius-edge ratios of the linear tets of ``mesh``."""
    return native().tet_quality(mesh.points, mesh.tets)


def certify_tet10(mesh: TetMesh, max_depth=6, scaled_jacobian=False):
    """Certifies each 10-node tet of ``mesh``: det J > 0 over the whole element, proved with the
    Bezier coefficients of det J, subdivision up to ``max_depth`` and rounding-error bounds.

    Returns a dict: counts ``certified``, ``invalid`` (det J <= 0 somewhere, proved) and
    ``undecided`` (treat as invalid); ``status`` (m,) int8 (0, 1, 2 in that order); ``min_bound``
    (m,); with ``scaled_jacobian``, ``min_scaled_jacobian`` (m,): min det J over det J of the
    straight tet, a lower bound within 1e-3. Raises ValueError unless tets has shape (m, 10)."""
    return native().tet10_certify(mesh.points, mesh.tets, max_depth=max_depth,
                                   scaled_jacobian=scaled_jacobian)


def orient3d(a, b, c, d) -> int:
    """Exact sign of det[b-a, c-a, d-a] (+1: d on the side of the right-hand normal of a, b, c)."""
    return native().orient3d(tuple(map(float, a)), tuple(map(float, b)), tuple(map(float, c)),
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


BSP_SEEDS = ("auto", "delaunay", "box")


def native_core_options(options):
    """The native ``MeshOptions`` (core/mesher.h for_each_mesh_option) for ``options``:
    ``allow_boundary_steiner``, ``steiner_effort`` and ``bsp_seed`` (absent: the core's
    defaults)."""

    values = {"allow_boundary_steiner": bool(options.get("allow_boundary_steiner", False))}
    effort = options.get("steiner_effort")
    if effort is not None:
        if isinstance(effort, bool) or not isinstance(effort, int) or effort < 0:
            raise InputError(f"steiner_effort must be an integer >= 0 (0: no bound), got {effort!r}")
        values["steiner_effort"] = effort
    seed = options.get("bsp_seed")
    if seed is not None:
        if seed not in BSP_SEEDS:
            raise InputError(f"bsp_seed must be one of {', '.join(BSP_SEEDS)}, got {seed!r}")
        values["bsp_seed"] = getattr(native().BspSeed, seed)
    native_options = native().MeshOptions()
    for name, value in values.items():
        setattr(native_options, MESH_OPTION_OF[name], value)
    return native_options


def tetrahedralize(surfaces, options=None, progress=None, cancel=None):
    """Tetrahedralizes the solid(s) bounded by ``surfaces`` (a Surface or a list, one per solid).

    BSP-assisted and exact (cpp_module/include/bsptet/core/mesher.h): the output boundary is the
    input triangulation (no Steiner point on it unless ``allow_boundary_steiner``); every tet is
    positive.
    Each surface is checked first (:func:`check_surface`); the check's self-intersection search
    runs on a second thread while the core meshes (``check_and_tetrahedralize``), with the same
    errors as checking first.

    ``options`` (dict): ``allow_boundary_steiner`` (bool, default False), ``steiner_effort`` (int:
    work (exact orientation tests, cavity growth) the core may spend removing one interior Steiner
    point, default 1000000; 0 = no bound: fewer interior Steiner points, possibly minutes more),
    ``bsp_seed`` ("auto", the default, "delaunay" or "box": what the BSP starts from, see mesher.h
    ``MeshOptions::seed``; ``stats["bsp_seed"]`` says which one the mesh came from),
    ``order`` (1 or 2),
    ``reorient`` (bool, default False: flip inconsistently oriented or inward-facing shells instead
    of refusing them, see :func:`check_surface`), ``max_memory`` (bytes or None: refuse, before
    meshing, a run whose estimated peak memory exceeds it, :class:`MemoryBudgetError`; see
    :mod:`memory_budget`), and the quality stage's options (see ``REFINE_OPTIONS`` and ``refine``):
    ``size``, ``min_size``, ``size_by_tag``, ``radius_edge``, ``min_dihedral``, ``surface_points``,
    ``projection``. When any of them is given the core's mesh goes through ``refine``; ``order`` 2
    alone only adds the mid-edge nodes (through ``projection`` if given).
    ``progress(stage, fraction)`` is called now and then; ``cancel()`` returning True stops the run
    (:class:`Cancelled`); Ctrl-C raises ``KeyboardInterrupt``.

    Returns ``(TetMesh, stats)``. Every mesh is checked exactly against its surface before it is
    returned; ``stats`` holds the core's figures (see ``cli.STATS_KEYS``) and the checker's quality.
    Raises ``InputError`` (bad surface; the message names the triangle) or ``InternalError``.
    """

    options = dict(options or {})
    unknown = set(options) - set(OPTION_NAMES)
    if unknown:
        raise InputError(f"unknown mesher option(s): {', '.join(sorted(unknown))}")
    order = int(options.get("order") or 1)
    if order not in (1, 2):
        raise InputError(f"order must be 1 or 2, got {order}")
    if isinstance(surfaces, Surface):
        surfaces = [surfaces]
    refining = any(options.get(k) is not None for k in REFINE_OPTIONS
                   if k not in ("order", "projection", "separate_face_tags", "thickness_ratio"))
    separating = bool(options.get("separate_face_tags"))
    lib = native()
    reorient = bool(options.get("reorient", False))
    # Every surface is checked before any is meshed, all but the self-intersection search, which
    # runs beside the core on a second thread (the native check_and_tetrahedralize) when its
    # surface is meshed: the same errors as check_surface's, a crossing reported after the other
    # surfaces' other problems.
    checked, flipped = [], 0
    for surface in surfaces:
        checked_surface, info = check_surface(surface, reorient=reorient, self_intersections=False)
        checked.append((surface, checked_surface))
        flipped += info["flipped_triangles"]
    originals = [original for original, _ in checked]
    surfaces = [surface for _, surface in checked]
    if options.get("max_memory") is not None:

        require_within_budget(surfaces, int(options["max_memory"]))
    meshes, all_stats = [], []
    for k, surface in enumerate(surfaces):
        label = f"solid {k + 1} of {len(surfaces)}: " if len(surfaces) > 1 else ""

        def report(stage, fraction, label=label):
            if progress is not None:
                progress(label + stage, fraction)

        with core_errors(surface, "mesher"), _self_intersection_errors(originals[k]):
            points, tets, st = lib.tetrahedralize(
                originals[k].points, originals[k].triangles, options=native_core_options(options),
                progress=report, cancel=cancel, check={"reorient": reorient})
        mesh = TetMesh(points, tets, surface.source)
        report_check = _checked(surface, mesh, "mesh")
        if refining or order == 2 or (separating and surface.face_tags is not None):
            refine_options = {k: v for k, v in options.items() if k in REFINE_OPTIONS}
            if not refining:
                refine_options = {"order": order, "projection": options.get("projection"),
                                  "separate_face_tags": separating}
            mesh, refine_stats = refine(surface, mesh, refine_options, progress=report,
                                        cancel=cancel)
            st["refine"] = refine_stats
            st["steiner_points"] = refine_stats["steiner_points"]
            st["boundary_steiner_points"] = refine_stats["boundary_steiner_points"]
            st["interior_steiner_points"] = (refine_stats["steiner_points"]
                                             - refine_stats["boundary_steiner_points"])
            st["points"] = refine_stats["points"]
            st["tets"] = refine_stats["tets"]
            st["quality"] = refine_stats["quality"]
        else:
            st["quality"] = report_check["quality"]
        meshes.append(mesh)
        all_stats.append(st)
    mesh = concatenate_meshes(meshes)
    stats = merge_stats(all_stats)
    stats["order"] = order
    stats["nodes"] = int(len(mesh.points))
    stats["valid"] = True
    stats["flipped_triangles"] = flipped
    notes = []
    if flipped:
        notes.append(f"re-oriented {flipped} triangle(s) (--reorient)")
    for st in all_stats:
        r = st.get("refine", {})
        if r.get("splits_no_exact_point"):
            notes.append(
                f"{r['splits_no_exact_point']} surface edge splits were skipped: no double lies exactly "
                "on those facets or edges near the midpoint, so elements there stay larger than the "
                "size (surface_points='rounded' / --surface-points rounded refines them, with the "
                "boundary then within rounding of the input)")
        if r.get("tag_conflicts_left"):
            notes.append(
                f"{r['tag_conflicts_left']} tets still have four corners on one CAD face (or three "
                "that are not their face there): FreeCAD's CalculiX writer, which finds element "
                "faces by their nodes, may load those faces wrongly; a smaller size usually "
                "removes them")
        if r.get("midnodes_straightened"):
            notes.append(f"{r['midnodes_straightened']} {MIDNODES_STRAIGHTENED_NOTE}")
    stats["notes"] = notes
    return mesh, stats


def concatenate_meshes(meshes):
    if len(meshes) == 1:
        return meshes[0]
    offsets = np.cumsum([0] + [len(m.points) for m in meshes[:-1]])
    return TetMesh(np.vstack([m.points for m in meshes]),
                   np.vstack([m.tets + off for m, off in zip(meshes, offsets)]),
                   " + ".join(m.source for m in meshes if m.source))


def merge_stats(all_stats):
    out = {}
    for st in all_stats:
        for k, v in st.items():
            if k == "quality":
                continue
            if k == "refine":
                agg = out.setdefault(k, {})
                for key, value in v.items():
                    if isinstance(value, (int, float)) and not isinstance(value, bool):
                        agg[key] = agg.get(key, 0) + value
                    elif key == "seconds_by_pass":
                        passes = agg.setdefault(key, {})
                        for name, seconds in value.items():
                            passes[name] = passes.get(name, 0) + seconds
                continue
            if k in ("seconds_by_stage", "steiner_seconds_by_phase", "steiner_removed_by_phase"):
                agg = out.setdefault(k, {})
                for stage, value in v.items():
                    agg[stage] = agg.get(stage, 0) + value
            elif isinstance(v, str):
                out[k] = v if out.get(k, v) == v else "mixed"
            else:
                out[k] = out.get(k, 0) + v
    qs = [st["quality"] for st in all_stats]
    out["min_dihedral_deg"] = min(q["min_dihedral_deg"] for q in qs)
    out["max_dihedral_deg"] = max(q["max_dihedral_deg"] for q in qs)
    out["max_radius_edge_ratio"] = max(q["max_radius_edge_ratio"] for q in qs)
    out["median_dihedral_deg"] = qs[0]["median_dihedral_deg"] if len(qs) == 1 else None
    out["median_radius_edge_ratio"] = qs[0]["median_radius_edge_ratio"] if len(qs) == 1 else None
    out["p1_dihedral_deg"] = qs[0]["p1_dihedral_deg"] if len(qs) == 1 else None
    out["dihedral_histogram"] = [sum(h) for h in zip(*(q["dihedral_histogram"] for q in qs))]
    out["solids"] = len(all_stats)
    return out


def _version():

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


# ---- Quality stage -----------------------------------------------------------------

#: Options of the quality stage (cpp_module/include/bsptet/refine/quality_refine.h), with their
#: meaning.
REFINE_OPTIONS = {
    "size": "target edge length h (model units; edges longer than 2 h are split, as FreeCAD's CharacteristicLengthMax for Gmsh)",
    "min_size": "edges shorter than 2 min_size are never split (default: smallest size / 8)",
    "size_by_tag": "{face tag: size} near the input triangles of that tag (a CAD face)",
    "size_from_surface": "True: the size at each input triangle is at most its mean edge length "
                         "(the volume grades from a surface already meshed to size, as Gmsh's "
                         "MeshSizeExtendFromBoundary)",
    "thickness_ratio": "thin walls: the size at a surface point is at most this times the solid's "
                       "local thickness there (distance to the nearest opposing face inside; "
                       "default 4; 0: off)",
    "radius_edge": "refine tets whose circumradius / shortest edge exceeds this (0 or None: off)",
    "min_dihedral": "the optimization stops once the smallest dihedral angle reaches this (deg)",
    "surface_points": "'exact' (default): new surface points exactly on the input facets, else "
                      "none; 'rounded': rounded midpoints (boundary within rounding of the input)",
    "projection": "callable (point (3,), tag, other_tag) -> point moving new surface points onto "
                  "the true surface (other_tag is -1 except on an edge between two face tags)",
    "order": "1 or 2 (10-node tets; boundary mid-nodes through projection)",
    "separate_face_tags": "True: no tet has four corners on one face tag, and three only as its "
                          "boundary face there, so that FEM tools that find element faces by node "
                          "membership (FreeCAD's CalculiX writer) load exactly the boundary faces",
}

#: The native RefineOptions field (quality_refine.h for_each_refine_option) of each Python option
#: whose name differs; the other options of REFINE_OPTIONS are the field of that name, except
#: ``projection``, a callback passed beside the options. A test checks this against the schema.
REFINE_OPTION_OF = {"radius_edge": "radius_edge_bound", "min_dihedral": "min_dihedral_deg"}

#: The native MeshOptions field (core/mesher.h for_each_mesh_option) of each core option of
#: :func:`tetrahedralize` (:func:`native_core_options` sets them through this table).
MESH_OPTION_OF = {"allow_boundary_steiner": "allow_boundary_steiner",
                  "steiner_effort": "steiner_effort", "bsp_seed": "seed"}

#: Options of :func:`tetrahedralize` handled in Python, not by a native options class.
PYTHON_OPTIONS = ("reorient", "max_memory", "projection")

#: Every option name :func:`tetrahedralize` accepts.
OPTION_NAMES = ("allow_boundary_steiner", "steiner_effort", "bsp_seed", "order", "reorient", "max_memory") + tuple(REFINE_OPTIONS)


def _positive_number(name, value, allow_zero=False):

    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"option {name} must be a number, got {value!r}") from None
    if not (v > 0 or (allow_zero and v == 0)) or v != v or v == float("inf"):
        raise InputError(f"option {name} must be a positive finite number"
                         f"{' or 0' if allow_zero else ''}, got {value!r}")
    return v


def refine(surface: Surface, mesh: TetMesh, options=None, progress=None, cancel=None):
    """Refines and optimizes ``mesh``, a valid linear tet mesh of ``surface`` (the core's output).

    ``options``: see ``REFINE_OPTIONS``. Returns ``(TetMesh, stats)``: the stats of the stage
    (splits, collapses, flips, ... see quality_refine.h) and ``quality`` (dihedral angles: min,
    1st percentile, median, histogram; radius-edge ratios). The result is checked exactly before
    it is returned: against ``surface`` in exact mode (the boundary tiles the input triangles);
    against its own boundary with ``surface_points='rounded'`` or a ``projection`` (positive tets,
    conforming faces, closed boundary; the boundary then is the refined, projected surface).
    Raises ``InputError`` for bad options, ``InternalError`` otherwise.
    """

    options = dict(options or {})
    unknown = set(options) - set(REFINE_OPTIONS)
    if unknown:
        raise InputError(f"unknown refinement option(s): {', '.join(sorted(unknown))}")
    size = options.get("size")
    size = float("inf") if size is None else _positive_number("size", size)
    min_size = options.get("min_size")
    min_size = 0.0 if min_size is None else _positive_number("min_size", min_size, allow_zero=True)
    by_tag = {}
    for tag, value in (options.get("size_by_tag") or {}).items():
        by_tag[int(tag)] = _positive_number(f"size_by_tag[{tag}]", value)
    radius_edge = options.get("radius_edge") or 0.0
    radius_edge = _positive_number("radius_edge", radius_edge, allow_zero=True)
    min_dihedral = options.get("min_dihedral") or 0.0
    min_dihedral = _positive_number("min_dihedral", min_dihedral, allow_zero=True)
    order = int(options.get("order") or 1)
    if order not in (1, 2):
        raise InputError(f"order must be 1 or 2, got {order}")
    mode = options.get("surface_points") or "exact"
    if mode not in ("exact", "rounded"):
        raise InputError(f"surface_points must be 'exact' or 'rounded', got {mode!r}")
    projection = options.get("projection")
    if projection is not None and not callable(projection):
        raise InputError("projection must be a callable (point, tag, other_tag) -> point")
    only_order = (set(k for k, v in options.items() if v is not None)
                  <= {"order", "projection", "separate_face_tags", "thickness_ratio"})
    lib = native()
    native_options = lib.RefineOptions()  # the core's defaults for what is not set here
    values = {"size": size, "min_size": min_size, "size_by_tag": by_tag,
              "radius_edge": radius_edge, "min_dihedral": min_dihedral, "order": order,
              "surface_points": getattr(lib.SurfacePoints, mode),
              "separate_face_tags": bool(options.get("separate_face_tags")),
              "size_from_surface": bool(options.get("size_from_surface"))}
    if options.get("thickness_ratio") is not None:
        values["thickness_ratio"] = _positive_number("thickness_ratio", options["thickness_ratio"],
                                                     allow_zero=True)
    for name, value in values.items():
        setattr(native_options, REFINE_OPTION_OF.get(name, name), value)
    if only_order:
        native_options.max_passes = 0  # no size passes: mid-edge nodes only
    with core_errors(surface, "refinement"):
        points, tets, st = lib.refine(
            surface.points, surface.triangles, surface.face_tags, mesh.points, mesh.tets[:, :4],
            options=native_options, projection=projection, progress=progress, cancel=cancel)
    out = TetMesh(points, tets, mesh.source)
    exact = mode == "exact" and projection is None
    reference = surface if exact else boundary_surface(out)
    report = _checked(reference, out, "refined mesh", source=surface.source)
    st["checked_against"] = "input surface" if exact else "own boundary"
    on_boundary = len(np.unique(boundary_surface(out).triangles))
    st["steiner_points"] = int(st["points"] - len(surface.points))
    st["boundary_steiner_points"] = int(on_boundary - len(surface.points))
    st["quality"] = report["quality"]
    return out, st


def boundary_surface(mesh: TetMesh) -> Surface:
    """The faces of exactly one tet of ``mesh`` (first four nodes), outward, as a Surface on the
    mesh's points. Used as the reference of the exact check when the boundary was moved on
    purpose (rounded surface points or a projection hook)."""
    tets = mesh.tets[:, :4]
    outward = ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))  # types.h, faces opposite 0..3
    faces = np.concatenate([tets[:, list(f)] for f in outward])
    key = np.sort(faces, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    return Surface(mesh.points, faces[first[counts == 1]], source=mesh.source)
