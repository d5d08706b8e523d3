# SPDX-License-Identifier: LGPL-2.1-or-later
"""The generators and the exponent fit of bench/scaling.py (the scaling benchmark).

Small sizes only; no mesher runs here (speed and memory are measured by the benchmark itself).
"""

import importlib.util
import math
import os

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _load():
    spec = importlib.util.spec_from_file_location("bench_scaling",
                                                  os.path.join(ROOT, "bench", "scaling.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


S = _load()


def _assert_closed_outward(points, tris, volume, rel=0.05):
    tris = np.asarray(tris)
    # Every directed edge once, and its reverse once: closed and consistently oriented.
    edges = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    directed = set(map(tuple, edges.tolist()))
    assert len(directed) == len(edges), "a directed edge is used twice"
    assert all((b, a) in directed for a, b in directed), "an edge without its reverse"
    assert S.edge_defects(tris) == (0, 0)
    # No degenerate triangle, no duplicate point.
    a, b, c = (points[tris[:, k]] for k in range(3))
    assert (np.linalg.norm(np.cross(b - a, c - a), axis=1) > 0).all()
    assert len(np.unique(points, axis=0)) == len(points)
    assert len(np.unique(tris)) == len(points), "a point used by no triangle"
    # Outward, close to the analytic volume (the inscribed polyhedron is a little smaller).
    v = S.signed_volume(points, tris)
    assert v > 0
    assert abs(v - volume) / volume < rel, (v, volume)


@pytest.mark.parametrize("n", [1, 2, 6, 7])
def test_cube_sphere(n):
    p, t = S.cube_sphere(n)
    assert len(t) == 12 * n * n
    assert len(p) == 6 * n * n + 2  # Euler: V - E + F = 2 with E = 3F/2
    assert np.allclose(np.linalg.norm(p, axis=1), 1.0, atol=1e-15)
    _assert_closed_outward(p, t, S.sphere_volume(), rel=0.05 if n >= 6 else 0.7)
    # Star-shaped from the centre: every triangle is seen counter-clockwise from outside.
    assert (np.einsum("ij,ij->i", p[t[:, 0]], np.cross(p[t[:, 1]], p[t[:, 2]])) > 0).all()


def test_cube_sphere_size():
    n = S.cube_sphere_n(500)
    assert n == 6 and 12 * n * n == 432
    for target in (1e3, 3e3, 1e4, 3e4, 1e5, 3e5, 1e6):
        n = S.cube_sphere_n(target)
        assert abs(12 * n * n / target - 1) < 0.12


# The inscribed grid loses about 1 - (m / 2 pi) sin(2 pi / m) of the tube's cross-section:
# 6.5 % for m = 10 (500 triangles), 1.1 % for m = 24.
@pytest.mark.parametrize("nm,rel", [((25, 10), 0.09), ((60, 24), 0.02), ((12, 5), 0.3),
                                    ((3, 3), 0.99)])
def test_torus(nm, rel):
    n, m = nm
    p, t = S.torus(n, m)
    assert len(t) == 2 * n * m and len(p) == n * m
    _assert_closed_outward(p, t, S.torus_volume(), rel=rel)


def test_torus_size():
    n, m = S.torus_nm(500)
    assert 2 * n * m == 500
    for target in (1e3, 3e3, 1e4, 3e4, 1e5, 3e5, 1e6):
        n, m = S.torus_nm(target)
        assert abs(2 * n * m / target - 1) < 0.05
        assert 0.3 < (m / n) / (S.TORUS_r / S.TORUS_R) < 3  # square-ish quads


def test_make_surface_counts():
    s, note = S.make_surface("sphere", 500)
    assert len(s.triangles) == 432 and "n=6" in note
    s, note = S.make_surface("torus", 500)
    assert len(s.triangles) == 500


def test_fit_exponent_recovers_slope():
    n = np.array([1e3, 3e3, 1e4, 3e4, 1e5])
    slope, coef = S.fit_exponent(n, 2.0 * n ** 1.3)
    assert slope == pytest.approx(1.3, abs=1e-9)
    assert coef == pytest.approx(2.0, rel=1e-9)
    # Noise of +-5 % moves the slope little.
    noise = np.array([1.05, 0.95, 1.03, 0.97, 1.0])
    assert S.fit_exponent(n, 2.0 * n ** 1.3 * noise)[0] == pytest.approx(1.3, abs=0.03)


def test_exponent_text_needs_three_points():
    assert S.exponent_text([1e3, 1e4], [1.0, 10.0]) == "n/a (2 points)"
    assert S.exponent_text([1e3], [1.0]) == "n/a (1 point)"
    assert S.exponent_text([], []) == "n/a (0 points)"
    assert S.exponent_text([1e3, 1e4, 1e5], [1.0, 10.0, 100.0]).startswith("1.00 ")
    with pytest.raises(ValueError):
        S.fit_exponent([1e3], [1.0])


def test_exponents_use_finished_runs_only():
    rows = []
    for tri, status in ((1000, "ok"), (10000, "ok"), (100000, "ok"), (1000000, "timeout")):
        rows.append({"family": "sphere", "mesher": S.OURS, "triangles": tri, "status": status,
                     "seconds": 0.001 * tri ** 1.5 if status == "ok" else 300.0,
                     "cpu_seconds": 0.001 * tri ** 1.5 if status == "ok" else None,
                     "peak_mb": 0.01 * tri})
    e = S.exponents(rows, ["sphere"], [S.OURS])[("sphere", S.OURS)]
    assert e["points"] == 3
    assert e["time"].startswith("1.50 ") and e["cpu"].startswith("1.50 ")
    assert e["memory"].startswith("1.00 ")
    assert math.isclose(float(e["time"].split()[0]), 1.5)


def test_local_slopes_and_timeout_bound():
    rows = [{"family": "torus", "mesher": S.OURS, "triangles": t, "status": st, "seconds": sec}
            for t, st, sec in ((1000, "ok", 1.0), (10000, "ok", 100.0), (100000, "timeout", 300.0),
                               (1000000, "not run", None))]
    text = S.local_slopes(rows, "torus", S.OURS, timeout=1000.0)
    assert text == "2.00, >1.00"
