"""The projection hook backed by OpenCASCADE: put a point on the CAD face (or CAD edge) it
belongs to, so that ``FemMesh.getNodesByFace`` finds it and FreeCAD constraints load it.

Contract of the hook (shared with the quality stage, ``core.tetrahedralize(...,
options={"projection": hook})``)::

    hook(point, face_tag, other_tag=-1) -> point
      point:     3 floats, global coordinates in mm (a point on or near the face's triangles)
      face_tag:  0-based index into ``shape.Faces`` (the ``Surface.face_tags`` of
                 :mod:`FemBspTet.cad_tessellation`)
      other_tag: -1, or the second face when the point is on a surface edge between two CAD
                 faces (then the point goes onto their common CAD edge)
      returns:  a tuple of 3 floats, the nearest point of the trimmed CAD face; for a point of
                one face (other_tag -1) whose nearest point of the untrimmed surface lies
                outside the trimmed face, three NaNs: the core then refuses the point (the
                nearest point of the bounded face is on a CAD edge, where a vertex the mesh
                treats as inside the face would make a flat "fin" triangle);
                :meth:`CadProjection.to_face` always gives the nearest point

:class:`CadProjection` is that hook for one ``Part.Shape``. It also projects onto the CAD edge
shared by two faces (:meth:`CadProjection.to_faces`), which is where a tet10 mid-node of a
surface edge belongs when the edge's two triangles carry different face tags: a point on only
one of the two faces is in general more than the face tolerance away from the other, and
``getNodesByFace`` of that other face would miss it (``/work/shared/design/freecad.md`` §7).

How a point is projected onto face F (tolerance ``BRep_Tool::Tolerance(F)``, ``F.Tolerance``):

1. ``(u, v) = F.Surface.parameter(p)`` (OCCT's ``GeomAPI_ProjectPointOnSurf``: the nearest point
   of the untrimmed surface) and ``q = F.Surface.value(u, v)``; if ``F.isPartOfDomain(u, v)``
   (inside the trimmed face) ``q`` is the answer: it lies on the surface itself.
2. Otherwise (the point is nearer to the surface outside the face's trimming, e.g. close to a
   boundary edge, or the surface projection fails) the nearest point of the bounded face by
   ``BRepExtrema_DistShapeShape`` (``F.distToShape(Part.Vertex(p))``).

Onto edge E: ``t = E.Curve.parameter(p)``; if ``t`` lies in ``E.ParameterRange`` the point is
``E.valueAt(t)``, else the nearest point of the bounded edge (``E.distToShape``).

Distances are not epsilon decisions about mesh topology: the mesh's validity is decided exactly
by the checker; this module only places points on curved geometry.
"""

from .errors import InputError, InternalError


