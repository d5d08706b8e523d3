"""Isotropic remeshing of a face-tagged CAD tessellation, every vertex kept on its CAD face.

Why: OpenCASCADE's BRepMesh tessellates by deflection only. A cylinder or a fillet comes out in
long strips of needle triangles (one triangle across the whole length of the face), planar faces
in fans of slivers. Tets built on such triangles are thin; a 10-node tet next to a curved face
then inverts when its mid-nodes are put on the CAD surface (the chord sag is larger than the
tet), and the quality stage cannot lift the worst dihedral angles of the boundary. Gmsh and
Netgen mesh the CAD surface first with triangles of the target size; this module does the same
for our pipeline, by local operations on the tessellation (after Botsch & Kobbelt, "A remeshing
approach to multiresolution modeling", 2004), with the CAD model as the reference surface.

Contract of :func:`remesh_surface`:

* Input: one closed, outward, face-tagged :class:`~FemBspTet.mesh_types.Surface` of
  :mod:`FemBspTet.cad_tessellation`, and the :class:`~FemBspTet.cad_projection.CadProjection`
  of the same shape.
* Output: a closed, outward surface with the same face tags. Every output vertex is a point of
  the CAD model: a vertex inside one CAD face is on that face (``projection.to_face``), a vertex
  on a CAD edge between faces A and B is on that edge (``projection.to_faces``), and vertices of
  the tessellation where three or more faces meet, or at a CAD vertex, are kept where they are
  and never removed. Triangles never change their tag; CAD edges stay chains of mesh edges.
* Edge lengths are driven towards a size field ``s``: ``min(h, sqrt(8 R d), R a)`` with ``R``
  the smallest radius of curvature of the CAD faces at the vertex, ``d`` the linear deflection
  and ``a`` the angular deflection (so a chord of length ``s`` sags at most ``d`` from the CAD
  face and turns by at most ``a``), that curvature term never below ``min_size`` (``h / 10`` if
  not given); at most the length of a CAD edge at the vertices of that edge (a tiny edge
  between two faces makes small triangles there, never below a given ``min_size``); graded
  (``s`` grows at most ``GRADATION`` times the distance).
* Faces listed in ``frozen_tags`` (faces shared by two solids of a CompSolid, which must stay
  identical on both sides) and their vertices are left untouched.

Operations, each applied only if it passes its checks (otherwise skipped): split edges longer
than 4/3 s at the projected midpoint; collapse edges shorter than 4/5 s (link condition, no
edge longer than 4/3 s made, no fold); flip edges inside a face where the smallest triangle
quality improves; tangential smoothing, each vertex moved towards the centre of its neighbours
(along its CAD edge for edge vertices) and projected back. The fold check compares each new
triangle's normal with the surface normal the tessellation had there (``MAX_FOLD_DEGREES``).
These are geometric heuristics that shape the input of the core, not topology decisions of the
mesh: the core checks the result exactly (closed, oriented, no self-intersection) and the
pipeline falls back to the tessellation itself if the core refuses the remeshed surface.

Deterministic: the same input gives the same output (edges are visited in sorted order).
"""

import math
import time

import numpy as np

from .errors import MeshingCancelled
from .mesh_types import Surface

#: Largest angle between a new triangle's normal and the tessellation's normal there.
MAX_FOLD_DEGREES = 60.0
#: The size field grows at most this much per unit of distance.
GRADATION = 1.0
#: Default number of split / collapse / flip / smooth rounds.
DEFAULT_ITERATIONS = 5
#: Without a minimum size, the size field never goes below h / this.
DEFAULT_MIN_SIZE_OF_H = 10.0

_FACE, _EDGE, _CORNER = 0, 1, 2


# ---- small vector helpers on tuples (faster than numpy for single points) ------------------

def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _norm(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def _dist(a, b):
    return _norm(_sub(a, b))


def _unit(a):
    n = _norm(a)
    return (a[0] / n, a[1] / n, a[2] / n) if n > 0 else (0.0, 0.0, 0.0)


def _quality(p, q, r):
    """4 sqrt(3) area / (sum of squared edge lengths): 1 for an equilateral triangle, 0 for a
    degenerate one."""
    n = _cross(_sub(q, p), _sub(r, p))
    s = _dot(_sub(q, p), _sub(q, p)) + _dot(_sub(r, q), _sub(r, q)) + _dot(_sub(p, r), _sub(p, r))
    return 2.0 * math.sqrt(3.0) * _norm(n) / s if s > 0 else 0.0


def triangle_quality_stats(points, triangles):
    """(minimum, median) of the triangles' quality (see :func:`_quality`) and the smallest
    angle in degrees, vectorized, for the remeshing stats."""
    p = np.asarray(points)[np.asarray(triangles)]
    e0, e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]
    area2 = np.linalg.norm(np.cross(e0, -e2), axis=1)
    s = (e0 * e0).sum(1) + (e1 * e1).sum(1) + (e2 * e2).sum(1)
    q = 2.0 * math.sqrt(3.0) * area2 / np.where(s > 0, s, 1.0)

    def angle(u, v):
        c = (u * v).sum(1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1),
                                        1e-300)
        return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))

    a = np.minimum(np.minimum(angle(e0, -e2), angle(e1, -e0)), angle(e2, -e1))
    return float(q.min()), float(np.median(q)), float(a.min())


def _curved_triangle_measure(x):
    """x: (6, 3) corners a, b, c and mid-nodes of ab, bc, ca of a 6-node triangle. Smallest
    n(L) . n_flat / |n_flat|^2 over the corners, edge midpoints and centroid."""
    nflat = np.cross(x[1] - x[0], x[2] - x[0])
    den = float(nflat @ nflat)
    if not den > 0:
        return -math.inf
    worst = math.inf
    for lam in _TRI_SAMPLES:
        g = []
        for i in range(3):
            gi = (4.0 * lam[i] - 1.0) * x[i]
            for e, (p, q) in enumerate(((0, 1), (1, 2), (2, 0))):
                if p == i:
                    gi = gi + 4.0 * lam[q] * x[3 + e]
                elif q == i:
                    gi = gi + 4.0 * lam[p] * x[3 + e]
            g.append(gi)
        worst = min(worst, float(np.cross(g[1] - g[0], g[2] - g[0]) @ nflat) / den)
    return worst


