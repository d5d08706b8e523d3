# SPDX-License-Identifier: LGPL-2.1-or-later
"""A picture of a tet mesh (PNG, matplotlib), for people who would rather look than read:
``fembsptet render MESH -o mesh.png [--cut]``.

* Without ``--cut``: the boundary triangles, shaded by a light from the viewer's upper left, each
  CAD face in its own colour when the file names the faces (our ``.msh``, ``.vtu``, ``.mesh``),
  else one colour; element edges drawn thin.
* ``--cut``: the tets whose centroid lies on the near side of the plane through the mesh's
  centre, normal to its shortest extent (a plate shows its profile, a shaft its length), are
  removed; the remaining tets' faces on the cut and on
  the boundary are drawn coloured by their tet's smallest dihedral angle (red: under 10 degrees,
  through yellow, to green: 40 degrees and above), so needles and slivers inside show at once.

:func:`render_bsp_cells` draws the paper's own view of a surface (its Figs. 2-6): the leaf cells of
the BSP, the box around the surface split by the planes of its triangles, each convex cell moved
away from the centre (exploded), the inside cells opaque, the outside ones faint when asked for
(``fembsptet cells SURFACE -o cells.png [--outside]``).

Corner triangles only (tet10 mid-nodes are not drawn). The view is isometric from (1, -1, 0.8)
of the mesh's box; matplotlib sorts the triangles by depth (a painter's algorithm), which is
exact enough for a picture of a convex-ish part and may mis-order some triangles in deep
concave pockets.
"""

import math
import os

import numpy as np

from .atomic_file import atomic_output
from ..kernel.core import native
from ..kernel.errors import InputError
from .volume_io import triangle_tags_in_file
from ..kernel.mesh_types import Surface, TetMesh, triangle_keys

#: corners of the four faces of a tet, outward for a positively oriented tet
_FACES = ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))
#: the two faces at each edge (a, b) of a tet (for the dihedral angle there)
_EDGE_FACES = ((2, 3), (0, 3), (1, 3), (1, 2), (0, 2), (0, 1))
VIEW = np.array([1.0, -1.0, 0.8])
#: the light comes from the viewer's upper left
LIGHT = np.array([-0.4, -0.6, 1.0]) / np.linalg.norm([-0.4, -0.6, 1.0])


def _shade(unit_normals):
    """Brightness factor of faces with these unit normals (two-sided: 0.45 to 1)."""
    return 0.45 + 0.55 * np.clip(np.abs(unit_normals @ LIGHT), 0, 1)


