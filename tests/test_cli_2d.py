# SPDX-License-Identifier: LGPL-2.1-or-later
"""`fembsptet mesh PART --dimension 2`: every CAD face as triangles (tria3 / tria6), written in
each format with a set per CAD face, read back by meshio and solved by CalculiX as a shell."""

import os
import shutil
import subprocess

import meshio
import numpy as np
import pytest

from FemBspTet.cli.main import main
from FemBspTet.fem.cad_mesh import mesh_cad_faces_file

PART = os.path.join(os.path.dirname(__file__), "data", "cad", "bracket.step")
FACES = 13  # the bracket's CAD faces


@pytest.fixture(scope="module")
def faces():
    return {order: mesh_cad_faces_file(PART, order=order) for order in (1, 2)}


def run(argv):
    return main(["mesh", PART, "--dimension", "2", "--quiet"] + argv, supervise=False)


def test_tria3_in_every_format_meshio_reads(tmp_path, faces):
    expected = faces[1]
    outs = [tmp_path / n for n in ("m.vtu", "m.msh", "m.inp", "m.mesh")]
    assert run(sum((["-o", str(o)] for o in outs), [])) == 0
    tri = expected.triangles
    for out in outs:
        m = meshio.read(out)
        assert np.array_equal(m.points, expected.points), out
        cells = [c for c in m.cells if c.type == "triangle"]
        assert sum(len(c.data) for c in cells) == len(tri), out
        assert not [c for c in m.cells if c.type.startswith("tetra")], out
        rows = np.concatenate([c.data for c in cells])
        assert {tuple(sorted(r)) for r in rows.tolist()} == {tuple(sorted(r)) for r in tri.tolist()}
    vtu = meshio.read(tmp_path / "m.vtu")
    assert np.array_equal(np.concatenate(vtu.cell_data["face_id"]), expected.face_tags + 1)
    inp = meshio.read(tmp_path / "m.inp")
    assert sorted(inp.cell_sets) == sorted(["Eall"] + [f"Face{k}" for k in range(1, FACES + 1)])
    for k in range(FACES):
        members = np.concatenate([c for c in inp.cell_sets[f"Face{k + 1}"] if c is not None])
        assert np.array_equal(np.sort(members), np.flatnonzero(expected.face_tags == k))
        assert set(inp.point_sets[f"Face{k + 1}"].tolist()) == \
            set(np.unique(tri[expected.face_tags == k]).tolist())
    medit = meshio.read(tmp_path / "m.mesh")
    assert np.array_equal(np.concatenate(medit.cell_data["medit:ref"]), expected.face_tags + 1)


def test_tria6_through_msh_4_1_and_vtu(tmp_path, faces):
    expected = faces[2]
    assert expected.triangles.shape[1] == 6
    assert run(["--order", "2", "--msh-version", "4.1", "-o", str(tmp_path / "m.msh"),
                "-o", str(tmp_path / "m.vtu")]) == 0
    msh = meshio.read(tmp_path / "m.msh")
    assert sum(len(c.data) for c in msh.cells if c.type == "triangle6") == len(expected.triangles)
    assert {f"Face{k}" for k in range(1, FACES + 1)} <= set(msh.cell_sets)
    assert not [n for n in msh.cell_sets if n.startswith("Solid")]
    vtu = meshio.read(tmp_path / "m.vtu")
    rows = np.concatenate([c.data for c in vtu.cells if c.type == "triangle6"])
    assert np.array_equal(rows, expected.triangles)


@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
def test_calculix_solves_the_s6_shells_through_the_face_sets(tmp_path, faces):
    """One face clamped, a pressure on another, by the sets' names: CalculiX accepts the S6
    deck and the clamped face carries the load (its reaction opposes the pressure's resultant;
    CalculiX's expansion of the shells at the part's edges keeps a few percent of it off the
    set's total)."""
    assert run(["--order", "2", "-o", str(tmp_path / "mesh.inp")]) == 0
    (tmp_path / "job.inp").write_text(
        "*INCLUDE, INPUT=mesh.inp\n*MATERIAL, NAME=STEEL\n*ELASTIC\n210000, 0.3\n"
        "*SHELL SECTION, ELSET=Eall, MATERIAL=STEEL\n1.0\n*STEP\n*STATIC\n*BOUNDARY\n"
        "Face1, 1, 6\n*DLOAD\nFace2, P, 1.0\n*NODE PRINT, NSET=Nall\nU\n"
        "*NODE PRINT, NSET=Face1, TOTALS=ONLY\nRF\n*END STEP\n")
    r = subprocess.run(["ccx", "job"], cwd=tmp_path, capture_output=True, text=True,
                       timeout=600, env=dict(os.environ, OMP_NUM_THREADS="1"))
    assert r.returncode == 0 and "*ERROR" not in r.stdout + r.stderr, r.stdout[-2000:]
    dat = (tmp_path / "job.dat").read_text()
    lines = dat.splitlines()
    at = next(i for i, line in enumerate(lines) if "total force" in line)
    reaction = np.array([float(v) for v in lines[at + 2].split()])
    f = faces[2]
    p = f.points[f.triangles[f.face_tags == 1][:, :3]]
    load = 0.5 * np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]).sum(axis=0)  # pressure 1 x area
    assert np.dot(reaction, load) < 0
    assert 0.85 < np.linalg.norm(reaction) / np.linalg.norm(load) < 1.05


def test_2d_needs_a_cad_file_and_a_2d_format(tmp_path):
    off = os.path.join(os.path.dirname(__file__), "data", "corpus", "cube.off")
    assert main(["mesh", off, "--dimension", "2", "-o", str(tmp_path / "c.vtu")],
                supervise=False) == 2
    assert run(["-o", str(tmp_path / "m.node")]) == 2
    assert run(["-o", str(tmp_path / "m.vtu"), "--compare-tetgen"]) == 2
    assert not os.listdir(tmp_path)


def test_freecad_formats_hold_the_triangles_and_their_groups(tmp_path, faces):
    from FemBspTet.kernel.freecad_env import freecad_available
    if not freecad_available():
        pytest.skip("FreeCAD is not installed")
    from FemBspTet.kernel.freecad_env import import_freecad
    import_freecad()
    import Fem
    expected = faces[2]
    outs = [tmp_path / "m.unv", tmp_path / "m.med"]
    assert run(["--order", "2"] + sum((["-o", str(o)] for o in outs), [])) == 0
    for out in outs:
        fem = Fem.read(str(out))
        assert (fem.NodeCount, fem.FaceCount, fem.VolumeCount) == \
            (len(expected.points), len(expected.triangles), 0), out
        names = {fem.getGroupName(g) for g in fem.Groups}
        assert {f"Face{k}" for k in range(1, FACES + 1)} <= names, out
