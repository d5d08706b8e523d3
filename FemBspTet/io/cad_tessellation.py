# SPDX-License-Identifier: LGPL-2.1-or-later
"""CAD solids (FreeCAD ``Part.Shape``, STEP / BREP / IGES files) -> closed, face-tagged surfaces.

Every triangle carries the CAD face it was made from, so the mesh boundary can be matched to the
names FreeCAD constraints reference (``"Face7"``).

Method (FreeCAD 0.20.2's Part module and OpenCASCADE's BRepMesh):

1. The shape is copied (``shape.copy()``: same topology and sub-shape order, no stored
   triangulation), so the caller's shape is never modified.
2. OCCT's ``BRepMesh_IncrementalMesh`` meshes the whole copy once, with the requested linear and
   angular deflection (through ``MeshPart.meshFromShape``, which stores the triangulation on the
   copy's faces; its own single-precision mesh is discarded). Meshing all faces together makes
   neighbouring faces share the same edge polylines.
3. Each face's stored triangulation is read back with ``Face.tessellate`` (double precision, global
   coordinates, triangles flipped for ``Reversed`` faces so they follow the face's orientation in
   the solid), and vertices of neighbouring faces are merged by *exact* coordinates; shared edge
   polylines are bit-identical, so this reproduces ``Shape.tessellate`` with face tags added.
   Triangles that collapse at a pole, and zero-volume folds BRepMesh makes next to poles of
   B-spline faces (two triangles of one face over the same three vertices, opposite
   orientation), are dropped.
4. Each solid's surface is checked: closed and consistently oriented (every directed edge used
   once, together with its reverse), and its signed volume positive and close to ``solid.Volume``.

Vertices lie on the CAD surfaces. For native FreeCAD geometry they are within 1e-7 mm of their
tagged faces (measured: below 1e-13). For imported files whose edges carry large tolerances, a
vertex near such an edge can lie on the underlying surface but outside the trimmed face, up to
about that edge tolerance (``bottle.brep``: up to 0.02 mm, edge tolerance 0.0155 mm).

Conventions (see :mod:`FemBspTet.kernel.mesh_types`):

* One :class:`~FemBspTet.kernel.mesh_types.Surface` per solid, in ``shape.Solids`` order.
* ``face_tags[t]`` is the 0-based index of the triangle's face in the ORIGINAL shape's
  ``shape.Faces`` list, for every solid (also inside a compound); ``face_names[k]`` is
  ``"Face<k+1>"``, the sub-element name FreeCAD uses for ``shape.Faces[k]``. ``face_names`` has
  ``len(shape.Faces)`` entries in every surface of the same shape.
* Triangles are counter-clockwise seen from outside the solid (outward normals); a solid with
  internal voids has its void boundaries oriented towards the void, so the signed volume is the
  solid's volume.
* Coordinates are FreeCAD's global coordinates, in mm (FreeCAD converts STEP units on import).

Default linear deflection of :func:`tessellate_file` (documented in its docstring):
``min(size / 10, diag / 200)`` when a target element size is given, else ``diag / 500``, with
``diag`` the bounding-box diagonal of the shape.
"""

import math
import os

import numpy as np

from ..kernel import core
from ..kernel.errors import InputError, InternalError
from ..kernel.freecad_env import import_freecad
from ..kernel.mesh_types import Surface

#: File extensions :func:`tessellate_file` reads, with the format names used in messages.
CAD_FORMATS = {
    ".step": "STEP", ".stp": "STEP",
    ".brep": "BREP", ".brp": "BREP",
    ".iges": "IGES", ".igs": "IGES",
}

#: Default linear deflection without a target size, as a fraction of the bounding-box diagonal.
DEFAULT_DEFLECTION_OF_DIAGONAL = 1.0 / 500.0
#: With a target element size h: deflection = min(h * this, diagonal * DEFLECTION_CAP_OF_DIAGONAL).
DEFLECTION_OF_SIZE = 1.0 / 10.0
#: Upper bound of the size-driven deflection, as a fraction of the bounding-box diagonal.
DEFLECTION_CAP_OF_DIAGONAL = 1.0 / 200.0

