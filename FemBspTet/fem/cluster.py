# SPDX-License-Identifier: LGPL-2.1-or-later
"""Pieces meshed on a Dask cluster (Debian's ``python3-distributed``): the engine of
:func:`FemBspTet.fem.pieces.tetrahedralize_in_pieces` with a ``scheduler``.

This process cuts the solid (``_bsptet.cut_into_pieces``), sends each piece's own surface to the
cluster as one task (``_bsptet.mesh_piece`` on a worker: the core, then the exact check of the
piece's mesh against its surface), and merges the pieces' meshes in piece order as they come
back, numbered by the ids ``cut_into_pieces`` returns (out_of_core.h ``merged_point_ids``): the
mesh is the one the threads of one process make, byte for byte.

Why Dask rather than MPI: the same code runs on a local cluster of processes and on a cluster of
machines (``dask scheduler`` and ``dask worker ADDRESS`` on each), a worker that dies has its task
re-run elsewhere by the scheduler, and a run needs no launcher: a FreeCAD macro or a script can
use a cluster as a library call. Every worker must be able to import ``FemBspTet`` (installed, or
on its ``PYTHONPATH``).
"""

import time

import numpy as np

from ..kernel.core import core_errors, native, native_core_options
from ..kernel.errors import InputError, InternalError, MeshingCancelled
from ..kernel.mesh_types import TetMesh

#: How often (seconds) a wait for the next piece looks at ``cancel``.
POLL_SECONDS = 0.05


def mesh_piece_task(points, triangles, name, core_options):
    """Runs on a worker: one piece's surface meshed by the core and checked exactly. Returns the
    Steiner points (the piece's own points come first in the core's mesh and are left out) and
    the tets over the piece's points then those Steiner points."""
    mesh_points, tets = native().mesh_piece(points, triangles, name, check=True, options=core_options)
    return mesh_points[len(points):], tets


def client_for(scheduler):
    """A ``distributed.Client`` for ``scheduler`` (an address, or a Client, returned as it is),
    and whether this call made it (then the caller closes it)."""
    try:
        from distributed import Client
    except ImportError as exc:
        raise InputError("meshing on a cluster needs Dask's distributed package (Debian: "
                         "apt install python3-distributed)") from exc
    if isinstance(scheduler, Client):
        return scheduler, False
    try:
        return Client(str(scheduler), timeout=30), True
    except OSError as exc:
        raise InputError(f"cannot reach the Dask scheduler at {scheduler}: {exc}; start one with "
                         "'dask scheduler' and workers with 'dask worker ADDRESS'") from exc


def cluster_workers(scheduler):
    """How many workers the cluster of ``scheduler`` has now (at least 1)."""
    client, own = client_for(scheduler)
    try:
        return max(1, len(client.scheduler_info().get("workers", {})))
    finally:
        if own:
            client.close()


def mesh_pieces_on_cluster(surface, max_piece_triangles, scheduler, options, progress=None, cancel=None):
    """The solid bounded by ``surface`` (checked) in pieces of at most ``max_piece_triangles``
    triangles, meshed on the cluster of ``scheduler``. Returns ``(TetMesh, stats)``, stats as
    ``_bsptet.tetrahedralize_in_pieces`` gives them."""
    lib = native()
    core_options = native_core_options(options)
    client, own = client_for(scheduler)
    try:
        if progress is not None:
            progress("cutting into pieces", 0.0)
        with core_errors(surface, "pieces mesher"):
            xyz, pieces, ids, stats = lib.cut_into_pieces(surface.points, surface.triangles,
                                                          max_piece_triangles, cancel=cancel, workers=2)
        started = time.perf_counter()
        futures, globals_of = [], []
        for k, piece in enumerate(pieces):
            globals_, local = np.unique(piece, return_inverse=True)
            globals_of.append(globals_)
            futures.append(client.submit(mesh_piece_task, xyz[globals_], local.reshape(-1, 3),
                                         f"piece {k + 1}/{len(pieces)}", core_options, pure=False))
        used = int(ids.max()) + 1
        points, tets, steiner = [xyz[ids >= 0]], [], 0  # ids grow with the index: in id order
        for k, future in enumerate(futures):
            while not future.done():
                time.sleep(POLL_SECONDS)
                if cancel is not None and cancel():
                    client.cancel(futures)
                    raise MeshingCancelled("cancelled")
            if progress is not None:
                progress(f"meshing {len(pieces)} pieces on the cluster", k / len(pieces))
            try:
                steiner_points, local_tets = future.result()
            except Exception as exc:  # the worker's error, re-raised here by Dask
                client.cancel(futures)
                raise InternalError(f"piece {k + 1}/{len(pieces)} failed on the cluster: {exc}") from exc
            future.release()
            nloc = len(globals_of[k])
            merged = np.where(local_tets < nloc, ids[globals_of[k][np.minimum(local_tets, nloc - 1)]],
                              used + steiner + (local_tets - nloc))
            points.append(steiner_points)
            tets.append(merged)
            steiner += len(steiner_points)
    finally:
        if own:
            client.close()
    mesh = TetMesh(np.concatenate(points), np.concatenate(tets).astype(np.int64), surface.source)
    stats.update({"points": len(mesh.points), "tets": len(mesh.tets), "steiner_points": steiner,
                  "seconds_meshing": time.perf_counter() - started,
                  "pieces_checked": True})
    return mesh, stats