_TRI_SAMPLES = [np.eye(3)[i] for i in range(3)] + \
    [0.5 * (np.eye(3)[i] + np.eye(3)[(i + 1) % 3]) for i in range(3)] + [np.full(3, 1.0 / 3.0)]


class RemeshError(Exception):
    """The remesher could not make a surface (the caller keeps the tessellation)."""


def remesh_surface(surface, projection, size, linear_deflection, angular_deflection,
                   min_size=0.0, frozen_tags=(), iterations=DEFAULT_ITERATIONS, cancel=None,
                   cad_vertices=None, size_points=None):
    """Remesh ``surface`` towards the size field described in the module docstring.

    surface:            closed face-tagged Surface (``face_tags`` required).
    projection:         ``CadProjection`` of the shape the tags refer to.
    size:               maximum edge length h (> 0).
    linear_deflection:  chord sag bound d (> 0), mm.
    angular_deflection: chord turning bound a (> 0), radians.
    min_size:           smallest target edge length (0: h / DEFAULT_MIN_SIZE_OF_H).
    frozen_tags:        face tags left exactly as they are.
    cancel:             ``cancel()`` returning True raises MeshingCancelled.
    cad_vertices:       (k, 3) points of the CAD vertices (default: all vertices of the faces
                        of ``projection``); tessellation vertices there are kept.
    size_points:        None or (k, 4) rows ``x, y, z, s``: the size field is at most ``s`` at
                        that point, growing by ``GRADATION`` with the distance from it (local
                        refinement asked by the caller, e.g. where curved tet10s inverted).

    Returns ``(Surface, stats)``; stats has the triangle counts, operation counts, the minimum
    and median triangle quality and smallest angle before and after, and seconds.
    Raises RemeshError if the input cannot be remeshed (no tags, not an edge-manifold surface).
    """
    t0 = time.perf_counter()
    if surface.face_tags is None or len(surface.face_tags) != len(surface.triangles):
        raise RemeshError("the surface has no face tags")
    if not (size > 0 and linear_deflection > 0 and angular_deflection > 0):
        raise RemeshError("size and deflections must be positive")
    r = _Remesher(surface, projection, float(size), float(linear_deflection),
                  float(angular_deflection), float(min_size),
                  set(int(t) for t in frozen_tags), cancel, cad_vertices, size_points)
    before = triangle_quality_stats(surface.points, surface.triangles)
    for _ in range(max(0, int(iterations))):
        r.split_long_edges()
        r.collapse_short_edges()
        r.flip_edges()
        r.fix_ears()
        r.smooth()
    r.flip_edges()
    r.fix_ears()
    out = r.surface()
    after = triangle_quality_stats(out.points, out.triangles)
    stats = {
        "triangles_before": int(len(surface.triangles)), "triangles_after": int(len(out.triangles)),
        "splits": r.count["split"], "collapses": r.count["collapse"], "flips": r.count["flip"],
        "moves": r.count["move"], "refused": r.count["refused"],
        "ears_removed": r.count.get("ears", 0),
        "min_quality_before": before[0], "median_quality_before": before[1],
        "min_angle_deg_before": before[2],
        "min_quality_after": after[0], "median_quality_after": after[1],
        "min_angle_deg_after": after[2],
        "seconds": time.perf_counter() - t0,
    }
    return out, stats


#: A curved (6-node) boundary triangle counts as folded where its area element, relative to
#: the flat triangle's, drops below this anywhere it is sampled (:func:`repair_curved_folds`).
CURVED_FOLD_THRESHOLD = 0.0
#: Rounds of :func:`repair_curved_folds` at most.
FOLD_REPAIR_ROUNDS = 8
#: Generations of split points :func:`repair_curved_folds` may make around one fold.
MAX_FOLD_SPLIT_DEPTH = 4


def repair_curved_folds(surface, projection, frozen_tags=(), rounds=FOLD_REPAIR_ROUNDS,
                        cancel=None, cad_vertices=None):
    """Change the tessellation only where its curved tet10 version would fold.

    A tet10 mid-node of a surface edge goes onto the CAD face (or onto the CAD edge of its two
    faces). Where a tessellation triangle is a needle along a curved CAD edge or a sliver face
    that tapers to a point, its two long edges bulge by different amounts and the curved
    triangle folds over near its sharp corner: every tet on it then has a negative Jacobian
    there, whatever is done inside. This finds the triangles whose 6-node version (corners and
    the CAD points of their edges' midpoints) has an area element below
    ``CURVED_FOLD_THRESHOLD`` times the flat one's somewhere (corners, edge midpoints, centroid),
    and mends each one locally: by flipping one of its edges inside its CAD face when both new
    triangles are better, or else by splitting its edge of largest sag at that edge's CAD point
    (which divides the sag by four). Nothing else moves: no smoothing, no collapse, no size
    field; the rest of the tessellation stays exactly as it was. Faces in ``frozen_tags`` are
    left alone.

    Returns ``(Surface, stats)`` with stats ``folded_before``, ``folded_after``, ``flips``,
    ``splits``, ``rounds``, ``seconds``. Raises RemeshError as :func:`remesh_surface`.
    """
    t0 = time.perf_counter()
    if surface.face_tags is None or len(surface.face_tags) != len(surface.triangles):
        raise RemeshError("the surface has no face tags")
    r = _Remesher(surface, projection, math.inf, 1.0, 1.0, 0.0,
                  set(int(t) for t in frozen_tags), cancel, cad_vertices, repair=True)
    folded = r.folded_triangles()
    before = len(folded)
    done = 0
    for done in range(1, max(0, int(rounds)) + 1):
        if not folded:
            done -= 1
            break
        changed = False
        for t in folded:
            r.check_cancel()
            if r.T[t] is None or r.curved_measure(r.T[t], r.tag[t]) > CURVED_FOLD_THRESHOLD:
                continue
            changed = r.mend_fold(t) or changed
        folded = r.folded_triangles()
        if not changed:
            break
    stats = {"folded_before": before, "folded_after": len(folded), "flips": r.count["flip"],
             "splits": r.count["split"], "rounds": done,
             "seconds": time.perf_counter() - t0}
    if before == 0:
        return surface, stats
    return r.surface(), stats


#: :func:`refine_around_points`: triangles of lower quality (:func:`_quality`) get their longest
#: edge split.
NEEDLE_QUALITY = 0.5
#: :func:`refine_around_points`: passes of splits and flips at most.
LOCAL_REFINE_PASSES = 6