#: Relative volume mismatch always tolerated between the tessellation and ``solid.Volume``.
VOLUME_REL_TOL = 0.05

_SHAPE_WORDS = {
    "Compound": "compound", "CompSolid": "composite solid", "Solid": "solid", "Shell": "shell",
    "Face": "face", "Wire": "wire", "Edge": "edge", "Vertex": "vertex",
}


# --------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------

def tessellate_shape(shape, linear_deflection, angular_deflection=0.5, relative=False, source=""):
    """Tessellate every solid of a FreeCAD shape into a closed, outward, face-tagged surface.

    shape:              ``Part.Shape``: a Solid, a CompSolid, or a Compound whose faces all
                        belong to solids (free edges and vertices are ignored).
    linear_deflection:  maximum distance between a triangle and the CAD surface, in mm (with
                        ``relative=True``: a fraction of each edge's / face's size, OCCT's
                        relative mode).
    angular_deflection: maximum angle in radians between the normals of neighbouring triangles
                        (and between neighbouring segments of an edge). OCCT's default is 0.5.
    relative:           see ``linear_deflection``.
    source:             text naming where the shape came from, used in messages and
                        ``Surface.source``.

    Returns a list with one :class:`Surface` per solid (``shape.Solids`` order); see the module
    docstring for the conventions (``face_tags`` index the original ``shape.Faces``).

    Raises InputError (``where`` = source or "shape") if the shape is null, not valid
    (``shape.isValid()`` is False), has no solid (a shell, faces, a wire, an empty compound:
    the message says what it is and what to do), has faces outside any solid, contains an
    inverted solid (negative ``Volume``), or if a solid's tessellation is not closed (the
    message names the CAD faces at the open edges), not consistently oriented, or encloses a
    volume far from ``solid.Volume``.
    """

    import_freecad()
    import Part

    where = source or "shape"
    lin = _positive_float(linear_deflection, "linear_deflection")
    ang = _positive_float(angular_deflection, "angular_deflection")
    if not isinstance(shape, Part.Shape):
        raise InputError("expected a Part.Shape, got %s" % type(shape).__name__, where=where)
    _check_shape(shape, where)

    n_faces = len(shape.Faces)
    face_names = ["Face%d" % (k + 1) for k in range(n_faces)]

    work = shape.copy()
    if (len(work.Faces) != n_faces or len(work.Solids) != len(shape.Solids)
            or any(len(a.Edges) != len(b.Edges) or a.Orientation != b.Orientation
                   for a, b in zip(work.Faces, shape.Faces))):
        raise InternalError("%s: shape.copy() changed the topology or the face order" % where)
    _mesh_whole_shape(work, lin, ang, bool(relative), where)
    face_index = _ShapeIndex(work.Faces)
    # Any value at least as coarse as the stored triangulation makes Face.tessellate reuse it.
    reuse_deflection = _reuse_deflection(work)

    solids = work.Solids
    surfaces = []
    for i, (solid, orig_solid) in enumerate(zip(solids, shape.Solids)):
        solid_where = "%s, Solid%d" % (where, i + 1) if len(solids) > 1 else where
        surf, empty = _tessellate_solid(solid, face_index, reuse_deflection, face_names,
                                        solid_where)
        check_closed(surf, solid_where, empty)
        lin_abs = lin * _diagonal(orig_solid) if relative else lin
        _check_volume(surf, orig_solid, lin_abs, solid_where)
        surfaces.append(surf)
    return surfaces


