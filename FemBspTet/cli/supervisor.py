# SPDX-License-Identifier: LGPL-2.1-or-later
"""Runs a meshing job so that it can always be stopped within a fraction of a second: in a child
process when a time or memory limit asks for one (:func:`run_supervised`), else in this process
(:func:`run_interruptible`: Ctrl-C and SIGTERM only).

    from FemBspTet.cli.supervisor import Limits, run_supervised
    code = run_supervised(job, Limits(timeout=60, max_memory=4 << 30), outputs=["out.vtu"])

Why a child process: the core checks for cancellation between steps, but some steps (and
OpenCASCADE's tessellation, which holds Python's GIL) run for seconds without a check, and a
crash of native code must not take the command line down. The parent only waits: it polls the
child every ``poll`` seconds and stops it (``SIGKILL`` to its process group, so helpers it started,
such as ``tetgen``, stop too) when

* the time limit is reached (``--timeout``)           -> exit code 124, :class:`TimeLimitReached`
* the parent gets SIGINT or SIGTERM (Ctrl-C)          -> exit code 130, :class:`Cancelled`
* the child's resident memory exceeds the budget      -> exit code 2,   :class:`MemoryBudgetError`
* the child dies of a signal (a crash)                -> exit code 1,   :class:`InternalError`

Then it removes the child's temporary output files (``atomic_file`` names them
``.<name>.<pid>.<random>.tmp``, FreeCAD exports use ``.<name>.tmp<pid>_<random>/``), so a stopped
run leaves no partial file, and prints one message saying why. Outputs are only ever renamed into
place complete, so a target either keeps its previous content or gets the complete new one.

``job`` runs in the child (after ``fork``) and returns the exit code; its own errors are its own
business (the CLI reports them). The child ignores SIGINT: stopping is the parent's job, which
keeps one message per run. Linux/POSIX only (``os.fork``).
"""

import os
import shutil
import signal
import sys
import threading
import time
from dataclasses import dataclass
import traceback

from ..kernel.errors import Cancelled, InternalError, MemoryBudgetError, TimeLimitReached

__all__ = ["Limits", "run_supervised", "run_interruptible", "child_rss_bytes",
           "remove_temporaries"]


@dataclass(frozen=True)
class Limits:
    """What the supervisor enforces. ``None`` means no limit."""

    timeout: float = None  #: seconds of wall-clock time for the whole job
    max_memory: int = None  #: bytes of resident memory of the child process
    poll: float = 0.02  #: seconds between two looks at the child


