"""Curved tet10 elements made valid by bending their interior edges.

When the mid-nodes of boundary edges go onto a curved CAD face, an element next to that face can
get a non-positive Jacobian determinant: at a corner A of a boundary face, the element's three
edge tangents are those of its two curved boundary edges and of its straight interior edge AD, so
if the surface bends towards D faster than D stands above it, the corner folds over. Interior
mid-nodes need not lie on their chords (``freecad.md`` §7: they "may stay linear"; nothing
requires it), so bending the interior edges with the boundary, as high-order meshers do
(Gmsh's HighOrderOptimize, Sherwin & Peiro's curvilinear meshes), repairs such elements without
moving a single boundary node or corner.

Contract of :func:`untangle_interior_midnodes`:

* only the mid-nodes of edges that are not on the boundary move (``movable``); corners and
  boundary mid-nodes keep their places exactly;
* a move is kept only if the smallest scaled Jacobian (the Jacobian determinant at the 10 nodes
  and the centroid, over the cube of the element's mean edge length, as
  :func:`FemBspTet.mesh_pipeline.tet10_jacobians` samples it) over every element containing that
  mid-node goes up: a move never makes any element worse than the worst it touched;
* deterministic: nodes are visited in increasing index order, with fixed steps.

The Jacobian determinant at a sample is cubic in one node's coordinates, so the search is a
projected ascent on the worst sample (finite-difference gradient) with a fixed ladder of steps.
"""

import numpy as np

#: Scaled Jacobian (see the module docstring) of a regular tet: 6 V / L^3 = 1 / sqrt(2).
REGULAR_SCALED_JACOBIAN = 2.0 ** -0.5

_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))


def _samples():
    eye = np.eye(4)
    s = [eye[i] for i in range(4)]
    s += [0.5 * (eye[i] + eye[j]) for i, j in _EDGES]
    s.append(np.full(4, 0.25))
    return np.array(s)


_SAMPLES = _samples()


def _grad_coefficients():
    """(11, 4, 10): dX/dL_i at each sample as a combination of the 10 node positions."""
    c = np.zeros((len(_SAMPLES), 4, 10))
    for s, lam in enumerate(_SAMPLES):
        for i in range(4):
            c[s, i, i] = 4.0 * lam[i] - 1.0
            for e, (a, b) in enumerate(_EDGES):
                if a == i:
                    c[s, i, 4 + e] += 4.0 * lam[b]
                elif b == i:
                    c[s, i, 4 + e] += 4.0 * lam[a]
    # the Jacobian columns are dX/dL_k - dX/dL_0, k = 1..3
    return c[:, 1:, :] - c[:, :1, :]


_COLUMNS = _grad_coefficients()  # (11, 3, 10)


def jacobians(x):
    """Jacobian determinants of 10-node elements with node coordinates ``x`` (m, 10, 3) at the
    10 nodes and the centroid: (m, 11). The same values as ``mesh_pipeline.tet10_jacobians``."""
    cols = np.einsum("skn,mnd->mskd", _COLUMNS, x)  # (m, 11, 3, 3)
    return np.einsum("msd,msd->ms", np.cross(cols[:, :, 0], cols[:, :, 1]), cols[:, :, 2])


def _scales(points, tets):
    c = points[tets[:, :4]]
    mean = np.zeros(len(tets))
    for i, j in _EDGES:
        mean += np.linalg.norm(c[:, i] - c[:, j], axis=1)
    mean /= 6.0
    return mean, mean ** 3


