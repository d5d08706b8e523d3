# SPDX-License-Identifier: LGPL-2.1-or-later
"""A solid meshed in pieces: for memory (the out-of-core mode, pieces small enough for a budget)
and for speed (pieces meshed at the same time, on the threads of this process or on the workers
of a Dask cluster). ``cpp_module/include/bsptet/pieces/out_of_core.h`` says how the solid is cut
and why the pieces' meshes are one conforming mesh.

    mesh, stats = tetrahedralize_in_pieces(surfaces, max_memory=4 << 30)       # out of core
    mesh, stats = tetrahedralize_in_pieces(surfaces, workers=2)                # 2 threads
    mesh, stats = tetrahedralize_in_pieces(surfaces, workers=4,
                                           scheduler="tcp://head:8786")      # a Dask cluster
"""

import concurrent.futures
import os
import tempfile

import numpy as np

from ..io.volume_io import read_tetgen
from .cluster import cluster_workers, mesh_pieces_on_cluster
from ..kernel.core import (OPTION_NAMES, REFINE_OPTIONS, check_surface, concatenate_meshes,
                           core_errors, merge_stats, native, native_core_options, tet_quality)
from ..kernel.errors import InputError, MemoryBudgetError
from ..kernel.memory_budget import BASE_BYTES, format_bytes
from ..kernel.mesh_types import Surface, TetMesh


#: What a run in pieces holds besides the core's runs on its pieces (bytes per input triangle):
#: the input surface, its pieces' triangle lists, and the finished mesh read back for writing.
OUT_OF_CORE_HOLD_PER_TRIANGLE = 256

#: Below this many triangles a solid is meshed whole even when several workers are at hand: the
#: cut and its checks cost about what the second worker saves (bench/parallel_pieces.py).
PARALLEL_MIN_TRIANGLES = 200_000


def default_workers(triangles):
    """The workers a run on ``triangles`` triangles uses when the caller names none: every core
    this process may run on for inputs of at least :data:`PARALLEL_MIN_TRIANGLES`, else 1."""
    if triangles < PARALLEL_MIN_TRIANGLES:
        return 1
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def _refuse_options(options):
    unknown = set(options) - set(OPTION_NAMES)
    if unknown:
        raise InputError(f"unknown mesher option(s): {', '.join(sorted(unknown))}")
    refused = sorted(k for k, v in options.items()
                     if v not in (None, False) and (k in REFINE_OPTIONS and not (k == "order" and int(v) == 1)
                                                    or k == "allow_boundary_steiner"))
    if refused:
        raise InputError("meshing in pieces makes the core's mesh only: drop "
                         + ", ".join(refused) + " (or mesh whole, without --out-of-core and with "
                         "--workers 1)")


def _piece_size(lib, triangles, total, max_memory, workers, max_piece_triangles, where):
    """The largest piece, in triangles, for a solid of ``triangles`` triangles in a run on
    ``total`` (see :func:`tetrahedralize_in_pieces`)."""
    if max_piece_triangles is not None:
        return int(max_piece_triangles)
    sizes = []
    if max_memory is not None:
        usable = (int(max_memory) - BASE_BYTES - OUT_OF_CORE_HOLD_PER_TRIANGLE * total) // workers
        piece = lib.piece_triangles_for_budget(usable) if usable > 0 else 0
        if usable <= 0 or lib.piece_triangles_for_budget(1) > piece:
            held = OUT_OF_CORE_HOLD_PER_TRIANGLE * total + BASE_BYTES
            raise MemoryBudgetError(
                f"a memory budget of {format_bytes(max_memory)} is too small even for the out-of-core "
                f"mode on {total} triangles with {workers} worker(s) (it holds about "
                f"{format_bytes(held)} besides the pieces); raise --max-memory or lower --workers",
                where=where, estimate=held, budget=int(max_memory))
        sizes.append(piece)
    if workers > 1:
        sizes.append(lib.piece_triangles_for_workers(triangles, workers))
    if not sizes:
        raise InputError("meshing in pieces needs a memory budget (--max-memory SIZE), more than one "
                         "worker or a piece size")
    return min(sizes)


