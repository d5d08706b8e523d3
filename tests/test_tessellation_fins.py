# SPDX-License-Identifier: LGPL-2.1-or-later
"""Fins of a CAD tessellation (FemBspTet.io.cad_tessellation.flip_out_fins): a near-collinear triangle
along a CAD edge is flipped away inside its face, nothing else changes, and the flat tet it forced
goes with it.

The solid is a unit cube, placed off the origin, whose bottom face (tag 0) and front face (tag 1)
share the edge from corner 0 to corner 1 with one more point b on it, as OpenCASCADE's edge
discretization puts points there. The bottom face's triangulation has the fin (0, 1, b): b lies
in the front face's plane, 1e-7 above the bottom's, so the fin is a real triangle of almost no
area. The meshes go through the core with separate_face_tags.
"""

import numpy as np

from FemBspTet.kernel import core
from FemBspTet.io.cad_tessellation import flip_out_fins
from FemBspTet.kernel.mesh_types import Surface

OFFSET = np.array([103.5, -7.25, 11.0])


def finned_cube():
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    b = (0.5, 0.0, 1e-7)
    points = np.array(corners + [b], dtype=np.float64) + OFFSET
    tris = [
        (0, 1, 8), (0, 2, 1), (0, 3, 2),  # bottom (tag 0): the fin, then the rest
        (0, 8, 5), (8, 1, 5), (0, 5, 4),  # front (tag 1), through b
        (4, 5, 6), (4, 6, 7),             # top
        (3, 7, 6), (3, 6, 2),             # back
        (0, 4, 7), (0, 7, 3),             # left
        (1, 2, 6), (1, 6, 5),             # right
    ]
    tags = [0, 0, 0, 1, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5]
    return Surface(points, np.array(tris), np.array(tags), ["Face%d" % (k + 1) for k in range(6)],
                   "finned cube")


def directed_edges(triangles):
    return [(int(t[k]), int(t[(k + 1) % 3])) for t in triangles for k in range(3)]


def min_dihedral(surface):
    mesh, stats = core.tetrahedralize(surface, options={"separate_face_tags": True})
    assert stats["valid"]
    return stats["min_dihedral_deg"], mesh


def test_the_fin_is_flipped_inside_its_face_and_nothing_else_changes():
    surf = finned_cube()
    core.check_surface(surf)  # a valid input: the fin is thin, not degenerate
    new, st = flip_out_fins(surf)
    assert st == {"fins_before": 1, "fins_after": 0, "flips": 1}
    assert np.array_equal(new.points, surf.points)  # no vertex moves or appears
    assert len(new.triangles) == len(surf.triangles)
    # only the fin and its neighbour across its longest edge changed, into two bottom triangles
    old_set = {tuple(sorted(t)) for t in surf.triangles.tolist()}
    new_set = {tuple(sorted(t)) for t in new.triangles.tolist()}
    assert old_set - new_set == {(0, 1, 8), (0, 1, 2)}
    assert new_set - old_set == {(0, 2, 8), (1, 2, 8)}
    changed = [k for k, t in enumerate(new.triangles.tolist()) if tuple(sorted(t)) in new_set - old_set]
    assert all(new.face_tags[k] == 0 for k in changed)
    assert np.array_equal(np.bincount(new.face_tags), np.bincount(surf.face_tags))
    # still closed and consistently oriented: every directed edge once, and its reverse too
    edges = directed_edges(new.triangles)
    assert len(set(edges)) == len(edges)
    assert all((b, a) in set(edges) for a, b in edges)
    core.check_surface(new)  # the core's exact input check (self-intersections included)


def test_the_flat_tet_on_the_fin_goes_with_it():
    before, _ = min_dihedral(finned_cube())
    new, _ = flip_out_fins(finned_cube())
    after, mesh = min_dihedral(new)
    assert before < 0.01, before  # any tet on the fin is flat
    assert after > 5.0, after
    vol = np.einsum("ij,ij->i", np.cross(mesh.points[mesh.tets[:, 1]] - mesh.points[mesh.tets[:, 0]],
                                         mesh.points[mesh.tets[:, 2]] - mesh.points[mesh.tets[:, 0]]),
                    mesh.points[mesh.tets[:, 3]] - mesh.points[mesh.tets[:, 0]]) / 6
    assert np.all(vol > 0)
    assert abs(vol.sum() - 1.0) < 1e-6


def test_faces_shared_by_two_solids_keep_their_fins():
    surf = finned_cube()
    new, st = flip_out_fins(surf, frozen_tags={0})
    assert new is surf
    assert st == {"fins_before": 1, "fins_after": 1, "flips": 0}


def test_a_fin_whose_long_edge_borders_another_face_is_left():
    # The same cube with the fin's long edge (0, 1) on the front face: the triangle across it
    # has another tag, so flipping would move a CAD edge. Left as it is.
    surf = finned_cube()
    tags = surf.face_tags.copy()
    tags[1] = 1  # the triangle (0, 2, 1) across the fin's long edge now belongs to the front
    odd = Surface(surf.points, surf.triangles, tags, surf.face_names, surf.source)
    new, st = flip_out_fins(odd)
    assert new is odd
    assert st["flips"] == 0 and st["fins_after"] == 1


def test_the_command_line_flips_the_fins_of_a_cad_file():
    """`fembsptet mesh --tessellation part.step` (and `compare`) read CAD files through
    cli.load_input: OpenCASCADE's bottle
    has 12 fins, the surface it meshes only those no flip can mend, with the same vertices."""
    import os

    import pytest

    from FemBspTet.kernel.freecad_env import freecad_available

    if not freecad_available():
        pytest.skip("FreeCAD (Debian package freecad-python3) is not available")
    from FemBspTet.io.cad_tessellation import tessellate_file
    from FemBspTet.cli.main import load_input

    path = os.path.join(os.path.dirname(__file__), "data", "cad", "bottle.brep")
    raw, = tessellate_file(path)
    used, = load_input(path)
    before = flip_out_fins(raw)[1]
    assert before["fins_before"] > before["fins_after"]
    assert flip_out_fins(used)[1] == {"fins_before": before["fins_after"],
                                      "fins_after": before["fins_after"], "flips": 0}
    assert np.array_equal(used.points, raw.points)
    assert len(used.triangles) == len(raw.triangles)
    core.check_surface(used)