def worst_dihedral(points, tets):
    """Each corner tet's smallest dihedral angle, degrees (0 for a flat tet)."""
    p = points[tets[:, :4]]
    normals = np.stack([np.cross(p[:, b] - p[:, a], p[:, c] - p[:, a]) for a, b, c in _FACES],
                       axis=1)
    length = np.linalg.norm(normals, axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = normals / length[:, :, None]
        cosines = np.stack([-np.einsum("ij,ij->i", unit[:, f], unit[:, g])
                            for f, g in _EDGE_FACES], axis=1)
    angles = np.degrees(np.arccos(np.clip(cosines, -1.0, 1.0)))
    return np.nan_to_num(angles, nan=0.0).min(axis=1)


def _faces_of(tets):
    """Faces of exactly one of ``tets`` (corner columns, outward) and the tet of each."""
    corners = tets[:, :4]
    faces = np.concatenate([corners[:, list(f)] for f in _FACES])
    owner = np.tile(np.arange(len(tets)), 4)
    key = triangle_keys(faces)
    _, first, counts = np.unique(key, return_index=True, return_counts=True)
    keep = first[counts == 1]
    return faces[keep], owner[keep]


def render_mesh(mesh: TetMesh, path, cut=False, size_px=900, title=None):
    """Writes the picture of ``mesh`` (module doc) to ``path`` (PNG, written whole or not at
    all). Returns a dict of what was drawn: ``triangles``, ``tets`` (drawn), ``cut``."""
    from matplotlib import cm, colors
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    points, tets = mesh.points, mesh.tets
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = (lo + hi) / 2
    kept = np.arange(len(tets))
    if cut:
        axis = int(np.argmin(hi - lo))
        centroid = points[tets[:, :4]].mean(axis=1)
        # the near side along the view direction's component on that axis is removed
        side = 1.0 if VIEW[axis] >= 0 else -1.0
        kept = np.flatnonzero(side * (centroid[:, axis] - centre[axis]) <= 0)
    faces, owner = _faces_of(tets[kept])
    tri = points[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
    shade = _shade(normal)
    if cut:
        angle = worst_dihedral(points, tets[kept][owner])
        base = cm.RdYlGn(colors.Normalize(10.0, 40.0)(np.clip(angle, 10.0, 40.0)))
    else:
        tags = triangle_tags_in_file(mesh, faces)
        if (tags >= 0).any():
            palette = cm.tab20(np.arange(20) % 20)
            base = np.where((tags >= 0)[:, None], palette[np.maximum(tags, 0) % 20],
                            np.array([0.75, 0.8, 0.9, 1.0]))
        else:
            base = np.tile([0.62, 0.74, 0.9, 1.0], (len(faces), 1))
    rgba = base.copy()
    rgba[:, :3] *= shade[:, None]
    # back faces (pointing away from the viewer) are hidden by the front ones of a closed
    # boundary: dropping them halves the sorting work and avoids mis-ordered fringes
    front = (normal @ VIEW) > 0 if not cut else np.ones(len(faces), dtype=bool)
    plt, fig, ax = _axes3d(size_px, lo, hi)
    ax.add_collection3d(Poly3DCollection(tri[front], facecolors=rgba[front],
                                         edgecolors=(0.1, 0.1, 0.1, 0.35), linewidths=0.15))
    label = title if title is not None else os.path.basename(mesh.source or "")
    kind = "tet10" if tets.shape[1] == 10 else "tet4"
    ax.set_title(f"{label}  {len(tets):,} {kind}" + (
        "  (cut; colour: worst dihedral, red < 10 deg, green >= 40 deg)" if cut else ""),
        fontsize=9)
    fig.subplots_adjust(0, 0, 1, 0.95)
    with atomic_output(os.fspath(path), "wb") as f:
        fig.savefig(f, format="png", dpi=100)
    plt.close(fig)
    return {"triangles": int(front.sum()), "tets": int(len(kept)), "cut": bool(cut)}


#: Above this many input triangles the box partition has too many cells for a picture.
MAX_CELL_VIEW_TRIANGLES = 5000


def _axes3d(size_px, lo, hi):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    inch = size_px / 100.0
    fig = plt.figure(figsize=(inch, inch), dpi=100)
    ax = fig.add_subplot(111, projection="3d")
    centre = (lo + hi) / 2
    radius = 0.75 * float(np.max(hi - lo)) / 2 or 1.0
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
        setter(c - radius, c + radius)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=math.degrees(math.atan2(VIEW[2], math.hypot(VIEW[0], VIEW[1]))),
                 azim=math.degrees(math.atan2(VIEW[1], VIEW[0])))
    ax.set_axis_off()
    return plt, fig, ax


def render_bsp_cells(surface: Surface, path, explode=0.4, outside=False, size_px=900, title=None):
    """Writes the exploded BSP cells of ``surface`` (module doc) to ``path`` (PNG, whole or not
    at all): the cells inside the solid, and with ``outside`` the others too (faint, out to the
    box around the surface). ``explode``: how far each cell moves from the centre, as a fraction
    of its centroid's distance. Returns a dict: ``cells``, ``inside``. InputError for a surface the core
    refuses, or one with more than :data:`MAX_CELL_VIEW_TRIANGLES` triangles."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    if len(surface.triangles) > MAX_CELL_VIEW_TRIANGLES:
        raise InputError(f"{len(surface.triangles)} triangles: the box partition of more than "
                         f"{MAX_CELL_VIEW_TRIANGLES} has too many cells to draw", where=surface.source)
    points, cells, inside = native().bsp_cells_view(surface.points, surface.triangles)
    points = np.asarray(points)
    lo, hi = surface.points.min(axis=0), surface.points.max(axis=0)
    centre = (lo + hi) / 2
    polygons, colours = [], []
    for faces, is_inside in zip(cells, inside):
        if not (is_inside or outside):
            continue
        used = np.unique(np.concatenate([np.asarray(f) for f in faces]))
        shift = explode * (points[used].mean(axis=0) - centre)
        base = np.array([0.93, 0.55, 0.2, 1.0]) if is_inside else np.array([0.55, 0.7, 0.9, 0.12])
        for face in faces:
            poly = points[np.asarray(face)] + shift
            normal = np.cross(poly[1] - poly[0], poly[2] - poly[0])
            length = np.linalg.norm(normal)
            if length == 0 or normal @ VIEW <= 0:
                continue  # seen from behind: the cell's front faces cover it
            rgba = base.copy()
            rgba[:3] *= _shade(normal / length)
            polygons.append(poly)
            colours.append(rgba)
    drawn = np.concatenate(polygons) if polygons else surface.points
    plt, fig, ax = _axes3d(size_px, drawn.min(axis=0), drawn.max(axis=0))
    ax.add_collection3d(Poly3DCollection(polygons, facecolors=colours,
                                         edgecolors=(0.1, 0.1, 0.1, 0.5), linewidths=0.3))
    label = title if title is not None else os.path.basename(surface.source or "")
    n_in = int(sum(inside))
    ax.set_title(f"{label}  BSP: {len(cells):,} convex cells, {n_in:,} inside (orange"
                 + (", outside faint)" if outside else ", drawn)"),
                 fontsize=9)
    fig.subplots_adjust(0, 0, 1, 0.95)
    with atomic_output(os.fspath(path), "wb") as f:
        fig.savefig(f, format="png", dpi=100)
    plt.close(fig)
    return {"cells": len(cells), "inside": n_in}
