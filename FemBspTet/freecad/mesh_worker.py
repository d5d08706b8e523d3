# SPDX-License-Identifier: LGPL-2.1-or-later
"""Meshing in a separate process, so that FreeCAD's GUI never freezes and a crash of the core
cannot take FreeCAD down.

Client side (GUI thread, or any script)::

    job = MeshJob(shape, params)           # params: mesh_pipeline.MeshParameters
    job.start()
    while job.running:                     # e.g. from a QTimer
        for stage, fraction in job.poll(): ...
    result = job.result()                  # MeshResult, or raises the worker's error
    job.cancel()                           # at any time: kills the worker, nothing is kept

Worker side: ``<python> -m FemBspTet.freecad.mesh_worker JOB_DIR`` with the checkout on PYTHONPATH.

Job directory protocol (a private temporary directory, removed by the client):

* ``shape.brep``: the shape to mesh as BREP text (``Shape.exportBrepToString``; BREP keeps
  the topology, so the faces keep their order, and ``face_count`` in the parameters is checked
  against the faces the FEM path reads). In-process runs mesh the same BREP text
  (``mesh_pipeline.mesh_cad_shape``), so both give identical meshes. The worker starts FreeCAD
  only for the comparison at the same size, to write the part as STEP for Netgen.
* ``parameters.json``: ``{"parameters": MeshParameters.to_dict(), "face_count": n,
  "source": label}``.
* stdout lines ``PROGRESS <fraction or -> <stage text>`` while it runs.
* On success ``result.npz`` + ``result.json`` (:meth:`MeshResult.save`), exit code 0.
* On failure ``error.json`` ``{"type": "InputError"|"InternalError"|"MeshingCancelled",
  "message": ...}``, exit code 2 (bad input) or 1.

The worker's interpreter is explicit (preference ``WorkerPython``, default ``/usr/bin/python3``):
inside the GUI ``sys.executable`` is FreeCAD itself.
"""

import json
import os
import queue
import shutil
import subprocess
import sys
import tempfile
import threading
import traceback

from ..compare.at_size import compare_at_size
from ..fem.mesh_pipeline import mesh_brep, MeshParameters, MeshResult
from ..kernel.errors import InputError, InternalError, MeshingCancelled
from ..peers.process import worker_env
from .preferences import worker_python



_ERROR_TYPES = {"InputError": InputError, "InternalError": InternalError,
                "MeshingCancelled": MeshingCancelled, "Cancelled": MeshingCancelled}


def write_job(job_dir, shape, params, source=""):
    """Write the job files for ``shape`` and ``params`` into ``job_dir``."""
    with open(os.path.join(job_dir, "shape.brep"), "w", encoding="utf-8") as f:
        f.write(shape.exportBrepToString())  # what mesh_pipeline.mesh_cad_shape meshes, too
    with open(os.path.join(job_dir, "parameters.json"), "w", encoding="utf-8") as f:
        json.dump({"parameters": params.to_dict(), "face_count": len(shape.Faces),
                   "source": source}, f)


def read_result(job_dir):
    """The MeshResult of a finished job, or raise the error the worker reported."""

    err = os.path.join(job_dir, "error.json")
    if os.path.isfile(err):
        with open(err, encoding="utf-8") as f:
            info = json.load(f)
        raise _ERROR_TYPES.get(info.get("type"), InternalError)(info.get("message", "?"))
    npz, meta = os.path.join(job_dir, "result.npz"), os.path.join(job_dir, "result.json")
    if not (os.path.isfile(npz) and os.path.isfile(meta)):
        raise InternalError("the meshing worker ended without a result or an error message")
    return MeshResult.load(npz, meta)


