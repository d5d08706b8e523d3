# SPDX-License-Identifier: LGPL-2.1-or-later
"""CAD shape -> FEM mesh for the FreeCAD mesher object: the FEM path
(:func:`FemBspTet.fem.cad_mesh.mesh_cad_brep`) on the shape's BREP, and what the object needs
around it, without any document object.

    params = MeshParameters(max_size=500.0, order=2)
    result = mesh_cad_shape(shape, params, progress=None, cancel=None)    # -> MeshResult

Used in-process by ``run_mesher`` / ``mesh_shape`` (:mod:`FemBspTet.freecad.mesher_tools`) and in the
worker process of the task panel (:mod:`FemBspTet.freecad.mesh_worker`, which meshes the BREP text with
:func:`mesh_brep`).

Stages:

1. The shape is written as BREP text (``Shape.exportBrepToString``: topology, placement and face
   order kept) and meshed natively (``cpp_module/include/bsptet/fem/fem_mesh.h``): every CAD
   edge and face meshed at the size field by our OpenCASCADE surface mesher, each solid
   tetrahedralized exactly on that surface, refined to the size with the new surface points and
   the tet10 boundary mid-nodes put on the CAD faces and edges, every tet10 certified valid.
   ``CharacteristicLengthMax`` 0 is automatic (the bounding-box diagonal / 20, lowered by
   curvature), ``CharacteristicLengthMin`` 0 is the size / 50.
2. The boundary triangles keep the CAD face they lie on (0-based: FreeCAD's ``Face<k+1>``); the
   tet10 boundary mid-nodes are read off the tets. They give the node groups per CAD face and
   what FreeCAD's constraints find.
3. Quality figures of the linear tets (:func:`FemBspTet.kernel.core.tet_quality`) and notes.
4. Optionally the comparison at the same size (TetGen on our surface, Gmsh and Netgen on the CAD
   part: :mod:`FemBspTet.compare.at_size`, handed in by the FreeCAD layer as ``compare``).
"""

import contextlib
import dataclasses
import json
import math
import time

import numpy as np

from ..kernel import core
from ..kernel.errors import Cancelled, InputError, InternalError, MeshingCancelled
from ..kernel.mesh_types import MeshGroups, TetMesh
from .cad_mesh import mesh_cad_brep, mesh_cad_faces_brep

#: FreeCAD property name of each MeshParameters field (for messages that name what to change).
PROPERTY_OF = {
    "max_size": "CharacteristicLengthMax",
    "min_size": "CharacteristicLengthMin",
    "order": "ElementOrder",
    "face_groups": "FaceGroups",
    "compare_peers": "CompareWithPeers",
    "dimension": "ElementDimension",
    "workers": "Workers",
}

#: The native FemOptions (the schema of ``fem/fem_mesh.h``) each MeshParameters field sets.
FEM_OPTION_OF_PARAMETER = {"max_size": "size", "min_size": "min_size", "order": "order",
                           "workers": "workers"}

#: Parameters of the former tessellation pipeline, by FreeCAD property name: the FEM path meshes
#: the CAD surface itself, so none of them has a meaning any more. Named in the message that
#: refuses them (``mesh_shape``, ``make_mesher``); saved documents lose them on opening
#: (:func:`FemBspTet.freecad.mesher_object.add_properties`).
REMOVED_PARAMETERS = {
    "linear_deflection": "LinearDeflection",
    "angular_deflection": "AngularDeflection",
    "quality_bound": "QualityBound",
    "thickness_ratio": "ThicknessRatio",
    "allow_boundary_steiner": "AllowBoundarySteiner",
    "remesh_surface": "RemeshSurface",
    "straighten_midnodes": "StraightenMidNodes",
}

#: Why the parameters of :data:`REMOVED_PARAMETERS` are gone (the end of the refusing message).
REMOVED_BECAUSE = ("the mesher meshes the CAD faces itself at the element size "
                   "(CharacteristicLengthMax / CharacteristicLengthMin) and puts every boundary "
                   "node and tet10 mid-node on the CAD, so tessellation, quality-bound, "
                   "thin-wall and mid-node options have no meaning; drop them")

