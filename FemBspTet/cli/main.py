# SPDX-License-Identifier: LGPL-2.1-or-later
"""The ``fembsptet`` command line.

    fembsptet mesh INPUT -o OUTPUT [-o OUTPUT ...] [--size H] [--min-size L] [--radius-edge B]
                   [--min-dihedral D] [--thickness-ratio K] [--surface-points exact|rounded] [--order 1|2]
                   [--dimension 2|3]
                   [--stats-json FILE] [--quiet] [--reorient] [--write-intersections FILE]
                   [--max-memory SIZE] [--out-of-core] [--workers N] [--scheduler ADDRESS]
                   [--timeout SECONDS]
    fembsptet check SURFACE TETMESH [--json]
    fembsptet compare INPUT [--size H] [--json FILE] [--plot FILE.png] [--timeout S] [--keep DIR]
    fembsptet benchmark MODELS_OR_FOLDERS... [--report FILE.md] [--divisions N] [--timeout S]

``compare`` exits 0 once its table is made, whatever each mesher did (a failing, missing or
timed-out mesher is a row that says so). Exit codes: 0 success; 2 bad input (the message says what and where), also for ``check`` when the
mesh is not valid, and for a run over its memory budget; 1 internal failure (also a crash of the
native code); 124 time limit reached (--timeout); 130 interrupted (Ctrl-C, SIGTERM).
``mesh`` runs in this process, stopped at once by Ctrl-C with no partial file; with --timeout or
--max-memory it runs in a supervised child process (:mod:`FemBspTet.cli.supervisor`) that
enforces them. Each command imports what it needs when it runs: a surface file meshes without
loading OpenCASCADE, FreeCAD or the comparison and picture modules.
Run it as ``bin/fembsptet`` (Debian's /usr/bin/python3) or ``/usr/bin/python3 -m FemBspTet.cli.main``.
"""

import argparse
import json
import math
import os
import sys
import time

import numpy as np

from .. import __version__
from ..io.atomic_file import atomic_output
from ..io.formats import (CAD_EXTENSIONS, extension, FREECAD_VOLUME_EXTENSIONS,
                          SURFACE_EXTENSIONS, VOLUME_EXTENSIONS)
from ..io.inputs import load_input
from ..io.surface_io import read_surface, write_surface
from ..io.volume_io import (MSH_VERSIONS, read_tet_mesh, stored_points, surface_groups,
                            write_tet_mesh)
from ..kernel import core
from ..kernel.errors import InputError, report_errors, SelfIntersectionError
from ..kernel.memory_budget import default_budget, parse_size
from ..kernel.mesh_types import MeshGroups, Surface, TetMesh
from ..kernel.progress import Progress
from ..peers.process import DEFAULT_TIMEOUT
from .supervisor import Limits, run_interruptible, run_supervised


# Keys of the stats JSON that scripts may rely on (stable; new keys may be added).
#: The FEM path's options (``FemOptions``, the schema of ``fem/fem_mesh.h``) that ``mesh`` flags
#: set for CAD input: argparse destination -> option (None: the option's default).
FEM_OPTION_OF_FLAG = {"size": "size", "min_size": "min_size", "order": "order",
                      "workers": "workers"}

STATS_KEYS = (
    "input_points",
    "input_triangles",
    "points",
    "tets",
    "steiner_points",
    "boundary_steiner_points",
    "interior_steiner_points",
    "bsp_nodes",
    "convex_cells",
    "min_dihedral_deg",
    "max_dihedral_deg",
    "max_radius_edge_ratio",
    "p1_dihedral_deg",
    "median_dihedral_deg",
    "seconds_total",
    "seconds_by_stage",
    "valid",
)


_ext = extension


def check_output_path(path):
    """Fails early (before meshing) on an output format we cannot write."""
    ext = _ext(path)
    if ext not in VOLUME_EXTENSIONS + FREECAD_VOLUME_EXTENSIONS:
        raise InputError(
            f"unknown output format '{ext or '(no extension)'}'; supported: "
            + ", ".join(VOLUME_EXTENSIONS + FREECAD_VOLUME_EXTENSIONS),
            where=path,
        )
    parent = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(parent):
        raise InputError("the output directory does not exist", where=parent)


def write_output(path, mesh, groups=None, msh_version="2.2"):
    """Write ``mesh`` (with its named sets ``groups``, a MeshGroups, when given) to ``path``."""
    ext = _ext(path)
    if ext in FREECAD_VOLUME_EXTENSIONS:
        from ..freecad.femmesh import write_via_freecad
        write_via_freecad(path, mesh, groups)
    else:

        _check_stored(path, mesh)
        write_tet_mesh(path, mesh, groups, msh_version=msh_version)


def _check_stored(path, mesh):
    """A format that rounds coordinates (``.inp``: CalculiX's 20-character fields) must not
    turn the valid mesh into an invalid one: the mesh as the file will hold it is checked
    exactly (orientation, flat tets, tet10 mid-nodes) before it is written."""

    points = stored_points(path, mesh.points)
    changed = (points != mesh.points).any(axis=1)
    if not changed.any() or len(mesh.tets) == 0:  # a 2D mesh has no tets to invert
        return
    stored = TetMesh(points, mesh.tets, source=mesh.source)
    report = core.check_mesh(core.boundary_surface(stored), stored, max_messages=3,
                             compute_quality=False)
    if not report["valid"]:
        raise InputError(
            f"the format's fixed-width fields round {int(changed.sum())} nodes' coordinates, "
            "and the rounded mesh is not valid (" + "; ".join(report["messages"]) + "); "
            "write .vtu, .msh or .mesh instead, or move the model away from values that need "
            "more than 20 characters (tiny non-zero coordinates)", where=path)


