# SPDX-License-Identifier: LGPL-2.1-or-later
"""Gmsh's 3D mesher as a separate program (GPL: never linked or imported), on the surface we mesh.

``run_gmsh(surface, size)`` writes the surface as a Gmsh MSH 2.2 file (one discrete surface,
coordinates with round-trip precision) and a ``.geo`` that merges it, closes it into a volume
(``Surface Loop`` + ``Volume``) and sets ``Mesh.CharacteristicLengthMax = size``; then runs
``gmsh <name>.geo -3 -nt 1 -format msh22`` and reads the tets back with our own reader
(:func:`FemBspTet.io.volume_io.read_tet_mesh`).

Two ways, as TetGen's ``-pY`` and ``-pq``:

* ``remesh_surface=False``: the discrete surface is not remeshed; Gmsh fills the given
  triangulation (its boundary is the input's unless its boundary recovery had to split it).
  Gmsh 4.8 then sizes the interior from the surface triangles: ``CharacteristicLengthMax`` has
  next to no effect (measured: the paper's box with a hole gives 29 tets at 0.5 as at 1.8).
* ``remesh_surface=True``: ``ClassifySurfaces{40 deg, 1, 1, 180 deg}; CreateGeometry;`` first
  (Gmsh's own reparametrization of a triangulated surface, as in its tutorial t13), so the
  surface is remeshed at the size too: new boundary points lie on Gmsh's reparametrized patches,
  not exactly on the input facets (as TetGen's ``-pq`` points are rounded).

Gmsh writes coordinates with 16 significant digits, which is not always enough to give back the
exact double: a node whose coordinates, printed the same way, equal those of an input vertex is
given that vertex's exact coordinates (:func:`restore_input_points`), so the exact checks see the
input surface again. Wall time and peak memory are those of the gmsh process alone
(:func:`.process.run_measured`).
"""

import dataclasses
import os
import shutil
import tempfile

import numpy as np

from ..io.volume_io import read_tet_mesh
from ..kernel.errors import InternalError
from ..kernel.mesh_types import Surface, TetMesh
from .process import run_measured


@dataclasses.dataclass
class GmshResult:
    mesh: TetMesh
    command: str
    seconds: float
    peak_rss_mb: float
    output: str
    mesh_path: str = ""  #: the .msh file Gmsh wrote (only meaningful with ``keep_dir``)


def gmsh_path():
    """The gmsh executable, or None."""
    return shutil.which("gmsh")


def gmsh_available() -> bool:
    return gmsh_path() is not None


def gmsh_version():
    """Gmsh's version string, or None when it is missing."""
    exe = gmsh_path()
    if exe is None:
        return None
    run = run_measured([exe, "--version"], timeout=30)
    return run.output.strip().splitlines()[-1] if run.output.strip() else None


def mean_edge_length(surface: Surface) -> float:
    """Mean length of the surface's triangle edges (each edge counted once per triangle)."""
    p, t = surface.points, surface.triangles
    edges = np.concatenate([p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 1]],
                            p[t[:, 0]] - p[t[:, 2]]])
    return float(np.linalg.norm(edges, axis=1).mean())