#: Prefix of the FemMesh face and node groups made for each CAD face (``BspTet_Face3``). FEM's CalculiX
#: writer only uses groups named ``<constraint object name>_...``; this prefix avoids them.
FACE_GROUP_PREFIX = "BspTet_"

_TET10_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
#: Outward faces of a positive tet (a, b, c, d): opposite d, c, a, b.
_OUTWARD_FACES = ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2))


def removed_parameter_message(names):
    """The message refusing the former parameters ``names`` (property or field names)."""
    names = sorted(names)
    return "%s %s no longer exist%s: %s" % (
        "parameter" if len(names) == 1 else "parameters", ", ".join(names),
        "s" if len(names) == 1 else "", REMOVED_BECAUSE)


@dataclasses.dataclass
class MeshParameters:
    """What the mesher object's properties ask for. Lengths in mm.

    max_size:       largest element size h (CharacteristicLengthMax); 0 = automatic: the
                    bounding-box diagonal / 20, lowered on curved faces and edges.
    min_size:       smallest element size (CharacteristicLengthMin); 0 = h / 50.
    order:          1 (tet4) or 2 (tet10, boundary mid-nodes on the CAD faces and edges).
    face_groups:    the boundary triangles as FemMesh faces, and per CAD face a face group and
                    a node group (``BspTet_Face<k>``).
    compare_peers:  also mesh at the same size with TetGen (on our surface), Gmsh and Netgen
                    (on the CAD part, where installed) and report their counts, angles, times.
    dimension:      3: the solids as tets; 2: every CAD face as triangles (tria3 / tria6, shell
                    and plane analyses); 0: from the shape (3 if it holds a solid, else 2).
    workers:        solids meshed at the same time, one thread each, a part of one big solid
                    cut in two or three pieces first; 0 = every core (the mesh is the same for
                    any value).
    """

    max_size: float = 0.0
    min_size: float = 0.0
    order: int = 2
    face_groups: bool = True
    compare_peers: bool = False
    dimension: int = 0
    workers: int = 0

    def validate(self):
        """Raise InputError naming the property if a value is out of range; return self."""
        for name in ("max_size", "min_size"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise InputError("%s must be a finite number >= 0 (0 = automatic), got %r"
                                 % (PROPERTY_OF[name], value))
        if self.dimension not in (0, 2, 3):
            raise InputError("%s must be From Shape, 2D or 3D (dimension 0, 2 or 3), got %r"
                             % (PROPERTY_OF["dimension"], self.dimension))
        if not (isinstance(self.workers, int) and self.workers >= 0):
            raise InputError("%s must be a whole number >= 0 (0 = every core), got %r"
                             % (PROPERTY_OF["workers"], self.workers))
        if self.order not in (1, 2):
            raise InputError("%s must be 1st or 2nd (order 1 or 2), got %r"
                             % (PROPERTY_OF["order"], self.order))
        if self.max_size > 0 and self.min_size > self.max_size:
            raise InputError("CharacteristicLengthMin (%g mm) is larger than "
                             "CharacteristicLengthMax (%g mm)" % (self.min_size, self.max_size))
        return self

    def to_dict(self):
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, values):
        """Build from a dict of field values; unknown keys raise InputError (former ones with
        the reason they are gone)."""
        names = {f.name for f in dataclasses.fields(cls)}
        removed = set(values) & set(REMOVED_PARAMETERS)
        if removed:
            raise InputError(removed_parameter_message(removed))
        unknown = set(values) - names
        if unknown:
            raise InputError("unknown mesh parameter(s): %s (known: %s)"
                             % (", ".join(sorted(unknown)), ", ".join(sorted(names))))
        kinds = {f.name: f.type for f in dataclasses.fields(cls)}
        converted = {}
        for key, value in values.items():
            kind = kinds[key]
            try:
                converted[key] = (bool(value) if kind in (bool, "bool") else
                                  int(value) if kind in (int, "int") else float(value))
            except (TypeError, ValueError):
                raise InputError("mesh parameter %s: cannot use %r" % (key, value)) from None
        return cls(**converted).validate()