class CadProjection:
    """``(point, face_tag) -> point`` onto ``shape.Faces[face_tag]``; see the module docstring.

    shape: a ``Part.Shape`` (the same shape, or an identical copy, that was tessellated; the
           face tags index its ``Faces``). The shape is not modified. Objects of this class hold
           no global state; one per shape.
    """

    def __init__(self, shape):
        from .freecad_env import import_freecad

        import_freecad()
        import Part

        self._part = Part
        self._vector = _vector_type()
        self._faces = list(shape.Faces)
        if not self._faces:
            raise InputError("the shape has no faces: nothing to project onto")
        self._edges_of_pair = {}
        #: Tag tuples of every to_faces call whose faces share no CAD edge or vertex.
        self.disjoint_placements = []

    @property
    def face_count(self):
        return len(self._faces)

    def face(self, face_tag):
        """The ``Part.Face`` of ``face_tag`` (0-based)."""
        tag = int(face_tag)
        if not 0 <= tag < len(self._faces):
            raise InputError("face tag %d is not a face of the shape (it has faces 0..%d, "
                             "Face1..Face%d)" % (tag, len(self._faces) - 1, len(self._faces)))
        return self._faces[tag]

    def face_tolerance(self, face_tag):
        """``BRep_Tool::Tolerance`` of the face: the limit ``getNodesByFace`` uses."""
        return float(self.face(face_tag).Tolerance)

    def __call__(self, point, face_tag, other_tag=-1):
        """The core's hook (``core.REFINE_OPTIONS["projection"]``): onto face ``face_tag``, or
        onto the CAD edge between ``face_tag`` and ``other_tag`` when ``other_tag`` is a
        different face (a point on a surface edge between two CAD faces)."""
        other_tag = int(other_tag)
        if other_tag >= 0 and other_tag != int(face_tag):
            return self.to_faces(point, (face_tag, other_tag))
        q, inside = self._to_face(point, face_tag)
        if not inside:
            # The point is inside one face's triangles but its nearest point of the surface is
            # outside the trimmed face: it sits in the sliver between a chord of the
            # tessellation and the curved CAD edge. Its nearest point of the bounded face is on
            # that CAD edge, where the mesh would treat it as a point inside the face: a flat
            # "fin" triangle with three corners on one CAD edge, under which every tet10 folds.
            # Refused (non-finite: the core does not insert it; a tet10 mid-node stays on its
            # chord there and the FreeCAD placement puts it on the face afterwards).
            nan = float("nan")
            return (nan, nan, nan)
        return q

    def to_face(self, point, face_tag):
        """The nearest point of the trimmed face ``face_tag`` to ``point`` (3 floats)."""
        return self._to_face(point, face_tag)[0]

    def _to_face(self, point, face_tag):
        """``(to_face(point, face_tag), whether the surface's own nearest point was inside the
        trimmed face)``."""
        face = self.face(face_tag)
        p = self._vector(*map(float, point))
        try:
            u, v = face.Surface.parameter(p)
            if face.isPartOfDomain(u, v):
                q = face.Surface.value(u, v)
                return (q.x, q.y, q.z), True
        except Exception:  # OCCT's projection did not converge: use the bounded-face search
            pass
        q = self._nearest_on_shape(face, p, "Face%d" % (int(face_tag) + 1))
        return q, False

    def to_edge(self, point, edge):
        """The nearest point of the bounded ``Part.Edge`` ``edge`` to ``point``."""
        p = self._vector(*map(float, point))
        try:
            t = edge.Curve.parameter(p)
            t0, t1 = edge.ParameterRange
            if t0 <= t <= t1:
                q = edge.valueAt(t)
                return (q.x, q.y, q.z)
        except Exception:  # no 3D curve, or the curve projection failed
            pass
        return self._nearest_on_shape(edge, p, "an edge")

    def common_edges(self, tag_a, tag_b):
        """The CAD edges shared by faces ``tag_a`` and ``tag_b`` (a list, possibly empty)."""
        key = (min(int(tag_a), int(tag_b)), max(int(tag_a), int(tag_b)))
        edges = self._edges_of_pair.get(key)
        if edges is None:
            fa, fb = self.face(key[0]), self.face(key[1])
            edges = [e for e in fa.Edges if any(e.isSame(g) for g in fb.Edges)]
            self._edges_of_pair[key] = edges
        return edges

    def to_faces(self, point, face_tags):
        """``point`` placed on every face of ``face_tags`` at once.

        One tag: :meth:`to_face`. Two tags: the nearest point on a CAD edge the two faces
        share (the nearest over all such edges). More tags, or two faces without a common edge
        (the point is where a vertex of the tessellation would be): the nearest CAD vertex
        shared by all the faces. Faces that share no edge or vertex (coinciding faces of
        touching solids, or faces the tessellation joined across a sliver face that got no
        triangles): the nearest point of the nearest of them, and the tags are appended to
        ``disjoint_placements``.
        """
        tags = sorted({int(t) for t in face_tags})
        if not tags:
            raise InternalError("to_faces needs at least one face tag")
        if len(tags) == 1:
            return self.to_face(point, tags[0])
        if len(tags) == 2:
            edges = self.common_edges(*tags)
            if edges:
                best = None
                for e in edges:
                    q = self.to_edge(point, e)
                    d = _dist2(q, point)
                    if best is None or d < best[0]:
                        best = (d, q)
                return best[1]
        vertices = None
        for t in tags:
            vs = self.face(t).Vertexes
            vertices = vs if vertices is None else [v for v in vertices
                                                    if any(v.isSame(w) for w in vs)]
        if not vertices:
            # Faces that share no edge or vertex: coinciding faces of two touching solids, or
            # faces the tessellation joins across a sliver face that got no triangles. No point
            # is on all of them in general: the nearest point of the nearest face, recorded for
            # the caller's notes.
            best = min((self.to_face(point, t) for t in tags), key=lambda q: _dist2(q, point))
            self.disjoint_placements.append(tuple(tags))
            return best
        best = min(vertices, key=lambda v: _dist2((v.X, v.Y, v.Z), point))
        return (best.X, best.Y, best.Z)

    def distance_to_face(self, point, face_tag):
        """Distance from ``point`` to the bounded face (``BRepExtrema``), as FreeCAD measures it
        in ``getNodesByFace``."""
        face = self.face(face_tag)
        return float(face.distToShape(self._part.Vertex(self._vector(*map(float, point))))[0])

    def nodes_within_tolerance(self, points, face_tag, candidates):
        """Those of ``candidates`` (indices into ``points``, (n, 3)) that lie within the face's
        tolerance of the bounded face ``face_tag``: the nodes ``FemMesh.getNodesByFace`` would
        return among them (same bounding-box pre-filter, then the distance)."""
        import numpy as np

        face = self.face(face_tag)
        tol = float(face.Tolerance)
        bb = face.BoundBox
        lo = np.array([bb.XMin, bb.YMin, bb.ZMin]) - tol
        hi = np.array([bb.XMax, bb.YMax, bb.ZMax]) + tol
        cand = np.asarray(candidates, dtype=np.int64)
        pts = np.asarray(points)[cand]
        inside = np.all((pts >= lo) & (pts <= hi), axis=1)
        found = []
        for n, p in zip(cand[inside].tolist(), pts[inside].tolist()):
            if self.distance_to_face(p, face_tag) < tol:
                found.append(n)
        return found

    def _nearest_on_shape(self, shape, p, what):
        try:
            dist, pairs, _info = shape.distToShape(self._part.Vertex(p))
        except Exception as e:
            raise InternalError("OpenCASCADE could not find the nearest point of %s to (%.17g, "
                                "%.17g, %.17g): %s" % (what, p.x, p.y, p.z, e)) from e
        if not pairs:
            raise InternalError("OpenCASCADE found no nearest point of %s to (%.17g, %.17g, "
                                "%.17g)" % (what, p.x, p.y, p.z))
        q = pairs[0][0]
        return (q.x, q.y, q.z)


def _vector_type():
    import FreeCAD

    return FreeCAD.Vector


def _dist2(a, b):
    return sum((float(x) - float(y)) ** 2 for x, y in zip(a, b))