def _write_surface_msh(path, surface: Surface):
    with open(path, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n")
        f.write(f"$Nodes\n{len(surface.points)}\n")
        for i, (x, y, z) in enumerate(surface.points.tolist()):
            f.write(f"{i + 1} {x!r} {y!r} {z!r}\n")
        f.write(f"$EndNodes\n$Elements\n{len(surface.triangles)}\n")
        for i, (a, b, c) in enumerate(surface.triangles.tolist()):
            f.write(f"{i + 1} 2 2 1 1 {a + 1} {b + 1} {c + 1}\n")
        f.write("$EndElements\n")


def _write_geo(path, msh_name, size, remesh_surface):
    with open(path, "w") as f:
        f.write(f'Merge "{msh_name}";\n')
        if remesh_surface:
            f.write("ClassifySurfaces{40 * Pi / 180, 1, 1, Pi};\nCreateGeometry;\n"
                    "Surface Loop(1) = Surface{:};\n")
        else:
            f.write("Surface Loop(1) = {1};\n")
        f.write(
                "Volume(1) = {1};\n"
                "Mesh.SaveAll = 1;\n"
                f"Mesh.CharacteristicLengthMax = {size!r};\n")


def restore_input_points(mesh: TetMesh, surface: Surface) -> int:
    """Gives nodes that are input vertices as printed with 16 digits their exact coordinates
    (in place). Returns how many nodes were changed."""
    def key16(row):
        return tuple(float("%.16g" % c) for c in row)

    exact = {tuple(row): i for i, row in enumerate(surface.points.tolist())}
    printed = {key16(row): i for i, row in enumerate(surface.points.tolist())}
    changed = 0
    for n, row in enumerate(mesh.points.tolist()):
        if tuple(row) in exact:
            continue
        i = printed.get(key16(row))
        if i is not None:
            mesh.points[n] = surface.points[i]
            changed += 1
    return changed


def _run_and_read(argv, out, timeout, workdir):
    """Runs gmsh (``argv``, writing ``out``) and reads its tets: ``(run, mesh)``. Raises
    InternalError when it times out, fails, reports an error or makes no tets."""
    run = run_measured(argv, timeout=timeout, cwd=workdir)
    if run.timed_out:
        raise InternalError(f"gmsh timed out after {timeout:g} s")
    errors = [ln for ln in run.output.splitlines() if ln.startswith("Error")]
    if run.returncode != 0 or errors or not os.path.exists(out):
        raise InternalError(f"gmsh failed (exit {run.returncode}): "
                            + ("; ".join(errors[:3]) or run.tail()))
    mesh = read_tet_mesh(out)
    if len(mesh.tets) == 0:
        raise InternalError("gmsh made no tetrahedra: " + run.tail())
    return run, mesh


def gmsh_command(size, remesh_surface=False):
    return (f"gmsh -3 ({'surface remeshed, ' if remesh_surface else ''}"
            f"CharacteristicLengthMax {size:.4g})")


def run_gmsh(surface: Surface, size: float, timeout=None, keep_dir=None, name="surface",
             remesh_surface=False) -> GmshResult:
    """Runs Gmsh's 3D mesher on ``surface`` with ``Mesh.CharacteristicLengthMax = size``
    (``remesh_surface``: see the module's doc).

    ``keep_dir``: work (and leave the files) there: ``<name>.gmsh_in.msh``, ``<name>.geo``,
    ``<name>.gmsh.msh``. Raises InternalError when Gmsh is missing, fails, makes no tets or
    times out (the message carries the end of its output).
    """
    exe = gmsh_path()
    if exe is None:
        raise InternalError("gmsh is not installed (Debian package gmsh); run scripts/setup.sh")

    workdir = keep_dir or tempfile.mkdtemp(prefix="fembsptet_gmsh_")
    try:
        msh_in = name + ".gmsh_in.msh"
        _write_surface_msh(os.path.join(workdir, msh_in), surface)
        geo = os.path.join(workdir, name + ".geo")
        _write_geo(geo, msh_in, float(size), remesh_surface)
        out = os.path.join(workdir, name + ".gmsh.msh")
        run, mesh = _run_and_read([exe, geo, "-3", "-nt", "1", "-format", "msh22", "-o", out],
                                  out, timeout, workdir)
        restore_input_points(mesh, surface)
        return GmshResult(mesh=mesh, command=gmsh_command(size, remesh_surface),
                          seconds=run.seconds,
                          peak_rss_mb=run.peak_rss_mb, output=run.output, mesh_path=out)
    finally:
        if keep_dir is None:
            shutil.rmtree(workdir, ignore_errors=True)


def gmsh_cad_command(size, order):
    return f"gmsh -3 -clmax {size:.4g} -order {int(order)}"


def run_gmsh_cad(part, size, order=2, timeout=None, keep_dir=None, name="part") -> GmshResult:
    """Gmsh on the CAD file ``part`` (STEP, IGES, BREP) at ``CharacteristicLengthMax = size``,
    ``order`` 1 or 2: ``gmsh PART -3 -clmax SIZE -order ORDER -nt 1``, Gmsh's defaults otherwise
    (what FreeCAD's Gmsh mesher runs with ``CharacteristicLengthMax`` set). The tets come back
    with the corners first (tet10 in Gmsh's order). Raises InternalError as :func:`run_gmsh`."""
    exe = gmsh_path()
    if exe is None:
        raise InternalError("gmsh is not installed (Debian package gmsh); run scripts/setup.sh")
    workdir = keep_dir or tempfile.mkdtemp(prefix="fembsptet_gmsh_")
    try:
        out = os.path.join(workdir, name + ".gmsh.msh")
        run, mesh = _run_and_read([exe, os.path.abspath(part), "-3", "-clmax", repr(float(size)),
                                   "-order", str(int(order)), "-nt", "1", "-format", "msh22",
                                   "-o", out], out, timeout, workdir)
        return GmshResult(mesh=mesh, command=gmsh_cad_command(size, order), seconds=run.seconds,
                          peak_rss_mb=run.peak_rss_mb, output=run.output, mesh_path=out)
    finally:
        if keep_dir is None:
            shutil.rmtree(workdir, ignore_errors=True)