def read_volume(path):
    ext = _ext(path)
    if ext in FREECAD_VOLUME_EXTENSIONS:
        from ..freecad.femmesh import read_via_freecad
        return read_via_freecad(path)
    if ext in VOLUME_EXTENSIONS:

        return read_tet_mesh(path)
    raise InputError(
        f"unknown tet mesh format '{ext or '(no extension)'}'; supported: "
        + ", ".join(VOLUME_EXTENSIONS + FREECAD_VOLUME_EXTENSIONS),
        where=path,
    )


def _check_mesh_args(args):
    """Option checks done before any work (and before the supervised child starts)."""
    for out in args.output:
        check_output_path(out)
    for name in ("size", "min_size", "radius_edge", "min_dihedral"):
        value = getattr(args, name, None)
        if value is not None and not (value > 0 and math.isfinite(value)):
            raise InputError(f"--{name.replace('_', '-')} must be a positive number, got {value}")
    if args.thickness_ratio is not None and not (args.thickness_ratio >= 0 and math.isfinite(args.thickness_ratio)):
        raise InputError(f"--thickness-ratio must be 0 (off) or a positive number, got {args.thickness_ratio}")
    if args.dimension == 2:
        if _ext(args.input) not in CAD_EXTENSIONS or getattr(args, "tessellation", False):
            raise InputError("--dimension 2 meshes the faces of a CAD file (.step .brep .iges); "
                             "a triangle surface is already 2D", where=args.input)
        for out in args.output:
            if _ext(out) in (".node", ".ele"):
                raise InputError("TetGen's .node / .ele hold tetrahedra; write a 2D mesh as "
                                 ".vtu, .msh, .inp or .mesh", where=out)
        if getattr(args, "compare_tetgen", False):
            raise InputError("--compare-tetgen compares volume meshes; drop it with --dimension 2")
    if args.timeout is not None and not (args.timeout > 0 and math.isfinite(args.timeout)):
        raise InputError(f"--timeout must be a positive number of seconds, got {args.timeout}")
    if args.write_intersections is not None:
        ext = _ext(args.write_intersections)
        if ext not in SURFACE_EXTENSIONS:
            raise InputError(
                f"unknown format '{ext or '(no extension)'}' for --write-intersections; supported: "
                + ", ".join(SURFACE_EXTENSIONS), where=args.write_intersections)
        parent = os.path.dirname(os.path.abspath(args.write_intersections))
        if not os.path.isdir(parent):
            raise InputError("the output directory does not exist", where=parent)

    if args.max_memory is not None:
        args.max_memory_bytes = parse_size(args.max_memory, option="--max-memory")
    else:
        args.max_memory_bytes = default_budget()


