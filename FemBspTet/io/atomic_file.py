# SPDX-License-Identifier: LGPL-2.1-or-later
"""Atomic file output: a file of the target name appears only complete, or not at all.

A writer opens :func:`atomic_output` (or :func:`atomic_outputs` for formats made of several
files, such as TetGen's ``.node`` + ``.ele``) and writes into the object it yields. The data
go to a temporary file in the *same directory* as the target, named
``.<target name>.<pid>.<random>.tmp`` (the process id lets a supervising process find and remove
the temporary files of a worker it had to stop: :mod:`FemBspTet.cli.supervisor`). On a normal exit the temporary file is flushed, ``fsync``-ed
and renamed onto the target with :func:`os.replace`, which is atomic on POSIX file systems.
On any exception inside the ``with`` block the temporary file is deleted, the exception
propagates unchanged and the target is untouched: a previous file of that name survives.

The new file gets the permissions an ordinary ``open(path, "w")`` would give it (``0o666``
less the umask), or keeps the mode of the file it replaces.

Errors of the file system itself (missing directory, no permission, disk full) are raised as
:class:`~FemBspTet.kernel.errors.InputError` naming the target path, since the user can fix them.
"""

import contextlib
import os
import stat
import tempfile

from ..kernel.errors import InputError

__all__ = ["atomic_output", "atomic_outputs"]

_MODES = ("w", "wb")


def _current_umask():
    """The process umask, read without changing it where the platform allows."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)  # fallback: read by setting (not thread-safe, Linux never gets here)
    os.umask(mask)
    return mask


def _target_mode(path):
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        return 0o666 & ~_current_umask()


def _fsync_directory(directory):
    """Make the rename durable; silently skipped where directories cannot be opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _remove_quietly(path):
    try:
        os.unlink(path)
    except OSError:
        pass


def _open_temporary(path, mode):
    """Create the temporary sibling of ``path``; returns ``(file object, temp path)``."""
    if mode not in _MODES:
        raise ValueError(f"atomic_output mode must be one of {_MODES}, got {mode!r}")
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    name = os.path.basename(path)
    if not name:
        raise InputError("the output path names a directory, not a file", where=path)
    if os.path.isdir(path):
        raise InputError("cannot write the file: a directory of that name exists", where=path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{name}.{os.getpid()}.", suffix=".tmp", dir=directory)
    except FileNotFoundError:
        raise InputError(f"cannot write the file: directory {directory!r} does not exist",
                         where=path) from None
    except OSError as exc:
        raise InputError(f"cannot write the file: {exc.strerror or exc}", where=path) from None
    try:
        os.chmod(tmp, _target_mode(path))
        if mode == "wb":
            handle = os.fdopen(fd, "wb")
        else:
            handle = os.fdopen(fd, "w", encoding="utf-8", newline="\n")
    except BaseException:
        os.close(fd)
        _remove_quietly(tmp)
        raise
    return handle, tmp


def _finish(handle, tmp, path):
    """Flush and fsync ``handle`` (then close it); file-system errors become InputError."""
    try:
        handle.flush()
        os.fsync(handle.fileno())
    except OSError as exc:
        raise InputError(f"cannot write the file: {exc.strerror or exc}", where=path) from None
    finally:
        handle.close()


@contextlib.contextmanager
def atomic_output(path, mode="w"):
    """Write ``path`` atomically.

    ``mode`` is ``"w"`` (text, UTF-8, ``"\\n"`` line ends) or ``"wb"`` (bytes). Yields the open
    file object. See the module documentation for the guarantees.
    """
    path = os.fspath(path)
    handle, tmp = _open_temporary(path, mode)
    try:
        yield handle
        _finish(handle, tmp, path)
        try:
            os.replace(tmp, path)
        except OSError as exc:
            raise InputError(f"cannot write the file: {exc.strerror or exc}",
                             where=path) from None
    except BaseException:
        if not handle.closed:
            handle.close()
        _remove_quietly(tmp)
        raise
    _fsync_directory(os.path.dirname(os.path.abspath(path)))


@contextlib.contextmanager
def atomic_outputs(paths, mode="w"):
    """Write several files that belong together (e.g. TetGen ``X.node`` and ``X.ele``).

    Yields a list of open file objects, one per path, in the order given. The targets are
    renamed into place only after *all* of them were written and synced; if the ``with``
    block raises, every temporary file is removed and no target is touched. (The renames
    themselves are consecutive: a crash of the machine between two renames can leave the new
    first file beside the old second one; the renames are done only after every byte is on
    disk, which makes that window as short as the file system allows.)
    """
    paths = [os.fspath(p) for p in paths]
    if len(set(os.path.abspath(p) for p in paths)) != len(paths):
        raise ValueError(f"atomic_outputs got the same path twice: {paths}")
    opened = []  # (handle, tmp, path)
    try:
        for path in paths:
            handle, tmp = _open_temporary(path, mode)
            opened.append((handle, tmp, path))
        yield [handle for handle, _, _ in opened]
        for handle, tmp, path in opened:
            _finish(handle, tmp, path)
        for index, (handle, tmp, path) in enumerate(opened):
            try:
                os.replace(tmp, path)
            except OSError as exc:
                raise InputError(f"cannot write the file: {exc.strerror or exc}",
                                 where=path) from None
            opened[index] = (handle, None, path)
    except BaseException:
        for handle, tmp, _ in opened:
            if not handle.closed:
                handle.close()
            if tmp is not None:
                _remove_quietly(tmp)
        raise
    for directory in sorted(set(os.path.dirname(os.path.abspath(p)) for p in paths)):
        _fsync_directory(directory)