def tetrahedralize_in_pieces(surfaces, options=None, *, max_memory=None, workers=None, scheduler=None,
                             max_piece_triangles=None, progress=None, cancel=None):
    """Meshes like :func:`FemBspTet.kernel.core.tetrahedralize` without quality options, each
    solid cut into pieces that are meshed by the core alone, each checked exactly against its own
    surface (which checks the whole mesh, piece by piece), and merged in piece order.

    The piece size: ``max_piece_triangles`` when given, else the smallest of what ``max_memory``
    bytes allow ``workers`` pieces at once (after what the run holds besides:
    ``OUT_OF_CORE_HOLD_PER_TRIANGLE`` bytes per triangle) and what lets ``workers`` pieces run at
    once (``piece_triangles_for_workers``). The mesh depends on the piece size only, never on
    ``workers`` or on where the pieces ran.

    ``scheduler``: None to mesh ``workers`` pieces at a time on threads of this process; a Dask
    scheduler's address (``tcp://host:8786``) or a ``distributed.Client`` to mesh them on that
    cluster's workers (:mod:`FemBspTet.fem.cluster`). ``workers`` None: the cluster's worker
    count, or without a cluster :func:`default_workers`.

    ``options``: ``steiner_effort``, ``bsp_seed``, ``reorient`` as for ``tetrahedralize``; the
    quality options, ``order`` 2 and ``allow_boundary_steiner`` are refused. Returns ``(TetMesh,
    stats)``; ``stats["pieces"]`` holds the pieces' figures (a list with several solids).
    """
    options = dict(options or {})
    _refuse_options(options)
    if isinstance(surfaces, Surface):
        surfaces = [surfaces]
    if workers is None and scheduler is not None:
        workers = cluster_workers(scheduler)
    elif workers is None:
        workers = default_workers(sum(len(s.triangles) for s in surfaces))
    workers = int(workers)
    if workers < 1:
        raise InputError(f"workers must be at least 1, got {workers}")
    lib = native()
    reorient = bool(options.get("reorient", False))
    checked, flipped = [], 0
    for surface in surfaces:  # all of the check but the self-intersection search (below)
        checked_surface, info = check_surface(surface, reorient=reorient, self_intersections=False)
        checked.append(checked_surface)
        flipped += info["flipped_triangles"]
    # The self-intersection search runs beside the cutting and meshing, as the core's own run
    # does it (mesher.h check_and_tetrahedralize): a surface it refuses stops the run and its
    # error is raised, whatever the pieces' runs made of it meanwhile.
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        search = pool.submit(lambda: [check_surface(s) for s in checked])

        def stop():
            return (search.done() and search.exception() is not None) or (cancel is not None and cancel())

        try:
            mesh, stats, sizes = _mesh_checked(lib, checked, options, max_memory, workers, scheduler,
                                               max_piece_triangles, progress, stop)
        except Exception:
            search.result()  # the surface's own error first
            raise
        search.result()
    _pieces_summary(stats, sizes, scheduler, workers, flipped)
    return mesh, stats


def _mesh_checked(lib, checked, options, max_memory, workers, scheduler, max_piece_triangles,
                  progress, cancel):
    """tetrahedralize_in_pieces on checked surfaces: (mesh, stats, piece size of each solid)."""
    total = sum(len(s.triangles) for s in checked)
    meshes, all_stats, sizes = [], [], []
    with tempfile.TemporaryDirectory(prefix="fembsptet_pieces_") as scratch:
        for k, surface in enumerate(checked):
            label = f"solid {k + 1} of {len(checked)}: " if len(checked) > 1 else ""

            def report(stage, fraction, label=label):
                if progress is not None:
                    progress(label + stage, fraction)

            piece = _piece_size(lib, len(surface.triangles), total, max_memory, workers,
                                max_piece_triangles, surface.source or None)
            sizes.append(piece)
            if scheduler is not None:
                mesh, pieces = mesh_pieces_on_cluster(surface, piece, scheduler, options,
                                                      progress=report, cancel=cancel)
            else:
                stem = os.path.join(scratch, f"solid{k}")
                with core_errors(surface, "pieces mesher"):
                    pieces = lib.tetrahedralize_in_pieces(
                        surface.points, surface.triangles, stem, piece, progress=report,
                        cancel=cancel, workers=workers, options=native_core_options(options))
                mesh = read_tetgen(stem)
                os.remove(stem + ".node")
                os.remove(stem + ".ele")
                mesh = TetMesh(mesh.points, mesh.tets, surface.source)
            pieces["workers"] = workers
            n_input = len(np.unique(surface.triangles))
            st = {"input_points": int(len(surface.points)), "input_triangles": int(len(surface.triangles)),
                  "points": int(pieces["points"]), "tets": int(pieces["tets"]),
                  "steiner_points": int(pieces["points"]) - n_input, "boundary_steiner_points": 0,
                  "interior_steiner_points": int(pieces["points"]) - n_input,
                  "quality": tet_quality(mesh), "pieces": dict(pieces)}
            meshes.append(mesh)
            all_stats.append(st)
    per_solid = [st.pop("pieces") for st in all_stats]
    mesh = concatenate_meshes(meshes)
    stats = merge_stats(all_stats)
    stats["pieces"] = per_solid[0] if len(per_solid) == 1 else per_solid
    stats["order"] = 1
    stats["nodes"] = int(len(mesh.points))
    stats["valid"] = True  # every piece was checked exactly (out_of_core.h)
    return mesh, stats, sizes


def _pieces_summary(stats, sizes, scheduler, workers, flipped):
    """The run's notes and ``flipped_triangles`` in ``stats``."""
    per_solid = stats["pieces"] if isinstance(stats["pieces"], list) else [stats["pieces"]]
    stats["flipped_triangles"] = flipped
    where = "on a Dask cluster" if scheduler is not None else f"on {workers} thread(s)"
    notes = [f"meshed in {sum(p['pieces'] for p in per_solid)} pieces of at most {max(sizes)} "
             f"triangles, {where}; {sum(p['cap_points'] for p in per_solid)} of the Steiner points "
             "are the caps' own points, inside the solid"]
    if flipped:
        notes.append(f"re-oriented {flipped} triangle(s) (--reorient)")
    for p in per_solid:
        notes.extend(p["uncut"])
    stats["notes"] = notes