def _write_intersections(path, exc):
    """Writes the triangles of the intersecting pairs of ``exc`` to ``path`` for viewing."""

    surface = exc.surface
    pairs = np.asarray(exc.pairs, dtype=np.int64).reshape(-1, 2)
    involved = np.unique(pairs)
    used = np.unique(surface.triangles[involved])
    remap = np.full(len(surface.points), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    # Face tags are the input's triangle indices: a viewer can colour or pick them by number.
    out = Surface(surface.points[used], remap[surface.triangles[involved]], involved.astype(np.int32))
    write_surface(path, out)
    print(f"fembsptet: wrote the {len(involved)} triangles of {len(pairs)} intersecting pair(s) to "
          f"{path} (face tags = triangle indices)", file=sys.stderr)


def _mesh_cad_fem(args, progress):
    """The default for a CAD file: the FEM path (FemBspTet.fem.cad_mesh, no FreeCAD): the CAD
    surface meshed at the size, the exact core, refinement with points and tet10 mid-nodes on
    the CAD. Returns (mesh, stats, MeshGroups: CAD faces and solids)."""
    from ..fem.cad_mesh import mesh_cad_faces_file, mesh_cad_file
    unsupported = [name for name, value in (("--min-dihedral", args.min_dihedral),
                                            ("--radius-edge", args.radius_edge),
                                            ("--thickness-ratio", args.thickness_ratio),
                                            ("--surface-points", args.surface_points),
                                            ("--steiner-effort", args.steiner_effort),
                                            ("--bsp-seed", args.bsp_seed),
                                            ("--reorient", args.reorient or None),
                                            ("--allow-boundary-steiner",
                                             args.allow_boundary_steiner or None),
                                            ("--out-of-core", getattr(args, "out_of_core", None)
                                             or None),
                                            ("--scheduler", args.scheduler))
                   if value is not None]
    if unsupported:
        raise InputError("a CAD file is meshed by the FEM path, which does not take "
                         + ", ".join(unsupported) + "; drop them, or add --tessellation to mesh "
                         "OpenCASCADE's display tessellation with the core instead",
                         where=args.input)

    options = {option: getattr(args, dest) for dest, option in FEM_OPTION_OF_FLAG.items()}
    if args.dimension == 2:
        faces = mesh_cad_faces_file(args.input, progress=progress, **options)
        # A 2D mesh: no tets; the elements are the groups' triangles (volume_io.write_tet_mesh).
        columns = 10 if faces.triangles.shape[1] == 6 else 4
        groups = MeshGroups(face_triangles=faces.triangles, face_tags=faces.face_tags,
                            face_names=faces.groups.face_names,
                            tet_solid=np.zeros(0, dtype=np.int32), solid_names=[])
        return (TetMesh(faces.points, np.zeros((0, columns), dtype=np.int64), source=args.input),
                faces.stats, groups)
    result = mesh_cad_file(args.input, progress=progress, **options)
    return result.mesh, result.stats, result.groups


def _surface_groups(mesh, surfaces, stats):
    """Named sets from a tagged input surface (a surface file's tags, a CAD tessellation's
    faces) when the mesh's boundary is that surface unchanged; None otherwise."""
    if len(surfaces) != 1 or surfaces[0].face_tags is None or \
            int(stats.get("boundary_steiner_points", 0)) != 0:
        return None

    return surface_groups(mesh, surfaces[0])


def _cmd_mesh(args):
    progress = Progress(enabled=not args.quiet)
    t0 = time.perf_counter()
    if not hasattr(args, "max_memory_bytes"):
        _check_mesh_args(args)
    fem_path = _ext(args.input) in CAD_EXTENSIONS and not getattr(args, "tessellation", False)
    if fem_path:
        progress("reading the CAD file")
        try:
            mesh, stats, groups = _mesh_cad_fem(args, progress)
        finally:
            progress.finish()
        return _finish_mesh(args, progress, t0, mesh, stats, surfaces=None, groups=groups)
    progress("reading input")
    surfaces = load_input(args.input, size=args.size)

    options = {k: v for k, v in (("size", args.size), ("min_size", args.min_size),
                                 ("radius_edge", args.radius_edge),
                                 ("min_dihedral", args.min_dihedral),
                                 ("thickness_ratio", args.thickness_ratio),
                                 ("surface_points", args.surface_points),
                                 ("order", args.order),
                                 ("allow_boundary_steiner", args.allow_boundary_steiner),
                                 ("steiner_effort", args.steiner_effort),
                                 ("bsp_seed", args.bsp_seed), ("reorient", args.reorient))
               if v not in (None, False) and not (k == "order" and v == 1)}
    from ..fem.pieces import default_workers, tetrahedralize_in_pieces
    workers = args.workers
    core_only = not set(options) - {"steiner_effort", "bsp_seed", "reorient"}
    if workers is None and args.scheduler is None:
        workers = default_workers(sum(len(s.triangles) for s in surfaces)) if core_only else 1
    if getattr(args, "out_of_core", False) or args.scheduler is not None or workers != 1:
        progress("tetrahedralizing in pieces")
        try:
            mesh, stats = tetrahedralize_in_pieces(
                surfaces, options, max_memory=args.max_memory_bytes, workers=workers,
                scheduler=args.scheduler, progress=progress)
        finally:
            progress.finish()
        return _finish_mesh(args, progress, t0, mesh, stats, surfaces)
    progress("tetrahedralizing")
    try:
        mesh, stats = core.tetrahedralize(
            surfaces,
            options={"size": args.size,
                     "min_size": args.min_size,
                     "radius_edge": args.radius_edge,
                     "min_dihedral": args.min_dihedral,
                     "thickness_ratio": args.thickness_ratio,
                     "surface_points": args.surface_points,
                     "order": args.order,
                     "allow_boundary_steiner": args.allow_boundary_steiner,
                     "steiner_effort": args.steiner_effort,
                     "bsp_seed": args.bsp_seed,
                     "reorient": args.reorient,
                     "max_memory": args.max_memory_bytes},
            progress=progress)
    except SelfIntersectionError as exc:
        if args.write_intersections:
            progress.finish()
            _write_intersections(args.write_intersections, exc)
        raise
    finally:
        progress.finish()
    return _finish_mesh(args, progress, t0, mesh, stats, surfaces)


def _finish_mesh(args, progress, t0, mesh, stats, surfaces, groups=None):
    progress("writing")
    t_write = time.perf_counter()
    if groups is None and surfaces is not None and args.output:
        groups = _surface_groups(mesh, surfaces, stats)
    for out in args.output:
        write_output(out, mesh, groups, msh_version=args.msh_version)
    progress.finish()
    stats["seconds_writing"] = time.perf_counter() - t_write
    stats["seconds_total"] = time.perf_counter() - t0
    unsized = surfaces is not None and all(
        getattr(args, k, None) is None for k in ("size", "radius_edge", "min_dihedral"))
    if unsized and args.output:
        stats.setdefault("notes", []).append(
            "this is the core's mesh of the surface as given: no element size and no quality "
            f"bound (worst dihedral angle {stats.get('min_dihedral_deg', float('nan')):.2f} "
            "degrees); for an FEM mesh give --size H (and --order 2), or mesh the CAD file")
    for note in stats.get("notes", []):
        print(f"fembsptet: note: {note}", file=sys.stderr)
    if args.stats_json:

        with atomic_output(args.stats_json) as f:
            json.dump(stats, f, indent=1)
    if args.json:
        print(json.dumps({k: stats.get(k) for k in STATS_KEYS}, indent=1))
    elif not args.quiet:
        print(mesh_summary(args.input, args.output, mesh, stats, groups))
    if args.compare_tetgen:
        if surfaces is None:
            from ..io.cad_tessellation import tessellate_file
            surfaces = tessellate_file(args.input, size=args.size)
        print(_tetgen_table(surfaces, stats))
    return 0


def _count(n):
    return f"{int(n):,}"


def mesh_summary(source, outputs, mesh, stats, groups):
    """What a person wants to read at the end of a run: what was read, what was written, the
    element counts of the written order, the quality figures, where the time went."""
    order = 2 if mesh.tets.shape[1] == 10 else 1
    fem_path = "surface_nodes" in stats
    lines = []
    if fem_path:
        lines.append(f"read     {source}: {_count(stats['solids'])} solid(s), "
                     f"{_count(stats['faces'])} CAD faces; meshed at size {stats['size']:.4g} "
                     f"(min {stats['min_size']:.3g})"
                     + (f" in {int(stats['pieces'])} pieces" if stats.get("pieces", 0) >
                        stats["solids"] else ""))
    else:
        lines.append(f"read     {source}: {_count(stats.get('input_points', 0))} points, "
                     f"{_count(stats.get('input_triangles', 0))} triangles")
    two_d = len(mesh.tets) == 0 and groups is not None and len(groups.face_triangles) > 0
    if two_d:  # the elements are the CAD faces' triangles
        kind = "tria6" if groups.face_triangles.shape[1] == 6 else "tria3"
        elements = len(groups.face_triangles)
    else:
        kind = "tet10" if order == 2 else "tet4"
        elements = len(mesh.tets)
    written = f"{_count(len(mesh.points))} nodes, {_count(elements)} {kind} elements"
    if groups is not None:
        faces = len(np.unique(groups.face_tags))
        solids = 1 if groups.tet_solid is None else len(np.unique(groups.tet_solid))
        written += f"; sets: {faces} CAD face(s)" + ("" if two_d else f", {solids} solid(s)")
    for out in outputs:
        lines.append(f"wrote    {out}: {written}")
    if not outputs:
        lines.append(f"made     {written} (no file written: give -o FILE)")
    if two_d:
        quality = (f"quality  smallest triangle angle {stats['min_triangle_angle_deg']:.1f} deg, "
                   f"median per-triangle smallest {stats['median_triangle_min_angle_deg']:.1f} "
                   "deg")
    else:
        quality = f"quality  worst dihedral {stats.get('min_dihedral_deg', float('nan')):.1f} deg"
    if stats.get("p1_dihedral_deg") is not None:
        quality += f", 1% of angles under {stats['p1_dihedral_deg']:.1f}"
    if "median_tet_min_dihedral_deg" in stats and not two_d:
        quality += (f", median per-tet worst {stats['median_tet_min_dihedral_deg']:.1f} deg, "
                    f"{stats.get('tets_below_10_deg', 0.0):.2f}% under 10 deg")
    if stats.get("max_radius_edge_ratio") is not None:
        quality += f"; worst radius-edge ratio {stats['max_radius_edge_ratio']:.3g}"
    lines.append(quality)
    if not fem_path:
        lines.append(f"points   Steiner {_count(stats.get('steiner_points', 0))} (on the surface "
                     f"{_count(stats.get('boundary_steiner_points', 0))})")
    parts = [(name, stats[key]) for name, key in (
        ("surface", "seconds_surface"), ("core", "seconds_core"), ("refine", "seconds_refine"),
        ("merge", "seconds_merge"), ("writing", "seconds_writing")) if key in stats]
    total = stats.get("seconds_total", 0.0)
    if two_d:  # no volume stages
        parts = [(k, v) for k, v in parts if k in ("surface", "writing")]
    if not fem_path:  # the core's stages: the four longest
        stages = sorted((stats.get("seconds_by_stage") or {}).items(), key=lambda kv: -kv[1])
        parts = [(k.replace("_", " "), v) for k, v in stages[:4] if v >= 0.005] + \
            [(k, v) for k, v in parts if k == "writing"]
    other = total - sum(v for _, v in parts)
    timing = ", ".join(f"{k} {v:.2f}" for k, v in parts)
    if fem_path and stats.get("pieces", stats.get("solids", 1)) > 1 and other < 0:
        # the solids (or the pieces of a cut solid) were meshed at the same time: their stage
        # seconds add up to more than the run
        timing += f"; the core and refine seconds add up over the {int(stats['pieces'])} pieces " \
                  "meshed at the same time"
        lines.append(f"time     {total:.2f} s ({timing})")
    else:
        lines.append(f"time     {total:.2f} s" + (f" ({timing}, the rest {other:.2f})"
                                                  if parts else ""))
    return "\n".join(lines)


def _tetgen_table(surfaces, stats):
    """Our counts beside `tetgen -pY` on the same surface(s) (compare/comparison.py)."""
    from ..compare.comparison import format_rows, row_from_stats, tetgen_pY_row
    return format_rows([row_from_stats(stats), tetgen_pY_row(surfaces)])


def _summary(report):
    q = report.get("quality", {})
    lines = [
        f"valid: {report['valid']}",
        f"points: {report['points']}  tets: {report['tets']}  boundary faces: "
        f"{report['boundary_faces']}  steiner points: {report['steiner_points']} "
        f"(boundary {report['boundary_steiner_points']})",
        f"volume: tets {report['tet_volume']:.17g}  enclosed {report['surface_volume']:.17g}  "
        f"equal: {report['volume_equal']}",
    ]
    if q:
        lines.append(
            f"dihedral angles: min {q['min_dihedral_deg']:.3f}  1% {q['p1_dihedral_deg']:.3f}  "
            f"median {q['median_dihedral_deg']:.3f}  max {q['max_dihedral_deg']:.3f} deg;  "
            f"max radius-edge ratio {q['max_radius_edge_ratio']:.4g}"
        )
    defects = [
        k
        for k in (
            "bad_indices",
            "nonfinite_points",
            "duplicate_points",
            "unreferenced_points",
            "inverted_tets",
            "flat_tets",
            "overshared_faces",
            "same_orientation_faces",
            "boundary_faces_off_surface",
            "boundary_faces_inward",
            "unpaired_boundary_edges",
            "miscovered_triangles",
            "inconsistent_midnodes",
        )
        if report.get(k)
    ]
    for k in defects:
        lines.append(f"  {k}: {report[k]}")
    for m in report["messages"]:
        lines.append(f"  - {m}")
    return "\n".join(lines)


def _cmd_check(args):

    if _ext(args.surface) in CAD_EXTENSIONS:
        return _check_against_cad(args)
    if _ext(args.surface) not in SURFACE_EXTENSIONS:
        raise InputError(
            "the reference must be a triangle surface file ("
            + ", ".join(SURFACE_EXTENSIONS) + ") or a CAD file ("
            + ", ".join(CAD_EXTENSIONS) + ")",
            where=args.surface,
        )
    surface = read_surface(args.surface)
    mesh = read_volume(args.tetmesh)
    if _ext(args.tetmesh) in VOLUME_EXTENSIONS:

        # the reference as the mesh's format stores coordinates (.inp rounds some)
        surface.points = stored_points(args.tetmesh, surface.points)
    report = core.check_mesh(surface, mesh, max_messages=args.max_messages)
    if args.json:
        json.dump(report, sys.stdout, indent=1)
        sys.stdout.write("\n")
    else:
        print(_summary(report))
    if not report["valid"]:
        if not args.json:
            print(f"fembsptet: {args.tetmesh} is NOT a valid mesh of {args.surface}", file=sys.stderr)
        return 2
    return 0


def _check_against_cad(args):
    """``check PART.step MESH``: the mesh's own exact validity, tet10 certified, and its boundary
    nodes on the CAD faces (FemBspTet.fem.cad_check)."""
    from ..fem.cad_check import check_against_cad
    if not os.path.isfile(args.surface):
        raise InputError("file not found", where=args.surface)
    mesh = read_volume(args.tetmesh)
    report = check_against_cad(args.surface, mesh, max_messages=args.max_messages)
    if args.json:
        json.dump(report, sys.stdout, indent=1, default=lambda v: v.item())
        sys.stdout.write("\n")
    else:
        print(_summary(report))
        if "tet10_certified" in report:
            print(f"tet10: {report['tet10_certified']} elements certified positive, "
                  f"{report['tet10_not_certified']} not")
        print(f"on the CAD: {report['boundary_nodes']} boundary nodes, {report['off_cad_nodes']} "
              f"farther than their face's tolerance; largest distance "
              f"{report['max_distance']:.3g} (Face{report['max_distance_face']}, tolerance "
              f"{report['max_distance_tolerance']:.3g}); {report['faces_tagged']} measured to the "
              "face their file names, the others to the nearest face")
    ok = report["valid"] and report["on_cad"]
    if not ok and not args.json:
        what = "NOT a valid mesh" if not report["valid"] else "valid, but NOT on the CAD faces"
        print(f"fembsptet: {args.tetmesh} is {what} of {args.surface}", file=sys.stderr)
    return 0 if ok else 2


def _cmd_render(args):
    from ..io.render import render_mesh
    if _ext(args.output) != ".png":
        raise InputError("the picture is written as PNG: name it FILE.png", where=args.output)
    parent = os.path.dirname(os.path.abspath(args.output))
    if not os.path.isdir(parent):
        raise InputError("the output directory does not exist", where=parent)
    mesh = read_volume(args.tetmesh)
    drawn = render_mesh(mesh, args.output, cut=args.cut, size_px=args.size)
    print(f"fembsptet: wrote {args.output} ({drawn['triangles']:,} triangles of "
          f"{drawn['tets']:,} tets drawn)")
    return 0


def _cmd_cells(args):
    from ..io.render import render_bsp_cells
    if _ext(args.output) != ".png":
        raise InputError("the picture is written as PNG: name it FILE.png", where=args.output)
    surfaces = load_input(args.input)
    if len(surfaces) != 1:
        raise InputError(f"{len(surfaces)} solids: the cell picture takes one", where=args.input)
    drawn = render_bsp_cells(surfaces[0], args.output, explode=args.explode,
                             outside=args.outside, size_px=args.size)
    print(f"fembsptet: wrote {args.output} ({drawn['cells']:,} cells, {drawn['inside']:,} inside)")
    return 0


def _cmd_freecad_install(args):
    from .addon_install import install
    for line in install(args.mod_dir, uninstall=args.uninstall):
        print(f"fembsptet: {line}")
    if not args.uninstall:
        print("fembsptet: restart FreeCAD; the mesher is in the FEM workbench's Mesh menu and "
              "toolbar")
    return 0


def _positive_option(value, option):
    if value is not None and not (value > 0 and math.isfinite(value)):
        raise InputError(f"{option} must be a positive number, got {value}")


def _cmd_compare(args):
    """Our mesher, TetGen and Gmsh on the same surface: one table (compare/comparison.py)."""
    from ..compare.comparison import compare, format_table, MESHERS, plot_histograms, write_json
    _positive_option(args.size, "--size")
    _positive_option(args.timeout, "--timeout")
    meshers = tuple(m for m in args.meshers.split(",") if m) if args.meshers else MESHERS
    unknown = set(meshers) - set(MESHERS)
    if unknown:
        raise InputError(f"unknown mesher(s) {', '.join(sorted(unknown))}; known: "
                         + ", ".join(MESHERS))
    for out in (args.json, args.plot):
        if out and not os.path.isdir(os.path.dirname(os.path.abspath(out))):
            raise InputError("the output directory does not exist", where=out)
    surfaces = load_input(args.input, size=args.size)
    result = compare(surfaces, size=args.size, timeout=args.timeout, workdir=args.keep,
                     meshers=meshers, source=args.input)
    print(format_table(result))
    if args.json:
        write_json(args.json, result)
    if args.plot:
        plot_histograms(args.plot, result)
    return 0


def _cmd_benchmark(args):
    """``compare`` over folders of models, as a markdown report (compare/benchmark.py)."""
    from ..compare.benchmark import model_paths, run_benchmark, write_report
    from ..compare.comparison import MESHERS
    _positive_option(args.divisions, "--divisions")
    _positive_option(args.timeout, "--timeout")
    if not os.path.isdir(os.path.dirname(os.path.abspath(args.report))):
        raise InputError("the output directory does not exist", where=args.report)
    paths = model_paths(args.models)
    if not paths:
        raise InputError("no models found (" + ", ".join(SURFACE_EXTENSIONS + CAD_EXTENSIONS)
                         + ")")
    meshers = tuple(m for m in args.meshers.split(",") if m) if args.meshers else MESHERS
    entries = run_benchmark(paths, timeout=args.timeout, divisions=args.divisions,
                            meshers=meshers, log=lambda line: print(line, flush=True))
    command = "fembsptet " + " ".join(args.raw_argv)
    png = write_report(args.report, entries, command=command)
    print(f"report: {args.report}" + (f" (+ {png})" if png else ""))
    return 0


def _non_negative_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {value}")
    return value


def build_parser():
    p = argparse.ArgumentParser(
        prog="fembsptet",
        description="BSP-assisted constrained tetrahedralization for FEM (FreeCAD addon CLI).",
    )
    p.add_argument("--version", action="version", version=f"fembsptet {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    m = sub.add_parser("mesh", help="tetrahedralize a closed surface or CAD solid")
    m.add_argument("input", help="surface (.off .stl .obj .ply) or CAD (.step .stp .brep .iges)")
    m.add_argument("-o", "--output", action="append", required=True,
                   help="output mesh; repeat for several (.vtu .msh .inp .node .mesh .unv .med .z88)")
    m.add_argument("--size", type=float, default=None,
                   help="element size h (target edge length; edges longer than 2 h are split, as "
                        "Gmsh's CharacteristicLengthMax); also the CAD tessellation size")
    m.add_argument("--min-size", type=float, default=None,
                   help="edges shorter than twice this are never split (default: size / 8)")
    m.add_argument("--radius-edge", type=float, default=None,
                   help="refine tets whose circumradius / shortest edge exceeds this (e.g. 2)")
    m.add_argument("--min-dihedral", type=float, default=None,
                   help="optimize until the smallest dihedral angle reaches this (degrees)")
    m.add_argument("--thickness-ratio", type=float, default=None, metavar="K",
                   help="thin walls: the size at a surface point is at most K times the solid's "
                        "local thickness there (default 4; 0: off)")
    m.add_argument("--surface-points", choices=("exact", "rounded"), default=None,
                   help="exact (default): new surface points exactly on the input facets, none "
                        "where no double lies on them; rounded: rounded midpoints everywhere "
                        "(boundary within rounding of the input, checked against itself)")
    m.add_argument("--order", type=int, choices=(1, 2), default=1,
                   help="element order (2: 10-node tets, 6-node triangles in 2D)")
    m.add_argument("--dimension", type=int, choices=(2, 3), default=3,
                   help="CAD input: 3 (default) the solids as tetrahedra; 2 every CAD face (of a "
                        "Face, a Shell or solids) as triangles, for shell and plane analyses "
                        "(.inp: S3 / S6 elements, a node and an element set per face)")
    m.add_argument("--stats-json", default=None, help="write the run's statistics here (JSON)")
    m.add_argument("--quiet", action="store_true", help="no progress and no summary")
    m.add_argument("--msh-version", choices=MSH_VERSIONS, default="2.2",
                   help="the MSH format of .msh outputs (default 2.2, read by every tool that "
                        "reads MSH; 4.1 is Gmsh 4's own)")
    m.add_argument("--json", action="store_true",
                   help="print the statistics as JSON on stdout instead of the summary")
    m.add_argument("--allow-boundary-steiner", action="store_true",
                   help="keep Steiner points on the surface where they are exactly doubles "
                        "(default: none on the surface, as tetgen -Y)")
    m.add_argument("--steiner-effort", type=_non_negative_int, default=None, metavar="N",
                   help="work (exact orientation tests, cavity growth) the core may spend removing "
                        "one interior Steiner point (default 1000000; 0: no bound, fewer Steiner "
                        "points, possibly much slower)")
    m.add_argument("--bsp-seed", choices=("auto", "delaunay", "box"), default=None,
                   help="where the core's BSP starts: the Delaunay tetrahedralization of the input "
                        "points (only the cells an input triangle crosses are split) or one box "
                        "(the paper's auto-partition); auto (default): the Delaunay seed unless "
                        "the input triangles cross more than 4 of its tets each on average")
    m.add_argument("--tessellation", action="store_true",
                   help="CAD input: mesh OpenCASCADE's display tessellation with the core (sized "
                        "only with --size; needs FreeCAD) instead of the FEM path, which meshes "
                        "the CAD surface itself at the size (default; automatic size: the "
                        "bounding-box diagonal / 20)")
    m.add_argument("--compare-tetgen", action="store_true",
                   help="also run tetgen -pY on the same surface and print both side by side")
    m.add_argument("--reorient", action="store_true",
                   help="flip inconsistently oriented triangles and inward-facing shells instead of "
                        "refusing the surface (cavities are made to face inward)")
    m.add_argument("--write-intersections", metavar="FILE", default=None,
                   help="if the surface intersects itself, write the intersecting triangles here "
                        "(.off .stl .obj .ply; face tags = triangle indices) for viewing")
    m.add_argument("--max-memory", metavar="SIZE", default=None,
                   help="memory budget, e.g. 4G or 512M (default: the memory available now); a "
                        "run estimated to need more is refused before it starts, one that uses "
                        "more is stopped (exit 2)")
    m.add_argument("--out-of-core", action="store_true",
                   help="mesh in pieces small enough for --max-memory, one after the other, each "
                        "written to disk before the next (the solid is cut along caps inside it; "
                        "their points become interior nodes); the core's mesh only: no --size, "
                        "quality or --order 2")
    m.add_argument("--workers", metavar="N", type=int, default=None,
                   help="a CAD file: mesh N solids at a time, one thread each, a single big "
                        "solid cut in two or three pieces first (default: every core; the mesh is "
                        "the same for any N). A triangle surface: mesh it in "
                        "about N pieces, N at a time (default: every core for a surface of at "
                        "least 200,000 triangles meshed by the core alone, else 1); the mesh "
                        "depends on N, not on where the pieces ran")
    m.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="mesh the pieces on the workers of this Dask cluster (tcp://HOST:8786; "
                        "python3-distributed; every worker must import FemBspTet); --workers then "
                        "defaults to the cluster's worker count")
    m.add_argument("--timeout", metavar="SECONDS", type=float, default=None,
                   help="stop the run after this many seconds (exit 124; no output is written)")
    m.set_defaults(func=_cmd_mesh)

    c = sub.add_parser("check", help="check a tet mesh against its surface or CAD part (exit 0 "
                                     "only if valid)")
    c.add_argument("surface", help="the closed input surface (.off .stl .obj .ply), or the CAD part "
                                   "(.step .stp .brep .iges): then the mesh is checked exactly by "
                                   "itself, tet10 certified, and its boundary nodes must lie on the "
                                   "CAD faces within their tolerance")
    c.add_argument("tetmesh", help="the tet mesh (.vtu .msh .inp .node/.ele .mesh .unv .med .z88)")
    c.add_argument("--json", action="store_true", help="print the full report as JSON")
    c.add_argument("--max-messages", type=int, default=20, help="problems listed (default 20)")
    c.set_defaults(func=_cmd_check)

    r = sub.add_parser("render", help="a picture of a tet mesh (PNG): the boundary coloured by CAD "
                                      "face, or --cut through the middle coloured by quality")
    r.add_argument("tetmesh", help="the tet mesh (.vtu .msh .inp .node/.ele .mesh .unv .med .z88)")
    r.add_argument("-o", "--output", required=True, metavar="FILE.png")
    r.add_argument("--cut", action="store_true",
                   help="remove the near half and colour the tets by their smallest dihedral angle")
    r.add_argument("--size", type=int, default=900, metavar="PIXELS", help="width and height")
    r.set_defaults(func=_cmd_render)

    b = sub.add_parser("cells", help="the paper's picture of a surface's BSP (PNG): the convex "
                                     "cells of the box split by the triangles' planes, exploded")
    b.add_argument("input", help="surface (.off .stl .obj .ply) or CAD file (tessellated through "
                                 "FreeCAD), at most 5000 triangles")
    b.add_argument("-o", "--output", required=True, metavar="FILE.png")
    b.add_argument("--explode", type=float, default=0.4,
                   help="how far the cells move apart (fraction of their distance to the centre)")
    b.add_argument("--outside", action="store_true",
                   help="draw the cells outside the solid too (faint, out to the box)")
    b.add_argument("--size", type=int, default=900, metavar="PIXELS", help="width and height")
    b.set_defaults(func=_cmd_cells)

    f = sub.add_parser("freecad-install",
                       help="link this FemBspTet into FreeCAD's user Mod folders (FreeCAD 0.20 "
                            "to 1.0: ~/.local/share/FreeCAD/Mod; 1.1+: its versioned folders)")
    f.add_argument("--mod-dir", action="append", default=None, metavar="DIR",
                   help="link into this Mod folder instead (repeatable)")
    f.add_argument("--uninstall", action="store_true", help="remove the links instead")
    f.set_defaults(func=_cmd_freecad_install)


    k = sub.add_parser("compare", help="our mesher, tetgen and gmsh on the same surface: a table")
    k.add_argument("input", help="surface (.off .stl .obj .ply) or CAD (.step .stp .brep .iges); "
                                 "a CAD file is tessellated once and every mesher gets the same "
                                 "triangles")
    k.add_argument("--size", type=float, default=None,
                   help="element size h: our quality stage at h, tetgen -pq1.414a<h^3/(6 sqrt "
                        "2)> and gmsh at CharacteristicLengthMax h (gmsh remeshes the surface); "
                        "without it: our default mesh, tetgen -pY and gmsh filling the surface "
                        "(at the mean input edge length)")
    k.add_argument("--json", metavar="FILE", default=None, help="write the table as JSON")
    k.add_argument("--plot", metavar="FILE.png", default=None,
                   help="draw the dihedral-angle histograms side by side (matplotlib)")
    k.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT,
                   help=f"seconds each mesher may run (default {DEFAULT_TIMEOUT:g})")
    k.add_argument("--keep", metavar="DIR", default=None,
                   help="keep every mesher's input and mesh files in DIR")
    k.add_argument("--meshers", default=None,
                   help="comma-separated subset of ours,tetgen-pY,tetgen-pq,gmsh (default: all)")
    k.set_defaults(func=_cmd_compare)

    b = sub.add_parser("benchmark", help="compare over folders of models: a markdown report")
    b.add_argument("models", nargs="+", help="model files and folders of models")
    b.add_argument("--report", default="compare-report.md",
                   help="markdown report (default compare-report.md; the histograms go to "
                        "the same name with .png)")
    b.add_argument("--divisions", type=float, default=None,
                   help="mesh every model at size h = bounding-box diagonal / N (default: the "
                        "default meshes, as compare without --size)")
    b.add_argument("--timeout", type=float, default=300.0,
                   help="seconds each mesher may run on one model (default 300)")
    b.add_argument("--meshers", default=None, help="as for compare")
    b.set_defaults(func=_cmd_benchmark)
    return p


