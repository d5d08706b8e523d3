# SPDX-License-Identifier: LGPL-2.1-or-later
"""The comparison the FreeCAD object and its task panel show: our mesh beside TetGen's, Gmsh's and
Netgen's at the same element size h.

    rows = compare_at_size(brep, mesh, boundary_faces, size, seconds, shape=None)

* **TetGen** (``tetgen -pq1.414a<V>``, ``o2`` for tet10; V the volume of the regular tet of edge
  h): on the surface our mesh was made from (the CAD faces meshed at h). The same surface and the
  same size bound: its counts are the element counts "compared with TetGen's" of the design.
* **Gmsh** (``gmsh PART -3 -clmax h -order o``) and **Netgen** (``maxh = h``, second order when
  asked) mesh the CAD part themselves, as FreeCAD's Gmsh and Netgen meshers do. Their rows appear
  only where they are installed (a row with status "skipped" says which is missing).

Every row is measured by our code on the corner tets (:func:`FemBspTet.kernel.core.tet_quality`):
nodes (all of them, mid-nodes included), tets, the smallest dihedral angle, the median over the
tets of each tet's smallest angle, seconds. The peers run as separate processes with a time
limit; a peer that fails gives a row with status "failed" and its message, never an exception.
"""

import dataclasses
import os
import shutil
import tempfile

import numpy as np

from ..kernel import core
from ..kernel.freecad_env import import_freecad
from ..kernel.mesh_types import Surface, TetMesh
from ..peers.gmsh import gmsh_available, gmsh_cad_command, run_gmsh_cad
from ..peers.netgen import netgen_command, NetgenMissing, NGOCC_EXTENSIONS, run_netgen
from ..peers.tetgen import quality_switches, run_tetgen, tetgen_available

#: Seconds each peer may take.
PEER_TIMEOUT = 600.0

OURS, TETGEN, GMSH, NETGEN = "FemBspTet", "TetGen", "Gmsh", "Netgen"
PEERS = (TETGEN, GMSH, NETGEN)


@dataclasses.dataclass
class SizeRow:
    """One mesher's mesh at the size (status "ok"), or why there is none."""

    mesher: str
    command: str
    status: str = "ok"  #: "ok", "failed" or "skipped"
    message: str = ""
    nodes: int = 0
    tets: int = 0
    min_dihedral_deg: float = 0.0
    median_tet_min_dihedral_deg: float = 0.0
    seconds: float = 0.0

    def to_dict(self):
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, values):
        names = {f.name for f in dataclasses.fields(cls)}
        return cls(**{k: v for k, v in values.items() if k in names})


def measured_row(mesher, command, points, tets, seconds):
    """A row for the mesh ``(points, tets)`` (tet4 or tet10, corners first)."""
    tets = np.asarray(tets)
    q = core.tet_quality(TetMesh(np.asarray(points, dtype=float),
                                 np.ascontiguousarray(tets[:, :4], dtype=np.int64)))
    used = np.unique(tets.reshape(-1)).size  # Gmsh's files hold unused geometry points
    return SizeRow(mesher=mesher, command=command, nodes=int(used), tets=int(len(tets)),
                   min_dihedral_deg=float(q["min_dihedral_deg"]),
                   median_tet_min_dihedral_deg=float(q["median_tet_min_dihedral_deg"]),
                   seconds=float(seconds))


def boundary_surface(points, triangles, source=""):
    """The surface of the boundary triangles: only their nodes, renumbered."""
    triangles = np.asarray(triangles, dtype=np.int64)
    used, inverse = np.unique(triangles.reshape(-1), return_inverse=True)
    return Surface(np.asarray(points, dtype=float)[used], inverse.reshape(-1, 3), source=source)


