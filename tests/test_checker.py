# SPDX-License-Identifier: LGPL-2.1-or-later
"""The mesh checker accepts TetGen's meshes and rejects damaged ones (dropped, flipped,
duplicated tets, points moved off the surface, inward shells)."""

import numpy as np
import pytest
from conftest import PAPER_MODELS, corpus_path

from FemBspTet.kernel import core
from FemBspTet.kernel.mesh_types import Surface, TetMesh

DEFECT_KEYS = (
    "inverted_tets", "flat_tets", "overshared_faces", "same_orientation_faces",
    "boundary_faces_off_surface", "boundary_faces_inward", "unpaired_boundary_edges",
    "miscovered_triangles", "duplicate_points", "unreferenced_points", "bad_indices",
)


def _copy(mesh):
    return TetMesh(mesh.points.copy(), mesh.tets.copy())


@pytest.mark.parametrize("name", PAPER_MODELS)
def test_accepts_tetgen_mesh(tetgen_meshes, name):
    surface, mesh = tetgen_meshes[name]
    r = core.check_mesh(surface, mesh)
    assert r["valid"], r["messages"]
    assert all(r[k] == 0 for k in DEFECT_KEYS)
    assert r["volume_equal"]
    assert r["tets"] == len(mesh.tets) and r["points"] == len(mesh.points)
    # The boundary is the input triangulation (TetGen -Y): one boundary face per input triangle.
    assert r["boundary_faces"] == len(surface.triangles)
    assert r["boundary_steiner_points"] == 0
    assert r["steiner_points"] == len(mesh.points) - len(surface.points)
    assert r["tet_volume"] == pytest.approx(core.signed_volume(surface), rel=1e-12)
    q = r["quality"]
    assert 0 < q["min_dihedral_deg"] <= q["median_dihedral_deg"] <= q["max_dihedral_deg"] < 180
    assert sum(q["dihedral_histogram"]) == 6 * len(mesh.tets)


@pytest.mark.parametrize("name", PAPER_MODELS)
def test_rejects_dropped_tet(tetgen_meshes, name):
    surface, mesh = tetgen_meshes[name]
    for k in (0, len(mesh.tets) - 1):
        bad = TetMesh(mesh.points, np.delete(mesh.tets, k, axis=0))
        r = core.check_mesh(surface, bad)
        assert not r["valid"]
        assert not r["volume_equal"]
        assert r["boundary_faces_off_surface"] + r["miscovered_triangles"] + r["unreferenced_points"] > 0


@pytest.mark.parametrize("name", PAPER_MODELS)
def test_rejects_flipped_tet(tetgen_meshes, name):
    surface, mesh = tetgen_meshes[name]
    bad = _copy(mesh)
    bad.tets[2, [0, 1]] = bad.tets[2, [1, 0]]
    r = core.check_mesh(surface, bad)
    assert not r["valid"]
    assert r["inverted_tets"] == 1
    assert any("tet 2 " in m and "inverted" in m for m in r["messages"]), r["messages"]


@pytest.mark.parametrize("name", PAPER_MODELS)
def test_rejects_duplicated_tet(tetgen_meshes, name):
    surface, mesh = tetgen_meshes[name]
    bad = TetMesh(mesh.points, np.vstack([mesh.tets, mesh.tets[:1]]))
    r = core.check_mesh(surface, bad)
    assert not r["valid"]
    assert r["overshared_faces"] + r["same_orientation_faces"] > 0


@pytest.mark.parametrize("name", PAPER_MODELS)
def test_rejects_point_moved_off_surface(tetgen_meshes, name):
    surface, mesh = tetgen_meshes[name]
    # Move input vertex 0 by one ulp in x: the faces around it leave their input triangles.
    bad = _copy(mesh)
    bad.points[0, 0] = np.nextafter(bad.points[0, 0], np.inf)
    r = core.check_mesh(surface, bad)
    assert not r["valid"]
    assert r["boundary_faces_off_surface"] > 0 or r["miscovered_triangles"] > 0