class MeshJob:
    """One meshing run in a worker process. Not thread-safe: use it from one thread."""

    def __init__(self, shape, params, source="", python=None):
        self._shape = shape
        self._params = params.validate()
        self._source = source
        self._python = python
        self._proc = None
        self._dir = None
        self._events = queue.Queue()
        self._output = []
        self._reader = None
        self.cancelled = False

    def command(self):
        """``(argv, env)`` of the worker process."""
        if self._python is None:

            self._python = worker_python()
        return [self._python, "-m", "FemBspTet.freecad.mesh_worker", self._dir], worker_env()

    def start(self):
        if self._proc is not None:
            raise InternalError("this meshing job was already started")
        if self._python is not None and not os.path.isfile(self._python):
            raise InputError("the worker interpreter %s does not exist (preference WorkerPython)"
                             % self._python)
        self._dir = tempfile.mkdtemp(prefix="fembsptet_job_")
        try:
            write_job(self._dir, self._shape, self._params, self._source)
            argv, env = self.command()
            if not os.path.isfile(argv[0]):
                raise InputError("the worker interpreter %s does not exist (Edit > Preferences "
                                 "> FEM > BspTet: worker Python)" % argv[0])
            self._proc = subprocess.Popen(argv, env=env, cwd=self._dir, stdout=subprocess.PIPE,
                                          stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        except BaseException:
            self.cleanup()
            raise
        self._reader = threading.Thread(target=self._read_output, daemon=True)
        self._reader.start()

    def _read_output(self):
        for raw in self._proc.stdout:
            line = raw.decode("utf-8", "replace").rstrip("\n")
            if line.startswith("PROGRESS "):
                _, frac, stage = (line.split(" ", 2) + [""])[:3]
                self._events.put((stage, None if frac == "-" else float(frac)))
            else:
                self._output.append(line)
        self._proc.stdout.close()

    @property
    def running(self):
        return self._proc is not None and self._proc.poll() is None

    def poll(self):
        """Progress events ``(stage, fraction)`` received since the last call."""
        out = []
        while True:
            try:
                out.append(self._events.get_nowait())
            except queue.Empty:
                return out

    def wait(self, timeout=None):
        """Wait for the worker to end; True if it ended."""
        try:
            self._proc.wait(timeout)
        except subprocess.TimeoutExpired:
            return False
        if self._reader is not None:
            self._reader.join(5)
        return True

    def cancel(self):
        """Stop the worker now (SIGKILL) and remove the job files. Nothing is kept."""
        self.cancelled = True
        if self._proc is not None and self._proc.poll() is None:
            self._proc.kill()
            self._proc.wait()
        self.cleanup()

    def result(self):
        """The MeshResult (after the worker ended), or raise its error. Removes the job files."""
        if self.cancelled:
            raise MeshingCancelled("cancelled: no mesh was made")
        if self._proc is None or self._proc.poll() is None:
            raise InternalError("the meshing worker has not finished")
        self.wait()
        try:
            try:
                return read_result(self._dir)
            except InternalError as e:
                if self._proc.returncode not in (0, 1, 2):
                    tail = "\n".join(self._output[-15:])
                    raise InternalError("the meshing worker died (exit code %s): %s\n%s"
                                        % (self._proc.returncode, e, tail)) from None
                raise
        finally:
            self.cleanup()

    def output(self):
        """What the worker printed besides progress lines (for the report view)."""
        return "\n".join(self._output)

    def cleanup(self):
        if self._dir is not None:
            shutil.rmtree(self._dir, ignore_errors=True)
            self._dir = None


def main(argv=None):
    """Worker entry point: mesh the job in ``argv[0]``; see the module docstring."""
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python3 -m FemBspTet.freecad.mesh_worker JOB_DIR", file=sys.stderr)
        return 2
    job_dir = argv[0]

    def progress(stage, fraction):
        frac = "-" if fraction is None else "%.4f" % float(fraction)
        sys.stdout.write("PROGRESS %s %s\n" % (frac, stage.replace("\n", " ")))
        sys.stdout.flush()

    try:

        with open(os.path.join(job_dir, "parameters.json"), encoding="utf-8") as f:
            job = json.load(f)
        params = MeshParameters.from_dict(job["parameters"])
        with open(os.path.join(job_dir, "shape.brep"), encoding="utf-8") as f:
            brep = f.read()
        result = mesh_brep(brep, job["face_count"], params, progress=progress,
                           source=job.get("source", ""), compare=compare_at_size)
        result.save(os.path.join(job_dir, "result.npz"), os.path.join(job_dir, "result.json"))
        return 0
    except Exception as e:  # reported to the client through error.json
        # subclasses (SelfIntersectionError, ...) travel as their base type
        kind = type(e).__name__ if type(e).__name__ in _ERROR_TYPES else next(
            (name for name in ("InputError", "MeshingCancelled")
             if isinstance(e, _ERROR_TYPES[name])), "InternalError")
        message = str(e) if kind != "InternalError" or isinstance(e, InternalError) else \
            "unexpected %s: %s\n%s" % (type(e).__name__, e, traceback.format_exc())
        with open(os.path.join(job_dir, "error.json"), "w", encoding="utf-8") as f:
            json.dump({"type": kind, "message": message}, f)
        return 2 if kind == "InputError" else 1


if __name__ == "__main__":
    sys.exit(main())