def tetgen_row(surface, size, order, timeout=PEER_TIMEOUT):
    switches = quality_switches(size) + ("o2" if order == 2 else "")
    command = "tetgen -" + switches
    if not tetgen_available():
        return SizeRow(TETGEN, command, "skipped", "tetgen is not installed (Debian package "
                       "tetgen)")
    try:
        run = run_tetgen(surface, switches, timeout=timeout)
    except Exception as e:  # noqa: BLE001  (a peer's failure is a row)
        return SizeRow(TETGEN, command, "failed", str(e)[:300])
    return measured_row(TETGEN, command, run.mesh.points, run.mesh.tets, run.seconds)


def gmsh_row(cad_path, size, order, timeout=PEER_TIMEOUT):
    command = gmsh_cad_command(size, order)
    if not gmsh_available():
        return SizeRow(GMSH, command, "skipped", "gmsh is not installed")
    try:
        run = run_gmsh_cad(cad_path, size, order, timeout=timeout)
    except Exception as e:  # noqa: BLE001
        return SizeRow(GMSH, command, "failed", str(e)[:300])
    return measured_row(GMSH, command, run.mesh.points, run.mesh.tets, run.seconds)


def netgen_row(cad_path, size, order, timeout=PEER_TIMEOUT):
    command = netgen_command(size, order)
    try:
        run = run_netgen(cad_path, size, order, timeout=timeout)
    except NetgenMissing:
        return SizeRow(NETGEN, command, "skipped", "Netgen's Python module is not installed "
                       "(Debian package python3-netgen)")
    except Exception as e:  # noqa: BLE001
        return SizeRow(NETGEN, command, "failed", str(e)[:300])
    return measured_row(NETGEN, command, run.points, run.tets, run.seconds)


def _step_of(brep_path, shape):
    """A STEP file of the part for Netgen 6.2.1905's reader (FreeCAD's Part writes it), or the
    BREP file itself when FreeCAD is not there (newer Netgen reads BREP)."""
    step = os.path.splitext(brep_path)[0] + ".step"
    try:
        if shape is None:
            import_freecad()
            import Part

            shape = Part.Shape()
            shape.importBrep(brep_path)
        shape.exportStep(step)
        return step
    except Exception:  # noqa: BLE001  (no FreeCAD here)
        return brep_path


def compare_at_size(brep, mesh, boundary_faces, size, seconds, shape=None, peers=PEERS,
                    progress=None, timeout=PEER_TIMEOUT):
    """Rows (dicts, :class:`SizeRow`) of our ``mesh`` (a TetMesh made in ``seconds``) and of
    TetGen, Gmsh and Netgen at element size ``size`` and the mesh's order: TetGen on our mesh's
    boundary (``boundary_faces``: its triangles, corner indices), Gmsh and Netgen on the CAD part
    (``brep``: its BREP text; ``shape``: its ``Part.Shape`` if at hand). ``progress(stage)`` is
    called before each peer."""
    order = 2 if mesh.tets.shape[1] == 10 else 1
    surface = boundary_surface(mesh.points, boundary_faces, mesh.source)
    report = progress or (lambda stage: None)
    workdir = tempfile.mkdtemp(prefix="fembsptet_peers_")
    try:
        brep_path = os.path.join(workdir, "part.brep")
        with open(brep_path, "w", encoding="utf-8") as f:
            f.write(brep)
        rows = [measured_row(OURS, "fembsptet (CharacteristicLengthMax %.4g)" % size,
                             mesh.points, mesh.tets, seconds)]
        for peer in peers:
            report("comparison: %s at the same size" % peer)
            if peer == TETGEN:
                rows.append(tetgen_row(surface, size, order, timeout))
            elif peer == GMSH:
                rows.append(gmsh_row(brep_path, size, order, timeout))
            elif peer == NETGEN:
                path = brep_path
                if not brep_path.lower().endswith(NGOCC_EXTENSIONS):
                    path = _step_of(brep_path, shape)
                rows.append(netgen_row(path, size, order, timeout))
        return [row.to_dict() for row in rows]
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