def test_rejects_mesh_of_another_surface(tetgen_meshes):
    surface, _ = tetgen_meshes["dented_box"]
    _, other = tetgen_meshes["box_with_hole"]
    assert not core.check_mesh(surface, other)["valid"]


def test_exact_at_power_of_two_scales(tetgen_meshes):
    surface, mesh = tetgen_meshes["schoenhardt"]
    for s, shift in ((2.0 ** -20, 0.0), (2.0 ** 20, 0.0), (1.0, 2.0 ** 30)):
        sc = Surface(surface.points * s + shift, surface.triangles)
        mc = TetMesh(mesh.points * s + shift, mesh.tets)
        r = core.check_mesh(sc, mc)
        assert r["valid"], (s, shift, r["messages"])


CORPUS_VALID = ("cube", "star", "tinytorus", "joint", "eight", "hinge", "pinion", "anchor")


@pytest.mark.parametrize("name", CORPUS_VALID)
def test_accepts_tetgen_on_corpus(name):
    from FemBspTet.peers.tetgen import run_tetgen
    from FemBspTet.io.surface_io import read_surface

    surface = read_surface(corpus_path(name))
    mesh = run_tetgen(surface, "pY").mesh
    r = core.check_mesh(surface, mesh)
    assert r["valid"], r["messages"]
    assert r["boundary_faces"] == len(surface.triangles)


def test_inward_surface_is_rejected():
    """engine_bracket's surface faces inward (manifest: signed volume < 0): TetGen still meshes it,
    but against the surface as given every boundary face is reversed."""
    from FemBspTet.peers.tetgen import run_tetgen
    from FemBspTet.io.surface_io import read_surface

    surface = read_surface(corpus_path("engine_bracket"))
    assert core.signed_volume(surface) < 0
    mesh = run_tetgen(surface, "pY").mesh
    r = core.check_mesh(surface, mesh)
    assert not r["valid"]
    assert r["boundary_faces_inward"] == len(surface.triangles)
    flipped = Surface(surface.points, surface.triangles[:, [0, 2, 1]])
    assert core.check_mesh(flipped, mesh)["valid"]


def test_tet_quality_of_regular_tet():
    s = 1.0 / np.sqrt(2.0)
    pts = np.array([[1, 0, -s], [-1, 0, -s], [0, 1, s], [0, -1, s]], float)
    tets = np.array([[0, 1, 2, 3]])
    if core.orient3d(*pts[tets[0]]) < 0:
        tets = tets[:, [1, 0, 2, 3]]
    q = core.tet_quality(TetMesh(pts, tets))
    assert q["min_dihedral_deg"] == pytest.approx(np.degrees(np.arccos(1 / 3)), abs=1e-9)
    assert q["max_dihedral_deg"] == pytest.approx(np.degrees(np.arccos(1 / 3)), abs=1e-9)
    assert q["max_radius_edge_ratio"] == pytest.approx(np.sqrt(6) / 4, rel=1e-12)


def test_filled_internal_void_is_rejected():
    """cray_left has an internal void. TetGen -pY without a hole point fills it, so the void's
    triangles end up inside the mesh, not on its boundary: the checker must say so."""
    from FemBspTet.peers.tetgen import run_tetgen
    from FemBspTet.io.surface_io import read_surface

    surface = read_surface(corpus_path("cray_left"))
    mesh = run_tetgen(surface, "pY").mesh
    r = core.check_mesh(surface, mesh)
    assert not r["valid"]
    assert not r["volume_equal"] and r["tet_volume"] > r["surface_volume"]
    # Every triangle of the inner shell is uncovered; the outer shell is the boundary.
    assert r["miscovered_triangles"] == len(surface.triangles) - r["boundary_faces"] > 0
    assert "covered 0 times" in r["messages"][0]
