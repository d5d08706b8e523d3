# SPDX-License-Identifier: LGPL-2.1-or-later
"""The checkout as a FreeCAD addon: package.xml passes FreeCAD's own metadata reader, and FreeCAD
loads the addon from ~/.local/share/FreeCAD/Mod/FemBspTet (a symlink to the checkout, as the
README says) and runs its App tests (``freecadcmd -t TestFemBspTetApp``) in a throw-away HOME.
"""

import os
import shutil
import subprocess

import pytest

import FemBspTet
from FemBspTet.kernel.freecad_env import freecad_available

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

if not freecad_available():
    pytest.skip("FreeCAD (Debian package freecad-python3) is not available",
                allow_module_level=True)


def test_package_xml_passes_freecads_metadata_reader():
    from FemBspTet.kernel.freecad_env import import_freecad

    freecad = import_freecad()
    md = freecad.Metadata(os.path.join(ROOT, "package.xml"))
    assert md.Name == "FemBspTet"
    assert md.Version == FemBspTet.__version__
    assert md.supportsCurrentFreeCAD()
    workbenches = md.Content["workbench"]
    assert [w.Classname for w in workbenches] == ["FemBspTetWorkbench"]
    with open(os.path.join(ROOT, "InitGui.py")) as f:
        assert "class FemBspTetWorkbench(" in f.read()
    for icon in (md.Icon, workbenches[0].Icon):
        assert os.path.isfile(os.path.join(ROOT, icon)), icon


def test_freecad_loads_the_addon_as_a_mod_and_runs_its_app_tests(tmp_path):
    assert shutil.which("freecadcmd"), "freecadcmd (freecad-python3) missing: scripts/setup.sh"
    mods = tmp_path / ".local" / "share" / "FreeCAD" / "Mod"
    mods.mkdir(parents=True)
    os.symlink(ROOT, mods / "FemBspTet")
    env = dict(os.environ, HOME=str(tmp_path))
    env.pop("PYTHONPATH", None)
    proc = subprocess.run(["freecadcmd", "-t", "TestFemBspTetApp"], env=env, cwd=str(tmp_path),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=300)
    out = proc.stdout.decode(errors="replace")
    assert proc.returncode == 0, out[-3000:]
    assert "Ran 1 test" in out and "\nOK" in out, out[-3000:]
