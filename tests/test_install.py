# SPDX-License-Identifier: LGPL-2.1-or-later
"""Installation as a package: `cmake --install` under a prefix puts a working `fembsptet` in
PREFIX/bin that runs from anywhere with no checkout on sys.path, makes `import FemBspTet` work
through a .pth file, and `fembsptet freecad-install` links the installed addon into FreeCAD's
Mod folder, where FreeCAD loads it and runs its App tests."""

import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from FemBspTet.kernel.freecad_env import freecad_available

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.environ.get("FEMBSPTET_BUILD_DIR", os.path.join(ROOT, "build"))
PY = f"python{sys.version_info.major}.{sys.version_info.minor}"


@pytest.fixture(scope="module")
def prefix(tmp_path_factory):
    if not os.path.isfile(os.path.join(BUILD, "CMakeCache.txt")):
        pytest.fail(f"no build in {BUILD}: run scripts/setup.sh", pytrace=False)
    prefix = tmp_path_factory.mktemp("prefix")
    subprocess.run(["cmake", "--install", BUILD, "--prefix", str(prefix)], check=True,
                   capture_output=True, timeout=300)
    return prefix


def clean_env(home):
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "FEMBSPTET_CORE_TOOL")}
    env["HOME"] = str(home)
    env.pop("XDG_DATA_HOME", None)
    return env


def test_the_installed_command_meshes_from_anywhere(prefix, tmp_path):
    exe = prefix / "bin" / "fembsptet"
    assert os.path.islink(exe) and os.access(exe, os.X_OK)
    addon = prefix / "share" / "fembsptet" / "FemBspTet"
    assert os.path.realpath(exe) == str(addon / "bin" / "fembsptet")
    assert list((addon / "FemBspTet").glob("_bsptet.*.so"))
    assert list((addon / "FemBspTet").glob("_bsptet_cad.*.so"))
    assert (addon / "libexec" / "bsptet_mesh").is_file()
    out = tmp_path / "m.vtu"
    r = subprocess.run([str(exe), "mesh", os.path.join(ROOT, "tests", "data", "cad",
                                                       "bracket.step"), "--order", "2",
                        "-o", str(out)], cwd=tmp_path, env=clean_env(tmp_path),
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("read ") and "tet10 elements" in r.stdout
    # the installed package did the work, not the checkout
    r = subprocess.run(["/usr/bin/python3", "-c",
                        "import site, sys; site.addsitedir(sys.argv[1]); import FemBspTet, "
                        "FemBspTet.kernel.core as c; print(FemBspTet.__file__); print(c.native().__file__)",
                        str(prefix / "lib" / PY / "dist-packages")],
                       cwd=tmp_path, env=clean_env(tmp_path), capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    package, native = r.stdout.split()
    assert package.startswith(str(addon)) and native.startswith(str(addon))
    from FemBspTet.io.volume_io import read_tet_mesh

    mesh = read_tet_mesh(out)
    assert mesh.tets.shape[1] == 10 and np.isfinite(mesh.points).all()


def test_freecad_install_links_the_installed_addon(prefix, tmp_path):
    exe = str(prefix / "bin" / "fembsptet")
    env = clean_env(tmp_path)
    (tmp_path / ".local" / "share" / "FreeCAD" / "v1-1").mkdir(parents=True)
    r = subprocess.run([exe, "freecad-install"], env=env, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    addon = str(prefix / "share" / "fembsptet" / "FemBspTet")
    for mod in ("Mod", "v1-1/Mod"):
        link = tmp_path / ".local" / "share" / "FreeCAD" / mod / "FemBspTet"
        assert os.path.islink(link) and os.path.realpath(link) == addon
    again = subprocess.run([exe, "freecad-install"], env=env, capture_output=True, text=True,
                           timeout=120)
    assert again.returncode == 0 and "already there" in again.stdout
    if freecad_available() and shutil.which("freecadcmd"):
        proc = subprocess.run(["freecadcmd", "-t", "TestFemBspTetApp"], env=env, cwd=tmp_path,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=300)
        out = proc.stdout.decode(errors="replace")
        assert proc.returncode == 0 and "\nOK" in out, out[-3000:]
    r = subprocess.run([exe, "freecad-install", "--uninstall"], env=env, capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 0
    assert not os.path.lexists(tmp_path / ".local" / "share" / "FreeCAD" / "Mod" / "FemBspTet")


def test_freecad_install_leaves_a_foreign_folder_alone(tmp_path):
    from FemBspTet.cli.addon_install import install
    from FemBspTet.kernel.errors import InputError

    mod = tmp_path / "Mod"
    (mod / "FemBspTet").mkdir(parents=True)
    with pytest.raises(InputError, match="not our link"):
        install([str(mod)])
    assert (mod / "FemBspTet").is_dir() and not os.path.islink(mod / "FemBspTet")
