"""The `fembsptet` command line, run as a user runs it: through bin/fembsptet."""

import json
import os
import subprocess

import pytest
from conftest import paper_path

from FemBspTet.mesh_types import TetMesh
from FemBspTet.volume_io import write_tet_mesh


def run(cli, *args):
    return subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.fixture()
def schoenhardt(tetgen_meshes, tmp_path):
    surface, mesh = tetgen_meshes["schoenhardt"]
    good = tmp_path / "good.vtu"
    write_tet_mesh(str(good), mesh)
    return surface, mesh, good


def test_version(cli):
    r = run(cli, "--version")
    assert r.returncode == 0 and r.stdout.startswith("fembsptet ")


def test_check_accepts_valid_mesh(cli, schoenhardt):
    _, mesh, good = schoenhardt
    r = run(cli, "check", paper_path("schoenhardt"), good)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "valid: True" in r.stdout
    r = run(cli, "check", paper_path("schoenhardt"), good, "--json")
    assert r.returncode == 0
    report = json.loads(r.stdout)
    assert report["valid"] is True and report["tets"] == len(mesh.tets)
    assert report["steiner_points"] == len(mesh.points) - 6


@pytest.mark.parametrize("fmt", [".msh", ".inp", ".node", ".mesh"])
def test_check_reads_every_volume_format(cli, tetgen_meshes, tmp_path, fmt):
    surface, mesh = tetgen_meshes["box_with_hole"]
    out = tmp_path / ("m" + fmt)
    write_tet_mesh(str(out), mesh)
    r = run(cli, "check", paper_path("box_with_hole"), out)
    assert r.returncode == 0, r.stdout + r.stderr


def test_check_rejects_inverted_tet(cli, schoenhardt, tmp_path):
    _, mesh, _ = schoenhardt
    tets = mesh.tets.copy()
    tets[1, [0, 1]] = tets[1, [1, 0]]
    bad = tmp_path / "bad.vtu"
    write_tet_mesh(str(bad), TetMesh(mesh.points, tets))
    r = run(cli, "check", paper_path("schoenhardt"), bad)
    assert r.returncode == 2
    assert "valid: False" in r.stdout and "tet 1 " in r.stdout and "inverted" in r.stdout
    assert "NOT a valid mesh" in r.stderr


def test_check_missing_and_unknown_files(cli, schoenhardt, tmp_path):
    _, _, good = schoenhardt
    missing = tmp_path / "nope.off"
    r = run(cli, "check", missing, good)
    assert r.returncode == 2 and str(missing) in r.stderr
    weird = tmp_path / "m.xyz"
    weird.write_text("1 2 3\n")
    r = run(cli, "check", paper_path("schoenhardt"), weird)
    assert r.returncode == 2 and "unknown tet mesh format '.xyz'" in r.stderr


def test_mesh_is_not_implemented_yet_and_writes_nothing(cli, tmp_path):
    out = tmp_path / "out.vtu"
    stats = tmp_path / "stats.json"
    r = run(cli, "mesh", paper_path("schoenhardt"), "-o", out, "--stats-json", stats, "--quiet")
    assert r.returncode == 1
    assert "not implemented yet" in r.stderr
    assert not out.exists() and not stats.exists()
    assert os.listdir(tmp_path) == []


def test_mesh_bad_input_exit_2(cli, tmp_path):
    out = tmp_path / "out.vtu"
    r = run(cli, "mesh", tmp_path / "missing.off", "-o", out)
    assert r.returncode == 2 and "missing.off" in r.stderr
    r = run(cli, "mesh", paper_path("schoenhardt"), "-o", tmp_path / "out.docx")
    assert r.returncode == 2 and "unknown output format '.docx'" in r.stderr
    r = run(cli, "mesh", paper_path("schoenhardt"), "-o", out, "--size", "-1")
    assert r.returncode == 2 and "--size" in r.stderr
    truncated = tmp_path / "t.off"
    truncated.write_text("OFF\n4 4 0\n0 0 0\n1 0 0\n")
    r = run(cli, "mesh", truncated, "-o", out)
    assert r.returncode == 2 and "t.off" in r.stderr
    assert not out.exists()


def test_mesh_rejects_open_cad_shell(cli, tmp_path):
    from FemBspTet.freecad_env import freecad_available, import_freecad

    if not freecad_available():
        pytest.skip("FreeCAD is not installed")
    import_freecad()
    import Part

    step = tmp_path / "open.step"
    Part.Shell(Part.makeBox(1, 2, 3).Faces[:5]).exportStep(str(step))
    out = tmp_path / "o.inp"
    r = run(cli, "mesh", step, "-o", out)
    assert r.returncode == 2
    assert "not a solid" in r.stderr and "open.step" in r.stderr
    assert not out.exists()


def test_stats_keys_are_documented():
    from FemBspTet.cli import STATS_KEYS

    assert set(STATS_KEYS) >= {
        "input_points", "input_triangles", "points", "tets", "steiner_points",
        "boundary_steiner_points", "bsp_nodes", "convex_cells", "min_dihedral_deg",
        "max_dihedral_deg", "max_radius_edge_ratio", "seconds_total", "seconds_by_stage", "valid",
    }


def test_progress_bar_is_silent_for_short_runs_and_draws_for_long_ones():
    import io

    from FemBspTet.progress import Progress

    buf = io.StringIO()
    p = Progress(stream=buf, delay=1.0)
    p("stage", 0.5)
    assert buf.getvalue() == ""
    p = Progress(stream=buf, delay=0.0)
    p("reading", 0.25)
    p.finish()
    assert "reading" in buf.getvalue() and "25%" in buf.getvalue()
    quiet = io.StringIO()
    p = Progress(enabled=False, stream=quiet, delay=0.0)
    p("x", 1.0)
    assert quiet.getvalue() == ""
