# SPDX-License-Identifier: LGPL-2.1-or-later
"""The `fembsptet` command line, run as a user runs it: through bin/fembsptet."""

import io
import json
import os
import re
import subprocess

import pytest
from conftest import paper_path

from FemBspTet.kernel.mesh_types import TetMesh
from FemBspTet.io.volume_io import write_tet_mesh


ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


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


@pytest.mark.parametrize("model", ["dented_box", "schoenhardt", "box_with_hole", "dented_prism"])
@pytest.mark.parametrize("fmt", [".vtu", ".inp", ".msh"])
def test_mesh_paper_model_is_valid_and_checked_independently(cli, tmp_path, model, fmt):
    out = tmp_path / ("out" + fmt)
    stats_file = tmp_path / "stats.json"
    r = run(cli, "mesh", paper_path(model), "-o", out, "--stats-json", stats_file, "--quiet")
    assert r.returncode == 0, r.stderr
    assert r.stdout == ""  # --quiet
    stats = json.loads(stats_file.read_text())
    from FemBspTet.cli.main import STATS_KEYS

    assert set(STATS_KEYS) <= set(stats)
    # The independent check reads the file back: counts must match what the stats claim.
    r = run(cli, "check", paper_path(model), out, "--json")
    assert r.returncode == 0, r.stdout
    report = json.loads(r.stdout)
    assert report["valid"] is True
    assert report["tets"] == stats["tets"]
    assert report["steiner_points"] == stats["steiner_points"]
    assert report["boundary_steiner_points"] == 0 == stats["boundary_steiner_points"]
    assert sorted(os.listdir(tmp_path)) == sorted([out.name, stats_file.name])


def test_mesh_second_order_is_valid(cli, tmp_path):
    out = tmp_path / "o2.inp"
    r = run(cli, "mesh", paper_path("box_with_hole"), "-o", out, "--order", "2", "--quiet")
    assert r.returncode == 0, r.stderr
    from FemBspTet.io.volume_io import read_tet_mesh

    mesh = read_tet_mesh(str(out))
    assert mesh.tets.shape[1] == 10
    r = run(cli, "check", paper_path("box_with_hole"), out, "--json")
    assert r.returncode == 0, r.stdout
    assert json.loads(r.stdout)["inconsistent_midnodes"] == 0


def test_a_surface_meshes_in_one_process_without_opencascade_or_freecad(tmp_path):
    """The start-up of ``fembsptet mesh SURFACE``: the command runs in this process (no
    supervisor child without --timeout or --max-memory) and loads neither the CAD extension
    (OpenCASCADE's libraries), FreeCAD, nor the comparison, picture and cluster modules."""
    out = tmp_path / "cube.vtu"
    code = (
        "import os, sys\n"
        "from FemBspTet.cli.main import main\n"
        "pid = os.getpid()\n"
        f"rc = main(['mesh', {os.path.join(ROOT, 'tests', 'data', 'corpus', 'cube.off')!r}, '-o', "
        f"{str(out)!r}, '--quiet'])\n"
        "maps = open('/proc/self/maps').read()\n"
        "print(rc, os.getpid() == pid, 'libTKernel' in maps, ' '.join(sorted(m for m in sys.modules if "
        "m.startswith(('FemBspTet._bsptet_cad', 'FreeCAD', 'Part', 'matplotlib', 'distributed', "
        "'FemBspTet.compare', 'FemBspTet.freecad', 'FemBspTet.io.render')))))\n")
    r = subprocess.run(["/usr/bin/python3", "-c", code], capture_output=True, text=True, timeout=120,
                       cwd=ROOT, env={**os.environ, "PYTHONPATH": ROOT})
    assert r.returncode == 0, r.stderr
    rc, same_process, occ, *loaded = r.stdout.split()
    assert rc == "0" and same_process == "True"
    assert occ == "False", "OpenCASCADE's libraries were loaded to mesh a triangle surface"
    assert loaded == [], f"modules the surface path does not need: {loaded}"
    assert out.stat().st_size > 0


