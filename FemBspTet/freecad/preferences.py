# SPDX-License-Identifier: LGPL-2.1-or-later
"""User preferences of the BspTet mesher (Edit > Preferences > FEM > BspTet).

Stored by FreeCAD under ``User parameter:BaseApp/Preferences/Mod/Fem/BspTet`` (the page
``resources/ui/PreferencesBspTet.ui`` writes them itself through ``prefPath``/``prefEntry``).
They are the defaults of new mesher objects (:func:`object_defaults`) and say which interpreter
runs the meshing worker of the task panel (:func:`worker_python`). Explicit arguments of
``make_mesher`` always win.
"""

#: FreeCAD parameter group of these preferences.
PARAM_PATH = "User parameter:BaseApp/Preferences/Mod/Fem/BspTet"
#: Interpreter of the worker process when the preference is empty: Debian's, the one FreeCAD's
#: Python modules load in (inside the GUI ``sys.executable`` is ``/usr/bin/freecad``).
DEFAULT_WORKER_PYTHON = "/usr/bin/python3"


def _group():
    import FreeCAD

    return FreeCAD.ParamGet(PARAM_PATH)


def object_defaults():
    """Property values for a new mesher object: ``{property name: value}``."""
    g = _group()
    return {
        "ElementOrder": "1st" if g.GetInt("ElementOrder", 1) == 0 else "2nd",
        "CompareWithPeers": g.GetBool("CompareWithPeers", True),
        "FaceGroups": g.GetBool("FaceGroups", True),
    }


def worker_python():
    """The interpreter that runs :mod:`FemBspTet.freecad.mesh_worker` (preference ``WorkerPython``)."""
    path = _group().GetString("WorkerPython", "").strip()
    return path or DEFAULT_WORKER_PYTHON
