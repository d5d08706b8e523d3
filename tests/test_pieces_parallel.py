# SPDX-License-Identifier: LGPL-2.1-or-later
"""Pieces meshed at the same time: on threads of one process, and on a Dask cluster started on
loopback the engine's own way (``distributed.LocalCluster``, worker processes). The merged mesh
is checked exactly against the input surface and must be byte for byte the one-thread run's."""

import subprocess

import numpy as np
import pytest
from conftest import corpus_path

from FemBspTet.fem.pieces import tetrahedralize_in_pieces
from FemBspTet.io.surface_io import read_surface
from FemBspTet.io.volume_io import read_tet_mesh, write_tet_mesh
from FemBspTet.kernel import core
from FemBspTet.kernel.errors import InputError, SelfIntersectionError
from FemBspTet.kernel.mesh_types import Surface

PIECE = 3000  # fertility has 9,000 triangles: 5 pieces


def assert_valid_mesh_of(surface, mesh):
    report = core.check_mesh(surface, mesh, max_messages=5)
    assert report["valid"], report["messages"]
    assert report["volume_equal"]
    assert report["boundary_steiner_points"] == 0


def written(mesh, path):
    write_tet_mesh(str(path), mesh)
    return path.with_suffix(".node").read_bytes() + path.with_suffix(".ele").read_bytes()


@pytest.fixture(scope="module")
def fertility():
    surface = read_surface(corpus_path("fertility"))
    mesh, stats = tetrahedralize_in_pieces(surface, workers=1, max_piece_triangles=PIECE)
    assert stats["pieces"]["pieces"] >= 5
    assert_valid_mesh_of(surface, mesh)
    return surface, mesh


def test_threads_make_the_one_thread_mesh(fertility, tmp_path):
    surface, one = fertility
    mesh, stats = tetrahedralize_in_pieces(surface, workers=2, max_piece_triangles=PIECE)
    assert stats["pieces"]["workers"] == 2 and stats["valid"]
    assert written(mesh, tmp_path / "two.node") == written(one, tmp_path / "one.node")


def test_a_local_dask_cluster_makes_the_one_thread_mesh(fertility, tmp_path):
    distributed = pytest.importorskip("distributed")
    surface, one = fertility
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        # An address, as a user on another machine gives it (the engine connects itself).
        mesh, stats = tetrahedralize_in_pieces(surface, scheduler=cluster.scheduler_address,
                                               max_piece_triangles=PIECE)
        assert stats["pieces"]["workers"] == 2  # the cluster's worker count
        with distributed.Client(cluster) as client:
            ran_on = {w["id"] for w in client.scheduler_info()["workers"].values()}
    assert len(ran_on) == 2
    assert stats["pieces"]["pieces_checked"] and stats["pieces"]["pieces"] >= 5
    assert_valid_mesh_of(surface, mesh)
    assert written(mesh, tmp_path / "cluster.node") == written(one, tmp_path / "one.node")


def test_the_cli_meshes_in_parallel(cli, tmp_path, fertility):
    surface, one = fertility
    out = tmp_path / "fertility.node"
    r = subprocess.run([cli, "mesh", corpus_path("fertility"), "-o", str(out), "--workers", "2"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "pieces" in r.stderr and "on 2 thread(s)" in r.stderr
    mesh = read_tet_mesh(str(out))
    assert_valid_mesh_of(surface, mesh)
    same, _ = tetrahedralize_in_pieces(surface, workers=2)
    assert np.array_equal(mesh.tets, same.tets) and np.array_equal(mesh.points, same.points)


def test_pieces_refuse_quality_options_and_bad_counts():
    surface = read_surface(corpus_path("spot"))
    with pytest.raises(InputError, match="core's mesh only"):
        tetrahedralize_in_pieces(surface, {"min_dihedral": 15}, workers=2)
    with pytest.raises(InputError, match="at least 1"):
        tetrahedralize_in_pieces(surface, workers=0)


def test_a_self_intersecting_surface_is_refused_while_the_pieces_run():
    # The self-intersection search runs beside the cutting and meshing: its error is the run's.
    one = read_surface(corpus_path("fertility"))
    shift = 0.1 * np.ptp(one.points, axis=0)
    twice = Surface(np.vstack([one.points, one.points + shift]),
                    np.vstack([one.triangles, one.triangles + len(one.points)]))
    with pytest.raises(SelfIntersectionError):
        tetrahedralize_in_pieces(twice, workers=2, max_piece_triangles=PIECE)
