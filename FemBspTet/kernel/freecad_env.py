# SPDX-License-Identifier: LGPL-2.1-or-later
"""Import FreeCAD on demand: inside FreeCAD itself, or headless in Debian's ``/usr/bin/python3``.

Nothing here imports FreeCAD at module import time; call :func:`import_freecad` where FreeCAD is
needed. The headless bootstrap is the one FreeCAD's own console uses (FreeCAD 0.20.2
from Debian 12, package ``freecad-python3``):

* ``/usr/lib/freecad-python3/lib`` holds ``FreeCAD.so`` and the compiled modules (``Part``, ``Fem``,
  ``MeshPart``, ...). It is appended to ``sys.path`` and ``FreeCAD`` is imported.
* FreeCAD derives its home directory from the real path of ``FreeCAD.so``, which has no ``Mod/``,
  so the bundled workbenches are not found and their ``Init.py`` files never run. We append every
  ``/usr/share/freecad/Mod/<name>`` and ``/usr/share/freecad/Ext`` (FreeCAD's PySide shim) to
  ``sys.path`` and execute each ``Mod/<name>/Init.py`` the way FreeCAD's own start-up does
  (``ObjectsFem``, ``femmesh``, import/export type registration, ...).
* In library mode ``FreeCAD.Console`` prints nothing; :func:`import_freecad` (``console=True``)
  turns messages, warnings and errors on.

Inside ``freecad``/``freecadcmd`` (or after another caller already did this bootstrap) the
module is simply returned. The bootstrap is idempotent and thread-safe.

``FreeCAD.so`` is linked against one ``libpython3.X``; loading it into another interpreter is
refused with a clear message (the ``python3`` first on ``PATH`` may be a different build).
"""

import importlib.util
import os
import re
import sys
import threading

from .errors import InternalError

#: Directory of Debian's ``FreeCAD.so`` (package ``freecad-python3``).
FREECAD_LIB_DIR = "/usr/lib/freecad-python3/lib"
#: Bundled workbenches of Debian's FreeCAD (``Fem``, ``Part``, ...), one directory each.
FREECAD_MOD_DIR = "/usr/share/freecad/Mod"
#: FreeCAD's ``PySide`` shim and the ``freecad`` namespace package.
FREECAD_EXT_DIR = "/usr/share/freecad/Ext"

_NOT_INSTALLED = "FreeCAD (Debian package freecad-python3) is not installed; run scripts/setup.sh"

_lock = threading.RLock()
_init_failures = {}


def _freecad_so():
    return os.path.join(FREECAD_LIB_DIR, "FreeCAD.so")


def _required_python(so_path):
    """``(major, minor)`` of the ``libpython`` that ``FreeCAD.so`` links against, or None."""
    try:
        with open(so_path, "rb") as f:
            data = f.read()
    except OSError:
        return None
    m = re.search(rb"libpython(\d+)\.(\d+)", data)
    return (int(m.group(1)), int(m.group(2))) if m else None


def _python_mismatch():
    """A message if this interpreter cannot load Debian's ``FreeCAD.so``, else None."""
    need = _required_python(_freecad_so())
    if need is not None and tuple(sys.version_info[:2]) != need:
        return (
            "FreeCAD.so in %s needs Python %d.%d, but this is Python %d.%d (%s); "
            "run with Debian's /usr/bin/python3"
            % (FREECAD_LIB_DIR, need[0], need[1], sys.version_info[0], sys.version_info[1],
               sys.executable)
        )
    return None


def freecad_available():
    """True if FreeCAD is importable here: already imported, or Debian's build fits this Python.

    Never imports FreeCAD (cheap; suitable for ``pytest.skip`` decisions).
    """
    if "FreeCAD" in sys.modules:
        return True
    if not os.path.isfile(_freecad_so()):
        return False
    return _python_mismatch() is None


def _workbenches_on_path():
    """True if FreeCAD's ``Mod/*`` directories are already on ``sys.path`` (FreeCAD's own
    start-up, or a previous bootstrap): then ``ObjectsFem`` (in ``Mod/Fem``) is importable."""
    return importlib.util.find_spec("ObjectsFem") is not None


def _bootstrap_workbenches(freecad):
    """Append ``Mod/*`` and ``Ext`` to ``sys.path`` and run every ``Mod/*/Init.py``."""
    mods = sorted(
        os.path.join(FREECAD_MOD_DIR, d) for d in os.listdir(FREECAD_MOD_DIR)
        if os.path.isdir(os.path.join(FREECAD_MOD_DIR, d))
    )
    for d in mods + [FREECAD_EXT_DIR]:
        if d not in sys.path:
            sys.path.append(d)
    for d in mods:
        init = os.path.join(d, "Init.py")
        if not os.path.isfile(init):
            continue
        try:
            with open(init, encoding="utf-8") as f:
                code = compile(f.read(), init, "exec")
            # FreeCAD's start-up exec()s Init.py with FreeCAD and FreeCAD.Console at hand.
            exec(code, {"__file__": init, "__name__": "FreeCADInit", "FreeCAD": freecad,
                        "App": freecad})
        except Exception as e:  # a workbench that needs the GUI or a missing dependency
            _init_failures[init] = "%s: %s" % (type(e).__name__, e)
            freecad.Console.PrintLog("FemBspTet: Init of %s failed: %s\n" % (d, e))


def set_console(freecad, on=True):
    """Turn FreeCAD's console output of messages, warnings and errors on (or off)."""
    for kind in ("Msg", "Wrn", "Err"):
        try:
            freecad.Console.SetStatus("Console", kind, bool(on))
        except Exception:  # older/newer FreeCAD without this observer: nothing to do
            pass


def import_freecad(console=False):
    """Return the ``FreeCAD`` module, bootstrapping it headless if needed.

    console: if True, turn FreeCAD's console output (messages, warnings, errors) on; it is left
             as it is otherwise (in library mode FreeCAD starts silent).
    Raises InternalError if FreeCAD is not installed or cannot be loaded into this interpreter.
    """
    with _lock:
        freecad = sys.modules.get("FreeCAD")
        if freecad is None:
            if not os.path.isfile(_freecad_so()):
                raise InternalError(_NOT_INSTALLED)
            mismatch = _python_mismatch()
            if mismatch:
                raise InternalError(mismatch)
            if FREECAD_LIB_DIR not in sys.path:
                sys.path.append(FREECAD_LIB_DIR)
            try:
                import FreeCAD as freecad  # noqa: N813
            except ImportError as e:
                raise InternalError("%s (import FreeCAD failed: %s)" % (_NOT_INSTALLED, e)) from e
        if not _workbenches_on_path():
            if not os.path.isdir(FREECAD_MOD_DIR):
                raise InternalError("FreeCAD's workbenches are missing (%s); %s"
                                    % (FREECAD_MOD_DIR, _NOT_INSTALLED))
            _bootstrap_workbenches(freecad)
        if console:
            set_console(freecad, True)
        return freecad
