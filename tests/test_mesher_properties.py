"""Property tests of the mesher: transformed, scaled and perturbed paper models and corpus models
(real CAD tessellations), random star-shaped polyhedra and twisted prisms. Each output is checked exactly against its input surface (valid, no
Steiner point on the surface). Seeds are fixed and printed, so a failure can be replayed."""

import numpy as np
import pytest
from analytic_surfaces import lat_long_sphere
from conftest import PAPER_MODELS, corpus_path, paper_path

from FemBspTet import core
from FemBspTet.mesh_types import Surface
from FemBspTet.surface_io import read_surface


def _mesh_and_check(surface, label):
    mesh, stats = core.tetrahedralize(surface)
    report = core.check_mesh(surface, mesh)
    assert report["valid"], f"{label}: " + "; ".join(report["messages"])
    assert report["boundary_steiner_points"] == 0, label
    assert stats["tets"] == len(mesh.tets)
    return mesh, stats


def _random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


@pytest.mark.parametrize("model", PAPER_MODELS)
@pytest.mark.parametrize("seed", [11, 12, 13])
@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_rotated_translated_scaled_paper_models(model, seed, scale):
    rng = np.random.default_rng(seed)
    s = read_surface(paper_path(model))
    pts = s.points @ _random_rotation(rng).T * scale + rng.uniform(-1e3, 1e3, size=3) * scale
    print(f"seed {seed} scale {scale:g} model {model}")
    _mesh_and_check(Surface(pts, s.triangles), f"{model} seed {seed} scale {scale:g}")


def _perturbed(path, seed, relative_sizes):
    """The surface at `path` with a third of its points moved by a random multiple of the model
    size times one of `relative_sizes` (a few ulps to 1e-12): coplanar faces become nearly
    coplanar, the hardest case for rounding."""
    rng = np.random.default_rng(seed)
    s = read_surface(path)
    size = np.ptp(s.points, axis=0).max()
    pts = s.points.copy()
    pick = rng.random(len(pts)) < 1 / 3
    pts[pick] += rng.normal(size=(pick.sum(), 3)) * size * rng.choice(relative_sizes)
    print(f"seed {seed} model {path}")
    return Surface(pts, s.triangles)


@pytest.mark.parametrize("model", PAPER_MODELS)
@pytest.mark.parametrize("seed", [21, 22])
def test_near_degenerate_perturbations(model, seed):
    s = _perturbed(paper_path(model), seed, [1e-15, 1e-13, 1e-12])
    _mesh_and_check(s, f"{model} perturbed seed {seed}")


@pytest.mark.parametrize("model,seed,scale", [("hinge", 51, 1e-3), ("pinion", 52, 1e3),
                                              ("anchor", 53, 1.0)])
def test_rotated_translated_scaled_corpus_models(model, seed, scale):
    # A rotation makes every plane of a CAD tessellation generic (none axis-aligned any more).
    rng = np.random.default_rng(seed)
    s = read_surface(corpus_path(model))
    pts = (s.points @ _random_rotation(rng).T) * scale + rng.normal(size=3) * scale * 100
    print(f"seed {seed} scale {scale:g} model {model}")
    _mesh_and_check(Surface(pts, s.triangles), f"{model} seed {seed} scale {scale:g}")


@pytest.mark.parametrize("model,seed", [("hinge", 61), ("pinion", 62)])
def test_near_degenerate_perturbations_of_corpus_models(model, seed):
    # Coplanar patches of a CAD tessellation become nearly coplanar (1e-13 of the size).
    s = _perturbed(corpus_path(model), seed, [1e-13])
    _mesh_and_check(s, f"{model} perturbed seed {seed}")


def star_shaped(rng, n_lat, n_lon):
    """A radial graph over a latitude/longitude sphere triangulation: closed, outward, simple."""
    pts, tris = lat_long_sphere(n_lat, n_lon)
    pts = pts * rng.uniform(0.4, 1.6, size=(len(pts), 1))
    return Surface(pts, tris)


@pytest.mark.parametrize("seed", range(31, 39))
def test_random_star_shaped_polyhedra(seed):
    rng = np.random.default_rng(seed)
    s = star_shaped(rng, int(rng.integers(3, 7)), int(rng.integers(3, 9)))
    assert core.signed_volume(s) > 0
    print(f"seed {seed}: {len(s.points)} points")
    _mesh_and_check(s, f"star-shaped seed {seed}")


def twisted_prism(n, twist_deg, height=1.0):
    """An n-gon prism whose top is turned by `twist_deg`, sides split the 'hard' way (Schönhardt
    for n = 3): no tetrahedralization without Steiner points for large enough twists."""
    ang = 2 * np.pi * np.arange(n) / n
    tw = np.radians(twist_deg)
    bottom = np.c_[np.cos(ang), np.sin(ang), np.zeros(n)]
    top = np.c_[np.cos(ang + tw), np.sin(ang + tw), np.full(n, height)]
    pts = np.vstack([bottom, top])
    tris = []
    for i in range(1, n - 1):
        tris.append((0, i + 1, i))              # bottom, outward -z
        tris.append((n, n + i, n + i + 1))      # top, outward +z
    for i in range(n):
        j = (i + 1) % n
        tris += [(i, j, n + j), (i, n + j, n + i)]
    return Surface(pts, np.array(tris))


@pytest.mark.parametrize("n", [3, 4, 5, 7])
@pytest.mark.parametrize("twist", [10.0, 25.0, 40.0])
def test_twisted_prisms(n, twist):
    s = twisted_prism(n, twist)
    assert core.signed_volume(s) > 0
    _mesh_and_check(s, f"twisted prism n={n} twist={twist}")
