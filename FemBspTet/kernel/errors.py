# SPDX-License-Identifier: LGPL-2.1-or-later
"""Typed errors of FemBspTet.

Every error names what is wrong and where (file, line, triangle or vertex index, CAD face) and,
where it can, what to do about it. The CLI maps them to exit codes:

* :class:`InputError`    -> exit code 2 (the input is bad; the user can fix it)
  (:class:`SelfIntersectionError` and :class:`MemoryBudgetError` are kinds of it)
* :class:`InternalError` -> exit code 1 (our fault, or a feature that does not exist yet)
* :class:`Cancelled`     -> exit code 130 (Ctrl-C, the task panel's Cancel, a ``cancel()`` callback)
* :class:`TimeLimitReached` -> exit code 124 (``--timeout``; the same code as coreutils' timeout)

:func:`report_errors` turns them into one message and that exit code.
"""

import enum
import sys
import traceback


class ErrorCode(str, enum.Enum):
    """What an :class:`InputError` is about (``error.code``), as the core names it
    (``cpp_module/include/bsptet/numerics/errors.h``, bound as ``_bsptet.ErrorCode``; a test keeps
    the two equal), and the codes of this package's own input errors. A member equals its string."""

    BAD_ARGUMENT = "bad_argument"
    NON_FINITE_COORDINATE = "non_finite_coordinate"
    DEGENERATE_TRIANGLE = "degenerate_triangle"
    DUPLICATE_TRIANGLE = "duplicate_triangle"
    OPEN_BOUNDARY = "open_boundary"
    NON_MANIFOLD = "non_manifold"
    INCONSISTENT_ORIENTATION = "inconsistent_orientation"
    INWARD_FACING = "inward_facing"
    SELF_INTERSECTION = "self_intersection"
    CANCELLED = "cancelled"
    INTERNAL = "internal"
    #: raised by this package, not the core: the memory budget is too small
    MEMORY_BUDGET = "memory_budget"

    def __str__(self):
        return self.value

    @classmethod
    def of(cls, code):
        """The member for ``code`` (a string or member), None for None or an unknown string."""
        if code is None or isinstance(code, cls):
            return code
        try:
            return cls(str(code))
        except ValueError:
            return None


class BspTetError(Exception):
    """Base class of every error FemBspTet raises on purpose."""

    exit_code = 1


class InputError(BspTetError, ValueError):
    """The input (file, surface, CAD shape, option) is invalid. ``where`` names the place."""

    exit_code = 2

    def __init__(self, message, where=None, code=None):
        self.where = where
        #: An :class:`ErrorCode` (equal to its snake_case string, "open_boundary", ...) or None.
        self.code = ErrorCode.of(code) if code is not None else None
        if code is not None and self.code is None:
            raise ValueError(f"unknown error code {code!r}")
        text = f"{where}: {message}" if where else message
        super().__init__(text)


class SelfIntersectionError(InputError):
    """The surface crosses or touches itself. ``pairs`` is an (k, 2) int array of intersecting
    triangle indices (sorted, first < second); ``complete`` is False when there were more than
    were collected. ``surface`` is the surface they index into."""

    def __init__(self, message, where=None, pairs=None, complete=True, surface=None):
        super().__init__(message, where=where, code=ErrorCode.SELF_INTERSECTION)
        self.pairs = pairs
        self.complete = complete
        self.surface = surface


class MemoryBudgetError(InputError):
    """The run would need (estimated before it starts) or needed more memory than the budget
    (``--max-memory``). ``estimate`` and ``budget`` are in bytes."""

    def __init__(self, message, where=None, estimate=None, budget=None):
        super().__init__(message, where=where, code=ErrorCode.MEMORY_BUDGET)
        self.estimate = estimate
        self.budget = budget


class InternalError(BspTetError, RuntimeError):
    """Something failed that is not the user's fault; please report it with the input."""

    exit_code = 1


class Cancelled(BspTetError):
    """The run was stopped on request (Ctrl-C, Cancel); nothing was written."""

    exit_code = 130


class TimeLimitReached(Cancelled):
    """The run was stopped because its time limit (``--timeout``) was reached; nothing was written."""

    exit_code = 124


class NotImplementedYetError(InternalError):
    """A feature that is planned but not built yet. Says which, never pretends."""


class MeshingCancelled(Cancelled):
    """The user stopped a FreeCAD meshing run (Cancel in the task panel, ``cancel()`` returning
    True). No mesh was made; an object's previous mesh is kept. A :class:`Cancelled` like the
    core's own cancellation, so ``except Cancelled`` catches both."""


def report_errors(func, args, program="fembsptet"):
    """Runs ``func(args)`` and returns its exit code; every error becomes one message on stderr
    (``program: error: ...``) and the exit code of the module doc (2 for bad input and out of
    memory, 130 for an interrupt, 1 for anything unexpected, with its traceback)."""
    try:
        return func(args)
    except InputError as exc:
        print(f"{program}: error: {exc}", file=sys.stderr)
        return 2
    except BspTetError as exc:
        print(f"{program}: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print(f"{program}: interrupted; no output was written", file=sys.stderr)
        return 130
    except MemoryError:
        print(f"{program}: error: out of memory; no output was written (set a --max-memory "
              "budget or mesh a coarser tessellation)", file=sys.stderr)
        return 2
    except Exception:  # noqa: BLE001 - last resort: report and exit 1, never a bare traceback
        print(f"{program}: internal error (please report it with the input):", file=sys.stderr)
        traceback.print_exc()
        return 1
