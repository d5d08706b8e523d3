# SPDX-License-Identifier: LGPL-2.1-or-later
"""CalculiX's own verdict on our tet10 meshes of CAD parts, with no FreeCAD: each part of
tests/data/cad meshed by the FEM path at its automatic size, one CAD face fixed and another
loaded per group of connected solids through the mesh file's named sets
(FemBspTet.fem.calculix_load_case), solved by ccx. CalculiX
refuses an element whose Jacobian is not positive at its integration points; the solve must
finish, with finite displacements, the fixed faces not moving and the loaded ones moving."""

import os
import shutil

import numpy as np
import pytest

from FemBspTet.fem.cad_mesh import mesh_cad_file
from FemBspTet.fem.calculix_load_case import _face_nodes, _read_displacements, solve_face_load

DATA = os.path.join(os.path.dirname(__file__), "data", "cad")
PARTS = ["bracket.step", "red_cube_blue_cylinder.step", "bottle.brep"]

if shutil.which("ccx") is None:
    pytest.fail("ccx is a declared dependency: run scripts/setup.sh", pytrace=False)


@pytest.mark.parametrize("part", PARTS)
def test_calculix_solves_a_face_load_on_our_tet10_mesh(part, tmp_path):
    result = mesh_cad_file(os.path.join(DATA, part), order=2)
    assert result.mesh.tets.shape[1] == 10
    figures = solve_face_load(result, str(tmp_path))
    assert figures["elements"] == len(result.mesh.tets)
    assert len(figures["loaded_faces"]) == figures["groups"] >= 1
    assert set(figures["fixed_faces"]).isdisjoint(figures["loaded_faces"])
    u = _read_displacements(os.path.join(tmp_path, "job.dat"))
    disp = np.array([u[i + 1] for i in range(len(result.mesh.points))])
    for face in figures["loaded_faces"]:
        assert np.linalg.norm(disp[_face_nodes(result, face - 1)], axis=1).max() > 0
    for face in figures["fixed_faces"]:
        assert np.abs(disp[_face_nodes(result, face - 1)]).max() == 0.0
    # the load went through the named sets only: the pressure on the *SURFACE's element faces
    # is balanced by the reaction on the fixed *NSET (a wrong element face number S1..S4 would
    # put the pressure on other faces, with another resultant)
    applied, reaction = np.array(figures["applied_force"]), np.array(figures["reaction_force"])
    assert figures["loads_touching_fixed_faces"] == 0
    if figures["loaded_faces"]:
        # 1000 N per loaded face; the resultants of several groups may cancel in the sum
        assert np.linalg.norm(applied + reaction) <= 1e-6 * 1000.0 * len(figures["loaded_faces"])
    deck = open(os.path.join(tmp_path, "job.inp")).read()
    assert "*CLOAD" not in deck and "*DSLOAD" in deck
    with open(os.path.join(tmp_path, "job.inp")) as deck:  # CalculiX reads 20-character fields
        assert all(len(field.strip()) <= 20 for line in deck if not line.startswith("*")
                   for field in line.split(","))
    log = open(os.path.join(tmp_path, "ccx.log")).read()
    assert "nonpositive jacobian" not in log.lower() and "*ERROR" not in log
