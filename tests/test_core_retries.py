# SPDX-License-Identifier: LGPL-2.1-or-later
"""Inputs on which the core's first attempt gets stuck, and the retries that mesh them.

``tetrahedralize`` (cpp_module/src/core/mesher.cpp) retries when its Steiner removal cannot move a
surface Steiner point inside: first with the other refinement of the covered faces (along whole
input edge lines), then with other BSP partitions (``BspComplex::set_candidate_shift`` 1, 2).
The first attempt starts the BSP from the Delaunay tetrahedralization of the
input points (``bsp_seed`` "auto"); a seeded attempt that fails is retried from the box, the
paper's partition, with the retries above. ``stats["retries"]`` counts the failed attempts, ``stats["bsp_candidate_shift"]`` names the
partition that made the mesh.

* ``regress/bottle_deflection_diag200.off``: ``bottle.brep`` of the public CAD corpus tessellated
  by ``cad_tessellation.tessellate_shape`` at a linear deflection of diag / 200 = 0.4697 mm (what
  the FreeCAD mesher uses at CharacteristicLengthMax = diag / 20). 2,890 triangles, closed, not
  self-intersecting. With the paper's sampling the Steiner removal cannot move the surface
  Steiner point at (-32.92279, -7.472853, 0.647637) (input triangle 1658, a needle 11.3 x 0.56 mm)
  inside, along lines neither; as far as diagnosed, its link holds input points 1254 and 1314,
  which differ by 7e-15 in x and 2e-15 in z (nearly on one line), three Steiner points on that
  line, and a BSP point 1.4e-14 from input point 1314: a plane passing within rounding of an input
  vertex leaves a fan of slivers that no candidate point sees strictly. Candidate shift 1 fails
  too with an older core; since the core's BSP cell ids and RELOCATE's candidate directions,
  shift 1 meshes it.
"""

import os

from FemBspTet.kernel import core
from FemBspTet.io.surface_io import read_surface

HERE = os.path.dirname(os.path.abspath(__file__))


def _bottle():
    return read_surface(os.path.join(HERE, "data", "regress", "bottle_deflection_diag200.off"))


def _valid_without_surface_steiner(s, mesh):
    report = core.check_mesh(s, mesh)
    assert report["valid"], "; ".join(report["messages"])
    assert report["boundary_steiner_points"] == 0


def test_bottle_at_deflection_diag200_meshes_after_retries():
    """The paper's partition (the BSP started from the box) gets stuck and the retries mesh it."""
    s = _bottle()
    mesh, stats = core.tetrahedralize(s, {"bsp_seed": "box"})
    _valid_without_surface_steiner(s, mesh)
    # The path it takes: the first attempt and the one along lines fail, shift 1 makes the mesh
    # (the retries of docs/design/core.md). If a prior attempt starts to succeed, update these
    # figures.
    assert stats["bsp_seed"] == "box"
    assert stats["retries"] == 2
    assert stats["bsp_candidate_shift"] == 1
    assert stats["retried_along_lines"] == 0


def test_bottle_at_deflection_diag200_meshes_at_once_from_the_delaunay_seed():
    """The default start (the Delaunay seed) meshes it at the first attempt: the seed's
    cells are split only by the triangles that cross them, and no plane passes within rounding of
    the needle's corners there."""
    s = _bottle()
    mesh, stats = core.tetrahedralize(s)
    _valid_without_surface_steiner(s, mesh)
    assert stats["bsp_seed"] == "delaunay"
    assert stats["retries"] == 0
    assert stats["seed_fell_back"] == 0
