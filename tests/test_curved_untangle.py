"""Bending interior edges of curved tet10 elements (FemBspTet.curved_untangle): a corner that a
curved boundary face folds over is mended by moving interior mid-nodes only; boundary nodes and
corners never move; no element that was valid becomes invalid; an element with no interior
mid-node is reported as still bad; the Jacobians are those of the pipeline's check."""

import numpy as np

from FemBspTet import curved_untangle as cu
from FemBspTet.mesh_pipeline import tet10_jacobians

EDGES = cu._EDGES


def tet10(corners, bulge=None):
    """Points (10, 3) of a tet10 with straight edges, plus ``bulge`` {edge index: vector}."""
    c = np.asarray(corners, dtype=float)
    mids = np.array([(c[i] + c[j]) / 2 for i, j in EDGES])
    for e, v in (bulge or {}).items():
        mids[e] += v
    return np.vstack([c, mids])


def concave_face_element(delta=0.22):
    """Face (A, B, C) on z = 0 curved up into the tet by ``delta`` at the mid-nodes of AB, CA (a
    concave surface), apex D low over A: corner A's Jacobian is 0.3 - 1.6 delta < 0."""
    corners = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0.2, 0.2, 0.3)]
    up = np.array([0.0, 0.0, delta])
    return tet10(corners, {0: up, 2: up})


def test_jacobians_match_the_pipeline_check():
    rng = np.random.default_rng(7)
    x = rng.normal(size=(20, 10, 3))
    points = x.reshape(-1, 3)
    tets = np.arange(200).reshape(20, 10)
    assert np.allclose(cu.jacobians(x), tet10_jacobians(points, tets), rtol=1e-12, atol=1e-12)


def test_straight_regular_tet_has_the_regular_scaled_jacobian():
    c = np.array([(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)], dtype=float)
    if np.linalg.det(np.array([c[1] - c[0], c[2] - c[0], c[3] - c[0]])) < 0:
        c[[1, 2]] = c[[2, 1]]
    x = tet10(c)
    j = cu.jacobians(x[None])[0]
    _, scale = cu._scales(x, np.arange(10)[None])
    assert np.allclose(j / scale[0], cu.REGULAR_SCALED_JACOBIAN)


def test_a_folded_corner_is_mended_by_bending_interior_edges_only():
    points = concave_face_element()
    tets = np.arange(10)[None]
    before = cu.jacobians(points[tets]).min()
    assert before < 0  # corner A folds
    movable = np.zeros(10, dtype=bool)
    movable[[7, 8, 9]] = True  # mid-nodes of AD, BD, CD; AB, BC, CA are on the boundary
    fixed = points[~movable].copy()
    still, moved = cu.untangle_interior_midnodes(points, tets, [0], movable)
    assert len(still) == 0
    assert set(moved.tolist()) <= {7, 8, 9} and len(moved) > 0
    assert np.array_equal(points[~movable], fixed)  # corners and boundary mid-nodes untouched
    assert cu.jacobians(points[tets]).min() > 0


def test_an_element_without_interior_mid_nodes_stays_bad():
    points = concave_face_element()
    tets = np.arange(10)[None]
    copy = points.copy()
    still, moved = cu.untangle_interior_midnodes(points, tets, [0], np.zeros(10, dtype=bool))
    assert still.tolist() == [0] and len(moved) == 0
    assert np.array_equal(points, copy)


def test_no_valid_neighbour_is_made_invalid():
    """Two elements share the interior edge AD: the bad one and a valid one on the other side
    of the plane through A, D and the x axis; the valid one must stay valid."""
    bad = concave_face_element()
    a, b, c, d = bad[:4]
    e = np.array([0.5, -1.0, 0.1])  # the neighbour (A, D, B', E): shares edge A-D
    neighbour = tet10([a, e, b, d])
    if cu.jacobians(neighbour[None]).min() < 0:
        neighbour = tet10([a, b, e, d])
    points = np.vstack([bad, neighbour])
    tets = np.array([np.arange(10), np.arange(10, 20)])
    # identify the shared nodes: A, D and the mid-node of AD of the neighbour with the first's
    shared = {10: 0, 13: 3}
    mid_ad_first = 4 + EDGES.index((0, 3))
    mid_ad_second = 10 + 4 + EDGES.index((0, 3))
    shared[mid_ad_second] = mid_ad_first
    for k, v in shared.items():
        tets[tets == k] = v
    assert cu.jacobians(points[tets[1:]]).min() > 0
    movable = np.zeros(len(points), dtype=bool)
    movable[[7, 8, 9]] = True
    still, moved = cu.untangle_interior_midnodes(points, tets, [0], movable)
    q = cu.jacobians(points[tets]).min(axis=1)
    assert q[1] > 0  # the valid neighbour stays valid
    assert len(still) == 0 and q[0] > 0
