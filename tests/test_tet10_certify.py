# SPDX-License-Identifier: LGPL-2.1-or-later
"""Validity certificate of 10-node tets through Python (core.certify_tet10, tet10.h): hand-made
elements, a curved mesh from the quality stage, and the shape checks of the binding."""

import numpy as np
import pytest

from analytic_surfaces import icosphere, sphere_projection
from FemBspTet.kernel import core
from FemBspTet.kernel.mesh_types import TetMesh

EDGES10 = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))  # m12 m23 m31 m14 m24 m34


def unit_tet10():
    corners = np.array([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], float)
    mids = np.array([(corners[i] + corners[j]) / 2 for i, j in EDGES10])
    return np.vstack([corners, mids])


def test_straight_valid_and_pushed_mid_node_invalid():
    straight = unit_tet10()
    pushed = unit_tet10()
    pushed[4] = (-2.0, 0.5, 0.5)  # m12 far across the face opposite n2
    points = np.vstack([straight, pushed])
    tets = np.array([np.arange(10), np.arange(10, 20)])
    r = core.certify_tet10(TetMesh(points, tets), scaled_jacobian=True)
    assert (r["certified"], r["invalid"], r["undecided"]) == (1, 1, 0)
    assert r["status"].tolist() == [0, 1]
    assert 0 < r["min_bound"][0] <= 1.0  # det J of the unit tet is 1 everywhere
    assert r["min_bound"][1] <= 0
    assert r["min_scaled_jacobian"][0] == pytest.approx(1.0, abs=1e-12)
    assert r["min_scaled_jacobian"][1] < 0


def test_curved_sphere_mesh_is_certified():
    radius = 2.0
    surface = icosphere(radius, 1)
    mesh, stats = core.tetrahedralize(
        surface, options={"size": radius / 3, "order": 2, "projection": sphere_projection(radius)})
    r = core.certify_tet10(mesh, scaled_jacobian=True)
    assert r["certified"] == len(mesh.tets)
    assert (r["min_bound"] > 0).all()
    assert (r["min_scaled_jacobian"] > 0).all() and (r["min_scaled_jacobian"] <= 1 + 1e-9).all()


def test_shapes_are_checked():
    with pytest.raises(ValueError, match=r"\(m, 10\)"):
        core.certify_tet10(TetMesh(unit_tet10(), np.array([[0, 1, 2, 3]])))
    with pytest.raises(ValueError, match="not a point index"):
        core.certify_tet10(TetMesh(unit_tet10(), np.array([np.arange(1, 11)])))
