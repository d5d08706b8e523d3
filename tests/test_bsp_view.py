# SPDX-License-Identifier: LGPL-2.1-or-later
"""The paper's picture of the BSP (`fembsptet cells`, mesher.h bsp_cells_view): the box around a
surface split by its triangles' planes into convex cells. The cells fill the box, the inside ones
fill the solid, every face of every cell is closed and outward (checked through volumes)."""

import os
import subprocess

import matplotlib.image
import numpy as np
import pytest
from conftest import paper_path

from FemBspTet.io.surface_io import read_surface
from FemBspTet.kernel.core import native, signed_volume


def cell_volume(points, faces):
    """Volume of a closed polyhedron from its faces (cycles counter-clockwise seen from outside):
    sum of the signed volumes of the tets (origin, fan triangle)."""
    total = 0.0
    for face in faces:
        p = points[np.asarray(face)]
        for k in range(1, len(p) - 1):
            total += np.dot(p[0], np.cross(p[k], p[k + 1])) / 6.0
    return total


@pytest.mark.parametrize("model", ["box_with_hole", "schoenhardt", "dented_prism", "dented_box"])
def test_cells_fill_the_box_and_the_inside_ones_the_solid(model):
    surface = read_surface(paper_path(model))
    points, cells, inside = native().bsp_cells_view(surface.points, surface.triangles)
    points = np.asarray(points)
    volumes = np.array([cell_volume(points, faces) for faces in cells])
    assert (volumes > 0).all()  # convex, closed, outward
    lo, hi = points.min(axis=0), points.max(axis=0)
    box = float(np.prod(hi - lo))
    assert volumes.sum() == pytest.approx(box, rel=1e-12)
    solid = signed_volume(surface)
    assert volumes[np.asarray(inside) == 1].sum() == pytest.approx(solid, rel=1e-12)
    assert 0 < sum(inside) < len(cells)


def test_cells_command_draws_a_png(cli, tmp_path):
    out = tmp_path / "cells.png"
    r = subprocess.run([cli, "cells", paper_path("schoenhardt"), "-o", str(out), "--outside",
                        "--size", "300"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "11 cells, 5 inside" in r.stdout
    image = matplotlib.image.imread(str(out))
    assert image.shape[:2] == (300, 300) and (image[:, :, :3] < 0.9).any()
    r = subprocess.run([cli, "cells", paper_path("schoenhardt"), "-o", str(tmp_path / "c.svg")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "PNG" in r.stderr
    assert not os.path.exists(tmp_path / "c.svg")