def tessellate_file(path, size=None, linear_deflection=None, angular_deflection=0.5):
    """Read a CAD file with FreeCAD's Part module and tessellate its solids.

    path:               ``.step/.stp``, ``.brep/.brp`` or ``.iges/.igs`` (any letter case).
    size:               target element size h of the volume mesh in mm, or None. Only used to
                        choose the default linear deflection.
    linear_deflection:  in mm; if None, ``min(h / 10, diag / 200)`` when ``size`` is given,
                        else ``diag / 500`` (``diag``: bounding-box diagonal of the shape).
                        h / 10 makes a circular arc of radius R come out in chords of length
                        about sqrt(0.8 R h), i.e. about h where R ~ h; the cap keeps curved
                        faces recognisable for a coarse h; diag / 500 is a 0.2 % geometric error.
    angular_deflection: in radians (OCCT's default 0.5 limits small circles to ~13 segments).

    Returns the list of :class:`Surface` of :func:`tessellate_shape` (one per solid), with
    ``source`` set to the path.

    Raises InputError (``where`` = the path) for a missing file, an unsupported extension, a
    file FreeCAD cannot read (garbage, truncated), a file without shapes or without a solid,
    and for every problem :func:`tessellate_shape` reports.
    """
    if size is not None:
        size = _positive_float(size, "size")
    if linear_deflection is not None:
        linear_deflection = _positive_float(linear_deflection, "linear_deflection")
    shape = read_cad_shape(path)
    path = os.fspath(path)
    if linear_deflection is None:
        linear_deflection = default_linear_deflection(shape, size)
    return tessellate_shape(shape, linear_deflection, angular_deflection, False, source=path)


def read_cad_shape(path):
    """The ``Part.Shape`` of a CAD file (``.step/.stp``, ``.brep/.brp``, ``.iges/.igs``).

    Raises InputError (``where`` = the path) for a missing file, an unsupported extension, a
    file FreeCAD cannot read and a file without shapes."""

    path = os.fspath(path)
    where = path
    ext = os.path.splitext(path)[1].lower()
    if ext not in CAD_FORMATS:
        raise InputError(
            "unsupported CAD file extension %r; FemBspTet reads %s"
            % (os.path.splitext(path)[1] or "(none)", ", ".join(sorted(CAD_FORMATS))),
            where=where)
    if not os.path.exists(path):
        raise InputError("file not found", where=where)
    if not os.path.isfile(path):
        raise InputError("not a regular file", where=where)

    import_freecad()
    import Part

    fmt = CAD_FORMATS[ext]
    try:
        shape = Part.read(path)
    except Exception as e:  # FreeCAD raises RuntimeError / OSError with OCCT's reader message
        raise InputError("FreeCAD cannot read this file as %s: %s" % (fmt, _fc_message(e)),
                         where=where) from e
    if shape.isNull():
        raise InputError("the %s file contains no shape (empty or no geometry FreeCAD can use)"
                         % fmt, where=where)
    return shape


def default_linear_deflection(shape, size=None):
    """The linear deflection (mm) used when none is given: ``min(size / 10, diag / 200)`` with a
    target element size, else ``diag / 500`` (``diag``: bounding-box diagonal of ``shape``; see
    :func:`tessellate_file` for why). A shape without extent counts as ``diag = 1``."""
    diag = _diagonal(shape)
    if not (diag > 0 and math.isfinite(diag)):
        diag = 1.0  # no extent (a vertex): tessellate_shape refuses it with a clear message
    if size is not None:
        return min(size * DEFLECTION_OF_SIZE, diag * DEFLECTION_CAP_OF_DIAGONAL)
    return diag * DEFAULT_DEFLECTION_OF_DIAGONAL


