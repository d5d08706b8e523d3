"""Typed errors of FemBspTet.

Every error names what is wrong and where (file, line, triangle or vertex index, CAD face) and,
where it can, what to do about it. The CLI maps them to exit codes:

* :class:`InputError`    -> exit code 2 (the input is bad; the user can fix it)
* :class:`InternalError` -> exit code 1 (our fault, or a feature that does not exist yet)
"""


class BspTetError(Exception):
    """Base class of every error FemBspTet raises on purpose."""

    exit_code = 1


class InputError(BspTetError, ValueError):
    """The input (file, surface, CAD shape, option) is invalid. ``where`` names the place."""

    exit_code = 2

    def __init__(self, message, where=None):
        self.where = where
        text = f"{where}: {message}" if where else message
        super().__init__(text)


class InternalError(BspTetError, RuntimeError):
    """Something failed that is not the user's fault; please report it with the input."""

    exit_code = 1


class NotImplementedYetError(InternalError):
    """A feature that is planned but not built yet. Says which, never pretends."""


class MeshingCancelled(InternalError):
    """The user stopped a meshing run (Cancel in the task panel, ``cancel()`` returning True).
    No mesh was made; an object's previous mesh is kept."""