def _mesh_outputs(args):
    """Every file a mesh run may write (the supervisor removes their temporaries)."""
    outputs = list(args.output)
    for extra in (args.stats_json, args.write_intersections):
        if extra:
            outputs.append(extra)
    for out in args.output:  # TetGen output is two files
        if _ext(out) in (".node", ".ele"):
            outputs += [os.path.splitext(out)[0] + ".node", os.path.splitext(out)[0] + ".ele"]
    return outputs


def _supervised_mesh(args):
    """``mesh`` in a supervised child process (--timeout, --max-memory: supervisor.py)."""

    _check_mesh_args(args)
    limits = Limits(timeout=args.timeout, max_memory=args.max_memory_bytes)
    return run_supervised(lambda: report_errors(_cmd_mesh, args), limits, _mesh_outputs(args))


def _interruptible_mesh(args):
    """``mesh`` in this process; Ctrl-C stops it at once and leaves no partial file."""

    _check_mesh_args(args)
    return run_interruptible(lambda: report_errors(_cmd_mesh, args), _mesh_outputs(args))


def main(argv=None, supervise=True):
    """The command line. ``mesh`` runs in this process, stopped at once by Ctrl-C; with
    ``--timeout`` or ``--max-memory`` it runs in a supervised child process that enforces them.
    ``supervise=False`` runs ``mesh`` in this process with no signal handling and no limits
    (for callers that supervise it themselves)."""
    args = build_parser().parse_args(argv)
    args.raw_argv = list(sys.argv[1:] if argv is None else argv)
    if args.command == "mesh" and supervise:
        limited = args.timeout is not None or args.max_memory is not None
        return report_errors(_supervised_mesh if limited else _interruptible_mesh, args)
    if args.command == "mesh" and args.timeout is not None:
        print("fembsptet: error: --timeout needs the supervised run", file=sys.stderr)
        return 2
    return report_errors(args.func, args)


if __name__ == "__main__":
    sys.exit(main())