def surfaces_to_single(surfaces):
    """Concatenate several surfaces (e.g. the solids of one compound) into one.

    Point and triangle arrays are stacked, triangle indices offset. Vertices are NOT merged:
    two solids that touch keep their own, coincident vertices and triangles.
    ``face_tags``: if every surface has tags and all share the same ``face_names`` (surfaces
    of one shape), tags and names are kept as they are (still ``shape.Faces`` indices);
    otherwise the name lists are concatenated and each surface's tags offset accordingly.
    If any surface has no tags, the result has none. ``source`` joins the distinct sources.
    """
    surfaces = list(surfaces)
    if not surfaces:
        raise InputError("no surfaces to concatenate")
    if len(surfaces) == 1:
        s = surfaces[0]
        return Surface(s.points.copy(), s.triangles.copy(),
                       None if s.face_tags is None else s.face_tags.copy(),
                       None if s.face_names is None else list(s.face_names), s.source)
    offsets = np.cumsum([0] + [len(s.points) for s in surfaces[:-1]])
    points = np.concatenate([s.points for s in surfaces])
    triangles = np.concatenate([s.triangles + off for s, off in zip(surfaces, offsets)])
    tags, names = None, None
    if all(s.face_tags is not None for s in surfaces):
        first = surfaces[0].face_names
        if first is not None and all(s.face_names == first for s in surfaces):
            tags, names = np.concatenate([s.face_tags for s in surfaces]), list(first)
        else:
            tag_parts, names = [], []
            for j, s in enumerate(surfaces):
                s_names = s.face_names
                if s_names is None:
                    n = int(s.face_tags.max()) + 1 if len(s.face_tags) else 0
                    s_names = ["surface%d:%d" % (j + 1, k) for k in range(n)]
                tag_parts.append(s.face_tags + len(names))
                names.extend(s_names)
            tags = np.concatenate(tag_parts)
    sources = []
    for s in surfaces:
        if s.source and s.source not in sources:
            sources.append(s.source)
    return Surface(points, triangles, tags, names, " + ".join(sources))


# --------------------------------------------------------------------------------------------
# shape checks
# --------------------------------------------------------------------------------------------

def _check_shape(shape, where):
    """Raise InputError unless ``shape`` is a valid shape whose faces all belong to solids."""
    if shape.isNull():
        raise InputError("the shape is empty (a null shape): nothing to mesh", where=where)
    solids = shape.Solids
    if not solids:
        raise InputError(_no_solid_message(shape), where=where)
    try:
        valid = shape.isValid()
    except Exception as e:
        raise InputError("the shape cannot be checked (%s)" % _fc_message(e), where=where) from e
    if not valid:
        raise InputError(
            "the %s is not a valid shape (OCCT's BRepCheck fails): run Part > Check geometry to "
            "see why, then repair it (e.g. Part > Refine shape, or shape.fix(...) in Python)"
            % _SHAPE_WORDS.get(shape.ShapeType, shape.ShapeType), where=where)

    in_solids = _ShapeIndex([f for s in solids for f in s.Faces])
    free = [k for k, f in enumerate(shape.Faces) if in_solids.find(f) is None]
    if free:
        raise InputError(
            "%s %s not part of any solid (the %s also holds loose faces or shells): FemBspTet "
            "meshes solids only; remove them, or make solids of them (Part > Convert to solid)"
            % (_face_list(free), "is" if len(free) == 1 else "are",
               _SHAPE_WORDS.get(shape.ShapeType, shape.ShapeType)),
            where=where)

    for i, s in enumerate(solids):
        if s.Volume < 0:
            raise InputError(
                "Solid%d is inverted: its volume is %.6g (negative), its faces point inward. "
                "Reverse it (in Python: solid.reversed()) or rebuild it from its shell "
                "(Part > Convert to solid)" % (i + 1, s.Volume), where=where)