def test_mesh_prints_stats_and_tetgen_table(cli, tmp_path):
    r = run(cli, "mesh", paper_path("schoenhardt"), "-o", tmp_path / "s.vtu", "--compare-tetgen",
            "--json")
    assert r.returncode == 0, r.stderr
    head, _, table = r.stdout.partition("}\n")
    stats = json.loads(head + "}")
    assert stats["valid"] is True and stats["tets"] > 0
    lines = [line.split() for line in table.splitlines() if line.strip()]
    heads, ours, tetgen = lines[0], lines[1], lines[2]
    assert ours[0] == "FemBspTet" and tetgen[:2] == ["tetgen", "-pY"]
    assert heads[:3] == ["mesher", "nodes", "tets"]
    assert ours[2] == str(stats["tets"]) and ours[1] == str(stats["points"])
    assert int(ours[3]) + int(ours[4]) == stats["steiner_points"]  # "Steiner in", "Steiner bd"


def test_mesh_open_surface_names_the_triangle_and_writes_nothing(cli, tmp_path):
    src = open(paper_path("schoenhardt")).read().split("\n")
    # Drop the last face line: the surface is open there.
    lines = [x for x in src if x.strip()]
    header = lines[1].split()
    header[1] = str(int(header[1]) - 1)
    lines[1] = " ".join(header)
    bad = tmp_path / "open.off"
    bad.write_text("\n".join(lines[:-1]) + "\n")
    out = tmp_path / "out.vtu"
    r = run(cli, "mesh", bad, "-o", out, "--quiet")
    assert r.returncode == 2, r.stderr
    assert "open" in r.stderr and "triangle" in r.stderr and "open.off" in r.stderr
    assert not out.exists()


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
    from FemBspTet.kernel.freecad_env import freecad_available, import_freecad

    if not freecad_available():
        pytest.skip("FreeCAD is not installed")
    import_freecad()
    import Part

    step = tmp_path / "open.step"
    Part.Shell(Part.makeBox(1, 2, 3).Faces[:5]).exportStep(str(step))
    out = tmp_path / "o.inp"
    r = run(cli, "mesh", step, "-o", out)
    assert r.returncode == 2
    assert "no solid" in r.stderr and "open.step" in r.stderr
    assert not out.exists()


def test_stats_keys_are_documented():
    from FemBspTet.cli.main import STATS_KEYS

    assert set(STATS_KEYS) >= {
        "input_points", "input_triangles", "points", "tets", "steiner_points",
        "boundary_steiner_points", "bsp_nodes", "convex_cells", "min_dihedral_deg",
        "max_dihedral_deg", "max_radius_edge_ratio", "seconds_total", "seconds_by_stage", "valid",
    }


class FakeTerminal(io.StringIO):
    def isatty(self):
        return True


ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


def test_progress_is_silent_for_short_runs_and_plain_lines_off_a_terminal():
    from FemBspTet.kernel.progress import Progress

    buf = io.StringIO()
    p = Progress(stream=buf, delay=1.0)
    p("stage", 0.5)
    assert buf.getvalue() == ""
    p = Progress(stream=buf, delay=0.0)
    for stage, fraction in [("reading", 0.25), ("reading", 0.5), ("meshing", None),
                            ("meshing", 0.9), ("writing", 1.0)]:
        p(stage, fraction)
    p.note("a message")
    p.finish()
    lines = buf.getvalue().splitlines()
    assert [ln.split(" (")[0] for ln in lines] == ["fembsptet: reading", "fembsptet: meshing",
                                                  "fembsptet: writing", "a message"]
    assert "\r" not in buf.getvalue() and "\x1b" not in buf.getvalue()
    quiet = io.StringIO()
    p = Progress(enabled=False, stream=quiet, delay=0.0)
    p("x", 1.0)
    assert quiet.getvalue() == ""


def test_progress_on_an_80_column_terminal_fits_and_never_goes_back(monkeypatch):
    from FemBspTet.kernel.progress import Progress

    monkeypatch.setenv("COLUMNS", "80")
    monkeypatch.setenv("TERM", "xterm")
    term = FakeTerminal()
    p = Progress(stream=term, delay=0.0)
    shown = []
    for stage, fraction in [("a long stage name that is longer than forty characters", 0.3),
                            ("a long stage name that is longer than forty characters", 0.1),
                            ("next", 0.5), ("next", 0.93), ("next", 0.2)]:
        p(stage, fraction)
        p._live.refresh()
        shown.append(p._live.tasks[0].percentage)
    p.note("a message on its own line")
    p.finish()
    assert shown == [30.0, 30.0, 50.0, 93.0, 93.0]  # monotone within a stage
    text = ANSI.sub("", term.getvalue())
    rows = [row for line in text.split("\n") for row in line.split("\r")]
    assert max(len(row) for row in rows) <= 80
    assert any(row.strip() == "a message on its own line" for row in rows)
    assert any("fembsptet next" in row and "93%" in row for row in rows)


