# SPDX-License-Identifier: LGPL-2.1-or-later
"""`fembsptet compare` and `benchmark`: the table's counts are those of the meshes each mesher
wrote, recomputed here from the files (not literals), by code independent of the package's."""

import collections
import json
import os
import subprocess

import numpy as np
import pytest
from conftest import PAPER_MODELS, ROOT, paper_path

from FemBspTet.io.surface_io import read_surface
from FemBspTet.io.volume_io import read_tet_mesh, read_tetgen

BRACKET = os.path.join(ROOT, "resources", "samples", "bracket.step")


def run(cli, *args, path=None):
    """``fembsptet ARGS`` as bin/fembsptet runs it, optionally with another PATH."""
    env = dict(os.environ, PYTHONPATH=ROOT)
    if path is not None:
        env["PATH"] = path
    return subprocess.run(["/usr/bin/python3", "-m", "FemBspTet.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=300, env=env)


def read_back(row, keep):
    """The mesh of ``row`` as its mesher wrote it in ``keep``."""
    files = row["mesh_files"]
    assert files and all(os.path.dirname(f) == str(keep) for f in files), files
    if row["mesher"].startswith("tetgen"):
        return read_tetgen(os.path.splitext(files[0])[0])
    return read_tet_mesh(files[0])


def recount(surface, mesh):
    """nodes, tets, interior and boundary Steiner points, recomputed from scratch. A node is an
    input vertex when it is within 1e-12 of the bounding-box diagonal of one (Gmsh prints 16
    digits); boundary nodes are the corners of faces used by one tet."""
    diag = np.linalg.norm(surface.points.max(0) - surface.points.min(0))
    dist = np.linalg.norm(mesh.points[:, None, :] - surface.points[None, :, :], axis=2).min(1)
    new = dist > 1e-12 * diag
    faces = collections.Counter()
    for t in mesh.tets[:, :4].tolist():
        for f in ((t[0], t[1], t[2]), (t[0], t[1], t[3]), (t[0], t[2], t[3]), (t[1], t[2], t[3])):
            faces[tuple(sorted(f))] += 1
    on_boundary = np.zeros(len(mesh.points), bool)
    for f, n in faces.items():
        if n == 1:
            on_boundary[list(f)] = True
    return {"nodes": len(mesh.points), "tets": len(mesh.tets),
            "steiner_interior": int((new & ~on_boundary).sum()),
            "steiner_boundary": int((new & on_boundary).sum())}


def compare_and_check(cli, tmp_path, model, *extra):
    keep = tmp_path / "keep"
    out_json = tmp_path / "cmp.json"
    r = run(cli, "compare", model, "--json", out_json, "--keep", keep, *extra)
    assert r.returncode == 0, r.stdout + r.stderr
    data = json.loads(out_json.read_text())
    # the input every mesher got: ours's copy of it (a CAD file's tessellation)
    surface = read_surface(str(keep / "solid0.off"))
    assert data["input_points"] == len(surface.points) and data["solids"] == 1
    table = r.stdout.splitlines()
    for row in data["rows"]:
        assert row["status"] == "ok", row
        assert row["valid"] is True, row
        counts = recount(surface, read_back(row, keep))
        assert {k: row[k] for k in counts} == counts, row["mesher"]
        assert row["steiner_points"] == counts["steiner_interior"] + counts["steiner_boundary"]
        # the printed table carries the same figures
        label = "FemBspTet" if row["mesher"] == "ours" else row["command"].split(" (")[0]
        line = next(x for x in table if x.startswith(label + " "))
        cells = line[len(label):].split()
        assert cells[:4] == [str(counts[k]) for k in ("nodes", "tets", "steiner_interior",
                                                      "steiner_boundary")]
        assert 0 <= row["min_dihedral_deg"] <= row["p1_dihedral_deg"] <= row[
            "median_dihedral_deg"] <= 180
        assert row["seconds"] > 0 and row["peak_rss_mb"] > 0
        assert sum(row["dihedral_histogram"]) == 6 * counts["tets"]
    return data


@pytest.mark.parametrize("name", PAPER_MODELS)
def test_compare_paper_polyhedra(cli, tmp_path, name):
    data = compare_and_check(cli, tmp_path, paper_path(name))
    assert [r["mesher"] for r in data["rows"]] == ["ours", "tetgen-pY", "gmsh"]
    assert data["gmsh_size_note"] == "mean input edge length"
    for row in data["rows"]:  # no Steiner point on the surface: the full check applies
        assert row["steiner_boundary"] == 0 and "boundary = input" in row["checks"]


def test_compare_with_size_adds_tetgen_quality_and_plots(cli, tmp_path):
    png = tmp_path / "h.png"
    data = compare_and_check(cli, tmp_path, paper_path("box_with_hole"), "--size", "0.75",
                             "--plot", png)
    rows = {r["mesher"]: r for r in data["rows"]}
    v = 0.75 ** 3 / (6 * 2 ** 0.5)
    assert rows["tetgen-pq"]["command"] == f"tetgen -pq1.414a{v:.6g}"
    assert rows["gmsh"]["command"] == "gmsh -3 (surface remeshed, CharacteristicLengthMax 0.75)"
    assert rows["gmsh"]["tets"] > 10 * rows["tetgen-pY"]["tets"]  # the size is honoured
    pq = rows["tetgen-pq"]
    assert pq["steiner_boundary"] > 0 and "closed boundary" in pq["checks"]  # not "invalid"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_compare_cad_part_on_its_tessellation(cli, tmp_path):
    data = compare_and_check(cli, tmp_path, BRACKET)
    assert data["input_triangles"] > 100


def test_missing_tetgen_and_gmsh_are_skipped_rows(cli, tmp_path):
    # neither tetgen nor gmsh on PATH
    r = run(cli, "compare", paper_path("dented_box"), "--json", tmp_path / "c.json",
            path=str(tmp_path))
    assert r.returncode == 0, r.stderr
    rows = {x["mesher"]: x for x in json.loads((tmp_path / "c.json").read_text())["rows"]}
    assert rows["ours"]["status"] == "ok" and rows["ours"]["tets"] > 0
    for mesher, program in (("tetgen-pY", "tetgen"), ("gmsh", "gmsh")):
        assert rows[mesher]["status"] == "skipped"
        assert f"{program} is not installed" in rows[mesher]["message"]
        assert f"skipped: {program} is not installed" in r.stdout


def test_timeout_is_a_row_not_a_crash(tmp_path):
    from FemBspTet.compare.comparison import compare

    # our worker alone needs more than 10 ms to start Python
    result = compare(read_surface(paper_path("schoenhardt")), timeout=0.01, meshers=("ours",))
    assert [r.status for r in result.rows] == ["timeout"]
    assert result.rows[0].tets is None and "0.01" in result.rows[0].message


def test_benchmark_report(cli, tmp_path):
    report = tmp_path / "report.md"
    r = run(cli, "benchmark", paper_path("schoenhardt"), paper_path("dented_prism"),
            "--report", report, "--timeout", "60")
    assert r.returncode == 0, r.stdout + r.stderr
    text = report.read_text()
    data = json.loads((tmp_path / "report.json").read_text())
    assert (tmp_path / "report.png").exists() and "](report.png)" in text
    for item in ("CPU", "RAM", "Debian", "TetGen", "Gmsh", "FemBspTet | git "):
        assert item in text
    for e in data["entries"]:
        for row in e["comparison"]["rows"]:
            label = "FemBspTet" if row["mesher"] == "ours" else row["command"].split(" (")[0]
            assert f"| {e['name']} | {label} | {row['nodes']} | {row['tets']} |" in text
    ours = [next(x for x in e["comparison"]["rows"] if x["mesher"] == "ours")
            for e in data["entries"]]
    tg = [next(x for x in e["comparison"]["rows"] if x["mesher"] == "tetgen-pY")
          for e in data["entries"]]
    median_tets = float(np.median([a["tets"] / b["tets"] for a, b in zip(ours, tg)]))
    line = next(x for x in text.splitlines() if x.startswith("| FemBspTet / tetgen -pY | 2 |"))
    assert line.split("|")[4].strip() == f"{median_tets:.3g}"


@pytest.mark.parametrize("name", ["schoenhardt", "dented_prism"])
def test_native_core_row_meshes_like_the_worker_and_is_checked_from_its_files(tmp_path, name):
    """``ours-native`` (bsptet_mesh --no-check, bench/core_vs_tetgen.py): the same mesh as our
    worker's (the same core), read back from the .node/.ele it wrote and checked exactly here;
    with a size it is left out (the core alone makes no quality mesh)."""
    from FemBspTet.compare.comparison import OURS, OURS_NATIVE, compare, core_tool_path

    assert core_tool_path() is not None  # scripts/setup.sh builds it
    surface = read_surface(paper_path(name))
    result = compare(surface, meshers=(OURS, OURS_NATIVE), workdir=str(tmp_path / "w"))
    ours, native = result.row(OURS), result.row(OURS_NATIVE)
    assert native.status == "ok" and native.valid, native.message
    assert (native.nodes, native.tets) == (ours.nodes, ours.tets)
    assert native.steiner_interior == ours.steiner_interior
    mesh = read_tetgen(native.mesh_files[0][:-len(".node")])
    assert len(mesh.tets) == native.tets
    assert [r.mesher for r in compare(surface, size=1.0, meshers=(OURS_NATIVE,)).rows] == []


def test_benchmark_repeats_short_runs_and_takes_their_median(monkeypatch):
    """``run_benchmark(repeats=N)``: a run under a second is made N times (only the meshers that
    were short), its seconds become the median; a long run is not repeated."""
    from FemBspTet.compare import benchmark
    from FemBspTet.compare.comparison import OURS_NATIVE, TETGEN_PY, Comparison, Row

    times = {OURS_NATIVE: iter([0.030, 0.010, 0.020, 0.500, 0.015]),
             TETGEN_PY: iter([5.0])}  # long: must not run again
    calls = []

    def fake_compare(surfaces, size=None, timeout=None, meshers=(), source=""):
        calls.append(tuple(meshers))
        return Comparison(source=source, input_points=0, input_triangles=0, solids=1, size=size,
                          gmsh_size=0.0, gmsh_size_note="",
                          rows=[Row(mesher=m, command=m, seconds=next(times[m]), nodes=8, tets=6,
                                        steiner_interior=0, steiner_boundary=0,
                                        min_dihedral_deg=45.0, p1_dihedral_deg=45.0,
                                        median_dihedral_deg=60.0, max_radius_edge_ratio=0.9,
                                        peak_rss_mb=5.0, valid=True) for m in meshers])

    monkeypatch.setattr(benchmark, "compare", fake_compare)
    entries = benchmark.run_benchmark([paper_path("dented_box")], meshers=(OURS_NATIVE, TETGEN_PY),
                                      repeats=5)
    rows = {r.mesher: r for r in entries[0].comparison.rows}
    assert calls == [(OURS_NATIVE, TETGEN_PY)] + [(OURS_NATIVE,)] * 4
    assert rows[OURS_NATIVE].seconds == 0.020  # median of 0.030 0.010 0.020 0.500 0.015
    assert rows[TETGEN_PY].seconds == 5.0
    text = benchmark.report_markdown(entries, "test", repeats=5)
    assert "made 5 times" in text
