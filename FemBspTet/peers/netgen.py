# SPDX-License-Identifier: LGPL-2.1-or-later
"""Netgen's CAD mesher (``python3-netgen``) on a CAD part at an element size, as a separate process.

    run = run_netgen("part.step", h=5.0, order=2, timeout=600)   # -> NetgenResult
    python3 -m FemBspTet.peers.netgen PART H ORDER OUT.npz        # the process it runs

The part is meshed by Netgen's own OpenCASCADE geometry with ``maxh = h`` and Netgen's other
defaults (grading 0.3, curvature safety 2, 3 optimization steps), second order with
``Mesh.SecondOrder()``, in a process of its own (``/usr/bin/python3``), so that Netgen's memory and
a crash of it stay out of ours. Two Python interfaces exist:

* Netgen 6.2.2 and later (Debian 13): ``netgen.occ.OCCGeometry(path)`` reads STEP, IGES and BREP.
* Netgen 6.2.1905 (Debian 12): ``netgen.NgOCC.LoadOCCGeometry(path)`` reads STEP and IGES (it
  takes any other file for STEP: BREP parts must be exported to STEP first), and its OCC
  meshing sizes edges and faces from the library's global ``netgen::mparam``, not from the
  MeshingParameters it is given (fixed upstream later in 2019), so ``maxh`` alone changes
  nothing on a box. :func:`_set_global_size_1905` sets that global as C++ callers do, through
  nglib's ``Ng_Meshing_Parameters`` (its layout checked against the constructor's defaults
  before anything is written).

The tets come back with the corners first; tet10 mid-nodes in VTK order (edges 01 12 02 03 13 23).
"""

import ctypes
import dataclasses
import importlib.util
import os
import shutil
import struct
import sys
import tempfile
import time

import numpy as np

from .process import DEFAULT_TIMEOUT, run_measured, worker_env

#: Netgen's ``Element3D.points`` of a tet10: corners, then the mid-nodes of edges 01 02 03 12 13
#: 23; this permutation gives VTK's order (01 12 02 03 13 23).
NETGEN_TO_VTK_TET10 = np.array([0, 1, 2, 3, 4, 7, 5, 6, 8, 9])
#: Interpreter of the Netgen process: Debian's, where ``python3-netgen`` is installed.
NETGEN_PYTHON = "/usr/bin/python3"
#: Exit code of the Netgen process when its interpreter has no Netgen module.
MISSING_EXIT = 3
#: Files Netgen 6.2.1905 reads itself; other CAD files go through STEP.
NGOCC_EXTENSIONS = (".step", ".stp", ".iges", ".igs")


@dataclasses.dataclass
class NetgenResult:
    points: np.ndarray  #: (n, 3)
    tets: np.ndarray  #: (m, 4) or (m, 10), VTK order
    seconds: float  #: Netgen's meshing time inside its process (geometry read included)
    process_seconds: float  #: the whole process, Python start-up included
    peak_rss_mb: float
    command: str


class NetgenMissing(RuntimeError):
    """The interpreter has no Netgen Python module (Debian package python3-netgen)."""


def netgen_command(h, order):
    return "netgen maxh %.4g%s" % (h, ", second order" if order == 2 else "")


def run_netgen(part, h, order=2, timeout=DEFAULT_TIMEOUT, python=NETGEN_PYTHON, workdir=None):
    """Netgen on the CAD file ``part`` (STEP, IGES; BREP on Netgen 6.2.2 and later) at
    ``maxh = h``. Raises NetgenMissing when ``python`` has no Netgen module (the process says
    so itself: no second process to find out), RuntimeError with Netgen's last words when it
    fails or times out."""
    own_dir = workdir is None
    workdir = workdir or tempfile.mkdtemp(prefix="fembsptet_netgen_")
    out = os.path.join(workdir, "netgen_mesh.npz")
    try:
        run = run_measured([python, "-m", __name__, os.path.abspath(part), repr(float(h)),
                            str(int(order)), out], timeout=timeout, cwd=workdir,
                           env=worker_env())
        if run.timed_out:
            raise RuntimeError("netgen timed out after %g s" % timeout)
        if run.returncode == MISSING_EXIT:
            raise NetgenMissing("%s has no Netgen module (Debian package python3-netgen)"
                                % python)
        if run.returncode != 0 or not os.path.isfile(out):
            raise RuntimeError("netgen failed (exit %s): %s" % (run.returncode, run.tail()))
        with np.load(out, allow_pickle=False) as z:
            return NetgenResult(points=z["points"], tets=z["tets"], seconds=float(z["seconds"]),
                                process_seconds=run.seconds, peak_rss_mb=run.peak_rss_mb,
                                command=netgen_command(h, order))
    finally:
        if own_dir:
            shutil.rmtree(workdir, ignore_errors=True)