def refine_around_points(surface, projection, points, frozen_tags=(),
                         passes=LOCAL_REFINE_PASSES, cancel=None, cad_vertices=None):
    """Make the tessellation's triangles around ``points`` well shaped, leaving the rest alone.

    For tet10 next to curved faces: the elements that stay invalid after curving sit on needle
    triangles of the CAD tessellation (a long thin triangle of a planar ring beside a small hole,
    a strip of a narrow fillet), where every tet on them is as thin as the needle is narrow and
    the chord sag of its curved edges is a large part of that. Triangles with a vertex at one of
    ``points`` (coordinates; (k, 3)), and the halves split from them, are treated in passes:
    each one whose quality is below ``NEEDLE_QUALITY`` gets its longest edge split at that
    edge's CAD point (on the CAD edge when the edge joins two faces; at most
    ``MAX_FOLD_SPLIT_DEPTH`` generations of new points), then the region's edges are flipped
    inside their CAD faces where that makes the worse triangle better (no fold, no crease).
    Tessellation vertices never move; faces in ``frozen_tags`` are left alone.

    Returns ``(Surface, stats)`` with stats ``region_triangles``, ``splits``, ``flips``,
    ``passes``, ``seconds``. Raises RemeshError as :func:`remesh_surface`.
    """
    t0 = time.perf_counter()
    if surface.face_tags is None or len(surface.face_tags) != len(surface.triangles):
        raise RemeshError("the surface has no face tags")
    r = _Remesher(surface, projection, math.inf, 1.0, 1.0, 0.0,
                  set(int(t) for t in frozen_tags), cancel, cad_vertices, repair=True)
    keys = {tuple(p) for p in np.asarray(points, dtype=np.float64).reshape(-1, 3).tolist()}
    region = {t for v, p in enumerate(r.P) if p in keys for t in r.VT[v]}
    stats = {"region_triangles": len(region), "splits": 0, "flips": 0, "passes": 0,
             "seconds": 0.0}
    if not region:
        stats["seconds"] = time.perf_counter() - t0
        return surface, stats
    splits0, flips0 = r.count["split"], r.count["flip"]
    for done in range(1, max(0, int(passes)) + 1):
        r.check_cancel()
        stats["passes"] = done
        changed = False
        for t in sorted((t for t in region if r.tag[t] not in r.frozen),
                        key=lambda t: (r.tri_quality(r.T[t]), t)):
            tri = r.T[t]
            if tri is None or r.tri_quality(tri) >= NEEDLE_QUALITY:
                continue
            first_new = len(r.T)
            ts = r.bisect_longest_edge(tri)
            if ts is not None:
                # the halves of a region triangle stay in the region (its neighbour's do not)
                region.update(first_new + k for k, t2 in enumerate(ts) if t2 in region)
                changed = True
        for a, b in sorted({(min(x, y), max(x, y)) for t in region if r.T[t] is not None
                            for x, y in zip(r.T[t], r.T[t][1:] + r.T[t][:1])}):
            ts = sorted(r.edge_tris(a, b))
            if len(ts) == 2 and r.tag[ts[0]] == r.tag[ts[1]] and r.flip(a, b, ts):
                changed = True
        if not changed:
            break
    stats["splits"] = r.count["split"] - splits0
    stats["flips"] = r.count["flip"] - flips0
    stats["seconds"] = time.perf_counter() - t0
    if stats["splits"] == 0 and stats["flips"] == 0:
        return surface, stats
    return r.surface(), stats



#: :func:`flip_out_fins`: a triangle whose largest angle exceeds this (degrees) is a fin.
FIN_ANGLE_DEGREES = 175.0


def _largest_angle(p, q, r):
    """Largest angle of triangle (p, q, r) in degrees, and the index (0, 1, 2) of its vertex."""
    best, at = -1.0, 0
    for k, (x, y, z) in enumerate(((p, q, r), (q, r, p), (r, p, q))):
        u, v = _sub(y, x), _sub(z, x)
        nu, nv = _norm(u), _norm(v)
        if nu == 0 or nv == 0:
            return 180.0, k
        a = math.degrees(math.acos(max(-1.0, min(1.0, _dot(u, v) / (nu * nv)))))
        if a > best:
            best, at = a, k
    return best, at


def flip_out_fins(surface, frozen_tags=(), fin_angle=FIN_ANGLE_DEGREES):
    """Flip away the fins of a CAD tessellation: triangles whose largest angle exceeds
    ``fin_angle`` (OpenCASCADE makes them where three points of one CAD edge, or of a face's
    boundary, are nearly collinear: a triangle of almost no area). Every tet on a fin is flat,
    whatever the volume mesher does, and it inverts as soon as a tet10 mid-node moves.

    A fin (b, c, a) with its largest angle at b is removed by flipping its longest edge (c, a)
    with the triangle (a, c, x) across it, into (b, c, x) and (b, x, a), when that triangle has
    the same face tag (not in ``frozen_tags``), the edge (b, x) is not already an edge, both new
    triangles face the way (a, c, x) did, and their largest angles are both below the fin's.
    No vertex moves or is added, so every vertex stays where the tessellation put it (on its CAD
    face); triangles keep their face's tag. Passes until nothing changes (each flip lowers the
    largest angle of the pair it replaces; at most 4 passes).

    Returns ``(Surface, stats)``; stats: ``fins_before``, ``fins_after``, ``flips``. The input
    is returned unchanged when no flip was made.
    """
    P = [tuple(p) for p in np.asarray(surface.points, dtype=np.float64).tolist()]
    T = [list(t) for t in np.asarray(surface.triangles).tolist()]
    tags = None if surface.face_tags is None else [int(t) for t in surface.face_tags.tolist()]
    frozen = set(int(t) for t in frozen_tags)
    edge_tri = {}
    for i, t in enumerate(T):
        for k in range(3):
            edge_tri[(t[k], t[(k + 1) % 3])] = i

    def largest(t):
        return _largest_angle(P[t[0]], P[t[1]], P[t[2]])

    before = sum(1 for t in T if largest(t)[0] > fin_angle)
    flips = 0
    for _ in range(4):
        changed = False
        for i in range(len(T)):
            t = T[i]
            angle, k = largest(t)
            if angle <= fin_angle:
                continue
            b, c, a = t[k], t[(k + 1) % 3], t[(k + 2) % 3]
            j = edge_tri.get((a, c))
            if j is None or j == i:
                continue
            if tags is not None and (tags[j] != tags[i] or tags[i] in frozen):
                continue
            s = T[j]
            x = [v for v in s if v != a and v != c][0]
            if x == b or (b, x) in edge_tri or (x, b) in edge_tri:
                continue
            n_s = _cross(_sub(P[c], P[a]), _sub(P[x], P[a]))
            new = ([b, c, x], [b, x, a])
            ok = True
            for u in new:
                n_u = _cross(_sub(P[u[1]], P[u[0]]), _sub(P[u[2]], P[u[0]]))
                if not _dot(n_u, n_s) > 0 or not largest(u)[0] < angle:
                    ok = False
                    break
            if not ok:
                continue
            for tri in (t, s):
                for m in range(3):
                    del edge_tri[(tri[m], tri[(m + 1) % 3])]
            T[i], T[j] = new[0], new[1]
            for idx in (i, j):
                for m in range(3):
                    edge_tri[(T[idx][m], T[idx][(m + 1) % 3])] = idx
            flips += 1
            changed = True
        if not changed:
            break
    after = sum(1 for t in T if largest(t)[0] > fin_angle)
    stats = {"fins_before": before, "fins_after": after, "flips": flips}
    if flips == 0:
        return surface, stats
    return Surface(surface.points, np.asarray(T, dtype=np.int64), surface.face_tags,
                   surface.face_names, surface.source), stats