def untangle_interior_midnodes(points, tets, bad, movable, rounds=40, cancel=None):
    """Bend interior edges so that the elements ``bad`` get a positive Jacobian.

    points:  (n, 3) float array, changed in place (only rows of movable mid-nodes).
    tets:    (m, 10) int array of 10-node elements (FreeCAD/SMESH-independent order: corners
             a, b, c, d, then mid-nodes of ab, bc, ca, ad, bd, cd).
    bad:     indices of the elements to repair.
    movable: (n,) bool, True for nodes that may move (interior mid-nodes).
    rounds:  passes over the nodes at most.
    cancel:  called now and then (it raises to stop).

    Returns ``(still_bad, moved)``: the elements of ``bad`` whose Jacobian is still not positive
    somewhere, and the indices of the nodes that moved. Every element that contains a moved node
    has a smallest scaled Jacobian at least as high as the smallest among those elements before.
    """
    bad = np.unique(np.asarray(bad, dtype=np.int64))
    if len(bad) == 0:
        return bad, np.zeros(0, dtype=np.int64)
    mids = tets[bad, 4:10].reshape(-1)
    nodes = np.unique(mids[movable[mids]])
    if len(nodes) == 0:
        return bad, np.zeros(0, dtype=np.int64)
    # the elements around each candidate node (an interior edge's ball)
    is_node = np.zeros(len(points), dtype=bool)
    is_node[nodes] = True
    hit_e, hit_k = np.nonzero(is_node[tets[:, 4:10]])
    owners = {}
    for e, k in zip(hit_e.tolist(), hit_k.tolist()):
        owners.setdefault(int(tets[e, 4 + k]), []).append(e)
    ball_elems = np.unique(hit_e)
    mean_edge, scale = np.zeros(len(tets)), np.ones(len(tets))
    mean_edge[ball_elems], scale[ball_elems] = _scales(points, tets[ball_elems])
    ladder = np.array([0.5, 0.25, 0.125, 0.0625, 0.03125, 0.015625, 0.0078125, 0.00390625,
                       0.001953125, 0.0009765625])

    target = 0.05 * REGULAR_SCALED_JACOBIAN  # good enough: stop bending there
    moved = set()

    def element_quality(elems):
        return (jacobians(points[tets[elems]]).min(axis=1) / scale[elems])

    pending = set(bad.tolist())
    for _ in range(rounds):
        if cancel is not None:
            cancel()
        improved = False
        for v in nodes.tolist():
            if not any(e in pending for e in owners[v]):
                continue
            elems = np.array(owners[v], dtype=np.int64)
            x = points[tets[elems]]  # (k, 10, 3)
            slot = (tets[elems] == v)  # (k, 10) where v sits in each element
            length = float(mean_edge[elems].min())
            h = 1e-6 * length
            # every sample of the ball, at v and at v moved by h along each axis
            probe = np.repeat(x[None], 4, axis=0)
            for k in range(3):
                probe[1 + k][slot] += h * np.eye(3)[k]
            js = jacobians(probe.reshape(-1, 10, 3)).reshape(4, len(elems), -1)
            js = js / scale[elems][None, :, None]
            base = js[0]
            q = base.min(axis=1)
            # the samples v can change: the worst of those is what this move improves
            grads = (js[1:] - base[None]) / h  # (3, k, 11)
            influenced = (np.abs(grads) > 1e-9).any(axis=0)
            if not influenced.any():
                continue
            masked = np.where(influenced, base, np.inf)
            worst = np.unravel_index(int(np.argmin(masked)), masked.shape)
            f0 = float(masked[worst])
            if f0 >= target:
                continue
            g = grads[:, worst[0], worst[1]]
            norm = float(np.linalg.norm(g))
            if not (norm > 0) or not np.isfinite(norm):
                continue
            d = g / norm
            p0 = points[v].copy()
            trial = np.repeat(x[None], len(ladder), axis=0)  # every step at once
            shift = (ladder * length)[:, None] * d[None, :]
            for step in range(len(ladder)):
                trial[step][slot] = p0 + shift[step]
            jt = jacobians(trial.reshape(-1, 10, 3)).reshape(len(ladder), len(elems), -1)
            jt = jt / scale[elems][None, :, None]
            qt = jt.min(axis=2)  # (steps, k)
            # no element that is valid may become worse than min(its quality, target)
            floor = np.where(q > 0, np.minimum(q, target), -np.inf)
            ok = (qt >= floor[None, :]).all(axis=1)
            gain = np.where(ok, np.where(influenced[None], jt, np.inf).min(axis=(1, 2)), -np.inf)
            best = int(np.argmax(gain))
            if gain[best] > f0:
                points[v] = p0 + shift[best]
                moved.add(v)
                improved = True
        ordered = np.array(sorted(pending), dtype=np.int64)
        pending = set(ordered[element_quality(ordered) < target].tolist())
        if not improved or not pending:
            break
    still_bad = bad[element_quality(bad) <= 0]
    return still_bad, np.array(sorted(moved), dtype=np.int64)