def test_progress_in_a_real_80_column_terminal(cli, tmp_path):
    """``fembsptet mesh`` with its stderr on a pseudo-terminal of 80 columns (as an xterm gives),
    a run long enough (about 3 s) for the bar to show: every screen row fits in 80 columns, the percentage never goes back within a stage, and the
    run ends with the summary on stdout."""
    import fcntl
    import pty
    import struct
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    env = dict(os.environ, TERM="xterm")
    env.pop("COLUMNS", None)
    env.pop("LINES", None)
    proc = subprocess.Popen([cli, "mesh", os.path.join(ROOT, "tests", "data", "cad",
                                                       "bracket.step"),
                             "--order", "2", "--size", "2", "-o", str(tmp_path / "b.vtu")],
                            stdout=subprocess.PIPE, stderr=slave, stdin=subprocess.DEVNULL,
                            env=env)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # the slave side closed: the process has ended
            break
        if not data:
            break
        chunks.append(data)
    out, _ = proc.communicate(timeout=300)
    os.close(master)
    assert proc.returncode == 0
    text = ANSI.sub("", b"".join(chunks).decode("utf-8", "replace"))
    rows = [row for line in text.split("\n") for row in line.split("\r")]
    assert max(len(row.rstrip()) for row in rows) <= 80, max(rows, key=len)
    shown = [(m.group(1).strip(), int(m.group(2)))
             for m in re.finditer(r"fembsptet ([^\n\r%]*?)\s+[━╸╺ ]*\s*(\d+)%", text)]
    assert shown, text[-2000:]
    for (stage, a), (next_stage, b) in zip(shown, shown[1:]):
        if stage == next_stage:
            assert b >= a, (stage, a, b)
    assert out.decode().startswith("read ")


def test_mesh_with_stderr_redirected_writes_plain_lines_and_a_summary(cli, tmp_path):
    err = tmp_path / "err.txt"
    out = tmp_path / "o.inp"
    with open(err, "w") as f:
        r = subprocess.run([cli, "mesh", os.path.join(ROOT, "tests", "data", "cad", "bracket.step"),
                            "--order", "2", "-o", out], stdout=subprocess.PIPE, stderr=f,
                           text=True, timeout=300)
    assert r.returncode == 0
    text = err.read_text()
    assert "\r" not in text and "\x1b" not in text
    assert all(line.startswith("fembsptet: ") for line in text.splitlines())
    summary = r.stdout.splitlines()
    assert summary[0].startswith("read ") and "1 solid(s), 13 CAD faces" in summary[0]
    from FemBspTet.io.volume_io import read_tet_mesh

    mesh = read_tet_mesh(out)
    assert summary[1] == (f"wrote    {out}: {len(mesh.points):,} nodes, {len(mesh.tets):,} tet10 "
                          "elements; sets: 13 CAD face(s), 1 solid(s)")
    assert summary[2].startswith("quality  worst dihedral ") and summary[3].startswith("time ")


@pytest.mark.parametrize("cad", ["tests/data/cad/red_cube_blue_cylinder.step", "resources/samples/bracket.step"])
def test_mesh_cad_solid_is_valid(cli, tmp_path, cad):
    from FemBspTet.kernel.freecad_env import freecad_available

    if not freecad_available():
        pytest.skip("FreeCAD is not installed")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = tmp_path / "part.inp"
    stats_file = tmp_path / "stats.json"
    r = run(cli, "mesh", os.path.join(root, cad), "-o", out, "--stats-json", stats_file, "--quiet")
    assert r.returncode == 0, r.stderr
    stats = json.loads(stats_file.read_text())
    # `mesh` checks its mesh exactly before writing; the file must hold what the stats say.
    from FemBspTet.io.volume_io import read_tet_mesh

    mesh = read_tet_mesh(str(out))
    assert stats["valid"] is True and stats["boundary_steiner_points"] == 0
    assert len(mesh.tets) == stats["tets"] and len(mesh.points) == stats["points"]
    assert stats["solids"] >= 1