class _Remesher:
    def __init__(self, surface, projection, h, defl, ang, min_size, frozen, cancel, cad_vertices,
                 size_points=None, repair=False):
        sp = np.zeros((0, 4)) if size_points is None else np.asarray(size_points, dtype=float)
        self.size_points = sp.reshape(-1, 4)
        self.proj = projection
        self.cancel = cancel
        self.source = surface.source
        self.face_names = surface.face_names
        self.cos_fold = math.cos(math.radians(MAX_FOLD_DEGREES))
        self.cos_crease = math.cos(ang)
        self.count = {"split": 0, "collapse": 0, "flip": 0, "move": 0, "refused": 0}
        self.P = [tuple(p) for p in surface.points.tolist()]
        self.T = [list(t) for t in surface.triangles.tolist()]
        self.tag = [int(t) for t in surface.face_tags.tolist()]
        self.VT = [set() for _ in self.P]
        for i, t in enumerate(self.T):
            for v in t:
                self.VT[v].add(i)
        self._classify(frozen, cad_vertices)
        self.frozen = frozen
        self.repair = repair
        self._mid_cache = {}
        self._measure_cache = {}
        self.depth = {}  # generation of points made by repair_curved_folds' splits
        if repair:  # only local mends: no snapping, no size field (splits are never refused
            self._axis_planes = {}  # for size)
            self._reference_normals()
            self.h, self.defl, self.ang, self.min_size, self.user_min_size = h, defl, ang, 0.0, 0.0
            self.s = [math.inf] * len(self.P)
            return
        self._axis_planes = self._find_axis_planes(frozen)
        self._snap_axis_planes(frozen)
        self._reference_normals()
        self._size_field(h, defl, ang, min_size or h / DEFAULT_MIN_SIZE_OF_H, min_size)

    # ---- set-up --------------------------------------------------------------------------

    def _classify(self, frozen, cad_vertices):
        n = len(self.P)
        self.kind = [_FACE] * n
        self.vtags = [()] * n
        for v in range(n):
            tags = sorted({self.tag[t] for t in self.VT[v]})
            if not tags:
                raise RemeshError("vertex %d is in no triangle" % v)
            self.vtags[v] = tuple(tags)
            if len(tags) >= 3 or any(t in frozen for t in tags):
                self.kind[v] = _CORNER
            elif len(tags) == 2:
                feature = [w for w in self.neighbours(v) if self.is_feature(v, w)]
                self.kind[v] = _EDGE if len(feature) == 2 else _CORNER
        for v in range(n):  # every edge must be manifold for the local operations
            for w in self.neighbours(v):
                if len(self.edge_tris(v, w)) != 2:
                    raise RemeshError("edge (%d, %d) is not shared by exactly two triangles"
                                      % (v, w))
        if cad_vertices is None:
            seen = []
            for k in range(self.proj.face_count):
                for vx in self.proj.face(k).Vertexes:
                    seen.append((vx.X, vx.Y, vx.Z, max(float(vx.Tolerance), 0.0)))
            cad_vertices = seen
        pts = np.asarray(self.P)
        for x, y, z, *tol in cad_vertices:
            d = np.linalg.norm(pts - np.array([x, y, z]), axis=1)
            tol = tol[0] if tol else 0.0
            near = np.flatnonzero(d <= max(tol, 1e-12 * (1.0 + abs(x) + abs(y) + abs(z))))
            if len(near) == 0:
                near = [int(np.argmin(d))] if d.min() <= 10.0 * max(tol, 1e-7) else []
            for v in near:
                self.kind[int(v)] = _CORNER

    def _reference_normals(self):
        """Per vertex and tag, the unit area-weighted normal of the tessellation's triangles of
        that tag around the vertex: the surface normal that fold checks compare with."""
        self.refn = [dict() for _ in self.P]
        acc = [dict() for _ in self.P]
        for i, t in enumerate(self.T):
            n = _cross(_sub(self.P[t[1]], self.P[t[0]]), _sub(self.P[t[2]], self.P[t[0]]))
            for v in t:
                a = acc[v].get(self.tag[i], (0.0, 0.0, 0.0))
                acc[v][self.tag[i]] = (a[0] + n[0], a[1] + n[1], a[2] + n[2])
        for v, d in enumerate(acc):
            self.refn[v] = {k: _unit(n) for k, n in d.items()}

    def curvature_at(self, point, tags):
        """Largest principal curvature (1/mm) at ``point`` over the CAD faces ``tags`` (0 for
        planes and where OCCT cannot tell, e.g. at a pole)."""
        best = 0.0
        for tag in tags:
            surf = self.proj.face(tag).Surface
            if type(surf).__name__ == "Plane":
                continue
            if self._vec is None:
                import FreeCAD

                self._vec = FreeCAD.Vector
            try:
                u, w = surf.parameter(self._vec(*point))
                k = max(abs(surf.curvature(u, w, "Max")), abs(surf.curvature(u, w, "Min")))
            except Exception:  # no curvature at a singular point (pole, apex): skip it
                continue
            if math.isfinite(k):
                best = max(best, k)
        return best

    def _cad_edge_chains(self):
        """The tessellation's CAD edges: chains of feature edges (edges between two faces) from
        corner to corner, each a list of vertex ids (closed chains without a corner too)."""
        seen = set()
        chains = []
        starts = [v for v in range(len(self.P)) if self.kind[v] == _CORNER] + \
                 [v for v in range(len(self.P)) if self.kind[v] == _EDGE]
        for v0 in starts:
            for w in sorted(self.neighbours(v0)):
                if (v0, w) in seen or not self.is_feature(v0, w):
                    continue
                chain = [v0, w]
                seen.update({(v0, w), (w, v0)})
                prev, cur = v0, w
                while self.kind[cur] == _EDGE and cur != v0:
                    nxt = [x for x in self.neighbours(cur) if x != prev and
                           self.is_feature(cur, x) and set(self.vtags[cur]) <= set(self.vtags[x])]
                    if len(nxt) != 1 or (cur, nxt[0]) in seen:
                        break
                    prev, cur = cur, nxt[0]
                    seen.update({(prev, cur), (cur, prev)})
                    chain.append(cur)
                chains.append(chain)
        return chains

    def size_at(self, point, tags):
        """The size field's own value at ``point`` (before gradation)."""
        if self.repair:
            return math.inf
        k = self.curvature_at(point, tags)
        s = self.h if k <= 0 else min(self.h, math.sqrt(8.0 * self.defl / k), self.ang / k)
        s = max(s, min(self.min_size, self.h))
        if len(self.size_points):
            d = np.linalg.norm(self.size_points[:, :3] - np.asarray(point), axis=1)
            s = min(s, float((self.size_points[:, 3] + GRADATION * d).min()))
        return s

    def _size_field(self, h, defl, ang, min_size, user_min_size):
        self.h, self.defl, self.ang, self.min_size = h, defl, ang, min_size
        self.user_min_size = user_min_size
        self._vec = None
        n = len(self.P)
        s = np.array([self.size_at(self.P[v], self.vtags[v]) for v in range(n)])
        # a CAD edge shorter than the size (a sliver face, a tiny edge between two fillets)
        # sets the size at its vertices: tets there must be that small to be well shaped
        for chain in self._cad_edge_chains():
            length = sum(_dist(self.P[a], self.P[b]) for a, b in zip(chain, chain[1:]))
            floor = self.user_min_size
            for v in chain:
                s[v] = min(s[v], max(length, floor))
        # grade: s[v] <= s[w] + GRADATION |vw| along the edges
        edges = np.array(sorted({(min(v, w), max(v, w)) for v in range(n)
                                 for w in self.neighbours(v)}), dtype=np.int64).reshape(-1, 2)
        if len(edges):
            pts = np.asarray(self.P)
            length = np.linalg.norm(pts[edges[:, 0]] - pts[edges[:, 1]], axis=1)
            for _ in range(200):
                new = s.copy()
                np.minimum.at(new, edges[:, 0], s[edges[:, 1]] + GRADATION * length)
                np.minimum.at(new, edges[:, 1], s[edges[:, 0]] + GRADATION * length)
                if np.array_equal(new, s):
                    break
                s = new
        self.s = s.tolist()

    # ---- queries -------------------------------------------------------------------------

    def neighbours(self, v):
        out = set()
        for t in self.VT[v]:
            out.update(self.T[t])
        out.discard(v)
        return out

    def edge_tris(self, a, b):
        return self.VT[a] & self.VT[b]

    def is_feature(self, a, b):
        ts = self.edge_tris(a, b)
        return len({self.tag[t] for t in ts}) > 1

    def target(self, a, b):
        return min(self.s[a], self.s[b])

    def ref_normal(self, tri, tag):
        acc = (0.0, 0.0, 0.0)
        for v in tri:
            n = self.refn[v].get(tag)
            if n is not None:
                acc = (acc[0] + n[0], acc[1] + n[1], acc[2] + n[2])
        return _unit(acc)

    def tri_ok(self, tri, tag, pos=None):
        """True if triangle ``tri`` (vertex ids; ``pos`` overrides some positions) is not
        degenerate and not folded against the reference normal of its tag."""
        P = self.P
        p = [pos.get(v, P[v]) if pos else P[v] for v in tri]
        n = _cross(_sub(p[1], p[0]), _sub(p[2], p[0]))
        ln = _norm(n)
        if not ln > 0:
            return False
        ref = self.ref_normal(tri, tag)
        return _dot(n, ref) >= self.cos_fold * ln

    def is_ear(self, tri, tag):
        """True if all three vertices of triangle ``tri`` (of face ``tag``) lie on one CAD edge
        of that face: a sliver as thin as the edge's sag, under which any tet is flat."""
        common = None
        for v in tri:
            if self.kind[v] == _FACE:
                return False
            common = set(self.vtags[v]) if common is None else common & set(self.vtags[v])
        common.discard(tag)
        if not common:
            return False
        # three vertices on one CAD edge have two feature edges among their three edges
        feature = sum(1 for i in range(3) if self.is_feature(tri[i], tri[(i + 1) % 3]))
        return feature >= 2

    def fix_ears(self):
        """Remove ears (:meth:`is_ear`): flip their inner edge, or split it (the new vertex
        goes onto the face, inside)."""
        self.check_cancel()
        for t in range(len(self.T)):
            tri = self.T[t]
            if tri is None or self.tag[t] in self.frozen or not self.is_ear(tri, self.tag[t]):
                continue
            for i in range(3):
                a, b = tri[i], tri[(i + 1) % 3]
                if self.is_feature(a, b):
                    continue
                ts = sorted(self.edge_tris(a, b))
                if len(ts) != 2:
                    continue
                if self.flip(a, b, ts, ear=True) or self.split(a, b, ts):
                    self.count["ears"] = self.count.get("ears", 0) + 1
                break

    def tri_normal(self, tri, pos=None):
        P = self.P
        p = [pos.get(v, P[v]) if pos else P[v] for v in tri]
        return _unit(_cross(_sub(p[1], p[0]), _sub(p[2], p[0])))

    def tri_quality(self, tri, pos=None):
        P = self.P
        p = [pos.get(v, P[v]) if pos else P[v] for v in tri]
        return _quality(*p)

    def all_edges(self):
        edges = set()
        for t in self.T:
            if t is None:
                continue
            for i in range(3):
                a, b = t[i], t[(i + 1) % 3]
                edges.add((a, b) if a < b else (b, a))
        return sorted(edges)

    def project(self, point, tags):
        """``point`` onto its CAD face (one tag) or CAD edge (two). Raises RemeshError for a
        point of one face whose nearest surface point lies outside the trimmed face: the
        bounded face's nearest point is then on a CAD edge, and a vertex there that the mesh
        treats as inside the face makes a flat fin triangle (three corners on one CAD edge)."""
        if len(tags) == 1:
            q, inside = self.proj._to_face(point, tags[0])
            if not inside:
                raise RemeshError("the point projects outside its face")
            q = [float(c) for c in q]
        else:
            q = [float(c) for c in self.proj.to_faces(point, tags)]
        for tag in tags:
            axis = self.axis_plane(tag)
            if axis is not None:
                q[axis[0]] = axis[1]
        return tuple(q)

    def axis_plane(self, tag):
        """``(axis, value)`` if face ``tag`` is a plane ``x[axis] = value`` along the coordinate
        axes (its normal within 1e-12 of an axis, its tessellation vertices within 1e-9 relative
        of one value), else None. The vertices of such a face are put exactly on the plane
        (:meth:`_snap_axis_planes`) and so are the points projected onto it later: OCCT's
        coordinates on such a plane differ by a few ulps, and four points of one planar face
        that are not exactly coplanar make the core fill the ulp-thin gap with a flat tet."""
        return self._axis_planes.get(tag)

    def _find_axis_planes(self, frozen):
        values = {}
        for t, tg in enumerate(self.tag):
            if tg in frozen:
                continue
            for v in self.T[t]:
                values.setdefault(tg, set()).add(v)
        out = {}
        for tg, verts in sorted(values.items()):
            surf = self.proj.face(tg).Surface
            if type(surf).__name__ != "Plane":
                continue
            n = surf.Axis
            comps = (abs(n.x), abs(n.y), abs(n.z))
            i = max(range(3), key=lambda k: comps[k])
            if not comps[i] >= 1.0 - 1e-12:
                continue
            coords = sorted(self.P[v][i] for v in verts)
            if coords[-1] - coords[0] > 1e-9 * (1.0 + abs(coords[0])):
                continue
            counts = {}
            for c in coords:
                counts[c] = counts.get(c, 0) + 1
            value = max(sorted(counts), key=lambda c: counts[c])
            out[tg] = (i, value)
        return out

    def _snap_axis_planes(self, frozen):
        """Every vertex of an axis plane face (:meth:`axis_plane`) exactly on the plane."""
        for v in range(len(self.P)):
            if any(t in frozen for t in self.vtags[v]):
                continue
            q = list(self.P[v])
            for tag in self.vtags[v]:
                axis = self._axis_planes.get(tag)
                if axis is not None:
                    q[axis[0]] = axis[1]
            self.P[v] = tuple(q)

    def check_cancel(self):
        if self.cancel is not None and self.cancel():
            raise MeshingCancelled("cancelled: no mesh was made")

    # ---- curved (tet10) triangles ----------------------------------------------------------

    def cad_midpoint(self, a, b):
        """The CAD point a tet10 mid-node of edge (a, b) goes to (as the pipeline places it:
        onto the face of its triangles, or onto the CAD edge of their two faces)."""
        key = (a, b) if a < b else (b, a)
        m = self._mid_cache.get(key)
        if m is None:
            mid = tuple(0.5 * (x + y) for x, y in zip(self.P[a], self.P[b]))
            tags = tuple(sorted({self.tag[t] for t in self.edge_tris(a, b)}))
            try:
                m = tuple(float(c) for c in (self.proj.to_face(mid, tags[0]) if len(tags) == 1
                                             else self.proj.to_faces(mid, tags)))
            except Exception:
                m = mid
            self._mid_cache[key] = m
        return m

    def curved_measure(self, tri, tag, mids=None):
        """Smallest area element of the 6-node triangle over the flat one's (1 when flat; <= 0
        where it folds), at the corners, edge midpoints and centroid. ``mids`` overrides the
        CAD midpoints of its edges (a, b), (b, c), (c, a)."""
        if mids is not None:
            return _curved_triangle_measure(np.array([self.P[v] for v in tri] + list(mids)))
        key = (tuple(tri), tag)  # vertices never move in repair mode: a triangle's value stays
        value = self._measure_cache.get(key)
        if value is None:
            x = np.array([self.P[v] for v in tri] +
                         [self.cad_midpoint(tri[i], tri[(i + 1) % 3]) for i in range(3)])
            value = _curved_triangle_measure(x)
            if self.repair:
                self._measure_cache[key] = value
        return value

    def folded_triangles(self):
        return [t for t, tri in enumerate(self.T)
                if tri is not None and self.tag[t] not in self.frozen and
                self.curved_measure(tri, self.tag[t]) <= CURVED_FOLD_THRESHOLD]

    def mend_fold(self, t):
        """One local change that makes folded triangle ``t`` better (see repair_curved_folds)."""
        tri, tag = self.T[t], self.tag[t]
        # a flip inside the face, if both new triangles beat the folded one
        for i in range(3):
            a, b = tri[i], tri[(i + 1) % 3]
            ts = sorted(self.edge_tris(a, b))
            if len(ts) != 2 or self.tag[ts[0]] != self.tag[ts[1]]:
                continue
            x, y, c = self._rotate_to(self.T[ts[0]], a, b)
            _, _, d = self._rotate_to(self.T[ts[1]], a, b)
            if c == d or d in self.neighbours(c):
                continue
            # the new edge (c, d) runs inside the face: its mid-node goes onto that face
            mid = tuple(0.5 * (p + q) for p, q in zip(self.P[c], self.P[d]))
            try:
                m_cd = tuple(float(k) for k in self.proj.to_face(mid, tag))
            except Exception:
                continue
            q1 = self.curved_measure((x, d, c), tag,
                                     (self.cad_midpoint(x, d), m_cd, self.cad_midpoint(c, x)))
            q2 = self.curved_measure((d, y, c), tag,
                                     (self.cad_midpoint(d, y), self.cad_midpoint(y, c), m_cd))
            if min(q1, q2) > CURVED_FOLD_THRESHOLD and self.flip(a, b, ts, ear=True):
                return True
        # else split its longest edge at its CAD point (longest-edge bisection: a needle
        # across a narrow fillet folds when its length squared exceeds about 2 R w, so halving
        # the strip's long edges mends it), if that makes the worst of the triangles better;
        # at most MAX_FOLD_SPLIT_DEPTH generations of new points (near a cusp, halving would go
        # on for ever)
        return self.bisect_longest_edge(tri, or_next=True) is not None

    def bisect_longest_edge(self, tri, or_next=False):
        """Split the longest edge of ``tri`` at its CAD point, unless it is not an edge of two
        triangles or a point on it is already of the MAX_FOLD_SPLIT_DEPTH-th generation (then,
        with ``or_next``, the next longest such edge). A refused split is not retried on a
        shorter edge: bisecting a shorter one makes worse shapes. Returns the triangles whose
        edge was split (their halves are appended to ``self.T`` in that order) or None."""
        for i in sorted(range(3), key=lambda i: (-_dist(self.P[tri[i]],
                                                         self.P[tri[(i + 1) % 3]]), i)):
            a, b = tri[i], tri[(i + 1) % 3]
            ts = sorted(self.edge_tris(a, b))
            if len(ts) == 2 and max(self.depth.get(a, 0), self.depth.get(b, 0)) < \
                    MAX_FOLD_SPLIT_DEPTH:
                if not self.split(a, b, ts):
                    return None
                self.depth[len(self.P) - 1] = max(self.depth.get(a, 0), self.depth.get(b, 0)) + 1
                return ts
            if not or_next:
                return None
        return None

    # ---- edits ---------------------------------------------------------------------------

    def _replace_tri(self, t, new):
        for v in self.T[t]:
            self.VT[v].discard(t)
        self.T[t] = list(new)
        for v in new:
            self.VT[v].add(t)

    def _add_tri(self, tri, tag):
        self.T.append(list(tri))
        self.tag.append(tag)
        i = len(self.T) - 1
        for v in tri:
            self.VT[v].add(i)
        return i

    def _delete_tri(self, t):
        for v in self.T[t]:
            self.VT[v].discard(t)
        self.T[t] = None

    @staticmethod
    def _rotate_to(tri, a, b):
        """``tri`` rotated so that it reads (a, b, c) or (b, a, c); returns (x, y, z) with
        (x, y) the edge in the triangle's own direction."""
        for i in range(3):
            x, y, z = tri[i], tri[(i + 1) % 3], tri[(i + 2) % 3]
            if {x, y} == {a, b}:
                return x, y, z
        raise KeyError("edge not in triangle")

    # ---- split ---------------------------------------------------------------------------

    def split_long_edges(self):
        edges = [(a, b) for a, b in self.all_edges()
                 if _dist(self.P[a], self.P[b]) > 4.0 / 3.0 * self.target(a, b)]
        edges.sort(key=lambda e: (-_dist(self.P[e[0]], self.P[e[1]]), e))
        for k, (a, b) in enumerate(edges):
            if k % 256 == 0:
                self.check_cancel()
            ts = sorted(self.edge_tris(a, b))
            if len(ts) != 2:
                continue
            self.split(a, b, ts)

    def split(self, a, b, ts):
        tags = tuple(sorted({self.tag[t] for t in ts}))
        if any(t in self.frozen for t in tags):
            return False
        pa, pb = self.P[a], self.P[b]
        mid = tuple(0.5 * (x + y) for x, y in zip(pa, pb))
        length = _dist(pa, pb)
        try:
            m = self.project(mid, tags)
        except Exception:
            self.count["refused"] += 1
            return False
        if _dist(m, mid) > 0.5 * length:
            self.count["refused"] += 1
            return False
        new_id = len(self.P)
        pos = {new_id: m}
        refn = {}
        for tag in tags:
            na, nb = self.refn[a].get(tag), self.refn[b].get(tag)
            refn[tag] = _unit(tuple(x + y for x, y in zip(na, nb)))
        # tentatively register the reference normal so that tri_ok can use it
        self.P.append(m)
        self.refn.append(refn)
        plan = []
        for t in ts:
            x, y, z = self._rotate_to(self.T[t], a, b)
            plan.append((t, (x, new_id, z), (new_id, y, z)))
        # a child must face the same side as the surface there or as its parent (a looser test
        # than the fold test of the other operations: splitting a needle next to a tiny CAD
        # edge tilts its children, and refining there is what makes the tets there well shaped)
        def child_ok(child, t):
            n = self.tri_normal(child, pos)
            return _norm(n) > 0 and (_dot(n, self.ref_normal(child, self.tag[t])) > 0.0 or
                                     _dot(n, self.tri_normal(self.T[t])) > 0.0)

        ok = all(child_ok(t1, t) and child_ok(t2, t) for t, t1, t2 in plan)
        if not ok:
            self.P.pop()
            self.refn.pop()
            self.count["refused"] += 1
            return False
        self.VT.append(set())
        self.kind.append(_EDGE if len(tags) == 2 else _FACE)
        self.vtags.append(tags)
        self.s.append(min(self.size_at(m, tags), self.s[a] + GRADATION * _dist(m, pa),
                          self.s[b] + GRADATION * _dist(m, pb)))
        for t, t1, t2 in plan:
            self._replace_tri(t, t1)
            self._add_tri(t2, self.tag[t])
        self.count["split"] += 1
        return True

    # ---- collapse ------------------------------------------------------------------------

    def collapse_short_edges(self):
        edges = [(a, b) for a, b in self.all_edges()
                 if _dist(self.P[a], self.P[b]) < 0.8 * self.target(a, b)]
        edges.sort(key=lambda e: (_dist(self.P[e[0]], self.P[e[1]]), e))
        for k, (a, b) in enumerate(edges):
            if k % 256 == 0:
                self.check_cancel()
            if not (self.VT[a] and self.VT[b]):
                continue
            if len(self.edge_tris(a, b)) != 2:
                continue
            if _dist(self.P[a], self.P[b]) >= 0.8 * self.target(a, b):
                continue
            if not self.collapse(a, b):
                self.collapse(b, a)

    def collapse(self, a, b):
        """Remove vertex ``a``, joining its triangles to ``b``."""
        ka, kb = self.kind[a], self.kind[b]
        if ka == _CORNER:
            return False
        feature = self.is_feature(a, b)
        if ka == _EDGE:
            if not feature or not set(self.vtags[a]) <= set(self.vtags[b]):
                return False
        elif feature:
            return False
        shared = self.edge_tris(a, b)
        opposite = set()
        for t in shared:
            opposite.update(self.T[t])
        opposite -= {a, b}
        na, nb = self.neighbours(a), self.neighbours(b)
        if na & nb != opposite or len(opposite) != 2:
            return False
        for c in opposite:
            if len(self.neighbours(c)) <= 3:
                return False
        if len(na) <= 3 and len(nb) <= 3:
            return False
        pb = self.P[b]
        limit = 4.0 / 3.0
        plan = []
        for t in self.VT[a]:
            if t in shared:
                continue
            new = [b if v == a else v for v in self.T[t]]
            if not self.tri_ok(new, self.tag[t]) or self.is_ear(new, self.tag[t]):
                return False
            old_n = self.tri_normal(self.T[t])
            if _dot(self.tri_normal(new), old_n) < self.cos_fold:
                return False
            for v in new:
                if v != b and _dist(self.P[v], pb) > limit * self.target(v, b):
                    return False
            plan.append((t, new))
        for t in sorted(shared):
            self._delete_tri(t)
        for t, new in plan:
            self._replace_tri(t, new)
        # a is now unused (VT[a] empty); its index stays until surface() compacts
        self.count["collapse"] += 1
        return True

    # ---- flip ----------------------------------------------------------------------------

    def flip_edges(self):
        self.check_cancel()
        for a, b in self.all_edges():
            ts = sorted(self.edge_tris(a, b))
            if len(ts) != 2 or self.tag[ts[0]] != self.tag[ts[1]]:
                continue
            self.flip(a, b, ts)

    def flip(self, a, b, ts, ear=False):
        """Flip edge (a, b) if that improves the worse triangle's quality (``ear``: if it
        removes an ear, whatever the quality) and makes no fold, crease or ear."""
        tag = self.tag[ts[0]]
        if tag in self.frozen:
            return False
        x, y, c = self._rotate_to(self.T[ts[0]], a, b)
        y2, x2, d = self._rotate_to(self.T[ts[1]], a, b)
        if (x2, y2) != (x, y) or c == d:
            return False
        if d in self.neighbours(c):
            return False
        if len(self.neighbours(a)) <= 3 or len(self.neighbours(b)) <= 3:
            return False
        if not ear and _dist(self.P[c], self.P[d]) > 4.0 / 3.0 * self.target(c, d):
            return False
        t1, t2 = (x, d, c), (d, y, c)
        if self.is_ear(t1, tag) or self.is_ear(t2, tag):
            return False
        q_old = min(self.tri_quality(self.T[ts[0]]), self.tri_quality(self.T[ts[1]]))
        q_new = min(self.tri_quality(t1), self.tri_quality(t2))
        if not ear and not q_new > q_old + 1e-6:
            return False
        if not (self.tri_ok(t1, tag) and self.tri_ok(t2, tag)):
            return False
        n_old = _dot(self.tri_normal(self.T[ts[0]]), self.tri_normal(self.T[ts[1]]))
        n_new = _dot(self.tri_normal(t1), self.tri_normal(t2))
        if n_new < min(n_old, self.cos_crease):
            return False
        self._replace_tri(ts[0], t1)
        self._replace_tri(ts[1], t2)
        self.count["flip"] += 1
        return True

    # ---- smoothing -----------------------------------------------------------------------

    def smooth(self):
        self.check_cancel()
        for v in range(len(self.P)):
            if v % 256 == 0:
                self.check_cancel()
            if not self.VT[v] or self.kind[v] == _CORNER:
                continue
            if self.kind[v] == _FACE:
                nbs = sorted(self.neighbours(v))
            else:
                nbs = sorted(w for w in self.neighbours(v) if self.is_feature(v, w))
                if len(nbs) != 2:
                    continue
            p = self.P[v]
            c = tuple(sum(self.P[w][i] for w in nbs) / len(nbs) for i in range(3))
            if self.kind[v] == _FACE:
                nrm = (0.0, 0.0, 0.0)
                for t in self.VT[v]:
                    n = _cross(_sub(self.P[self.T[t][1]], self.P[self.T[t][0]]),
                               _sub(self.P[self.T[t][2]], self.P[self.T[t][0]]))
                    nrm = (nrm[0] + n[0], nrm[1] + n[1], nrm[2] + n[2])
                nrm = _unit(nrm)
                d = _sub(c, p)
                k = _dot(d, nrm)
                c = (c[0] - k * nrm[0], c[1] - k * nrm[1], c[2] - k * nrm[2])
            if _dist(c, p) <= 1e-3 * self.s[v]:
                continue
            try:
                q = self.project(c, self.vtags[v])
            except Exception:
                self.count["refused"] += 1
                continue
            pos = {v: q}
            old_q = min(self.tri_quality(self.T[t]) for t in self.VT[v])
            new_q = min(self.tri_quality(self.T[t], pos) for t in self.VT[v])
            if new_q < min(old_q, 0.5):
                continue
            if not all(self.tri_ok(self.T[t], self.tag[t], pos) and
                       _dot(self.tri_normal(self.T[t], pos), self.tri_normal(self.T[t]))
                       >= self.cos_fold for t in self.VT[v]):
                continue
            self.P[v] = q
            self.count["move"] += 1

    # ---- output --------------------------------------------------------------------------

    def surface(self):
        live = [i for i, t in enumerate(self.T) if t is not None]
        used = sorted({v for i in live for v in self.T[i]})
        index = {v: k for k, v in enumerate(used)}
        points = np.array([self.P[v] for v in used], dtype=np.float64).reshape(-1, 3)
        tris = np.array([[index[v] for v in self.T[i]] for i in live],
                        dtype=np.int64).reshape(-1, 3)
        tags = np.array([self.tag[i] for i in live], dtype=np.int32)
        return Surface(points, tris, tags, self.face_names, source=self.source)