def child_rss_bytes(pid):
    """Resident memory of process ``pid`` in bytes (``VmRSS``), or 0 if it cannot be read."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return 0


def remove_temporaries(paths, pid):
    """Removes the temporary files and folders process ``pid`` made next to ``paths``."""
    removed = []
    for directory in sorted({os.path.dirname(os.path.abspath(p)) for p in paths}):
        try:
            names = os.listdir(directory)
        except OSError:
            continue
        for name in names:
            full = os.path.join(directory, name)
            if not name.startswith("."):
                continue
            if f".{pid}." in name and name.endswith(".tmp") and os.path.isfile(full):
                try:
                    os.unlink(full)
                    removed.append(full)
                except OSError:
                    pass
            elif f".tmp{pid}_" in name and os.path.isdir(full):
                shutil.rmtree(full, ignore_errors=True)
                removed.append(full)
    return removed


def _format_bytes(n):
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024.0
    return f"{n} B"  # pragma: no cover


def _run_child(job):
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    os.setpgid(0, 0)  # its own process group: the parent stops helpers with it
    code = 1
    try:
        code = int(job())
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    except BaseException:  # noqa: BLE001 - the job reports its own errors; this is the last resort

        traceback.print_exc()
        code = 1
    finally:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(code)


def run_supervised(job, limits=Limits(), outputs=()):
    """Runs ``job()`` in a child process under ``limits``; returns the child's exit code.

    Raises :class:`TimeLimitReached`, :class:`Cancelled`, :class:`MemoryBudgetError` or
    :class:`InternalError` (the child crashed) after stopping the child and removing its
    temporary files next to ``outputs``.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    stop = {}

    def on_signal(signum, frame):
        stop.setdefault("signal", signum)

    old_int = signal.signal(signal.SIGINT, on_signal)
    old_term = signal.signal(signal.SIGTERM, on_signal)
    try:
        pid = os.fork()
        if pid == 0:  # pragma: no cover - runs in the child, which never returns
            _run_child(job)
        try:
            os.setpgid(pid, pid)  # as the child does: no race with killpg below
        except OSError:
            pass
        start = time.monotonic()
        peak = 0
        reason = None
        while True:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            elapsed = time.monotonic() - start
            if "signal" in stop:
                reason = "signal"
            elif limits.timeout is not None and elapsed >= limits.timeout:
                reason = "timeout"
            elif limits.max_memory is not None:
                peak = max(peak, child_rss_bytes(pid))
                if peak > limits.max_memory:
                    reason = "memory"
            if reason:
                try:
                    os.killpg(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                except PermissionError:  # pragma: no cover - the group is ours
                    os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                break
            time.sleep(limits.poll)
        elapsed = time.monotonic() - start
    finally:
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)
    if reason is None and os.WIFEXITED(status):
        return os.WEXITSTATUS(status)
    remove_temporaries(outputs, pid)
    if sys.stderr.isatty():  # the child's progress bar: cursor shown again, its line cleared
        sys.stderr.write("\x1b[?25h\r\x1b[2K")
        sys.stderr.flush()
    if reason == "timeout":
        raise TimeLimitReached(
            f"stopped: the time limit of {limits.timeout:g} s (--timeout) was reached; "
            "no output was written")
    if reason == "signal":
        name = signal.Signals(stop["signal"]).name
        raise Cancelled(f"interrupted ({name}) after {elapsed:.1f} s; no output was written")
    if reason == "memory":
        raise MemoryBudgetError(
            f"stopped: the run used {_format_bytes(peak)}, more than the memory budget of "
            f"{_format_bytes(limits.max_memory)} (--max-memory); no output was written. "
            "Raise the budget, or mesh a coarser tessellation (--size)",
            estimate=peak, budget=limits.max_memory)
    signum = os.WTERMSIG(status)
    try:
        name = signal.Signals(signum).name
    except ValueError:
        name = str(signum)
    raise InternalError(
        f"internal error: the mesher crashed ({name}); no output was written. "
        "Please report it with the input")


def run_interruptible(job, outputs=()):
    """Runs ``job()`` in this process (no limits asked for: no child process) and returns its
    exit code; SIGINT (Ctrl-C) or SIGTERM end the process within a fraction of a second: the
    temporary files next to ``outputs`` are removed, one message is printed, exit code 130.

    The native core runs without Python's GIL, so a watcher thread can act while it works: the
    signal's C handler writes to a wakeup pipe (``signal.set_wakeup_fd``) whatever the main
    thread is doing, and the watcher ends the process there. Outputs are only ever renamed into
    place complete, so a target keeps its previous content or gets the complete new one.
    Call from the main thread.
    """
    read_fd, write_fd = os.pipe()
    os.set_blocking(write_fd, False)
    start = time.monotonic()

    def watch():
        try:
            data = os.read(read_fd, 1)
        except OSError:
            return
        if not data:  # the job ended: the pipe was closed
            return
        remove_temporaries(outputs, os.getpid())
        try:
            name = signal.Signals(data[0]).name
        except ValueError:
            name = f"signal {data[0]}"
        lead = "\x1b[?25h\r\x1b[2K" if sys.stderr.isatty() else ""  # over the progress bar
        os.write(sys.stderr.fileno(), (f"{lead}fembsptet: interrupted ({name}) after "
                                       f"{time.monotonic() - start:.1f} s; no output was "
                                       "written\n").encode())
        os._exit(130)

    watcher = threading.Thread(target=watch, name="fembsptet-interrupt", daemon=True)
    watcher.start()
    old_int = signal.signal(signal.SIGINT, lambda signum, frame: None)
    old_term = signal.signal(signal.SIGTERM, lambda signum, frame: None)
    old_fd = signal.set_wakeup_fd(write_fd, warn_on_full_buffer=False)
    try:
        return job()
    finally:
        signal.set_wakeup_fd(old_fd)
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)
        os.close(write_fd)
        watcher.join()
        os.close(read_fd)