# ------------------------------------------------------------------------------------------
# inside the Netgen process
# ------------------------------------------------------------------------------------------

# nglib's Ng_Meshing_Parameters (Netgen 6.2.1905): byte offsets of the fields set here, and the
# defaults its constructor must leave there (checked before anything is written).
_NGLIB_PARAMS = {"uselocalh": (0, "i", 1), "maxh": (8, "d", 1000.0), "grading": (32, "d", 0.3),
                 "elementsperedge": (40, "d", 2.0), "elementspercurve": (48, "d", 2.0),
                 "meshsize_filename": (96, "Q", 0), "optsteps_3d": (112, "i", 3)}


def _set_global_size_1905(h):
    """Netgen 6.2.1905: the global ``netgen::mparam`` with maxh = h, segments per edge 1,
    curvature safety 2, grading 0.3 (MeshingParameters' defaults), through nglib's
    Ng_Meshing_Parameters and Transfer_Parameters(). Returns what must stay alive while
    meshing."""
    import netgen

    lib_dir = getattr(netgen, "_netgen_lib_dir", "/usr/lib/x86_64-linux-gnu/netgen")
    lib = ctypes.CDLL(os.path.join(lib_dir, "libnglib.so.6.2"))
    construct = lib["_ZN5nglib21Ng_Meshing_ParametersC1Ev"]
    transfer = lib["_ZN5nglib21Ng_Meshing_Parameters19Transfer_ParametersEv"]
    for f in (construct, transfer):
        f.argtypes, f.restype = [ctypes.c_void_p], None
    params = ctypes.create_string_buffer(512)
    construct(params)
    for name, (offset, kind, default) in _NGLIB_PARAMS.items():
        if struct.unpack_from("<" + kind, params, offset)[0] != default:
            raise RuntimeError("nglib's Ng_Meshing_Parameters has another layout (%s)" % name)
    empty = ctypes.c_char_p(b"")
    values = {"maxh": h, "elementsperedge": 1.0, "elementspercurve": 2.0, "grading": 0.3,
              "meshsize_filename": ctypes.cast(empty, ctypes.c_void_p).value}
    for name, value in values.items():
        offset, kind, _ = _NGLIB_PARAMS[name]
        struct.pack_into("<" + kind, params, offset, value)
    transfer(params)
    return params, empty


def mesh_with_netgen(part, h, order):
    """In the Netgen process: ``(points, tets in VTK order, seconds, settings)``."""
    t0 = time.perf_counter()
    try:
        from netgen.occ import OCCGeometry  # Netgen 6.2.2 and later
    except ImportError:
        OCCGeometry = None
    if OCCGeometry is not None:
        mesh = OCCGeometry(part).GenerateMesh(maxh=h)
        settings = {"maxh": h, "interface": "netgen.occ"}
    else:
        from netgen.meshing import MeshingParameters
        from netgen.NgOCC import LoadOCCGeometry

        global_size = _set_global_size_1905(h)
        mesh = LoadOCCGeometry(part).GenerateMesh(mp=MeshingParameters(maxh=h))
        del global_size  # kept alive until here
        settings = {"maxh": h, "interface": "netgen.NgOCC (global mparam set the same)"}
    if order == 2:
        mesh.SecondOrder()
    seconds = time.perf_counter() - t0
    points = np.array([p.p for p in mesh.Points()], dtype=float)
    tets = np.array([[v.nr - 1 for v in e.points] for e in mesh.Elements3D()], dtype=np.int64)
    if len(tets) == 0:
        raise RuntimeError("netgen made no volume elements")
    if tets.shape[1] == 10:
        tets = tets[:, NETGEN_TO_VTK_TET10]
    settings.update(second_order=order == 2, others="Netgen's defaults (grading 0.3, "
                    "curvature safety 2, 3 optimization steps)")
    return points, tets, seconds, settings


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 4:
        print("usage: python3 -m FemBspTet.peers.netgen PART H ORDER OUT.npz", file=sys.stderr)
        return 2
    part, h, order, out = argv[0], float(argv[1]), int(argv[2]), argv[3]
    if importlib.util.find_spec("netgen") is None:
        return MISSING_EXIT
    points, tets, seconds, _ = mesh_with_netgen(part, h, order)
    np.savez(out, points=points, tets=tets, seconds=np.float64(seconds))
    return 0


if __name__ == "__main__":
    sys.exit(main())
