# SPDX-License-Identifier: LGPL-2.1-or-later
"""Plain numpy containers passed between the readers, the core, the checker and the writers.

Conventions (stated once, here):

* ``Surface.triangles`` are oriented counter-clockwise seen from outside (outward normals,
  right-hand rule): for a closed solid, sum of signed tet volumes of (origin, a, b, c) > 0.
* A tetrahedron ``(a, b, c, d)`` is *positively oriented* when
  ``det[b - a, c - a, d - a] > 0``, i.e. ``d`` lies on the side into which the right-hand normal
  of ``(a, b, c)`` points. This is the VTK / Gmsh / CalculiX convention. FreeCAD's SMESH uses the
  opposite sign; the FreeCAD writer swaps nodes 1 and 2.
* Second-order tets have 10 nodes ``[n1, n2, n3, n4, m12, m23, m31, m14, m24, m34]`` (the
  SMESH / CalculiX C3D10 / VTK order); writers for formats with another order convert.
* Indices are 0-based in memory; readers and writers convert for 1-based formats.
"""

from dataclasses import dataclass, field
from typing import List, Optional

import numpy as np


def triangle_keys(rows):
    """One hashable value per row of corner triples (the first three columns, in any order): a
    void view of the sorted triple, for np.unique, np.isin and np.searchsorted."""
    rows = np.ascontiguousarray(np.sort(np.asarray(rows)[:, :3], axis=1).astype(np.int64))
    return rows.view(np.dtype((np.void, 24))).ravel()


@dataclass
class Surface:
    """A triangle surface.

    points:     (n, 3) float64
    triangles:  (m, 3) int64, 0-based, outward CCW
    face_tags:  (m,) int32 or None; CAD face index (0-based, ``shape.Faces[tag]``) per triangle
    face_names: names per tag (e.g. ``"Face1"``) or None
    source:     where it came from (file path or description), for messages
    """

    points: np.ndarray
    triangles: np.ndarray
    face_tags: Optional[np.ndarray] = None
    face_names: Optional[List[str]] = None
    source: str = ""

    def __post_init__(self):
        self.points = np.ascontiguousarray(self.points, dtype=np.float64).reshape(-1, 3)
        self.triangles = np.ascontiguousarray(self.triangles, dtype=np.int64).reshape(-1, 3)
        if self.face_tags is not None:
            self.face_tags = np.ascontiguousarray(self.face_tags, dtype=np.int32).reshape(-1)


@dataclass
class TetMesh:
    """A tetrahedral mesh.

    points: (n, 3) float64
    tets:   (m, 4) or (m, 10) int64, 0-based, positively oriented (see module doc)
    source: where it came from, for messages
    """

    points: np.ndarray
    tets: np.ndarray
    source: str = ""
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        self.points = np.ascontiguousarray(self.points, dtype=np.float64).reshape(-1, 3)
        tets = np.asarray(self.tets, dtype=np.int64)
        if tets.ndim != 2 or tets.shape[1] not in (4, 10):
            if tets.size == 0:
                tets = tets.reshape(0, 4)
            else:
                raise ValueError(f"tets must have shape (m, 4) or (m, 10), got {tets.shape}")
        self.tets = np.ascontiguousarray(tets)

    @property
    def order(self):
        return 2 if self.tets.shape[1] == 10 else 1


@dataclass
class MeshGroups:
    """Named groups of a :class:`TetMesh`, as the CAD defines them; the writers turn them into
    each format's sets (``.inp`` ``*NSET`` / ``*ELSET`` / ``*SURFACE``, ``.msh`` physical
    groups, ``.vtu`` cell data, Medit references, TetGen region attributes).

    face_triangles: (k, 3) or (k, 6) int64, 0-based mesh nodes of the triangles of the CAD faces
                    (corners, then for tet10 the mid-edge nodes ``m_ab, m_bc, m_ca``); a face
                    between two solids is listed once
    face_tags:      (k,) int32, 0-based CAD face of each triangle (``shape.Faces[tag]``)
    face_names:     name of each face tag (``"Face1"`` for tag 0 unless the CAD names it)
    tet_solid:      (m,) int32 or None, 0-based CAD solid of each tet
    solid_names:    name of each solid index (``"Solid1"`` for index 0 unless the CAD names it)
    """

    face_triangles: np.ndarray
    face_tags: np.ndarray
    face_names: List[str]
    tet_solid: Optional[np.ndarray] = None
    solid_names: Optional[List[str]] = None

    def __post_init__(self):
        tri = np.asarray(self.face_triangles, dtype=np.int64)
        self.face_triangles = np.ascontiguousarray(tri.reshape(-1, tri.shape[-1] if tri.ndim == 2
                                                               else 3))
        self.face_tags = np.ascontiguousarray(self.face_tags, dtype=np.int32).reshape(-1)
        if len(self.face_tags) != len(self.face_triangles):
            raise ValueError("face_tags must give one tag per face triangle")
        if self.face_tags.size and (self.face_tags.min() < 0
                                    or self.face_tags.max() >= len(self.face_names)):
            raise ValueError("a face tag has no name")
        if self.tet_solid is not None:
            self.tet_solid = np.ascontiguousarray(self.tet_solid, dtype=np.int32).reshape(-1)
            names = self.solid_names or []
            if self.tet_solid.size and (self.tet_solid.min() < 0
                                        or self.tet_solid.max() >= len(names)):
                raise ValueError("a tet's solid has no name")

    @staticmethod
    def default_names(prefix, count):
        """``[prefix + "1", prefix + "2", ...]``: FreeCAD's names of a shape's sub-elements."""
        return [f"{prefix}{i + 1}" for i in range(count)]