#: :func:`straighten_midnodes`: the fractions of its way back to the CAD tried for each pulled
#: mid-node, largest first (0 = on its chord, 1 = where it was).
STRAIGHTEN_FRACTIONS = (0.875, 0.75, 0.625, 0.5, 0.375, 0.25, 0.125)


def straighten_midnodes(points, tets, bad, cancel=None):
    """The last resort for curved elements that stay inverted: pull mid-nodes onto their chords.

    A tet10 element whose six mid-nodes are the midpoints of its edges is its straight tet, whose
    Jacobian is constant and positive wherever the corners are positively oriented. So: every
    mid-node of an element of ``bad`` that is off its chord goes to the chord's midpoint; every
    element that this makes non-positive somewhere has its mid-nodes pulled too, until none is
    left (at worst a whole region straight). Then each pulled node goes back towards where it
    was, to the largest fraction of ``STRAIGHTEN_FRACTIONS`` that keeps every element containing
    it at least half as good as it is on the chord (and above zero). Only mid-nodes move; a
    boundary mid-node pulled off its CAD face stays on the tessellation's side of it, at most the
    chord sag away.

    points: (n, 3) float array, changed in place; tets: (m, 10) (corner order as
    :func:`untangle_interior_midnodes`); bad: element indices; cancel: called now and then.

    Returns ``(still_bad, pulled, off)``: the elements that are still not positive at a sample
    (their corners are inverted: no mid-node can mend that), the pulled node indices (sorted)
    and, for each, its distance from where it was.
    """
    bad = np.unique(np.asarray(bad, dtype=np.int64))
    if len(bad) == 0:
        return bad, np.zeros(0, dtype=np.int64), np.zeros(0)
    edges = np.array(_EDGES)
    # the elements containing each mid-node: element indices grouped by node (sorted once)
    slots = tets[:, 4:10].reshape(-1)
    order = np.argsort(slots, kind="stable")
    grouped = slots[order]

    def owners(m):
        lo, hi = np.searchsorted(grouped, [m, m + 1])
        return (order[lo:hi] // 6).tolist()

    chord = {}  # each pulled mid-node's chord midpoint
    _, scale = _scales(points, tets)

    def mid_of(e, k):
        return 0.5 * (points[tets[e, edges[k, 0]]] + points[tets[e, edges[k, 1]]])

    def quality(elems):
        elems = np.asarray(elems, dtype=np.int64)
        return jacobians(points[tets[elems]]).min(axis=1) / scale[elems]

    home = {}
    pending = set(bad.tolist())
    while pending:
        if cancel is not None:
            cancel()
        pulled_now = []
        for e in sorted(pending):
            for k in range(6):
                m = int(tets[e, 4 + k])
                if m in home:
                    continue
                c = mid_of(e, k)
                if np.array_equal(points[m], c):
                    continue
                home[m] = points[m].copy()
                chord[m] = c
                points[m] = c
                pulled_now.append(m)
        if not pulled_now:
            break  # what is left has inverted corners
        around = sorted({e for m in pulled_now for e in owners(m)} | pending)
        q = quality(around)
        pending = {e for e, v in zip(around, q.tolist()) if v <= 0}
    pulled = np.array(sorted(home), dtype=np.int64)
    for m in pulled.tolist():
        if cancel is not None:
            cancel()
        elems = owners(m)
        on_chord = quality(elems)
        floor = np.where(on_chord > 0, 0.5 * on_chord, np.inf)
        for frac in STRAIGHTEN_FRACTIONS:
            points[m] = chord[m] + frac * (home[m] - chord[m])
            if (quality(elems) >= floor).all():
                break
        else:
            points[m] = chord[m]
    touched = sorted({e for m in pulled.tolist() for e in owners(m)} | set(bad.tolist()))
    q = quality(touched)
    still_bad = np.array([e for e, v in zip(touched, q.tolist()) if v <= 0], dtype=np.int64)
    off = np.array([float(np.linalg.norm(points[m] - home[m])) for m in pulled.tolist()])
    return still_bad, pulled, off