def _no_solid_message(shape):
    """What the solid-less ``shape`` is, and how a FreeCAD user turns it into a solid."""
    st = shape.ShapeType
    word = _SHAPE_WORDS.get(st, st)
    shells, n_faces = shape.Shells, len(shape.Faces)
    to_solid = ("make a solid from the shell: Part > Convert to solid (in Python: "
                "Part.Solid(shell))")
    if shells:
        what = "a shell" if st == "Shell" else "a %s of %d shell(s)" % (word, len(shells))
        if all(sh.isClosed() for sh in shells):
            return "the shape is %s (%d faces), not a solid: %s" % (what, n_faces, to_solid)
        return ("the shape is %s (%d faces) that is not closed%s, not a solid: close the gaps "
                "(repair the CAD model, or Part > Shape builder), then %s"
                % (what, n_faces, _open_boundary_text(shape, shells), to_solid))
    if n_faces:
        what = "a face" if st == "Face" else "a %s of %d faces" % (word, n_faces)
        return ("the shape is %s, not a solid%s: make a closed shell from the faces (Part > "
                "Create shape > Shell from faces), then a solid from the shell (Part > Convert "
                "to solid)" % (what, _open_boundary_text(shape, None)))
    if shape.Edges or shape.Vertexes:
        what = {"Wire": "a wire", "Edge": "an edge", "Vertex": "a vertex"}.get(
            st, "a %s of %d edge(s) and %d vertex(es)" % (word, len(shape.Edges),
                                                          len(shape.Vertexes)))
        return ("the shape is %s, without faces: there is no volume to mesh; build a solid from "
                "it first (e.g. Part > Extrude or Part > Revolve of a closed profile)" % what)
    return "the shape is an empty %s (no solids, faces or edges): nothing to mesh" % word


def _open_boundary_text(shape, shells):
    """`` (open boundary at Face2 / Face5: 4 free edges)`` for shells (or, if ``shells`` is
    None, loose faces) of ``shape``; empty if that cannot be worked out."""
    import Part

    try:
        if shells is None:
            shells = [Part.Shell(shape.Faces)]
        free = [e for sh in shells if not sh.isClosed() for e in sh.getFreeEdges().Edges]
    except Exception:  # OCCT could not analyse the faces: the message stays generic
        return ""
    if not free:
        return ""
    free_index = _ShapeIndex(free)
    faces = [k for k, f in enumerate(shape.Faces)
             if any(free_index.find(e) is not None for e in f.Edges)]
    return " (open boundary at %s: %d free edge%s)" % (
        _face_list(faces, sep=" / "), len(free), "" if len(free) == 1 else "s")


# --------------------------------------------------------------------------------------------
# tessellation
# --------------------------------------------------------------------------------------------

class _ShapeIndex:
    """Position of a sub-shape in a list, found with ``isSame`` (same TShape and location, any
    orientation), bucketed by ``hashCode`` (which ignores the orientation too)."""

    def __init__(self, shapes):
        self._shapes = list(shapes)
        self._buckets = {}
        for k, f in enumerate(self._shapes):
            self._buckets.setdefault(f.hashCode(), []).append(k)

    def find(self, shape):
        for k in self._buckets.get(shape.hashCode(), ()):
            if self._shapes[k].isSame(shape):
                return k
        return None


def _mesh_whole_shape(work, lin, ang, relative, where):
    """Run OCCT's BRepMesh on the whole (copied) shape; the triangulation stays on its faces."""
    import MeshPart

    try:
        MeshPart.meshFromShape(Shape=work, LinearDeflection=lin, AngularDeflection=ang,
                               Relative=relative)
    except Exception as e:
        raise InputError("OCCT could not tessellate the shape (linear deflection %g, angular "
                         "deflection %g): %s" % (lin, ang, _fc_message(e)), where=where) from e


def _reuse_deflection(work):
    """A linear deflection coarser than any stored triangulation (Face.tessellate then keeps
    the stored one instead of remeshing the face on its own). Parsed as a C float."""
    d = _diagonal(work)
    return float(min(max(10.0 * d, 1.0), 1e30)) if math.isfinite(d) else 1e30


