# SPDX-License-Identifier: LGPL-2.1-or-later
"""The out-of-core mode: a solid too big for the memory budget cut into pieces, each meshed by the
core alone and written to disk, the pieces read back as one mesh
(``cpp_module/include/bsptet/pieces/out_of_core.h``).

    mesh, stats = tetrahedralize_out_of_core(surfaces, max_memory=4 << 30)
"""

import os
import tempfile

import numpy as np

from ..io.volume_io import read_tetgen
from ..kernel.core import (OPTION_NAMES, REFINE_OPTIONS, check_surface, concatenate_meshes,
                           core_errors, merge_stats, native, native_core_options, tet_quality)
from ..kernel.errors import InputError, MemoryBudgetError
from ..kernel.memory_budget import BASE_BYTES, format_bytes
from ..kernel.mesh_types import Surface, TetMesh


#: What the out-of-core mode holds besides the core's run on one piece (bytes per input triangle):
#: the input surface, its pieces' triangle lists, and the finished mesh read back for writing.
OUT_OF_CORE_HOLD_PER_TRIANGLE = 256


def tetrahedralize_out_of_core(surfaces, max_memory, options=None, progress=None, cancel=None):
    """Meshes like :func:`tetrahedralize`, in pieces small enough for ``max_memory`` bytes: the
    out-of-core mode (``cpp_module/include/bsptet/pieces/out_of_core.h``; the paper's Sec. 4.3 swaps
    finished cells to disk, this core's peak being in its seed instead the solid is cut).

    Each solid is cut into pieces along caps inside it made of its own vertices and points of
    their own (so the pieces meet exactly and the caps' points are interior Steiner points of the
    mesh), each piece is meshed by the core alone, checked exactly against its own surface (which
    checks the whole mesh, piece by piece) and written to disk, then the pieces are streamed into
    one file and read back. The piece size comes from the budget (``piece_triangles_for_budget``,
    after what the run holds besides: ``OUT_OF_CORE_HOLD_PER_TRIANGLE`` bytes per triangle).

    ``options``: ``steiner_effort``, ``bsp_seed``, ``reorient`` as for :func:`tetrahedralize`;
    the quality options, ``order`` 2 and ``allow_boundary_steiner`` are refused (the core's mesh
    only). Returns ``(TetMesh, stats)``; ``stats["out_of_core"]`` holds the pieces' figures.
    """
    options = dict(options or {})
    unknown = set(options) - set(OPTION_NAMES)
    if unknown:
        raise InputError(f"unknown mesher option(s): {', '.join(sorted(unknown))}")
    refused = sorted(k for k, v in options.items()
                     if v not in (None, False) and (k in REFINE_OPTIONS and not (k == "order" and int(v) == 1)
                                                    or k == "allow_boundary_steiner"))
    if refused:
        raise InputError("the out-of-core mode makes the core's mesh only: drop "
                         + ", ".join(refused) + " (or mesh in memory, without --out-of-core)")
    if max_memory is None:
        raise InputError("the out-of-core mode needs a memory budget (--max-memory SIZE): the "
                         "memory available could not be read")
    if isinstance(surfaces, Surface):
        surfaces = [surfaces]
    lib = native()
    reorient = bool(options.get("reorient", False))
    checked, flipped = [], 0
    for surface in surfaces:
        checked_surface, info = check_surface(surface, reorient=reorient)
        checked.append(checked_surface)
        flipped += info["flipped_triangles"]
    total = sum(len(s.triangles) for s in checked)
    usable = int(max_memory) - BASE_BYTES - OUT_OF_CORE_HOLD_PER_TRIANGLE * total
    piece = lib.piece_triangles_for_budget(usable) if usable > 0 else 0
    if usable <= 0 or lib.piece_triangles_for_budget(1) > piece:
        raise MemoryBudgetError(
            f"a memory budget of {format_bytes(max_memory)} is too small even for the out-of-core "
            f"mode on {total} triangles (it holds about {format_bytes(OUT_OF_CORE_HOLD_PER_TRIANGLE * total + BASE_BYTES)} "
            "besides the pieces); raise --max-memory", where=checked[0].source or None,
            estimate=OUT_OF_CORE_HOLD_PER_TRIANGLE * total + BASE_BYTES, budget=int(max_memory))
    meshes, all_stats = [], []
    with tempfile.TemporaryDirectory(prefix="fembsptet_pieces_") as scratch:
        for k, surface in enumerate(checked):
            label = f"solid {k + 1} of {len(checked)}: " if len(checked) > 1 else ""

            def report(stage, fraction, label=label):
                if progress is not None:
                    progress(label + stage, fraction)

            stem = os.path.join(scratch, f"solid{k}")
            with core_errors(surface, "out-of-core mesher"):
                pieces = lib.tetrahedralize_in_pieces(
                    surface.points, surface.triangles, stem, piece, progress=report, cancel=cancel,
                    **native_core_options(options))
            mesh = read_tetgen(stem)
            os.remove(stem + ".node")
            os.remove(stem + ".ele")
            mesh = TetMesh(mesh.points, mesh.tets, surface.source)
            n_input = len(np.unique(surface.triangles))
            st = {"input_points": int(len(surface.points)), "input_triangles": int(len(surface.triangles)),
                  "points": int(pieces["points"]), "tets": int(pieces["tets"]),
                  "steiner_points": int(pieces["points"]) - n_input, "boundary_steiner_points": 0,
                  "interior_steiner_points": int(pieces["points"]) - n_input,
                  "quality": tet_quality(mesh), "out_of_core": dict(pieces)}
            meshes.append(mesh)
            all_stats.append(st)
    out_of_core = [st.pop("out_of_core") for st in all_stats]
    mesh = concatenate_meshes(meshes)
    stats = merge_stats(all_stats)
    stats["out_of_core"] = out_of_core[0] if len(out_of_core) == 1 else out_of_core
    stats["order"] = 1
    stats["nodes"] = int(len(mesh.points))
    stats["valid"] = True  # every piece was checked exactly (tetrahedralize_in_pieces)
    stats["flipped_triangles"] = flipped
    notes = [f"meshed out of core: {sum(p['pieces'] for p in out_of_core)} pieces of at most "
             f"{piece} triangles; {sum(p['cap_points'] for p in out_of_core)} of the Steiner points "
             "are the caps' own points, inside the solid"]
    if flipped:
        notes.append(f"re-oriented {flipped} triangle(s) (--reorient)")
    for p in out_of_core:
        notes.extend(p["uncut"])
    stats["notes"] = notes
    return mesh, stats
