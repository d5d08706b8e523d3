# SPDX-License-Identifier: LGPL-2.1-or-later
"""`fembsptet check PART.step MESH`: a mesh checked against its CAD part (FemBspTet.fem.cad_check):
exact validity by itself, tet10 certified, every boundary node on its CAD face within the face's
tolerance; what fails is named."""

import json
import os
import subprocess

import numpy as np
import pytest

from FemBspTet.kernel.core import boundary_surface
from FemBspTet.fem.cad_check import check_against_cad
from FemBspTet.fem.cad_mesh import mesh_cad_file
from FemBspTet.kernel.mesh_types import TetMesh
from FemBspTet.io.volume_io import read_tet_mesh, write_tet_mesh

DATA = os.path.join(os.path.dirname(__file__), "data", "cad")
PART = os.path.join(DATA, "red_cube_blue_cylinder.step")


@pytest.fixture(scope="module")
def meshed():
    return mesh_cad_file(PART, order=2)


def run(cli, *args):
    return subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("ext", [".msh", ".inp"])
def test_our_tet10_mesh_is_on_the_cad(cli, meshed, tmp_path, ext):
    path = tmp_path / f"m{ext}"
    write_tet_mesh(path, meshed.mesh, meshed.groups)
    r = run(cli, "check", PART, path, "--json")
    assert r.returncode == 0, r.stdout + r.stderr
    report = json.loads(r.stdout)
    assert report["valid"] and report["on_cad"] and report["off_cad_nodes"] == 0
    assert report["tet10_certified"] == len(meshed.mesh.tets)
    assert report["tet10_not_certified"] == 0
    # corners and mid-nodes of every boundary triangle
    boundary = boundary_surface(TetMesh(meshed.mesh.points, meshed.mesh.tets[:, :4]))
    corners = len(np.unique(boundary.triangles))
    assert report["boundary_nodes"] == corners + len(boundary.triangles) * 3 // 2
    # .msh names each triangle's CAD face; .inp has no triangles: the nearest face is searched
    assert report["faces_tagged"] == (report["boundary_nodes"] if ext == ".msh" else 0)
    assert report["max_distance"] <= report["max_distance_tolerance"]


def test_a_boundary_node_moved_off_its_face_is_named(cli, meshed, tmp_path):
    mesh = meshed.mesh
    groups = meshed.groups
    # a mid-node of a triangle of the cube's flat Face9 (z = min), pushed 0.001 into the solid
    tri = groups.face_triangles[groups.face_tags == 8]
    node = int(tri[0, 3])
    points = mesh.points.copy()
    points[node, 2] += 1e-3
    path = tmp_path / "moved.msh"
    write_tet_mesh(path, TetMesh(points, mesh.tets), groups)
    report = check_against_cad(PART, read_tet_mesh(path))
    assert report["valid"] and not report["on_cad"] and report["off_cad_nodes"] == 1
    assert report["max_distance_face"] == 9
    assert report["max_distance"] == pytest.approx(1e-3, rel=1e-9)
    assert f"node {node} at 0.001 from Face9" in report["messages"][-1]
    r = run(cli, "check", PART, path)
    assert r.returncode == 2
    assert "valid, but NOT on the CAD faces" in r.stderr
    assert "1 farther than their face's tolerance" in r.stdout


def test_an_inverted_tet_is_not_valid(cli, meshed, tmp_path):
    mesh = meshed.mesh
    tets = mesh.tets.copy()
    # swap two corners and their mid-nodes accordingly: the element turns inside out
    tets[0] = tets[0][[1, 0, 2, 3, 4, 6, 5, 8, 7, 9]]
    path = tmp_path / "inverted.vtu"
    write_tet_mesh(path, TetMesh(mesh.points, tets))
    r = run(cli, "check", PART, path)
    assert r.returncode == 2
    assert "valid: False" in r.stdout and "NOT a valid mesh" in r.stderr


def test_a_missing_cad_file_is_named(cli, meshed, tmp_path):
    path = tmp_path / "m.vtu"
    write_tet_mesh(path, meshed.mesh)
    r = run(cli, "check", tmp_path / "nope.step", path)
    assert r.returncode == 2 and "nope.step" in r.stderr and "not found" in r.stderr