def _tessellate_solid(solid, face_index, reuse_deflection, face_names, where):
    """Merge the stored per-face triangulations of one solid into a face-tagged Surface.

    Returns ``(surface, empty_faces)``: the shape.Faces indices of faces without triangles."""
    key_to_index = {}
    points = []
    triangles = []
    tags = []
    empty_faces = []
    for face in solid.Faces:
        k = face_index.find(face)
        if k is None:
            raise InternalError("%s: a face of the solid is not in shape.Faces" % where)
        try:
            verts, tris = face.tessellate(reuse_deflection)
        except Exception as e:
            raise InputError("%s cannot be tessellated: %s" % (face_names[k], _fc_message(e)),
                             where=where) from e
        if not tris:
            empty_faces.append(k)
            continue
        local = []
        for v in verts:
            key = (v.x, v.y, v.z)
            idx = key_to_index.get(key)
            if idx is None:
                idx = len(points)
                key_to_index[key] = idx
                points.append(key)
            local.append(idx)
        for a, b, c in tris:
            ia, ib, ic = local[a], local[b], local[c]
            if ia == ib or ib == ic or ic == ia:
                continue  # collapsed at a degenerate edge (e.g. a sphere pole): no area
            triangles.append((ia, ib, ic))
            tags.append(k)
    triangles = np.array(triangles, dtype=np.int64).reshape(-1, 3)
    tags = np.array(tags, dtype=np.int32)
    points = np.array(points, dtype=np.float64).reshape(-1, 3)
    keep = ~_cancelling_pairs(triangles, tags)
    triangles, tags = triangles[keep], tags[keep]
    used = np.zeros(len(points), dtype=bool)
    used[triangles.reshape(-1)] = True
    if not used.all():  # vertices only removed triangles used: drop them, keep the order
        new_index = np.cumsum(used) - 1
        points, triangles = points[used], new_index[triangles]
    surf = Surface(points, triangles, tags, list(face_names), where)
    return surf, empty_faces