def test_mesh_bottle_tessellation_is_valid(cli, tmp_path):
    """bottle.brep as the former FreeCAD tessellation pipeline tessellated it: the core used to stop with "could not move
    the surface Steiner point ... inside the solid" (interior points left ulps from the surface
    closed the point's kernel; steiner_removal.h, PUSH). Needs no FreeCAD."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = tmp_path / "bottle.vtu"
    stats_file = tmp_path / "stats.json"
    r = run(cli, "mesh", os.path.join(root, "tests", "data", "cad", "bottle_freecad.off"), "-o", out,
            "--stats-json", stats_file, "--quiet")
    assert r.returncode == 0, r.stderr
    stats = json.loads(stats_file.read_text())
    assert stats["valid"] is True and stats["boundary_steiner_points"] == 0
    assert stats["tets"] > 0


def test_mesh_steiner_effort_bounds_the_interior_removal(cli, tmp_path):
    """``--steiner-effort 1`` leaves the interior Steiner points the expensive phases would take
    (joint: more of them), still a valid mesh with none on the surface; a bad value is refused."""
    joint = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "corpus", "joint.off")
    counts = {}
    for effort in ("1", "0"):
        out = tmp_path / f"joint_{effort}.vtu"
        stats_file = tmp_path / f"joint_{effort}.json"
        r = run(cli, "mesh", joint, "-o", out, "--stats-json", stats_file, "--quiet", "--steiner-effort", effort)
        assert r.returncode == 0, r.stderr
        stats = json.loads(stats_file.read_text())
        r = run(cli, "check", joint, out, "--json")
        assert r.returncode == 0, r.stdout
        report = json.loads(r.stdout)
        assert report["valid"] is True and report["boundary_steiner_points"] == 0
        counts[effort] = stats["steiner_points"]
    assert counts["1"] > counts["0"], counts
    r = run(cli, "mesh", joint, "-o", tmp_path / "x.vtu", "--steiner-effort", "-3")
    assert r.returncode == 2 and "steiner-effort" in r.stderr
    assert not (tmp_path / "x.vtu").exists()


def test_mesh_bsp_seed_picks_where_the_bsp_starts(cli, tmp_path):
    """``--bsp-seed delaunay|box``: the stats say which start made the mesh, both meshes pass the
    checker with no Steiner point on the surface; an unknown value is refused (exit 2)."""
    hinge = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "corpus", "hinge.off")
    for seed in ("delaunay", "box"):
        out = tmp_path / f"hinge_{seed}.vtu"
        stats_file = tmp_path / f"hinge_{seed}.json"
        r = run(cli, "mesh", hinge, "-o", out, "--stats-json", stats_file, "--quiet", "--bsp-seed", seed)
        assert r.returncode == 0, r.stderr
        assert json.loads(stats_file.read_text())["bsp_seed"] == seed
        r = run(cli, "check", hinge, out, "--json")
        assert r.returncode == 0, r.stdout
        assert json.loads(r.stdout)["boundary_steiner_points"] == 0
    r = run(cli, "mesh", hinge, "-o", tmp_path / "x.vtu", "--bsp-seed", "octree")
    assert r.returncode == 2 and "bsp-seed" in r.stderr
    assert not (tmp_path / "x.vtu").exists()


def _boundary_nodes_off_cad(mesh, shape):
    """Largest distance from a boundary node (corners and tet10 mid-nodes of boundary faces) to
    the CAD shape's faces."""
    import Part
    from FemBspTet.fem.mesh_pipeline import boundary_faces_of, boundary_midnodes

    faces = boundary_faces_of(mesh.tets[:, :4])
    nodes = set(faces.reshape(-1).tolist())
    if mesh.tets.shape[1] == 10:
        nodes |= set(boundary_midnodes(mesh, faces).reshape(-1).tolist())
    import FreeCAD

    shell = Part.Compound(shape.Faces)
    worst = 0.0
    for n in sorted(nodes):
        p = mesh.points[n]
        worst = max(worst, shell.distToShape(Part.Vertex(FreeCAD.Vector(*map(float, p))))[0])
    return worst


