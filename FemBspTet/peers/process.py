# SPDX-License-Identifier: LGPL-2.1-or-later
"""One external program, measured alone: wall time, peak resident memory, output, exit code.

    run = run_measured(["tetgen", "-pYQ", "surface.off"], timeout=600, cwd=workdir)
    run.seconds, run.peak_rss_mb, run.returncode, run.output, run.timed_out

Every mesher of the comparison (TetGen, Gmsh and our own worker) runs through this function, so
their figures are measured the same way: the wall time from start to exit of the process
(start-up included) and its peak resident set size.

The peak memory comes from GNU time (``/usr/bin/time -f %M -o FILE``, Debian package ``time``),
which forks the program from its own small process. Python's ``os.wait4`` on a child we fork
ourselves would not do: Linux carries the high-water mark of the forking process (this Python,
tens of MB) over ``exec`` into the child's ``ru_maxrss``, so every small run would show this
process's size; and ``getrusage(RUSAGE_CHILDREN)`` gives the largest of *all* children so far.
Without GNU time the figure is ``os.wait4``'s, with that floor (``ProcessRun.rss_floor`` says so).

The child gets its own process group; on timeout the whole group is killed (SIGKILL), so helpers
it started die too. Nothing here raises for a failing program: the caller decides what a
non-zero exit code means.
"""

import dataclasses
import os
import shutil
import signal
import subprocess
import time
import tempfile
import threading

from ..kernel.paths import ADDON_DIR

#: Seconds a comparison run may take by default (``--timeout`` changes it).
DEFAULT_TIMEOUT = 600.0


@dataclasses.dataclass
class ProcessRun:
    command: list
    seconds: float
    peak_rss_mb: float
    returncode: int  #: exit code; negative: killed by that signal; None: timed out
    output: str  #: stdout and stderr, interleaved
    timed_out: bool = False
    rss_floor: bool = False  #: True: no GNU time, the peak includes this process's size

    def tail(self, lines=3, chars=400):
        """The last lines of the output, for messages."""
        text = "\n".join(self.output.strip().splitlines()[-lines:])
        return text[-chars:]


def run_measured(command, timeout=DEFAULT_TIMEOUT, cwd=None, env=None):
    """Runs ``command`` (a list) and waits for it, at most ``timeout`` seconds (None: no limit).

    Output goes to a temporary file, not a pipe, so a chatty program cannot block on a full
    pipe while we wait. The wait is a blocking ``os.wait4`` in a helper thread, so the wall time
    is taken the moment the process exits (no polling step: a run of 10 ms and one of 40 ms are
    told apart, which matters for the time ratios of small models).
    """

    command = [str(c) for c in command]
    gnu_time = shutil.which("time", path="/usr/bin:/bin")
    with tempfile.TemporaryFile(mode="w+b") as out, \
            tempfile.NamedTemporaryFile(mode="r", prefix="fembsptet_rss_") as rss_file:
        argv = command if gnu_time is None else \
            [gnu_time, "-q", "-f", "%M", "-o", rss_file.name] + command
        start = time.perf_counter()
        proc = subprocess.Popen(argv, stdout=out, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, cwd=cwd, env=env,
                                start_new_session=True)
        waited = {}

        def wait():
            waited["status"] = os.wait4(proc.pid, 0)
            waited["end"] = time.perf_counter()

        waiter = threading.Thread(target=wait, daemon=True)
        waiter.start()
        waiter.join(timeout)
        timed_out = waiter.is_alive()
        if timed_out:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            waiter.join()
        _, status, usage = waited["status"]
        seconds = waited["end"] - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        text = out.read().decode(errors="replace")
        peak_kib = usage.ru_maxrss
        if gnu_time is not None and not timed_out:
            try:
                peak_kib = int(rss_file.read().strip().splitlines()[-1])
            except (ValueError, IndexError):
                pass
    return ProcessRun(command=command, seconds=seconds, peak_rss_mb=peak_kib / 1024.0,
                      returncode=None if timed_out else proc.returncode, output=text,
                      timed_out=timed_out, rss_floor=gnu_time is None)


def worker_env():
    """Environment of a worker interpreter of ours: the addon folder first on its PYTHONPATH,
    and no PYTHONHOME (FreeCAD's own, if any, is not the worker's)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = ADDON_DIR + (os.pathsep + env["PYTHONPATH"]
                                     if env.get("PYTHONPATH") else "")
    env.pop("PYTHONHOME", None)
    return env
