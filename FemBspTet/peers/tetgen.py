# SPDX-License-Identifier: LGPL-2.1-or-later
"""TetGen as a separate program (AGPL: never linked), on exactly the surface we mesh.

``run_tetgen(surface, switches)`` writes the surface as OFF with round-trip precision, runs
``tetgen -<switches>Q`` in a temporary directory, reads the mesh back and measures the wall time
and the peak resident memory of that process alone (:func:`.process.run_measured`).
"""

import dataclasses
import os
import shutil
import tempfile

from ..io.volume_io import read_tetgen
from ..kernel.errors import InternalError
from ..kernel.mesh_types import Surface, TetMesh
from .process import run_measured


@dataclasses.dataclass
class TetgenResult:
    mesh: TetMesh
    command: str
    seconds: float
    peak_rss_mb: float
    steiner_points: int  # output points - input points (TetGen -Y keeps every input point)
    output: str
    mesh_path: str = ""  #: stem of the .node/.ele files (only meaningful with ``keep_dir``)


def tetgen_path():
    """The tetgen executable, or None."""
    return shutil.which("tetgen")


def tetgen_available() -> bool:
    return tetgen_path() is not None


def regular_tet_volume(h: float) -> float:
    """Volume of the regular tetrahedron of edge h: h^3 / (6 sqrt 2)."""
    return h ** 3 / (6.0 * 2.0 ** 0.5)


def quality_switches(h: float) -> str:
    """TetGen's quality mesh at size h: radius-edge 1.414 and the volume of the regular tet of
    edge h as the maximum tet volume (``pq1.414a<V>``)."""
    return f"pq1.414a{regular_tet_volume(h):.6g}"


def _write_off(path, surface: Surface):
    with open(path, "w") as f:
        f.write(f"OFF\n{len(surface.points)} {len(surface.triangles)} 0\n")
        for x, y, z in surface.points.tolist():
            f.write(f"{x!r} {y!r} {z!r}\n")
        for a, b, c in surface.triangles.tolist():
            f.write(f"3 {a} {b} {c}\n")


def run_tetgen(surface: Surface, switches="pY", timeout=None, keep_dir=None,
               name="surface") -> TetgenResult:
    """Runs TetGen on ``surface``. ``switches`` without the dash, e.g. "pY" or "pq1.414a0.01".

    ``keep_dir``: work (and leave the files) there, as ``<name>.off`` and ``<name>.1.node/.ele``.
    Raises InternalError when TetGen is missing, fails or times out (the message carries its
    output).
    """
    exe = tetgen_path()
    if exe is None:
        raise InternalError("tetgen is not installed (Debian package tetgen); run scripts/setup.sh")

    workdir = keep_dir or tempfile.mkdtemp(prefix="fembsptet_tetgen_")
    try:
        src = os.path.join(workdir, name + ".off")
        _write_off(src, surface)
        run = run_measured([exe, f"-{switches}Q", src], timeout=timeout, cwd=workdir)
        if run.timed_out:
            raise InternalError(f"tetgen timed out after {timeout:g} s: {' '.join(run.command)}")
        if run.returncode != 0:
            raise InternalError(
                f"tetgen failed (exit {run.returncode}) on {surface.source or 'the surface'}: "
                f"{run.output.strip()[-500:]}"
            )
        stem = os.path.join(workdir, name + ".1")
        mesh = read_tetgen(stem)
        return TetgenResult(
            mesh=mesh,
            command="tetgen -" + switches,
            seconds=run.seconds,
            peak_rss_mb=run.peak_rss_mb,
            steiner_points=len(mesh.points) - len(surface.points),
            output=run.output,
            mesh_path=stem,
        )
    finally:
        if keep_dir is None:
            shutil.rmtree(workdir, ignore_errors=True)
