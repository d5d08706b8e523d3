"""TetGen as a separate program (AGPL: never linked), on exactly the surface we mesh.

``run_tetgen(surface, switches)`` writes the surface as OFF with round-trip precision, runs
``tetgen -<switches>Q`` in a temporary directory, reads the mesh back and measures the wall time
and the peak resident memory of that process alone (``os.wait4``).
"""

import dataclasses
import os
import shutil
import subprocess
import tempfile
import time

from ..errors import InternalError
from ..mesh_types import Surface, TetMesh


@dataclasses.dataclass
class TetgenResult:
    mesh: TetMesh
    command: str
    seconds: float
    peak_rss_mb: float
    steiner_points: int  # output points - input points (TetGen -Y keeps every input point)
    output: str


def tetgen_path():
    """The tetgen executable, or None."""
    return shutil.which("tetgen")


def tetgen_available() -> bool:
    return tetgen_path() is not None


def regular_tet_volume(h: float) -> float:
    """Volume of the regular tetrahedron of edge h: h^3 / (6 sqrt 2)."""
    return h ** 3 / (6.0 * 2.0 ** 0.5)


def _write_off(path, surface: Surface):
    with open(path, "w") as f:
        f.write(f"OFF\n{len(surface.points)} {len(surface.triangles)} 0\n")
        for x, y, z in surface.points.tolist():
            f.write(f"{x!r} {y!r} {z!r}\n")
        for a, b, c in surface.triangles.tolist():
            f.write(f"3 {a} {b} {c}\n")


def run_tetgen(surface: Surface, switches="pY", timeout=None, keep_dir=None) -> TetgenResult:
    """Runs TetGen on ``surface``. ``switches`` without the dash, e.g. "pY" or "pq1.414a0.01".

    Raises InternalError when TetGen is missing, fails or times out (the message carries its
    output).
    """
    exe = tetgen_path()
    if exe is None:
        raise InternalError("tetgen is not installed (Debian package tetgen); run scripts/setup.sh")
    from ..volume_io import read_tetgen

    workdir = keep_dir or tempfile.mkdtemp(prefix="fembsptet_tetgen_")
    try:
        src = os.path.join(workdir, "surface.off")
        _write_off(src, surface)
        cmd = [exe, f"-{switches}Q", src]
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, cwd=workdir)
        deadline = None if timeout is None else start + timeout
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid != 0:
                break
            if deadline is not None and time.perf_counter() > deadline:
                proc.kill()
                os.wait4(proc.pid, 0)
                raise InternalError(f"tetgen timed out after {timeout} s: {' '.join(cmd)}")
            time.sleep(0.005)
        seconds = time.perf_counter() - start
        out = proc.stdout.read().decode(errors="replace")
        proc.stdout.close()
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode != 0:
            raise InternalError(
                f"tetgen failed (exit {proc.returncode}) on {surface.source or 'the surface'}: "
                f"{out.strip()[-500:]}"
            )
        mesh = read_tetgen(os.path.join(workdir, "surface.1"))
        return TetgenResult(
            mesh=mesh,
            command="tetgen -" + switches,
            seconds=seconds,
            peak_rss_mb=usage.ru_maxrss / 1024.0,
            steiner_points=len(mesh.points) - len(surface.points),
            output=out,
        )
    finally:
        if keep_dir is None:
            shutil.rmtree(workdir, ignore_errors=True)
