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


def shared_pair(first, second, shared):
    """Points and (2, 10) tets of two elements, ``shared`` {second's local index: first's}."""
    points = np.vstack([first, second])
    tets = np.array([np.arange(10), np.arange(10, 20)])
    for k, v in shared.items():
        tets[tets == 10 + k] = v
    return points, tets


def test_straightening_makes_a_folded_element_valid_and_pulls_back_as_little_as_it_can():
    """The folded element of the tests above, its boundary mid-nodes (AB, CA) curved 0.22 into
    it and no interior mid-node allowed to help: straighten_midnodes pulls them towards their
    chords, only as far as needed (not all the way: the element is valid half way), and says how
    far each moved. Corners never move."""
    points = concave_face_element()
    tets = np.arange(10)[None]
    corners = points[:4].copy()
    curved = points.copy()
    assert cu.jacobians(points[tets]).min() < 0
    still, pulled, off = cu.straighten_midnodes(points, tets, [0])
    assert len(still) == 0
    assert cu.jacobians(points[tets]).min() > 0
    assert pulled.tolist() == [4, 6]  # the mid-nodes of AB and CA: the only ones off their chords
    assert np.array_equal(points[:4], corners)
    assert np.allclose(off, np.linalg.norm(points[pulled] - curved[pulled], axis=1))
    assert (off > 0).all() and (off < 0.22).all()  # pulled part of the way, never past the chord
    for m, (i, j) in zip(pulled.tolist(), (EDGES[0], EDGES[2])):
        chord = 0.5 * (points[i] + points[j])
        # still on the segment from the chord's midpoint to where it was
        t = np.dot(points[m] - chord, curved[m] - chord) / np.dot(curved[m] - chord,
                                                                    curved[m] - chord)
        assert 0 <= t < 1
        assert np.allclose(points[m], chord + t * (curved[m] - chord))


def test_straightening_keeps_a_neighbour_sharing_a_pulled_mid_node_valid():
    """A valid neighbour below face ABC shares corners A, B and the curved mid-node of AB with
    the folded element: after the pull every element is positive everywhere, the neighbour
    included, and the nodes that were on their chords stay exactly there."""
    bad = concave_face_element()
    a, b = bad[0], bad[1]
    second = tet10([b, a, (0.5, -0.5, 0.0), (0.4, -0.1, -0.6)])
    if cu.jacobians(second[None]).min() < 0:
        second = tet10([a, b, (0.5, -0.5, 0.0), (0.4, -0.1, -0.6)])
    second[4 + EDGES.index((0, 1))] = bad[4]  # the shared, curved mid-node of AB
    assert cu.jacobians(second[None]).min() > 0
    a_in, b_in = (1, 0) if np.array_equal(second[0], b) else (0, 1)
    points, tets = shared_pair(bad, second, {a_in: 0, b_in: 1, 4 + EDGES.index((0, 1)): 4})
    before = points.copy()
    still, pulled, off = cu.straighten_midnodes(points, tets, [0])
    assert len(still) == 0
    assert (cu.jacobians(points[tets]).min(axis=1) > 0).all()
    assert set(pulled.tolist()) <= {4, 6}
    for n in set(np.unique(tets[:, 4:]).tolist()) - {4, 6}:
        assert np.array_equal(points[n], before[n])


def test_inverted_corners_stay_reported():
    """An element whose corners are inverted cannot be mended by mid-nodes: it is returned as
    still bad (and its straight mid-nodes are left alone)."""
    points = tet10([(0, 0, 0), (0, 1, 0), (1, 0, 0), (0, 0, 1)])  # negative orientation
    tets = np.arange(10)[None]
    before = points.copy()
    still, pulled, off = cu.straighten_midnodes(points, tets, [0])
    assert still.tolist() == [0] and len(pulled) == 0
    assert np.array_equal(points, before)
