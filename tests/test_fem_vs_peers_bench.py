# SPDX-License-Identifier: LGPL-2.1-or-later
"""bench/fem_vs_peers.py: its measuring code on hand-made tets with known answers, its process
measurement, and one short run of the whole benchmark on the bracket."""

import importlib.util
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPT = os.path.join(ROOT, "bench", "fem_vs_peers.py")
BRACKET = os.path.join(ROOT, "resources", "samples", "bracket.step")


def _load():
    spec = importlib.util.spec_from_file_location("bench_fem_vs_peers", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


B = _load()

REFERENCE = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
REGULAR = np.array([[1.0, 1, 1], [-1, 1, -1], [1, -1, -1], [-1, -1, 1]])  # det > 0


def straight_tet10(corners):
    """Points and connectivity of one straight tet10 (VTK order) on the given corners."""
    mids = [(corners[i] + corners[j]) / 2 for i, j in B.TET10_EDGES]
    return np.vstack([corners, mids]), np.arange(10)[None, :]


def test_the_report_command_names_no_file_of_this_machine():
    argv = ["--order", "2", "--json", "runs/figures.json", "--workdir=runs", "--out-dir", "out",
            "--timeout", "300", "part.step"]
    assert B.report_argv(argv) == ["--order", "2", "--timeout", "300", "part.step"]


def test_regular_tet_dihedrals_are_all_70_53():
    assert B.corner_volumes6(REGULAR, np.array([[0, 1, 2, 3]]))[0] > 0
    angles = B.dihedral_angles(REGULAR, np.array([[0, 1, 2, 3]]))
    assert angles.shape == (1, 6)
    assert np.allclose(angles, math.degrees(math.acos(1 / 3)), atol=1e-9)
    assert abs(angles[0, 0] - 70.5288) < 1e-4


def test_corner_tet_dihedrals_in_edge_order_and_either_orientation():
    # Edges along the axes meet at right angles; the three slanted edges at acos(1/sqrt 3).
    slanted = math.degrees(math.acos(1 / math.sqrt(3)))
    expected = {(0, 1): 90, (0, 2): 90, (0, 3): 90, (1, 2): slanted, (1, 3): slanted,
                (2, 3): slanted}
    want = [expected[e] for e in B.TET10_EDGES]
    for tet in ([0, 1, 2, 3], [0, 2, 1, 3]):  # positive, then inverted
        got = B.dihedral_angles(REFERENCE, np.array([tet]))[0]
        if tet[1] == 2:
            want_here = [expected[tuple(sorted((tet[i], tet[j])))] for i, j in B.TET10_EDGES]
        else:
            want_here = want
        assert np.allclose(got, want_here, atol=1e-9)
    assert abs(B.worst_dihedral(REFERENCE, np.array([[0, 1, 2, 3]]))[0] - slanted) < 1e-9


def test_flat_tet_has_worst_angle_zero():
    flat = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    assert B.worst_dihedral(flat, np.array([[0, 1, 2, 3]]))[0] == pytest.approx(0.0, abs=1e-6)
    assert B.count_nonpositive_jacobians(flat, np.array([[0, 1, 2, 3]])) == 1


def test_check_points_are_barycentric_and_gauss_rule_integrates_quadratics():
    pts = B.tet10_check_points()
    assert pts.shape == (14, 4)
    assert np.allclose(pts.sum(axis=1), 1.0)
    gauss = pts[10:]
    # Exact for degree 2 on the tet: mean of L0^2 is 2!/(5!/3!) = 1/10, of L0 L1 is 1/20.
    assert np.mean(gauss[:, 0] ** 2) == pytest.approx(0.1, abs=1e-12)
    assert np.mean(gauss[:, 0] * gauss[:, 1]) == pytest.approx(0.05, abs=1e-12)


def test_shape_gradients_sum_to_zero_and_reproduce_a_linear_map():
    x = np.array([[2.0, 0, 0], [0, 3, 0], [0, 0, 5]])
    points, tets = straight_tet10(REFERENCE @ x.T)
    for bary in B.tet10_check_points():
        g = B.tet10_shape_gradients(bary)
        assert np.allclose(g.sum(axis=0), 0.0)  # partition of unity
        assert np.allclose(points[tets[0]].T @ g, x)  # the Jacobian of a straight element
    assert np.allclose(B.jacobian_determinants(points, tets), 30.0)


def test_straight_tet10_jacobian_is_six_volumes_everywhere():
    points, tets = straight_tet10(REGULAR)
    dets = B.jacobian_determinants(points, tets)
    assert dets.shape == (1, 14)
    assert np.allclose(dets, B.corner_volumes6(points, tets)[0])
    assert B.count_nonpositive_jacobians(points, tets) == 0


def test_moved_midnode_jacobian_matches_the_formula():
    # Mid-node of edge (0,1) moved by dx along x: det J = 1 + 4 dx (L0 - L1) on the reference tet.
    for dx in (-0.1, -0.25, 0.2):
        points, tets = straight_tet10(REFERENCE)
        points[4, 0] += dx
        bary = B.tet10_check_points()
        assert np.allclose(B.jacobian_determinants(points, tets)[0],
                           1 + 4 * dx * (bary[:, 0] - bary[:, 1]), atol=1e-12)
    points, tets = straight_tet10(REFERENCE)
    points[4, 0] -= 0.1
    assert B.count_nonpositive_jacobians(points, tets) == 0  # curved but valid: min 0.6
    points[4, 0] -= 0.15
    assert B.count_nonpositive_jacobians(points, tets) == 1  # det 0 at corner 0: not positive


def test_midnode_pushed_through_the_opposite_face_gives_negative_jacobian():
    # Mid-node of edge (0,1) pushed from (0.5, 0, 0) through the face x = 0 (opposite corner 1)
    # to (-0.5, 0, 0): det J = 1 - 4 (L0 - L1), -3 at corner 0. The corner tet is untouched.
    points, tets = straight_tet10(REFERENCE)
    points[4] = (-0.5, 0, 0)
    dets = B.jacobian_determinants(points, tets)[0]
    assert dets[0] == pytest.approx(-3.0)
    assert dets[1] == pytest.approx(5.0)
    assert B.corner_volumes6(points, tets)[0] == pytest.approx(1.0)
    # In a two-element mesh only that element counts, in either orientation convention.
    good_points, good = straight_tet10(REGULAR + 10)
    all_points = np.vstack([points, good_points])
    mesh = np.vstack([tets, good + 10])
    assert B.count_nonpositive_jacobians(all_points, mesh) == 1
    flipped = mesh[:, B.TET10_FLIP]
    assert B.count_nonpositive_jacobians(all_points, flipped) == 2  # both read inverted
    reoriented, was_flipped = B.orient_positive(all_points, flipped)
    assert was_flipped
    assert B.count_nonpositive_jacobians(all_points, reoriented) == 1


def test_flip_permutation_keeps_every_midnode_on_its_edge():
    points, tets = straight_tet10(REGULAR)
    flipped = tets[:, B.TET10_FLIP]
    assert B.corner_volumes6(points, flipped)[0] < 0
    assert B.midnode_offset(points, flipped) == pytest.approx(0.0, abs=1e-15)
    assert np.allclose(B.jacobian_determinants(points, flipped), -B.corner_volumes6(points, tets))


def test_netgen_order_conversion():
    # Netgen: mid-nodes of (0,1) (0,2) (0,3) (1,2) (1,3) (2,3) after the corners.
    netgen_edges = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
    points = np.vstack([REGULAR] + [(REGULAR[i] + REGULAR[j]) / 2 for i, j in netgen_edges])
    netgen = np.arange(10)[None, :]
    assert B.midnode_offset(points, netgen) > 0.5  # read as VTK order it is wrong
    from FemBspTet.peers.netgen import NETGEN_TO_VTK_TET10

    assert B.midnode_offset(points, netgen[:, NETGEN_TO_VTK_TET10]) == pytest.approx(0.0)


def star_mesh(order):
    """Four tets around an interior point (node 4) of a big tet: (points, tets)."""
    corners = REGULAR * 2.0
    points = np.vstack([corners, [[0.0, 0, 0]]])
    # The big tet's outward faces, reversed, with the centre: positive tets.
    tets = np.array([[f[0], f[2], f[1], 4] for f in B.TET_FACES])
    assert (B.corner_volumes6(points, tets) > 0).all()
    if order == 1:
        return points, tets
    mid_id = {}
    rows = []
    for t in tets:
        row = list(t)
        for i, j in B.TET10_EDGES:
            key = frozenset((t[i], t[j]))
            if key not in mid_id:
                mid_id[key] = len(points) + len(mid_id)
            row.append(mid_id[key])
        rows.append(row)
    mids = sorted(mid_id.items(), key=lambda kv: kv[1])
    points = np.vstack([points] + [points[list(k)].mean(axis=0) for k, _ in mids])
    return points, np.array(rows)


def test_boundary_of_a_star():
    points, tets = star_mesh(1)
    local, elements = B.boundary_faces(tets)
    assert len(local) == 4
    assert list(B.boundary_nodes(tets)) == [0, 1, 2, 3]
    points, tets10 = star_mesh(2)
    assert len(points) == 15 and B.midnode_offset(points, tets10) == pytest.approx(0.0)
    nodes = B.boundary_nodes(tets10)
    assert len(nodes) == 10  # 4 corners + the 6 mid-nodes of the big tet's edges
    assert 4 not in nodes
    inner = [n for n in range(15) if n not in nodes]
    assert np.allclose(np.linalg.norm(points[inner], axis=1)[1:],
                       np.linalg.norm(REGULAR[0] * 2) / 2)  # mid-nodes of the spokes
    # The rendered polygons face outward, each a 6-ring corner, mid, corner, ...
    ring, normals = B.boundary_polygons(points, tets10)
    assert ring.shape == (4, 6)
    centres = points[ring[:, ::2]].mean(axis=1)
    assert (np.einsum("ij,ij->i", normals, centres) > 0).all()


def test_cad_distance_is_to_the_faces_not_the_solid(fc):
    _, Part, _ = fc
    box = Part.makeBox(10, 10, 10)
    cad = B.CadDistance(box)
    assert cad(np.array([5.0, 5, 5])) == pytest.approx(5.0)  # inside: 5 from every face
    assert cad(np.array([12.0, 5, 5])) == pytest.approx(2.0)
    assert cad(np.array([5.0, 5, 10])) == pytest.approx(0.0, abs=1e-12)
    assert cad(np.array([13.0, 14, 10])) == pytest.approx(5.0)  # 3-4-5 from an edge
    points = np.array([[0.0, 0, 0], [5, 5, 5], [10, 3, 3], [2, 2, 9]])
    assert B.max_distance_to_cad(points, [0, 2, 3], cad, 0) == (pytest.approx(1.0), 3)
    distance, measured = B.max_distance_to_cad(points, [0, 1, 2, 3], cad, 2)
    assert measured == 2 and distance in (pytest.approx(0.0), pytest.approx(1.0),
                                          pytest.approx(5.0))


def test_run_measured_memory_failure_and_timeout(tmp_path):
    stem = str(tmp_path / "big")
    run = B.run_measured([sys.executable, "-c", "b = b'x' * (300 * 10**6)"], 60, stem)
    assert run.ok and run.returncode == 0 and run.message == ""
    assert run.peak_bytes > 300e6
    run = B.run_measured([sys.executable, "-c", "import sys; print('first', file=sys.stderr); "
                          "sys.exit('the reason')"], 60, str(tmp_path / "fail"))
    assert not run.ok and run.returncode == 1 and run.message == "the reason"
    run = B.run_measured(["sleep", "30"], 1.0, str(tmp_path / "slow"))
    assert not run.ok and "stopped after 1 s" in run.message and run.cpu_seconds is None
    assert 0.9 < run.seconds < 5


def test_benchmark_on_the_bracket(tmp_path):
    out = tmp_path / "out"
    report = tmp_path / "r.json"
    proc = subprocess.run(["/usr/bin/python3", SCRIPT, BRACKET, "--divisions", "20", "--timeout",
                           "120", "--distance-sample", "300", "--out-dir", str(out), "--json",
                           str(report)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "bracket.step D=20" in proc.stderr and "gmsh" in proc.stderr
    (entry,) = json.loads(report.read_text())
    (case,) = entry["cases"]
    assert case["h"] == pytest.approx(entry["diagonal"] / 20)
    for peer in ("gmsh", "netgen"):
        row = case["rows"][peer]
        assert row["ok"], row["message"]
        assert row["order"] == 2 and row["tets"] > 1000 and row["bad_jacobian"] == 0
        assert 5 < row["min_dihedral"] <= row["p1_dihedral"] <= row["median_dihedral"] < 70.6
        assert row["max_distance"] < 1e-6 * entry["diagonal"]  # peers' nodes are on the CAD
        assert row["distance_nodes"] == 300 and row["seconds"] > 0 and row["peak_mb"] > 20
    ours = case["rows"]["ours"]
    if ours["ok"]:
        assert ours["tets"] > 0 and ours["order"] == 2 and ours["max_distance"] is not None
    else:
        assert ours["message"]  # the failure is recorded with its reason
    text = (out / "fem-vs-peers.md").read_text()
    assert "Command: `bench/fem_vs_peers.py " in text and "Gmsh 4.8" in text
    assert "| netgen | ok |" in text
    assert (out / "fem-vs-peers-histograms.png").stat().st_size > 10000
    assert (out / "fem-vs-peers-bracket.png").stat().st_size > 10000


def test_netgen_worker_honours_maxh_on_a_box(fc, tmp_path):
    # Without the global size (set_netgen_global_size) Netgen 6.2.1905 meshes this box with 5
    # tets whatever maxh is.
    _, Part, _ = fc
    step = str(tmp_path / "box.step")
    Part.makeBox(10, 10, 10).exportStep(step)
    counts = {}
    for h in (5.0, 2.0):
        out = str(tmp_path / ("box-%g.vtu" % h))
        run = B.run_measured(B.worker_command("netgen", step, h, 2, out), 120,
                             str(tmp_path / ("netgen-%g" % h)))
        assert run.ok, run.message
        points, tets = B.read_tets(out)
        tets, flipped = B.orient_positive(points, tets)
        assert flipped  # Netgen's convention is negative
        assert B.count_nonpositive_jacobians(points, tets) == 0
        assert B.midnode_offset(points, tets) == pytest.approx(0.0, abs=1e-9)  # all flat here
        edges = np.linalg.norm(points[tets[:, 1]] - points[tets[:, 0]], axis=1)
        assert np.median(edges) < 1.5 * h  # maxh is not a strict bound in Netgen
        counts[h] = len(tets)
    assert counts[5.0] > 5 and counts[2.0] > 4 * counts[5.0]
