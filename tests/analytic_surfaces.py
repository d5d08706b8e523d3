# SPDX-License-Identifier: LGPL-2.1-or-later
"""Closed triangle surfaces of analytic solids, with their exact surface and a projection hook,
for the quality-stage tests (no data files: generated, deterministic)."""

import math

import numpy as np

from FemBspTet.kernel.mesh_types import Surface


def icosphere(radius=1.0, subdivisions=1):
    """A sphere of `radius` about the origin: a subdivided icosahedron, vertices on the sphere
    (up to rounding), outward CCW, one face tag (0)."""
    t = (1.0 + 5 ** 0.5) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    pts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        mid = {}
        nf = []

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                m = pts[a] + pts[b]
                pts.append(m / np.linalg.norm(m))
                mid[key] = len(pts) - 1
            return mid[key]

        for a, b, c in f:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    p = np.array(pts) * radius
    return Surface(p, np.array(f), np.zeros(len(f), np.int32), source="icosphere")


def sphere_projection(radius):
    def project(point, tag, other_tag):
        p = np.asarray(point, float)
        return p * (radius / np.linalg.norm(p))
    return project


def sphere_distance(points, radius):
    return np.abs(np.linalg.norm(points, axis=1) - radius)


def cylinder(radius=1.0, height=2.0, segments=12):
    """A closed cylinder about the z axis from z = 0 to z = height: side tag 0, bottom cap tag 1,
    top cap tag 2 (caps fanned from their centre). Outward CCW."""
    ang = [2 * math.pi * k / segments for k in range(segments)]
    ring = [(radius * math.cos(a), radius * math.sin(a)) for a in ang]
    pts = [(x, y, 0.0) for x, y in ring] + [(x, y, height) for x, y in ring]
    pts += [(0.0, 0.0, 0.0), (0.0, 0.0, height)]
    cb, ct = 2 * segments, 2 * segments + 1
    tris, tags = [], []
    for k in range(segments):
        a, b = k, (k + 1) % segments
        tris += [(a, b, b + segments), (a, b + segments, a + segments)]
        tags += [0, 0]
        tris.append((cb, b, a))
        tags.append(1)
        tris.append((ct, a + segments, b + segments))
        tags.append(2)
    return Surface(np.array(pts), np.array(tris), np.array(tags, np.int32), source="cylinder")


def cylinder_projection(radius, height):
    def onto(p, tag):
        p = np.array(p, float)
        if tag == 0:
            r = math.hypot(p[0], p[1])
            p[0], p[1] = p[0] * radius / r, p[1] * radius / r
        elif tag == 1:
            p[2] = 0.0
        elif tag == 2:
            p[2] = height
        return p

    return two_tag_projection(onto)


def two_tag_projection(onto):
    """The core's hook (point, tag, other_tag) from ``onto(point, tag)``: onto the tag's surface,
    then, on an edge between two tags, onto the other's (their common curve, for the surfaces
    here: a cylinder and a plane perpendicular to its axis)."""
    def project(point, tag, other_tag):
        p = onto(point, tag)
        return onto(p, other_tag) if other_tag >= 0 else p
    return project


def cylinder_distance(points, radius, height):
    """Distance of each point to the closed cylinder's surface (side and caps)."""
    r = np.hypot(points[:, 0], points[:, 1])
    z = points[:, 2]
    side = np.where((z >= 0) & (z <= height), np.abs(r - radius), np.inf)
    bottom = np.where(r <= radius, np.abs(z), np.inf)
    top = np.where(r <= radius, np.abs(z - height), np.inf)
    return np.minimum(side, np.minimum(bottom, top))


def lat_long_sphere(n_lat, n_lon):
    """The unit sphere as a latitude/longitude triangulation: poles 0 and the last point, n_lat - 1
    rings of n_lon points; closed and outward. Returns (points (n, 3), triangles (m, 3))."""
    pts = [(0.0, 0.0, 1.0)]
    for i in range(1, n_lat):
        th = np.pi * i / n_lat
        for j in range(n_lon):
            ph = 2 * np.pi * j / n_lon
            pts.append((np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)))
    pts.append((0.0, 0.0, -1.0))
    ring = lambda i, j: 1 + (i - 1) * n_lon + (j % n_lon)  # noqa: E731
    south = len(pts) - 1
    tris = []
    for j in range(n_lon):
        tris.append((0, ring(1, j), ring(1, j + 1)))
        tris.append((south, ring(n_lat - 1, j + 1), ring(n_lat - 1, j)))
    for i in range(1, n_lat - 1):
        for j in range(n_lon):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
            tris += [(a, c, b), (b, c, d)]
    return np.array(pts), np.array(tris)


def tube(outer=1.0, inner=0.8, height=2.0, segments=12):
    """A closed tube (cylinder with a coaxial cylindrical hole) from z = 0 to z = height: outer
    wall tag 0, inner wall (concave seen from the solid) tag 1, bottom ring tag 2, top ring tag 3.
    Outward CCW."""
    ang = [2 * math.pi * k / segments for k in range(segments)]
    n = segments
    pts = []
    for radius in (outer, inner):
        for z in (0.0, height):
            pts += [(radius * math.cos(a), radius * math.sin(a), z) for a in ang]
    ob, ot, ib, it = 0, n, 2 * n, 3 * n  # first index of each ring
    tris, tags = [], []
    for k in range(n):
        a, b = k, (k + 1) % n
        tris += [(ob + a, ob + b, ot + b), (ob + a, ot + b, ot + a)]  # outer wall, normal out
        tags += [0, 0]
        tris += [(ib + a, it + b, ib + b), (ib + a, it + a, it + b)]  # inner wall, normal to axis
        tags += [1, 1]
        tris += [(ob + a, ib + b, ob + b), (ob + a, ib + a, ib + b)]  # bottom ring, normal -z
        tags += [2, 2]
        tris += [(ot + a, ot + b, it + b), (ot + a, it + b, it + a)]  # top ring, normal +z
        tags += [3, 3]
    return Surface(np.array(pts), np.array(tris), np.array(tags, np.int32), source="tube")


def tube_projection(outer, inner, height):
    def onto(p, tag):
        p = np.array(p, float)
        if tag in (0, 1):
            radius = outer if tag == 0 else inner
            r = math.hypot(p[0], p[1])
            p[0], p[1] = p[0] * radius / r, p[1] * radius / r
        elif tag == 2:
            p[2] = 0.0
        elif tag == 3:
            p[2] = height
        return p

    return two_tag_projection(onto)


def tube_distance(points, outer, inner, height):
    """Distance of each point to the nearest of the tube's four surfaces, untrimmed (what
    tube_projection projects onto: a mid-node of a coarse end-ring edge from the outer to the inner
    circle lies on the plane z = 0 but inside the hole's radius, as on a CAD plane whose
    tessellation cuts across its trimming circle)."""
    r = np.hypot(points[:, 0], points[:, 1])
    z = points[:, 2]
    walls = np.minimum(np.abs(r - outer), np.abs(r - inner))
    ends = np.minimum(np.abs(z), np.abs(z - height))
    return np.minimum(walls, ends)