def test_mesh_cad_puts_tet10_mid_nodes_on_the_cad(cli, tmp_path):
    """A CAD file is meshed by the FEM path: every boundary node of the tet10 mesh (corners and
    mid-nodes, the cylinder's included) lies on the CAD; ``--tessellation`` fills the display
    tessellation with the core instead, its mid-nodes on the chords of the cylinder."""
    from FemBspTet.kernel.freecad_env import freecad_available, import_freecad

    if not freecad_available():
        pytest.skip("FreeCAD is not installed")
    import_freecad()
    import Part

    from FemBspTet.io.volume_io import read_tet_mesh

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    cad = os.path.join(root, "tests", "data", "cad", "red_cube_blue_cylinder.step")
    shape = Part.read(cad)
    off = {}
    for flag in (None, "--tessellation"):
        out = tmp_path / ("tess.vtu" if flag else "fem.vtu")
        args = ["mesh", cad, "-o", out, "--order", "2", "--quiet"] + ([flag] if flag else [])
        r = run(cli, *args)
        assert r.returncode == 0, r.stderr
        mesh = read_tet_mesh(str(out))
        assert mesh.tets.shape[1] == 10
        off[flag] = _boundary_nodes_off_cad(mesh, shape)
    assert off[None] < 1e-6
    assert off["--tessellation"] > 1e-3  # chord sag of the cylinder's tessellation


def test_mesh_refuses_the_former_on_cad_flags(cli, tmp_path):
    """``--on-cad`` and ``--no-straighten-midnodes`` are gone (the FEM path is the default for
    CAD files): argparse refuses them with exit 2 and no file is written."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    cad = os.path.join(root, "tests", "data", "cad", "red_cube_blue_cylinder.step")
    for flag in ("--on-cad", "--no-straighten-midnodes"):
        r = run(cli, "mesh", cad, "-o", tmp_path / "x.vtu", flag)
        assert r.returncode == 2 and "unrecognized arguments: " + flag in r.stderr
    assert not (tmp_path / "x.vtu").exists()


def test_inp_output_refused_when_its_rounding_would_flatten_a_tet(tmp_path):
    """.inp coordinates are rounded to CalculiX's 20-character fields; the mesh as the file
    would hold it is checked exactly first. Here d's x and z differ in the 17th digit only:
    rounded, d lies on the plane z = x through a, b, c and the tet is flat."""
    import numpy as np

    from FemBspTet.kernel import core
    from FemBspTet.cli.main import write_output
    from FemBspTet.kernel.errors import InputError

    pts = np.array([[0, 0, 0], [1, 0, 1], [0, 1, 0],
                    [-0.00012345678901234567, 0.5, -0.00012345678901234564]])
    tet = [0, 1, 2, 3] if core.orient3d(*pts) > 0 else [1, 0, 2, 3]
    mesh = TetMesh(pts, np.array([tet]))
    assert core.check_mesh(core.boundary_surface(mesh), mesh)["valid"]
    write_output(str(tmp_path / "ok.vtu"), mesh)  # exact formats take it
    with pytest.raises(InputError) as exc:
        write_output(str(tmp_path / "bad.inp"), mesh)
    assert "bad.inp" in str(exc.value) and "20 characters" in str(exc.value)
    assert not (tmp_path / "bad.inp").exists()


def test_render_draws_the_boundary_and_a_cut_coloured_by_quality(cli, tmp_path):
    import matplotlib.image

    from FemBspTet.fem.cad_mesh import mesh_cad_file
    from FemBspTet.io.render import render_mesh

    result = mesh_cad_file(os.path.join(ROOT, "tests", "data", "cad", "bracket.step"), order=2)
    mesh_file = tmp_path / "b.msh"
    write_tet_mesh(str(mesh_file), result.mesh, result.groups)
    for extra, name in (([], "b.png"), (["--cut"], "c.png")):
        r = run(cli, "render", mesh_file, "-o", tmp_path / name, "--size", "400", *extra)
        assert r.returncode == 0, r.stderr
        image = matplotlib.image.imread(str(tmp_path / name))
        assert image.shape[:2] == (400, 400)
        assert (image[:, :, :3] < 0.95).any()  # something was drawn on the white page
    assert "of 5," in run(cli, "render", mesh_file, "-o", tmp_path / "d.png").stdout
    # a sliver shows red in the cut view
    sliver = TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0.5, 0.01]], [[0, 1, 2, 3]])
    drawn = render_mesh(sliver, tmp_path / "s.png", cut=True, size_px=300)
    assert drawn["tets"] == 1
    rgb = matplotlib.image.imread(str(tmp_path / "s.png"))[:, :, :3]
    assert ((rgb[:, :, 0] > 0.45) & (rgb[:, :, 1] < 0.25) & (rgb[:, :, 2] < 0.25)).any()
    r = run(cli, "render", mesh_file, "-o", tmp_path / "x.jpg")
    assert r.returncode == 2 and "PNG" in r.stderr
