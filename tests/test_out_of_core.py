# SPDX-License-Identifier: LGPL-2.1-or-later
"""The out-of-core mode: a solid meshed in pieces small enough for a memory budget,
from Python and from the command line. Every mesh is read back and checked exactly against the
input surface (the checker knows nothing of the pieces)."""

import json
import os
import subprocess

import numpy as np
import pytest
from conftest import DATA, corpus_path

from FemBspTet.kernel import core
from FemBspTet.kernel.errors import InputError, MemoryBudgetError
from FemBspTet.kernel.memory_budget import BASE_BYTES
from FemBspTet.io.surface_io import read_surface
from FemBspTet.io.volume_io import read_tet_mesh
from FemBspTet.fem.pieces import OUT_OF_CORE_HOLD_PER_TRIANGLE, tetrahedralize_in_pieces


def budget_for_pieces(surface, piece_triangles):
    """The budget under which tetrahedralize_in_pieces cuts ``surface`` into pieces of about
    ``piece_triangles`` triangles (out_of_core.h's estimate: 32 MiB + 2 KiB per triangle)."""
    return (BASE_BYTES + OUT_OF_CORE_HOLD_PER_TRIANGLE * len(surface.triangles)
            + (32 << 20) + 2048 * piece_triangles)


def assert_valid_mesh_of(surface, mesh):
    report = core.check_mesh(surface, mesh, max_messages=5)
    assert report["valid"], report["messages"]
    assert report["volume_equal"]
    assert report["boundary_steiner_points"] == 0


@pytest.mark.parametrize("name", ["fertility", "knot2", "fandisk"])
def test_pieces_make_one_valid_mesh(name):
    surface = read_surface(corpus_path(name))
    mesh, stats = tetrahedralize_in_pieces(surface, max_memory=budget_for_pieces(surface, 2500), workers=1)
    assert_valid_mesh_of(surface, mesh)
    pieces = stats["pieces"]
    assert pieces["pieces"] >= 3
    assert pieces["largest_piece_triangles"] <= max(2500, 1000) or pieces["uncut"]
    assert stats["tets"] == len(mesh.tets) and stats["points"] == len(mesh.points)
    assert stats["valid"] and pieces["pieces_checked"]
    # The caps' points are interior Steiner points: the input points come first, unchanged.
    n = len(surface.points)
    assert np.array_equal(mesh.points[:n], surface.points)


def test_out_of_core_refuses_what_it_cannot_do():
    surface = read_surface(corpus_path("spot"))
    with pytest.raises(InputError, match="pieces makes the core's mesh only"):
        tetrahedralize_in_pieces(surface, {"size": 0.1}, max_memory=1 << 30)
    with pytest.raises(InputError, match="allow_boundary_steiner"):
        tetrahedralize_in_pieces(surface, {"allow_boundary_steiner": True}, max_memory=1 << 30)
    with pytest.raises(MemoryBudgetError, match="too small even for the out-of-core mode"):
        tetrahedralize_in_pieces(surface, max_memory=64 << 20, workers=1)


def run(cli, *args):
    return subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("fmt", [".vtu", ".node"])
def test_cli_out_of_core_writes_a_valid_mesh(cli, tmp_path, fmt):
    surface = read_surface(corpus_path("fertility"))
    out = tmp_path / ("fertility" + fmt)
    budget = budget_for_pieces(surface, 2500)
    r = run(cli, "mesh", corpus_path("fertility"), "-o", out, "--max-memory", budget, "--out-of-core",
            "--stats-json", tmp_path / "stats.json")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "meshed in" in r.stderr and "pieces" in r.stderr
    stats = json.loads((tmp_path / "stats.json").read_text())
    assert stats["pieces"]["pieces"] >= 3
    assert_valid_mesh_of(surface, read_tet_mesh(str(out)))
    assert not [p for p in os.listdir(tmp_path) if "spool" in p or p.endswith(".part")]


def test_cli_budget_refusal_points_to_out_of_core(cli, tmp_path):
    r = run(cli, "mesh", os.path.join(DATA, "corpus", "fandisk.off"), "-o", tmp_path / "m.vtu",
            "--max-memory", "100M")
    assert r.returncode == 2
    assert "--out-of-core" in r.stderr
    assert not (tmp_path / "m.vtu").exists()


def test_cli_out_of_core_refuses_quality_options(cli, tmp_path):
    r = run(cli, "mesh", corpus_path("spot"), "-o", tmp_path / "m.vtu", "--out-of-core",
            "--max-memory", "1G", "--size", "0.1")
    assert r.returncode == 2
    assert "core's mesh only" in r.stderr and "size" in r.stderr
    assert not (tmp_path / "m.vtu").exists()


def test_benchmark_script_runs_and_checks_every_mesh(tmp_path):
    """bench/out_of_core.py end to end on a small model: the in-memory core, two budgets and
    tetgen -pY, every mesh read back and checked (the figures themselves are the benchmark's)."""
    import sys

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    report = tmp_path / "ooc.md"
    r = subprocess.run([sys.executable, os.path.join(root, "bench", "out_of_core.py"), "--inputs",
                        corpus_path("fertility"), "--budgets", "40M,1G", "--check", "--markdown", report],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    rows = [line for line in report.read_text().splitlines() if line.startswith("| fertility")]
    assert len(rows) == 4  # in memory, two budgets, tetgen -pY
    assert all(row.rstrip(" |").endswith("True") for row in rows), rows
    pieces = [row.split("|")[11].strip() for row in rows]
    assert int(pieces[1]) >= 3 and pieces[2] == "1"  # 40M: several pieces; 1G: one