@dataclasses.dataclass
class MeshResult:
    """A mesh made by :func:`mesh_cad_shape`.

    mesh:               positively oriented TetMesh (tet4 or tet10, corner nodes first), global
                        coordinates in mm.
    boundary_faces:     (k, 3) corner node indices of the boundary triangles, outward CCW (faces
                        two solids share are inside the mesh and not listed).
    boundary_face_tags: (k,) CAD face index (``shape.Faces``) of each boundary triangle.
    boundary_midnodes:  (k, 3) mid-node indices of edges (a,b), (b,c), (c,a) of each boundary
                        triangle (tet10), or an empty (0, 3) array (tet4).
    face_names:         ``"Face<k+1>"`` for every face of the shape.
    stats:              the FEM path's stats (``fem.cad_mesh``), the quality figures of
                        ``cli.STATS_KEYS``, ``seconds_total``.
    comparison:         rows of the comparison at the same size as dicts, ours first
                        (:class:`FemBspTet.compare.at_size.SizeRow`), or empty.
    notes:              things the user should know.
    """

    mesh: TetMesh
    boundary_faces: np.ndarray
    boundary_face_tags: np.ndarray
    boundary_midnodes: np.ndarray
    face_names: list
    stats: dict
    comparison: list = dataclasses.field(default_factory=list)
    notes: list = dataclasses.field(default_factory=list)

    def face_nodes(self, face_tag):
        """Sorted node indices of every boundary node on CAD face ``face_tag`` (corner and
        mid-nodes of its boundary triangles)."""
        sel = self.boundary_face_tags == int(face_tag)
        parts = [self.boundary_faces[sel].reshape(-1)]
        if len(self.boundary_midnodes):
            parts.append(self.boundary_midnodes[sel].reshape(-1))
        return np.unique(np.concatenate(parts))

    def groups(self):
        """The boundary triangles (with their mid-nodes) per CAD face as
        :class:`~FemBspTet.kernel.mesh_types.MeshGroups` (no solid numbers: the tets' solids are not
        kept)."""
        tri = self.boundary_faces
        if len(self.boundary_midnodes):
            tri = np.column_stack([tri, self.boundary_midnodes])
        return MeshGroups(face_triangles=tri, face_tags=self.boundary_face_tags,
                          face_names=list(self.face_names))

    # -- files (the worker process hands its result over through these) ---------------------

    def save(self, npz_path, json_path):
        """Arrays to ``npz_path`` (numpy, no pickle), the rest to ``json_path``."""
        np.savez(npz_path, points=self.mesh.points, tets=self.mesh.tets,
                 boundary_faces=self.boundary_faces, boundary_face_tags=self.boundary_face_tags,
                 boundary_midnodes=self.boundary_midnodes)
        with open(json_path, "w", encoding="utf-8") as f:
            json.dump({"face_names": self.face_names, "stats": self.stats,
                       "comparison": self.comparison,
                       "notes": self.notes, "source": self.mesh.source}, f, default=_json_default)

    @classmethod
    def load(cls, npz_path, json_path):
        with np.load(npz_path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        with open(json_path, encoding="utf-8") as f:
            meta = json.load(f)
        return cls(TetMesh(arrays["points"], arrays["tets"], meta.get("source", "")),
                   arrays["boundary_faces"].reshape(-1, 3),
                   arrays["boundary_face_tags"].reshape(-1),
                   arrays["boundary_midnodes"].reshape(-1, 3),
                   meta["face_names"], meta["stats"], meta.get("comparison", []),
                   meta.get("notes", []))


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError("not JSON serialisable: %r" % type(value).__name__)


# ------------------------------------------------------------------------------------------
# the pipeline
# ------------------------------------------------------------------------------------------

def mesh_cad_shape(shape, params, progress=None, cancel=None, source="", compare=None):
    """Mesh every solid of ``shape`` (a ``Part.Shape``) with ``params``; see the module docstring.

    progress: ``progress(stage, fraction)`` (fraction in [0, 1] or None), called now and then.
    cancel:   ``cancel()`` returning True stops the run with MeshingCancelled.
    source:   a name for messages (the document object's label, a file name).
    compare:  the comparison at the same size (see :func:`mesh_brep`), run if
              ``params.compare_peers``.

    Returns a :class:`MeshResult`. Raises InputError (no solid, a bad parameter, a part the
    surface mesher cannot mesh: the message names the CAD face or solid), MeshingCancelled, or
    InternalError (a stage failed on valid input; the message says so).
    """
    params = _validated(params)
    where = source or "shape"
    if shape is None or not hasattr(shape, "exportBrepToString"):
        raise InputError("expected a Part.Shape, got %s" % type(shape).__name__, where=where)
    if shape.isNull():
        raise InputError("the shape is empty: nothing to mesh", where=where)
    params = dataclasses.replace(params, dimension=dimension_of(shape, params.dimension))
    return mesh_brep(shape.exportBrepToString(), len(shape.Faces), params, progress=progress,
                     cancel=cancel, source=source, shape=shape, compare=compare)


def mesh_brep(brep, face_count, params, progress=None, cancel=None, source="", shape=None,
              compare=None):
    """:func:`mesh_cad_shape` on the shape's BREP text ``brep`` (``Shape.exportBrepToString``)
    with ``face_count`` faces. With ``params.compare_peers``, ``compare(brep, mesh,
    boundary_faces, size, seconds, shape=shape, progress=...)``
    (:func:`FemBspTet.compare.at_size.compare_at_size`, handed in by the FreeCAD layer) gives
    the comparison's rows at the size our mesh was made at (``shape``: the ``Part.Shape`` if at
    hand)."""

    params = _validated(params)
    t_start = time.perf_counter()
    report = progress or (lambda stage, fraction: None)

    def fem_progress(stage, fraction):
        report(stage, None if fraction is None else 0.9 * float(fraction))

    mesher = mesh_cad_faces_brep if params.dimension == 2 else mesh_cad_brep
    with _named_errors(source):
        fem = mesher(brep, progress=fem_progress, cancel=cancel, source=source or "shape",
                     **{option: getattr(params, field)
                        for field, option in FEM_OPTION_OF_PARAMETER.items()})
    if int(fem.stats["faces"]) != int(face_count):
        raise InternalError("%s: the FEM path read %d CAD faces from the BREP, the shape has %d"
                            % (source or "shape", fem.stats["faces"], face_count))
    if params.dimension == 2:
        return _faces_result(fem, face_count, source, t_start, report)
    mesh = fem.mesh
    mesh.source = source or mesh.source
    faces = fem.boundary.triangles
    tags = fem.boundary.face_tags
    midnodes = fem.boundary_midnodes

    report("quality figures", 0.9)
    stats = dict(fem.stats)
    quality = core.tet_quality(TetMesh(mesh.points, mesh.tets[:, :4]))
    for key in ("min_dihedral_deg", "max_dihedral_deg", "p1_dihedral_deg",
                "median_dihedral_deg", "max_radius_edge_ratio"):
        stats[key] = float(quality[key])
    # Points added to the CAD surface mesh: by the core (none on the surface) and by the
    # refinement (surface_splits of them on the CAD faces).
    added = max(0, int(stats["corner_nodes"]) - int(stats["surface_nodes"]))
    boundary_added = min(added, int(stats.get("surface_splits", 0)))
    stats.update(steiner_points=added, boundary_steiner_points=boundary_added,
                 interior_steiner_points=added - boundary_added)
    notes = []
    straightened = int(stats.get("midnodes_straightened", 0)) + \
        int(stats.get("midnodes_straightened_at_merge", 0))
    if mesh.order == 2 and straightened:
        notes.append(
            "tet10: %d boundary mid-node(s) were put back on their straight edges, where the "
            "curved element would not have been valid: on a curved CAD face they lie off it by "
            "up to the chord sag, and getNodesByFace may miss them (a smaller "
            "CharacteristicLengthMax there, or ElementOrder 1st, avoids it)" % straightened)
    if cancel is not None and cancel():
        raise MeshingCancelled("cancelled: no mesh was made")

    stats["seconds_total"] = time.perf_counter() - t_start
    comparison = []
    if params.compare_peers and compare is not None:
        comparison = compare(brep, mesh, faces, float(stats["size"]), stats["seconds_total"],
                             shape=shape, progress=lambda stage: report(stage, 0.92))
    report("done", 1.0)
    return MeshResult(mesh, faces, tags, midnodes,
                      ["Face%d" % (k + 1) for k in range(int(face_count))], stats, comparison,
                      notes)


#: How the native BREP reader names its input at the start of a message.
_BREP_SOURCE = "BREP string: "


def dimension_of(shape, dimension):
    """``dimension`` (MeshParameters.dimension) with 0 resolved for ``shape``: 3 when it holds a
    solid, else 2."""
    if dimension:
        return dimension
    return 3 if len(shape.Solids) else 2


@contextlib.contextmanager
def _named_errors(source):
    """The native run's errors as the object's: cancelled runs as MeshingCancelled, and messages
    naming the object where the native reader says "BREP string"."""
    try:
        yield
    except MeshingCancelled:
        raise
    except Cancelled:
        raise MeshingCancelled("cancelled: no mesh was made") from None
    except InputError as e:
        text = str(e)
        if source and text.startswith(_BREP_SOURCE) and type(e) is InputError:
            raise InputError(text[len(_BREP_SOURCE):], where=source, code=e.code) from None
        raise


def _faces_result(fem, face_count, source, t_start, report):
    """The MeshResult of a 2D mesh (:class:`~FemBspTet.fem.cad_mesh.CadFacesResult`): no tets;
    the triangles of every CAD face are its elements."""
    tri = fem.triangles
    mesh = TetMesh(fem.points, np.zeros((0, 4), dtype=np.int64), source or "shape")
    stats = dict(fem.stats)
    notes = []
    if tri.shape[1] == 6 and int(stats.get("midnodes_straightened", 0)):
        notes.append("tria6: %d mid-node(s) were put back on their straight edges, where the "
                     "curved triangle would have folded" % int(stats["midnodes_straightened"]))
    stats["seconds_total"] = time.perf_counter() - t_start
    report("done", 1.0)
    return MeshResult(mesh, tri[:, :3], fem.face_tags,
                      tri[:, 3:6] if tri.shape[1] == 6 else np.zeros((0, 3), dtype=np.int64),
                      ["Face%d" % (k + 1) for k in range(int(face_count))], stats, [], notes)


def _validated(params):
    return params.validate() if isinstance(params, MeshParameters) else \
        MeshParameters.from_dict(dict(params))


# ------------------------------------------------------------------------------------------
# boundary faces and mid-nodes
# ------------------------------------------------------------------------------------------

def boundary_faces_of(tets):
    """(k, 3) outward boundary triangles (faces used by one tet) of positive tets (corner
    indices), in a deterministic order (sorted by their sorted corner triple)."""
    corners = np.asarray(tets)[:, :4]
    faces = np.concatenate([corners[:, list(f)] for f in _OUTWARD_FACES])
    key = np.sort(faces, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[np.sort(first[counts == 1])] if len(first) else faces[:0]


def boundary_midnodes(mesh, faces):
    """(k, 3) mid-node of edges (a,b), (b,c), (c,a) of each boundary triangle of a tet10 mesh."""
    tets = mesh.tets
    pairs = np.concatenate([tets[:, [i, j]] for i, j in _TET10_EDGES])
    mids = tets[:, 4:10].T.reshape(-1)
    key = np.sort(pairs, axis=1)
    mid_of = {}
    for (u, v), m in zip(key.tolist(), mids.tolist()):
        mid_of[(u, v)] = m
    out = np.empty((len(faces), 3), dtype=np.int64)
    for k, (a, b, c) in enumerate(np.asarray(faces).tolist()):
        for j, (u, v) in enumerate(((a, b), (b, c), (c, a))):
            out[k, j] = mid_of[(u, v) if u < v else (v, u)]
    return out