def _cancelling_pairs(triangles, tags):
    """Mask of triangles of one CAD face (same tag) that come in pairs over the same three
    vertices with opposite orientation (a zero-volume fold). BRepMesh makes such pairs on
    faces with a degenerated edge (a pole; seen on B-spline faces of U_Joint_2.stp): distinct
    UV nodes of the pole become one 3D vertex and two triangles on either side of a UV edge
    collapse onto each other. Both triangles of a pair are removed; they cancel exactly in
    every surface integral and in the edge counts, so a closed surface stays closed. Groups of any other make-up, and pairs from two different faces, are kept
    (and reported by the closedness check).
    """
    mask = np.zeros(len(triangles), dtype=bool)
    if len(triangles) < 2:
        return mask
    srt = np.column_stack([np.sort(triangles, axis=1), tags])
    _, inv, counts = np.unique(srt, axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    dup = np.nonzero(counts[inv] == 2)[0]
    if len(dup) == 0:
        return mask
    # parity of the vertex order: even (1) if (a, b, c) is a rotation of the sorted triple
    t = triangles[dup]
    rot = np.argmin(t, axis=1)
    nxt = t[np.arange(len(t)), (rot + 1) % 3]
    prv = t[np.arange(len(t)), (rot + 2) % 3]
    even = nxt < prv
    order = np.argsort(inv[dup], kind="stable")
    first, second = dup[order[0::2]], dup[order[1::2]]
    opposite = even[order[0::2]] != even[order[1::2]]
    mask[first[opposite]] = True
    mask[second[opposite]] = True
    return mask


# --------------------------------------------------------------------------------------------
# surface checks
# --------------------------------------------------------------------------------------------

def directed_edge_defects(triangles):
    """Classify the edges of a triangle list by how the triangles use them.

    triangles: (m, 3) int array. Returns ``(open_, nonmanifold, misoriented, tri_of)``:
    boolean masks over the unique undirected edges (used by one triangle; by more than two;
    by two triangles in the same direction), and for each of the 3m directed half-edges the
    index of its unique undirected edge (``tri_of`` has shape (m, 3)).

    A surface is closed and consistently oriented iff all three masks are False, i.e. every
    directed edge (a, b) occurs exactly once and (b, a) occurs exactly once.
    """
    tri = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    a = tri.reshape(-1)
    b = tri[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    n = int(tri.max()) + 1 if tri.size else 1
    key = lo * n + hi
    uniq, inv, count = np.unique(key, return_inverse=True, return_counts=True)
    forward = (a < b).astype(np.int64)
    n_forward = np.bincount(inv, weights=forward, minlength=len(uniq)).astype(np.int64)
    open_ = count == 1
    nonmanifold = count > 2
    misoriented = (count == 2) & (n_forward != 1)
    return open_, nonmanifold, misoriented, inv.reshape(-1, 3)


def signed_volume(points, triangles):
    """Sum of the signed volumes of the tets (origin, a, b, c): > 0 for an outward closed surface.

    The centroid of the points is used as the origin to limit cancellation.
    """
    p = np.asarray(points, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(t) == 0:
        return 0.0
    c = p.mean(axis=0)
    a, b, d = p[t[:, 0]] - c, p[t[:, 1]] - c, p[t[:, 2]] - c
    return float(np.einsum("ij,ij->i", a, np.cross(b, d)).sum() / 6.0)


def check_closed(surf, where=None, empty_faces=()):
    """Raise InputError unless ``surf`` is closed and consistently oriented.

    Every directed edge (a, b) must occur exactly once and its reverse (b, a) exactly once. The
    message names the CAD faces (``surf.face_names`` of the tags of the triangles at the bad
    edges; triangle indices if the surface has no tags) and counts open, non-manifold and
    misoriented edges. ``empty_faces``: indices of CAD faces that produced no triangles, added to
    the message. ``where`` defaults to ``surf.source``.
    """
    where = where or surf.source or None
    if len(surf.triangles) == 0:
        raise InputError("the solid produced no triangles (its faces %s gave none): it is "
                         "degenerate or cannot be meshed" % _face_list(empty_faces),
                         where=where)
    open_, nonman, misor, edge_of = directed_edge_defects(surf.triangles)
    problems = []
    for mask, text in ((open_, "shared by one triangle only: the shape is not a closed solid "
                                "there, or OCCT could not mesh a face consistently"),
                       (nonman, "shared by more than two triangles (non-manifold)"),
                       (misor, "used twice in the same direction (inconsistent face "
                               "orientation)")):
        n_bad = int(mask.sum())
        if n_bad:
            bad_tris = np.nonzero(mask[edge_of].any(axis=1))[0]
            problems.append("%s: %d edge%s %s" % (_triangle_places(surf, bad_tris), n_bad,
                                                 "" if n_bad == 1 else "s", text))
    if problems:
        msg = "the tessellation is not closed: open boundary or defect at " + "; ".join(problems)
        if empty_faces:
            msg += "; %s produced no triangles" % _face_list(empty_faces)
        msg += (". Check the shape with Part > Check geometry; a finer or coarser deflection may "
                "also help")
        raise InputError(msg, where=where)


def _triangle_places(surf, tris, limit=12):
    """``"Face3 / Face7"`` (CAD faces of the triangles ``tris``) or ``"triangles 4, 9"``."""
    if surf.face_tags is not None:
        keys = sorted(set(int(k) for k in surf.face_tags[tris]))
        names = [surf.face_names[k] if surf.face_names and k < len(surf.face_names)
                 else "face tag %d" % k for k in keys]
    else:
        names = ["triangle %d" % t for t in tris]
    text = " / ".join(names[:limit])
    return text + (" and %d more" % (len(names) - limit) if len(names) > limit else "")


def _check_volume(surf, solid, lin_abs, where):
    """Raise InputError if the closed surface's signed volume is not positive or too far from
    ``solid.Volume`` (allowance: VOLUME_REL_TOL, or area * 2 * deflection if larger)."""
    vol = signed_volume(surf.points, surf.triangles)
    ref = float(solid.Volume)
    if vol <= 0:
        raise InputError(
            "the tessellation encloses a non-positive volume (%.6g; the solid's volume is %.6g): "
            "its faces are oriented inward or cancel out" % (vol, ref), where=where)
    allowance = max(VOLUME_REL_TOL * abs(ref), 2.0 * lin_abs * float(solid.Area))
    if abs(vol - ref) > allowance:
        raise InputError(
            "the tessellation encloses %.6g mm^3 but the solid's volume is %.6g mm^3 (%.1f %% "
            "off): the solid may be self-intersecting or have faces OCCT meshes badly; run Part "
            "> Check geometry" % (vol, ref, 100.0 * abs(vol - ref) / abs(ref) if ref else
                                  float("inf")), where=where)


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------

def _positive_float(value, name):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError("%s must be a number, got %r" % (name, value)) from None
    if not (v > 0 and math.isfinite(v)):
        raise InputError("%s must be a positive finite number, got %r" % (name, value))
    return v


def _diagonal(shape):
    bb = shape.BoundBox
    return math.sqrt(bb.XLength ** 2 + bb.YLength ** 2 + bb.ZLength ** 2)


def _face_list(indices, limit=12, sep=", "):
    """``"Face3, Face7"`` for 0-based face indices (at most ``limit`` names, then a count)."""
    names = ["Face%d" % (k + 1) for k in indices]
    if len(names) > limit:
        return sep.join(names[:limit]) + " and %d more" % (len(names) - limit)
    return sep.join(names)


def _fc_message(exc):
    """The readable text of a FreeCAD exception (FreeCAD packs a dict into OSError args)."""
    if exc.args and isinstance(exc.args[0], dict):
        d = exc.args[0]
        return str(d.get("sErrMsg") or d.get("swhat") or d)
    text = str(exc)
    prefix = "FreeCAD exception thrown ("
    if text.startswith(prefix) and text.endswith(")"):
        text = text[len(prefix):-1]
    return text or type(exc).__name__


# --------------------------------------------------------------------------------------------
# fins
# --------------------------------------------------------------------------------------------

#: :func:`flip_out_fins`: a triangle whose largest angle exceeds this (degrees) is a fin.
FIN_ANGLE_DEGREES = 175.0


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _largest_angle(p, q, r):
    """Largest angle of triangle (p, q, r) in degrees, and the index (0, 1, 2) of its vertex
    (points as tuples: faster than numpy for single points)."""
    best, at = -1.0, 0
    for k, (x, y, z) in enumerate(((p, q, r), (q, r, p), (r, p, q))):
        u, v = _sub(y, x), _sub(z, x)
        nu, nv = math.sqrt(_dot(u, u)), math.sqrt(_dot(v, v))
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
    whatever the volume mesher does.

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

    def normal(t):
        return _cross(_sub(P[t[1]], P[t[0]]), _sub(P[t[2]], P[t[0]]))

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
            n_s = normal([a, c, x])
            new = ([b, c, x], [b, x, a])
            if not all(_dot(normal(u), n_s) > 0 and largest(u)[0] < angle for u in new):
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


def shared_face_tags(surfaces):
    """Face tags that appear in more than one solid's surface (faces two solids share: both
    sides must stay identical, so they are never changed)."""
    counts = {}
    for surf in surfaces:
        for tag in set(surf.face_tags.tolist()):
            counts[tag] = counts.get(tag, 0) + 1
    return {tag for tag, c in counts.items() if c > 1}


def flip_out_fins_of(surfaces):
    """Each solid's tessellation through :func:`flip_out_fins` (faces two solids share are left
    alone). A changed surface is used only if it passes the core's exact input check; else the
    solid keeps its tessellation. Returns ``(surfaces, stats)``: ``fins_before``, ``fins_after``
    and ``flips`` summed over the solids whose surface is used, and ``not_used``."""

    frozen = shared_face_tags(surfaces)
    out, total = [], {"fins_before": 0, "fins_after": 0, "flips": 0, "not_used": 0}
    for surf in surfaces:
        new, st = flip_out_fins(surf, frozen_tags=frozen)
        if new is not surf:
            try:
                core.check_surface(new)
            except InputError:
                total["not_used"] += 1
                out.append(surf)
                continue
        for k in ("fins_before", "fins_after", "flips"):
            total[k] += st[k]
        out.append(new)
    return out, total
