# SPDX-License-Identifier: LGPL-2.1-or-later
"""Coordinates at any sane scale: models translated far from the origin, alone and with
rotations and scales, mesh as well as the original. Scales 1e-6..1e6 with moderate translations
are in test_mesher_properties.py; here the translation dominates the coordinates (up to 1e8 times
the model size, leaving about 26 bits of the doubles for the shape). Each mesh is checked exactly
against its own (translated) surface."""

import numpy as np
import pytest
from conftest import PAPER_MODELS, corpus_path, paper_path

from FemBspTet.kernel import core
from FemBspTet.kernel.mesh_types import Surface
from FemBspTet.io.surface_io import read_surface

MODELS = [paper_path(m) for m in PAPER_MODELS] + [corpus_path(m) for m in ("cube", "star",
                                                                             "tinytorus")]


def _mesh(surface, label):
    mesh, stats = core.tetrahedralize(surface)
    report = core.check_mesh(surface, mesh)
    assert report["valid"], f"{label}: " + "; ".join(report["messages"])
    assert report["boundary_steiner_points"] == 0, label
    assert report["volume_equal"], label
    return stats


@pytest.fixture(scope="module")
def originals():
    return {path: _mesh(read_surface(path), path) for path in MODELS}


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.rsplit("/", 1)[-1])
@pytest.mark.parametrize("offset", [1e4, 1e6, 1e8, -3.3e7])
@pytest.mark.parametrize("direction", [(1.0, 0.0, 0.0), (1.0, -1.0, 1.0)])
def test_translated_far_meshes_as_well(originals, path, offset, direction):
    s = read_surface(path)
    size = np.ptp(s.points, axis=0).max()
    moved = Surface(s.points + offset * size * np.array(direction), s.triangles)
    label = f"{path} moved by {offset:g} x size along {direction}"
    print(label)
    stats = _mesh(moved, label)
    base = originals[path]
    # As well as the original: the same order of Steiner points and tets (rounding far from the
    # origin may make coplanar faces slightly non-coplanar, which can cost a cut or two).
    assert stats["steiner_points"] <= 2 * base["steiner_points"] + 2, label
    assert stats["tets"] <= 1.5 * base["tets"] + 8, label


@pytest.mark.parametrize("seed", [41, 42])
@pytest.mark.parametrize("scale", [1e-6, 1e6])
def test_rotated_scaled_and_translated_far(seed, scale):
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    s = read_surface(paper_path("dented_prism"))
    pts = (s.points @ q.T) * scale + rng.uniform(1e6, 1e7, size=3) * scale
    print(f"seed {seed} scale {scale:g}")
    _mesh(Surface(pts, s.triangles), f"dented_prism seed {seed} scale {scale:g} far away")
