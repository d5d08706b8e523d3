"""CAD shape -> tet mesh whose boundary nodes lie on the CAD faces: the meshing pipeline behind the
FreeCAD mesher object, without any document object.

    params = MeshParameters(max_size=500.0, order=2)
    result = mesh_cad_shape(shape, params, progress=None, cancel=None)    # -> MeshResult

Used in-process by ``run_mesher`` / ``mesh_shape`` (:mod:`FemBspTet.mesher_tools`) and in the
worker process of the task panel (:mod:`FemBspTet.mesh_worker`). Needs FreeCAD's ``Part``
(OpenCASCADE), never a document or the GUI.

Stages:

1. Tessellate every solid of ``shape`` into a closed, face-tagged surface
   (:func:`FemBspTet.cad_tessellation.tessellate_shape`; linear deflection from
   :attr:`MeshParameters.linear_deflection`, or the default tied to the element size).
2. ``core.tetrahedralize(surfaces, options)``: options from :func:`core_options`. The OCCT
   projection hook (:class:`FemBspTet.cad_projection.CadProjection`) is passed as
   ``options["projection"]`` when the core accepts it (the quality stage adds it).
3. Boundary faces of the tet mesh, each with the CAD face tag of the input triangle it lies on
   (matched by exact corner coordinates; faces with boundary Steiner points by the nearest
   input triangle).
4. Every boundary node that is not a tessellation vertex is put on its CAD geometry: tet10
   mid-nodes of surface edges inside a face onto that face, those of edges between two faces
   onto the CAD edge the faces share, boundary Steiner points likewise. Tessellation vertices
   already lie on their faces and are not moved. Interior mid-nodes stay straight unless
   bending them is what keeps an element valid (``/work/shared/design/freecad.md`` §7 allows
   both). Projection is idempotent, so this is
   harmless when the core already applied the hook.
   tet10: an element that the curved boundary would invert gets its interior edges bent
   (:mod:`FemBspTet.curved_untangle`: interior mid-nodes move, boundary nodes never); if some
   elements stay inverted, one more attempt meshes the tessellation with its folding curved
   triangles mended (:func:`repair_curved_folds_of`), and the attempt with fewer inverted
   elements is kept; then a tessellation with half the AngularDeflection is tried. Last resort
   (``MeshParameters.straighten_midnodes``, on by default): the mid-nodes of the elements still
   inverted are pulled towards their chords (:func:`straighten_inverted`), with a note naming how
   many boundary mid-nodes are how far off which CAD faces.
5. Moved nodes must not invert an element: every tet with a moved node is checked (positive
   signed volume of the corners; for tet10 a positive Jacobian determinant at the 10 nodes and
   the centroid). A failure raises InternalError naming the tet and the CAD face.
6. Optionally ``tetgen -pY`` on the same surfaces, for the comparison table.
"""

import dataclasses
import json
import math
import time

import numpy as np

from .errors import BspTetError, InputError, InternalError, MeshingCancelled
from .mesh_types import TetMesh


class CurvedElementsInverted(InternalError):
    """tet10: placing the boundary mid-nodes on the CAD faces would invert elements, after
    every mend the pipeline has. ``summary``: the sentence naming how many (``count``), the
    first element and its CAD face; the message is ``summary`` followed by ``advice``."""

    def __init__(self, summary, count, advice):
        self.summary = summary
        self.count = count
        super().__init__(summary + advice)

#: Name of each MeshParameters field in ``core.tetrahedralize``'s options (``core.OPTION_NAMES``).
CORE_OPTION_OF = {
    "max_size": "size",
    "min_size": "min_size",
    "quality_bound": "radius_edge",
    "thickness_ratio": "thickness_ratio",
    "order": "order",
    "allow_boundary_steiner": "allow_boundary_steiner",
}
#: Option under which the core takes the projection hook (``cad_projection.CadProjection``).
CORE_PROJECTION_OPTION = "projection"

#: FreeCAD property name of each MeshParameters field (for messages that name what to change).
PROPERTY_OF = {
    "max_size": "CharacteristicLengthMax",
    "min_size": "CharacteristicLengthMin",
    "order": "ElementOrder",
    "linear_deflection": "LinearDeflection",
    "angular_deflection": "AngularDeflection",
    "quality_bound": "QualityBound",
    "thickness_ratio": "ThicknessRatio",
    "allow_boundary_steiner": "AllowBoundarySteiner",
    "face_groups": "FaceGroups",
    "compare_tetgen": "CompareWithTetGen",
    "remesh_surface": "RemeshSurface",
    "straighten_midnodes": "StraightenMidNodes",
}

#: Prefix of the FemMesh node group made for each CAD face (``BspTet_Face3``). FEM's CalculiX
#: writer only uses groups named ``<constraint object name>_...``; this prefix avoids them.
FACE_GROUP_PREFIX = "BspTet_"

#: Switches of the TetGen run the comparison uses (``tetgen -pY``: the same surface, no Steiner
#: point on it, no quality or size bound, as our core without the quality stage).
TETGEN_SWITCHES = "pY"

_TET10_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
#: Outward faces of a positive tet (a, b, c, d): opposite d, c, a, b.
_OUTWARD_FACES = ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2))


@dataclasses.dataclass
class MeshParameters:
    """What the mesher object's properties ask for. Lengths in mm, angles in radians.

    max_size:               maximum element size h (CharacteristicLengthMax); 0 = automatic:
                            with remesh_surface, h = the bounding-box diagonal / 20 (surface
                            and volume); without it, the tessellation is filled as it is.
                            Also sets the tessellation's default deflection.
    min_size:               minimum element size (CharacteristicLengthMin); 0 = none. Needs the
                            quality stage (refused with a message otherwise).
    order:                  1 (tet4) or 2 (tet10).
    linear_deflection:      distance between the tessellation and the CAD surface; 0 = automatic
                            (``cad_tessellation.default_linear_deflection``).
    angular_deflection:     angle between neighbouring triangles' normals (OCCT default 0.5).
    quality_bound:          radius-edge ratio bound of quality refinement; 0 = no refinement.
                            Needs the quality stage (refused with a message otherwise).
    thickness_ratio:        thin walls: the size on a face is at most this times the solid's
                            local thickness there (the quality stage's thickness_ratio; 0 = off).
    allow_boundary_steiner: keep Steiner points on the surface (they are projected onto the CAD).
    face_groups:            one FemMesh node group per CAD face (``BspTet_Face<k>``).
    compare_tetgen:         also run ``tetgen -pY`` on the same surface and report its counts.
    remesh_surface:         remesh the tessellation of each CAD face towards the element size
                            (:mod:`FemBspTet.surface_remesh`) before the volume mesh, and make
                            the volume to that size; off (default): the core fills
                            OpenCASCADE's tessellation as it is (README: what it gains, costs).
    straighten_midnodes:    tet10: where curved mid-nodes still invert elements after every mend
                            (and, without remesh_surface, a finer tessellation), pull them
                            towards their straight edges (:func:`FemBspTet.curved_untangle.
                            straighten_midnodes`) and say so in a note, instead of stopping with
                            the error; a pulled boundary mid-node is off its CAD face by at most
                            the chord sag, and getNodesByFace may miss it.
    """

    max_size: float = 0.0
    min_size: float = 0.0
    order: int = 2
    linear_deflection: float = 0.0
    angular_deflection: float = 0.5
    quality_bound: float = 0.0
    thickness_ratio: float = 4.0
    allow_boundary_steiner: bool = False
    face_groups: bool = False
    compare_tetgen: bool = False
    remesh_surface: bool = False
    straighten_midnodes: bool = True

    def validate(self):
        """Raise InputError naming the property if a value is out of range; return self."""
        for name in ("max_size", "min_size", "linear_deflection", "quality_bound",
                     "thickness_ratio"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise InputError("%s must be a finite number >= 0 (0 = automatic/off), got %r"
                                 % (PROPERTY_OF[name], value))
        if not (math.isfinite(self.angular_deflection) and 0 < self.angular_deflection < math.pi):
            raise InputError("%s must be between 0 and 180 degrees (exclusive), got %g rad"
                             % (PROPERTY_OF["angular_deflection"], self.angular_deflection))
        if self.order not in (1, 2):
            raise InputError("%s must be 1st or 2nd (order 1 or 2), got %r"
                             % (PROPERTY_OF["order"], self.order))
        if self.max_size > 0 and self.min_size > self.max_size:
            raise InputError("CharacteristicLengthMin (%g mm) is larger than "
                             "CharacteristicLengthMax (%g mm)" % (self.min_size, self.max_size))
        if 0 < self.quality_bound < 1:
            raise InputError("QualityBound is a radius-edge ratio bound (>= 1, e.g. 1.414; "
                             "0 = off), got %g" % self.quality_bound)
        return self

    def to_dict(self):
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, values):
        """Build from a dict of field values; unknown keys raise InputError."""
        names = {f.name for f in dataclasses.fields(cls)}
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

    mesh:               positively oriented TetMesh (tet4 or tet10), global coordinates in mm.
    boundary_faces:     (k, 3) corner node indices of the boundary triangles, outward CCW.
    boundary_face_tags: (k,) CAD face index (``shape.Faces``) of each boundary triangle.
    boundary_midnodes:  (k, 3) mid-node indices of edges (a,b), (b,c), (c,a) of each boundary
                        triangle (tet10), or an empty (0, 3) array (tet4).
    face_names:         ``"Face<k+1>"`` for every face of the shape.
    stats:              the core's stats (``cli.STATS_KEYS`` and more) plus ``projected_nodes``,
                        ``max_projection_mm``, ``seconds_total``, ``linear_deflection``.
    tetgen:             None, or the ``tetgen -pY`` row of the comparison as a dict
                        (:func:`FemBspTet.compare.comparison.row_dict`).
    notes:              things the user should know (e.g. a parameter the core cannot honour).
    """

    mesh: TetMesh
    boundary_faces: np.ndarray
    boundary_face_tags: np.ndarray
    boundary_midnodes: np.ndarray
    face_names: list
    stats: dict
    tetgen: object = None
    notes: list = dataclasses.field(default_factory=list)

    def face_nodes(self, face_tag):
        """Sorted node indices of every boundary node on CAD face ``face_tag`` (corner and
        mid-nodes of its boundary triangles)."""
        sel = self.boundary_face_tags == int(face_tag)
        parts = [self.boundary_faces[sel].reshape(-1)]
        if len(self.boundary_midnodes):
            parts.append(self.boundary_midnodes[sel].reshape(-1))
        return np.unique(np.concatenate(parts))

    def face_node_groups(self):
        """``{"BspTet_Face<k>": node indices}`` for every CAD face with boundary triangles."""
        return {FACE_GROUP_PREFIX + self.face_names[t]: self.face_nodes(t)
                for t in np.unique(self.boundary_face_tags).tolist()}

    # -- files (the worker process hands its result over through these) ---------------------

    def save(self, npz_path, json_path):
        """Arrays to ``npz_path`` (numpy, no pickle), the rest to ``json_path``."""
        np.savez(npz_path, points=self.mesh.points, tets=self.mesh.tets,
                 boundary_faces=self.boundary_faces, boundary_face_tags=self.boundary_face_tags,
                 boundary_midnodes=self.boundary_midnodes)
        with open(json_path, "w", encoding="utf-8") as f:
            json.dump({"face_names": self.face_names, "stats": self.stats, "tetgen": self.tetgen,
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
                   meta["face_names"], meta["stats"], meta.get("tetgen"), meta.get("notes", []))


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError("not JSON serialisable: %r" % type(value).__name__)


# ------------------------------------------------------------------------------------------
# options for the core
# ------------------------------------------------------------------------------------------

#: Where the core's BSP starts in this pipeline (``core.tetrahedralize``'s ``bsp_seed``), by
#: ElementOrder. Measured on the 13 public CAD parts (bench/freecad_cad_corpus.py
#: /work/shared/data/corpus/cad --order 2, session 13):
#:  * tet10: from the Delaunay seed (with its flips) 10 parts mesh, from the paper's box 8
#:    (bottle and featuretype mesh only from the seed; SampleCrankshaft4A and U_Joint_2 from
#:    neither): the seed;
#:  * the worst dihedral angle of the 8 parts that mesh both ways is higher from the box on 6
#:    (Kurbelwelle 2.36 against 0.84 deg, t20_data 4.83 against 2.59; part.step 1.87 against
#:    2.02), and at order 1 every part but the open shell meshes from the box: the box there.
PIPELINE_BSP_SEED = {1: "box", 2: "auto"}


def core_options(params, projection=None):
    """The ``options`` dict for ``core.tetrahedralize`` from ``params`` (zero, i.e. automatic
    or off, values are left out; the names are in ``core.OPTION_NAMES``)."""
    # FreeCAD finds the element faces under a constraint by node membership (freecad.md §7):
    # the mesh must not let a tet look as if it had a face on a CAD face it does not have.
    opts = {CORE_OPTION_OF["order"]: int(params.order),
            CORE_OPTION_OF["allow_boundary_steiner"]: bool(params.allow_boundary_steiner),
            "separate_face_tags": True,
            "bsp_seed": PIPELINE_BSP_SEED[int(params.order)]}
    for field in ("max_size", "min_size", "quality_bound"):
        value = getattr(params, field)
        if value > 0:
            opts[CORE_OPTION_OF[field]] = float(value)
    opts[CORE_OPTION_OF["thickness_ratio"]] = float(params.thickness_ratio)  # 0 turns it off
    if projection is not None:
        opts[CORE_PROJECTION_OPTION] = projection
    return opts


# ------------------------------------------------------------------------------------------
# the pipeline
# ------------------------------------------------------------------------------------------

def brep_copy(shape):
    """``shape`` written as BREP text and read back: exactly the shape the worker process reads
    from its job file (BREP text is not bit-exact for every curve, so both paths mesh this copy
    and give identical meshes)."""
    import Part

    copy = Part.Shape()
    copy.importBrepFromString(shape.exportBrepToString())
    return copy


#: tet10: when every mend leaves inverted elements, one more attempt on a tessellation whose
#: AngularDeflection is this many times finer (featuretype meshes so, with twice the tets).
FINER_TESSELLATION_FACTOR = 2.0


def mesh_cad_shape(shape, params, progress=None, cancel=None, source="", shape_is_brep_copy=False):
    """Mesh every solid of ``shape`` (a ``Part.Shape``) with ``params``; see the module docstring.

    The shape is first replaced by its :func:`brep_copy` (same faces in the same order), unless
    ``shape_is_brep_copy`` says it already is one (the worker, which read it from BREP).

    progress: ``progress(stage, fraction)`` (fraction in [0, 1] or None), called now and then.
    cancel:   ``cancel()`` returning True stops the run with MeshingCancelled.
    source:   a name for messages (the document object's label, a file name).

    tet10 without RemeshSurface: if curved mid-nodes still invert elements after every mend,
    the shape is meshed once more from a tessellation with an AngularDeflection
    ``FINER_TESSELLATION_FACTOR`` times finer (one core run and the local mends, no surface
    rounds); its mesh is returned with a note saying so and ``stats["angular_deflection_used"]``,
    or, if that fails too, the first attempt's error is raised with a sentence on the second.

    Returns a :class:`MeshResult`. Raises InputError (not a solid, open shell, bad parameter,
    an option the core cannot honour: the message says what and where), MeshingCancelled, or
    InternalError (the core failed; the message says so; :class:`CurvedElementsInverted` for
    tet10 elements the curved boundary inverts).
    """
    params = params.validate() if isinstance(params, MeshParameters) else \
        MeshParameters.from_dict(dict(params))
    if not shape_is_brep_copy:
        shape = brep_copy(shape)
    try:
        # with RemeshSurface there is no finer-tessellation attempt: straighten at once
        return _mesh_cad_shape_once(shape, params, progress, cancel, source,
                                    straighten=params.remesh_surface)
    except CurvedElementsInverted as first:
        if params.order != 2 or params.remesh_surface:
            raise
        finer = dataclasses.replace(
            params, angular_deflection=params.angular_deflection / FINER_TESSELLATION_FACTOR)
        report = progress or (lambda stage, fraction: None)

        def again(stage, fraction):
            report("finer tessellation (AngularDeflection %.3g): %s"
                   % (finer.angular_deflection, stage), fraction)

        try:
            result = _mesh_cad_shape_once(shape, finer, again, cancel, source, repair_rounds=0)
        except CurvedElementsInverted as second:
            both = CurvedElementsInverted(
                first.summary, first.count,
                "%s. A finer tessellation (AngularDeflection %.3g) was tried too: it inverted %d "
                "element(s)" % (str(first)[len(first.summary):].rstrip("."),
                                finer.angular_deflection, second.count))
            if not params.straighten_midnodes:
                raise CurvedElementsInverted(
                    both.summary, both.count,
                    str(both)[len(both.summary):] + ". StraightenMidNodes (on by default) makes a "
                    "valid mesh with their mid-nodes pulled towards their straight edges") \
                    from None
            # the attempt that inverted fewer, once more (the pipeline is deterministic), its
            # inverted elements' mid-nodes pulled towards their chords
            if first.count <= second.count:
                retry, retry_report, rounds = params, report, None
            else:
                retry, retry_report, rounds = finer, again, 0
            try:
                result = _mesh_cad_shape_once(shape, retry, retry_report, cancel, source,
                                              repair_rounds=rounds, straighten=True)
            except CurvedElementsInverted:
                raise both from None
            if retry is finer:
                result.stats["angular_deflection_used"] = float(finer.angular_deflection)
            return result
        result.stats["angular_deflection_used"] = float(finer.angular_deflection)
        result.notes.append(
            "tet10: with AngularDeflection %.3g the curved mid-nodes inverted elements (%s); the "
            "mesh was made from a finer tessellation, AngularDeflection %.3g"
            % (params.angular_deflection, first.summary, finer.angular_deflection))
        return result


def _mesh_cad_shape_once(shape, params, progress, cancel, source, repair_rounds=None,
                         straighten=False):
    """One run of the pipeline on ``shape`` (a BREP copy) with validated ``params``.
    ``repair_rounds``: tet10 attempts on a mended surface after the first (None: the default,
    ``LOCAL_REFINEMENT_ROUNDS`` with RemeshSurface, ``CURVED_REPAIR_ROUNDS`` without).
    ``straighten``: with ``params.straighten_midnodes``, tet10 elements still inverted after
    every mend get their mid-nodes pulled towards their chords (:func:`straighten_inverted`)
    instead of the error. The rest as :func:`mesh_cad_shape`.
    """
    from . import cad_tessellation, core
    from .cad_projection import CadProjection

    t_start = time.perf_counter()
    report = progress or (lambda stage, fraction: None)

    def check_cancel():
        if cancel is not None and cancel():
            raise MeshingCancelled("cancelled: no mesh was made")

    report("tessellating the CAD faces", 0.0)
    size = params.max_size if params.max_size > 0 else None
    deflection = params.linear_deflection or \
        cad_tessellation.default_linear_deflection(shape, size)
    surfaces = cad_tessellation.tessellate_shape(shape, deflection, params.angular_deflection,
                                                 source=source)
    check_cancel()
    # fins (near-collinear triangles along CAD edges) make flat tets whatever the core does
    surfaces, fin_stats = flip_out_fins_of(surfaces)
    projection = CadProjection(shape)
    options = core_options(params, projection)
    element_size = params.max_size if params.max_size > 0 else automatic_element_size(shape)
    if params.remesh_surface:
        # the surface gets the element size: the volume follows it (without this, the core
        # would fill a fine surface with long tets reaching across the solid)
        options[CORE_OPTION_OF["max_size"]] = float(element_size)
    tessellation = surfaces
    size_points = np.zeros((0, 4))
    # tet10: with RemeshSurface, rounds of local refinement; without, CURVED_REPAIR_ROUNDS more
    # attempts on the best surface so far, its folding curved triangles (repair_curved_folds_of)
    # or its needles around the inverted elements (refine_around_points_of) mended, each kept
    # only if it inverts fewer elements (they help some parts and not others: measured)
    if repair_rounds is None:
        repair_rounds = LOCAL_REFINEMENT_ROUNDS if params.remesh_surface else CURVED_REPAIR_ROUNDS
    rounds = repair_rounds if params.order == 2 else 0

    def core_progress(stage, fraction):
        report(stage, None if fraction is None else 0.05 + 0.8 * float(fraction))

    best = None
    for attempt in range(rounds + 1):
        remesh_notes, remesh_stats = [], {}
        projection.disjoint_placements.clear()
        if params.remesh_surface:
            report("remeshing the CAD faces" if attempt == 0 else
                   "remeshing the CAD faces finer where curved tet10s inverted (round %d)"
                   % attempt, 0.02)
            surfaces, remesh_notes, remesh_stats = remesh_cad_surfaces(
                tessellation, projection, element_size, params, deflection, cancel=check_cancel,
                size_points=size_points)
        fold_stats = {}
        if attempt >= 1 and not params.remesh_surface:
            report("mending tessellation triangles around the curved tet10s that inverted "
                   "(round %d)" % attempt, 0.03)
            # round 1 mends folded triangles (if any); later rounds, or round 1 without folds,
            # split the needles around the elements that stayed inverted (separately: on
            # SampleCrankshaft4A the folds' mend alone gave 34, both at once 85)
            base, base_mesh, base_bad = best[1], best[4], best[-1]
            surfaces = base
            if attempt == 1:
                surfaces, fold_stats = repair_curved_folds_of(base, projection,
                                                              cancel=check_cancel)
            if all(a is b for a, b in zip(surfaces, base)):
                corners = base_mesh.points[base_mesh.tets[base_bad, :4]].reshape(-1, 3)
                surfaces, near_stats = refine_around_points_of(base, projection, corners,
                                                               cancel=check_cancel)
                fold_stats.update({"needle_" + k: v for k, v in near_stats.items()})
            if all(a is b for a, b in zip(surfaces, base)):
                break  # nothing changed: the best attempt stands
        try:
            mesh, stats = core.tetrahedralize(surfaces, options=options, progress=core_progress,
                                              cancel=cancel)
        except BspTetError:
            check_cancel()  # the core stopped because cancel() said so (whatever it raised)
            if best is not None and not params.remesh_surface:
                break  # the mended surface failed where the tessellation did not: keep that
            raise
        check_cancel()

        report("placing boundary nodes on the CAD faces", 0.87)
        faces, tags = boundary_faces_with_tags(mesh, surfaces)
        midnodes = boundary_midnodes(mesh, faces) if mesh.tets.shape[1] == 10 else \
            np.zeros((0, 3), dtype=np.int64)
        input_points = np.concatenate([s.points for s in surfaces])
        moved, max_move, kept = place_boundary_nodes_on_cad(
            mesh, faces, tags, midnodes, input_points, projection, cancel=check_cancel)
        bad = elements_inverted_by_projection(mesh, moved)
        if len(bad) and mesh.tets.shape[1] == 10:
            report("bending interior edges of curved tet10 elements", 0.88)
            bad, bent = bend_interior_edges(mesh, midnodes, bad, cancel=check_cancel)
            fold_stats["bent_interior_midnodes"] = int(len(bent))
            if len(bent):  # (moved stays the projected boundary nodes, for the stats)
                bad = elements_inverted_by_projection(mesh, np.union1d(moved, bent))
            if len(bad):
                report("sliding boundary mid-nodes along the CAD faces", 0.885)
                bad, slid = slide_boundary_midnodes(mesh, faces, tags, midnodes, bad, projection,
                                                    cancel=check_cancel)
                fold_stats["slid_boundary_midnodes"] = int(len(slid))
                if len(slid):
                    bad, bent2 = bend_interior_edges(mesh, midnodes, bad, cancel=check_cancel)
                    bent = np.union1d(bent, bent2)
                    fold_stats["bent_interior_midnodes"] = int(len(bent))
                    bad = elements_inverted_by_projection(mesh, np.union1d(moved, bent))
        if fold_stats:
            stats = dict(stats)
            stats["curved_repair"] = fold_stats
        if best is not None and len(bad) >= len(best[-1]):
            break  # refining made it no better: keep the best attempt
        best = (attempt, surfaces, remesh_notes, remesh_stats, mesh, stats, faces, tags, midnodes,
                moved, max_move, kept, bad)
        if len(bad) == 0 or attempt == rounds:
            break
        size_points = np.vstack([size_points, refinement_points(mesh, bad, params.min_size)])
    (attempt, surfaces, remesh_notes, remesh_stats, mesh, stats, faces, tags, midnodes, moved,
     max_move, kept, bad) = best
    straightened = None
    if len(bad) and straighten and params.straighten_midnodes and mesh.tets.shape[1] == 10:
        report("pulling the mid-nodes of elements that stay inverted towards their chords", 0.89)
        bad, straightened = straighten_inverted(mesh, midnodes, tags, bad, projection,
                                                cancel=check_cancel)
        stats = dict(stats)
        stats["curved_repair"] = dict(stats.get("curved_repair", {}), **straightened)
    check_elements_after_projection(mesh, moved, faces, tags, shape_face_names(projection),
                                    stats.get("min_dihedral_deg"), bad=bad)
    if attempt and params.remesh_surface:
        remesh_stats["local_refinement_rounds"] = attempt
    elif attempt:
        stats = dict(stats)
        stats["curved_repair"] = dict(stats.get("curved_repair", {}), used=True)
    check_cancel()

    report("looking for interior nodes within the CAD face tolerance", 0.9)
    near = interior_nodes_near_faces(mesh, faces, midnodes, projection)
    check_cancel()

    stats = dict(stats)
    stats["interior_nodes_on_faces"] = int(sum(len(v) for v in near.values()))
    stats["projected_nodes"] = int(len(moved))
    stats["max_projection_mm"] = float(max_move)
    stats["linear_deflection"] = float(deflection)
    if fin_stats["flips"]:
        stats["tessellation_fins"] = fin_stats
    if remesh_stats:
        stats["surface_remesh"] = remesh_stats
    # (the core's note on mid-nodes it left on their chords no longer holds: every boundary
    # mid-node went onto the CAD above, and what stays off is said below)
    notes = remesh_notes + [n for n in stats.get("notes", [])
                            if not n.endswith(core.MIDNODES_STRAIGHTENED_NOTE)]
    if projection.disjoint_placements:
        pairs = sorted({", ".join("Face%d" % (t + 1) for t in ts)
                        for ts in projection.disjoint_placements})
        notes.append(
            "%d boundary node(s) belong to CAD faces that share no edge or vertex (%s%s): faces "
            "of touching solids that coincide, or faces the tessellation joins across a face too "
            "small to get triangles; each node was put on the nearest of them"
            % (len(projection.disjoint_placements), "; ".join(pairs[:4]),
               " and %d more" % (len(pairs) - 4) if len(pairs) > 4 else ""))
    if kept:
        worst = max(d for _, d in kept.values())
        faces_named = sorted({"Face%d" % (t + 1) for ts, _ in kept.values() for t in ts})
        notes.append(
            "%d boundary node(s) stay off the CAD (up to %.3g mm, at %s): their place on the CAD "
            "edge is another node's (the mesh edge there is not along the CAD edge of its two "
            "faces), so getNodesByFace may miss them" % (len(kept), worst, ", ".join(faces_named)))
    if straightened is not None and straightened["straightened_midnodes"]:
        on_cad = straightened["straightened_boundary_midnodes"]
        notes.append(
            "tet10: curved mid-nodes inverted %d element(s) after every mend; %d mid-node(s) were "
            "pulled towards their straight edges to keep every element valid%s. A finer "
            "AngularDeflection or LinearDeflection, or ElementOrder 1st, keeps every boundary node "
            "on the CAD" % (straightened["inverted_before_straightening"],
                            straightened["straightened_midnodes"],
                            "" if not on_cad else
                            ", %d of them on the boundary, now up to %.3g mm off the CAD faces "
                            "(%s): getNodesByFace may miss those"
                            % (on_cad, straightened["max_off_cad_mm"],
                               ", ".join(shape_face_names(projection)[t]
                                         for t in straightened["faces"]))))
    if near:
        notes.append(
            "%d interior node(s) lie within the CAD face tolerance of a face (%s): FreeCAD's "
            "getNodesByFace counts them as nodes of that face, so a constraint there also acts "
            "on them (interior Steiner points the core put closer to the surface than the face "
            "tolerance)" % (stats["interior_nodes_on_faces"],
                            ", ".join("Face%d: %d" % (t + 1, len(v)) for t, v in near.items())))
    tetgen = None
    if params.compare_tetgen:
        report("tetgen -%s on the same surface" % TETGEN_SWITCHES, 0.92)
        tetgen = run_tetgen_comparison(surfaces)
    stats["seconds_total"] = time.perf_counter() - t_start
    report("done", 1.0)
    mesh.source = source or mesh.source
    return MeshResult(mesh, faces, tags, midnodes, shape_face_names(projection), stats, tetgen,
                      notes)


#: CharacteristicLengthMax 0 (automatic) with RemeshSurface: h = bounding-box diagonal / this.
AUTOMATIC_SIZE_OF_DIAGONAL = 20.0


def automatic_element_size(shape):
    """The element size of CharacteristicLengthMax 0: the shape's bounding-box diagonal / 20."""
    from . import cad_tessellation

    return cad_tessellation._diagonal(shape) / AUTOMATIC_SIZE_OF_DIAGONAL


def remesh_cad_surfaces(surfaces, projection, size, params, deflection, cancel=None,
                        size_points=None):
    """Each solid's tessellation remeshed by :func:`FemBspTet.surface_remesh.remesh_surface`
    towards the element size ``size``, with the tessellation's deflections as the curvature
    bounds. Faces that two solids share are left as they are (both
    sides must stay identical). A remeshed surface the core's exact input check refuses (a
    self-intersection the remeshing made, say) is replaced by the tessellation itself, with a
    note. Returns ``(surfaces, notes, stats)``: stats summed over the solids."""
    from . import core
    from .errors import InputError
    from .surface_remesh import RemeshError, remesh_surface

    frozen = shared_face_tags(surfaces)
    out, notes, total = [], [], {}
    for i, surf in enumerate(surfaces):
        where = "solid %d" % (i + 1) if len(surfaces) > 1 else "the solid"
        try:
            new, st = remesh_surface(surf, projection, size, deflection, params.angular_deflection,
                                     min_size=params.min_size, frozen_tags=frozen, cancel=cancel,
                                     size_points=size_points)
            core.check_surface(new)
        except (RemeshError, InputError) as e:
            notes.append("the surface remeshing of %s was not used (%s): the volume mesh is made "
                         "on OpenCASCADE's tessellation" % (where, e))
            out.append(surf)
            continue
        for k, v in st.items():
            if k.startswith(("min_", "median_")):
                total[k] = min(total.get(k, v), v)
            else:
                total[k] = total.get(k, 0) + v
        out.append(new)
    return out, notes, total


def shared_face_tags(surfaces):
    """Face tags that appear in more than one solid's surface (faces two solids share: both
    sides must stay identical, so they are never changed)."""
    counts = {}
    for surf in surfaces:
        for tag in set(surf.face_tags.tolist()):
            counts[tag] = counts.get(tag, 0) + 1
    return {tag for tag, c in counts.items() if c > 1}


def _mend_each_surface(surfaces, mend, summed, better=lambda st: True):
    """``mend(surface, frozen_tags) -> (Surface, stats)`` on each solid's surface. A changed
    surface is used only if ``better(stats)`` and it passes the core's exact input check; else
    the solid keeps its surface. Returns ``(surfaces, stats)``: the ``summed`` stats added over
    the solids whose surface was used, and ``not_used``."""
    from . import core
    from .errors import InputError
    from .surface_remesh import RemeshError

    frozen = shared_face_tags(surfaces)
    out, total = [], dict({k: 0 for k in summed}, seconds=0.0, not_used=0)
    for surf in surfaces:
        try:
            new, st = mend(surf, frozen)
            if new is not surf:
                if not better(st):
                    raise RemeshError("no better")
                core.check_surface(new)
        except (RemeshError, InputError):
            total["not_used"] += 1
            out.append(surf)
            continue
        for k in summed + ("seconds",):
            total[k] += st[k]
        out.append(new)
    return out, total


def flip_out_fins_of(surfaces):
    """Each solid's tessellation through :func:`FemBspTet.surface_remesh.flip_out_fins` (its
    near-collinear triangles flipped away inside their CAD faces; faces two solids share are
    left alone). A changed surface is used only if it passes the core's exact input check; else
    the solid keeps its tessellation. Returns ``(surfaces, stats)``, stats summed over the
    solids whose surface changed (``fins_before``, ``fins_after``, ``flips``, ``not_used``)."""
    from .surface_remesh import flip_out_fins

    def mend(surf, frozen):
        t0 = time.perf_counter()
        new, st = flip_out_fins(surf, frozen_tags=frozen)
        return new, dict(st, seconds=time.perf_counter() - t0)

    return _mend_each_surface(surfaces, mend, ("fins_before", "fins_after", "flips"))


def repair_curved_folds_of(surfaces, projection, cancel=None):
    """Each solid's tessellation through :func:`FemBspTet.surface_remesh.repair_curved_folds`
    (tet10 only). A repaired surface is used only if it has fewer folded triangles and passes
    the core's exact input check; else the solid keeps its tessellation. Returns ``(surfaces,
    stats)``, stats summed over the solids (``folded_before``, ``folded_after``, ``flips``,
    ``splits``, ``seconds``, ``not_used``)."""
    from .surface_remesh import repair_curved_folds

    return _mend_each_surface(
        surfaces,
        lambda surf, frozen: repair_curved_folds(surf, projection, frozen_tags=frozen,
                                                 cancel=cancel),
        ("folded_before", "folded_after", "flips", "splits"),
        better=lambda st: st["folded_after"] < st["folded_before"])


def refine_around_points_of(surfaces, projection, points, cancel=None):
    """Each solid's surface through :func:`FemBspTet.surface_remesh.refine_around_points`
    (tet10 only): its needle triangles around ``points`` (the corners of elements that curving
    inverted) split and flipped. A changed surface is used only if it passes the core's exact
    input check; else the solid keeps its surface. Returns ``(surfaces, stats)``, stats summed
    over the solids (``region_triangles``, ``splits``, ``flips``, ``seconds``, ``not_used``)."""
    from .surface_remesh import refine_around_points

    return _mend_each_surface(
        surfaces,
        lambda surf, frozen: refine_around_points(surf, projection, points, frozen_tags=frozen,
                                                  cancel=cancel),
        ("region_triangles", "splits", "flips"))


def bend_interior_edges(mesh, midnodes, bad, cancel=None):
    """:func:`FemBspTet.curved_untangle.untangle_interior_midnodes` on the elements ``bad`` of
    a tet10 mesh whose boundary mid-nodes are ``midnodes``: only interior mid-nodes move.
    Returns ``(still bad, moved nodes)``."""
    from .curved_untangle import untangle_interior_midnodes

    movable = np.zeros(len(mesh.points), dtype=bool)
    movable[mesh.tets[:, 4:10].reshape(-1)] = True
    if len(midnodes):
        movable[np.asarray(midnodes).reshape(-1)] = False
    return untangle_interior_midnodes(mesh.points, mesh.tets, bad, movable, cancel=cancel)


#: :func:`slide_boundary_midnodes`: where on its chord a mid-node's CAD place is sought (the
#: fraction from the edge's first corner), in the order tried; 1/2 is where the projection puts
#: it. Beyond 0.3 / 0.7 the element nears a quarter-point one (its Jacobian vanishes at a corner).
SLIDE_FRACTIONS = (0.6, 0.4, 0.65, 0.35, 0.7, 0.3, 0.55, 0.45)
#: :func:`slide_boundary_midnodes`: passes over the inverted elements at most.
SLIDE_ROUNDS = 4


def slide_boundary_midnodes(mesh, faces, tags, midnodes, bad, projection, rounds=None,
                            cancel=None):
    """Slide boundary mid-nodes of the tet10 elements ``bad`` along their CAD face or edge.

    A boundary mid-node must lie on its CAD face (or on the CAD edge of its two faces) for
    FreeCAD's constraints to find it, but not at the projection of its chord's midpoint: any
    point of the CAD there is as good for that. Where a needle triangle runs along a curved CAD
    edge, the curved edge's tangent at the needle's sharp corner turns past the needle's other
    edge and every element on it folds there; putting the mid-node nearer the other corner
    (the CAD point nearest the chord point at fraction ``SLIDE_FRACTIONS`` of the way) turns
    that tangent back, at the expense of the other end. A place is taken when it raises the
    smallest scaled Jacobian (:mod:`FemBspTet.curved_untangle`) over every element containing
    the mid-node; corners and interior nodes never move here, and a place where another node
    already is is never taken. Modifies ``mesh.points`` in place.

    ``rounds``: passes over ``bad`` at most (None: ``SLIDE_ROUNDS``). Returns ``(still bad,
    slid nodes)``.
    """
    from .curved_untangle import _scales, jacobians

    rounds = SLIDE_ROUNDS if rounds is None else rounds
    bad = np.unique(np.asarray(bad, dtype=np.int64))
    if len(bad) == 0 or len(midnodes) == 0:
        return bad, np.zeros(0, dtype=np.int64)
    pts, tets = mesh.points, mesh.tets
    node_tags = midnode_face_tags(midnodes, tags)
    owners = {}
    hit_e, hit_k = np.nonzero(np.isin(tets[:, 4:10], list(node_tags)))
    for e, k in zip(hit_e.tolist(), hit_k.tolist()):
        owners.setdefault(int(tets[e, 4 + k]), []).append((e, k))
    _, scale = _scales(pts, tets)
    taken = {tuple(p) for p in pts.tolist()}

    def worst(elems):
        return float((jacobians(pts[tets[elems]]).min(axis=1) / scale[elems]).min())

    slid = set()
    for _ in range(max(0, int(rounds))):
        if cancel is not None:
            cancel()
        changed = False
        for e in bad.tolist():
            for k in range(6):
                m = int(tets[e, 4 + k])
                if m not in node_tags:
                    continue
                elems = np.array(sorted({el for el, _ in owners[m]}), dtype=np.int64)
                i, j = _TET10_EDGES[k]
                u, v = pts[tets[e, i]], pts[tets[e, j]]
                home = pts[m].copy()
                best = (worst(elems), None)
                for frac in SLIDE_FRACTIONS:
                    q = np.array(projection.to_faces(u + frac * (v - u), node_tags[m]),
                                 dtype=np.float64)
                    if not np.all(np.isfinite(q)) or tuple(q.tolist()) in taken:
                        continue
                    pts[m] = q
                    value = worst(elems)
                    pts[m] = home
                    if value > best[0]:
                        best = (value, q)
                if best[1] is not None:
                    taken.discard(tuple(home.tolist()))
                    pts[m] = best[1]
                    taken.add(tuple(best[1].tolist()))
                    slid.add(m)
                    changed = True
        jac = jacobians(pts[tets[bad]]).min(axis=1)
        bad = bad[jac <= 0]
        if not changed or len(bad) == 0:
            break
    return bad, np.array(sorted(slid), dtype=np.int64)


def midnode_face_tags(midnodes, tags):
    """``{boundary mid-node: set of CAD face tags}``: the tags of the boundary triangles whose
    edges it is the mid-node of (``midnodes`` (k, 3) and ``tags`` (k,) per boundary triangle)."""
    node_tags = {}
    for f, t in zip(np.asarray(midnodes).tolist(), np.asarray(tags).tolist()):
        for m in f:
            node_tags.setdefault(m, set()).add(int(t))
    return node_tags


def straighten_inverted(mesh, midnodes, tags, bad, projection, cancel=None):
    """:func:`FemBspTet.curved_untangle.straighten_midnodes` on the elements ``bad`` of a tet10
    mesh (``mesh.points`` changed in place). Returns ``(still bad, stats)``; the stats say how
    many elements were inverted, how many mid-nodes were pulled (boundary ones apart), how far
    the pulled boundary ones are from their CAD faces at most (mm: from their places on the CAD,
    ``projection.to_faces``), and on which CAD faces (``faces``, sorted tags; a boundary
    mid-node belongs to the faces of the boundary triangles that share its edge)."""
    from .curved_untangle import straighten_midnodes

    count = int(len(bad))
    still, pulled, _ = straighten_midnodes(mesh.points, mesh.tets, bad, cancel=cancel)
    every = midnode_face_tags(midnodes, tags)
    node_tags = {m: every[m] for m in pulled.tolist() if m in every}  # the boundary ones
    off = 0.0
    for m, ts in sorted(node_tags.items()):
        q = np.array(projection.to_faces(mesh.points[m], ts), dtype=np.float64)
        off = max(off, float(np.linalg.norm(q - mesh.points[m])))
    return still, {"inverted_before_straightening": count,
                   "straightened_midnodes": int(len(pulled)),
                   "straightened_boundary_midnodes": len(node_tags),
                   "max_off_cad_mm": off,
                   "faces": sorted(set().union(*node_tags.values())) if node_tags else []}


def shape_face_names(projection):
    return ["Face%d" % (k + 1) for k in range(projection.face_count)]


def run_tetgen_comparison(surfaces):
    """``tetgen -pY`` on the surfaces: the comparison's row (:func:`FemBspTet.compare.comparison.
    tetgen_pY_row`) as a dict; a missing or failing TetGen is a row with ``status`` and
    ``message`` (never raises)."""
    from .compare.comparison import row_dict, tetgen_pY_row

    return row_dict(tetgen_pY_row(surfaces))


# ------------------------------------------------------------------------------------------
# boundary faces and their CAD face tags
# ------------------------------------------------------------------------------------------

def boundary_faces_of(tets):
    """(k, 3) outward boundary triangles (faces used by one tet) of positive tets (corner
    indices), in a deterministic order (sorted by their sorted corner triple)."""
    corners = np.asarray(tets)[:, :4]
    faces = np.concatenate([corners[:, list(f)] for f in _OUTWARD_FACES])
    key = np.sort(faces, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[np.sort(first[counts == 1])] if len(first) else faces[:0]


def boundary_faces_with_tags(mesh, surfaces):
    """Boundary triangles of ``mesh`` and the CAD face tag of each.

    A boundary triangle whose three corners are exactly the corners of an input triangle, in the
    same cyclic order, takes its tag (exact coordinate match: the core's boundary is the input
    triangulation; the order tells apart the coinciding faces of touching solids). One with a
    boundary Steiner point lies inside an input triangle: it takes the tag of the nearest input
    triangle facing the same way. Raises InternalError if the surfaces carry no tags.
    """
    faces = boundary_faces_of(mesh.tets)
    pts = mesh.points
    lookup = {}
    for s in surfaces:
        if s.face_tags is None:
            raise InternalError("%s: the surface has no CAD face tags" % (s.source or "surface"))
        for tri, tag in zip(s.triangles.tolist(), s.face_tags.tolist()):
            lookup.setdefault(_corner_key(s.points[tri]), tag)
    tags = np.full(len(faces), -1, dtype=np.int32)
    for k, f in enumerate(faces.tolist()):
        tags[k] = lookup.get(_corner_key(pts[f]), -1)
    missing = np.nonzero(tags < 0)[0]
    if len(missing):
        all_pts = [s.points[s.triangles] for s in surfaces]
        all_tags = np.concatenate([s.face_tags for s in surfaces])
        tri_pts = np.concatenate(all_pts)
        tri_normals = np.cross(tri_pts[:, 1] - tri_pts[:, 0], tri_pts[:, 2] - tri_pts[:, 0])
        for k in missing.tolist():
            corners = pts[faces[k]]
            centroid = corners.mean(axis=0)
            d2 = _point_triangle_dist2(centroid, tri_pts)
            # among the nearest input triangles, one facing the same way (a touching solid's
            # coinciding face faces the other way)
            normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
            d2 = np.where(tri_normals @ normal > 0, d2, d2 + np.inf)
            if not np.isfinite(d2).any():
                d2 = _point_triangle_dist2(centroid, tri_pts)
            tags[k] = all_tags[int(np.argmin(d2))]
    return faces, tags


def _corner_key(three_points):
    """The triangle's corners in their cyclic order, starting at the smallest: oriented, so
    that the coinciding faces of two touching solids (opposite orientations) differ."""
    rows = [tuple(r) for r in np.asarray(three_points, dtype=np.float64).tolist()]
    k = rows.index(min(rows))
    return tuple(rows[k:] + rows[:k])


def _point_triangle_dist2(p, tri):
    """Squared distance from point ``p`` to each triangle of ``tri`` (m, 3, 3)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    # Closest point on each triangle (Ericson, Real-Time Collision Detection 5.1.5), vectorised.
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp = p - b
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    cp = p - c
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
    q = a + ab * v[:, None] + ac * w[:, None]  # interior region
    # vertex and edge regions
    t_ab = np.clip(np.where(d1 - d3 != 0, d1 / np.where(d1 - d3 != 0, d1 - d3, 1), 0), 0, 1)
    t_ac = np.clip(np.where(d2 - d6 != 0, d2 / np.where(d2 - d6 != 0, d2 - d6, 1), 0), 0, 1)
    e_bc_num, e_bc_den = d4 - d3, (d4 - d3) + (d5 - d6)
    t_bc = np.clip(np.where(e_bc_den != 0, e_bc_num / np.where(e_bc_den != 0, e_bc_den, 1), 0),
                   0, 1)
    on_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    on_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    on_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    q = np.where(on_ab[:, None], a + ab * t_ab[:, None], q)
    q = np.where(on_ac[:, None], a + ac * t_ac[:, None], q)
    q = np.where(on_bc[:, None], b + (c - b) * t_bc[:, None], q)
    q = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, q)
    q = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, q)
    q = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, q)
    diff = q - p
    return _dot(diff, diff)


def _dot(u, v):
    return np.einsum("ij,ij->i", u, v)


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
    for k, (a, b, c) in enumerate(faces.tolist()):
        for j, (u, v) in enumerate(((a, b), (b, c), (c, a))):
            out[k, j] = mid_of[(u, v) if u < v else (v, u)]
    return out


# ------------------------------------------------------------------------------------------
# projection of boundary nodes
# ------------------------------------------------------------------------------------------

def place_boundary_nodes_on_cad(mesh, faces, tags, midnodes, input_points, projection,
                                cancel=None):
    """Move boundary nodes that are not tessellation vertices onto their CAD face or edge.

    A node's CAD faces are the tags of the boundary triangles it belongs to (for a mid-node:
    the triangles sharing its edge); one face: projected onto it; two: onto their common CAD
    edge (:meth:`CadProjection.to_faces`). Modifies ``mesh.points`` in place. A node whose
    projection lands exactly on another node (OpenCASCADE clamps to a CAD vertex when the mesh
    edge is not along the CAD edge its two faces share) is left where it is: two nodes at one
    place would make the mesh non-conforming. Returns ``(moved node indices, largest
    displacement in mm, {node: (tags, distance to its CAD place in mm)} of the nodes left)``.
    """
    pts = mesh.points
    node_tags = {}
    input_keys = {tuple(p) for p in np.asarray(input_points).tolist()}
    for k, (f, t) in enumerate(zip(faces.tolist(), tags.tolist())):
        for n in f:
            if tuple(pts[n].tolist()) not in input_keys:  # a boundary Steiner point
                node_tags.setdefault(n, set()).add(t)
        if len(midnodes):
            for m in midnodes[k].tolist():
                node_tags.setdefault(m, set()).add(t)
    moved, max_move, kept = [], 0.0, {}
    taken = {tuple(p) for p in pts.tolist()}
    for i, (n, ts) in enumerate(sorted(node_tags.items())):
        if cancel is not None and i % 256 == 0:
            cancel()
        q = np.array(projection.to_faces(pts[n], ts), dtype=np.float64)
        d = float(np.linalg.norm(q - pts[n]))
        if d > 0:
            if tuple(q.tolist()) in taken:
                kept[n] = (sorted(ts), d)
                continue
            pts[n] = q
            taken.add(tuple(q.tolist()))
            moved.append(n)
            max_move = max(max_move, d)
    return np.array(moved, dtype=np.int64), max_move, kept


def interior_nodes_near_faces(mesh, faces, midnodes, projection):
    """``{face tag: [node, ...]}`` of the nodes that are not boundary nodes of a face but lie
    within its tolerance (``FemMesh.getNodesByFace`` would return them too). Faces without such
    nodes are left out."""
    on_boundary = np.zeros(len(mesh.points), dtype=bool)
    on_boundary[faces.reshape(-1)] = True
    if len(midnodes):
        on_boundary[midnodes.reshape(-1)] = True
    interior = np.nonzero(~on_boundary)[0]
    out = {}
    if len(interior) == 0:
        return out
    for tag in range(projection.face_count):
        found = projection.nodes_within_tolerance(mesh.points, tag, interior)
        if found:
            out[tag] = found
    return out


def tet10_jacobians(points, tets):
    """Jacobian determinants of 10-node tets at their 10 nodes and the centroid: (m, 11).

    Shape functions in barycentric coordinates: corner ``L_i (2 L_i - 1)``, mid-node
    ``4 L_i L_j``; for straight edges every value equals ``det[b - a, c - a, d - a]``
    (:func:`FemBspTet.curved_untangle.jacobians`).
    """
    from .curved_untangle import jacobians

    return jacobians(points[tets])


#: tet10 without RemeshSurface: how many times the surface around the elements that curving
#: inverted is mended (round 1: folded triangles; then needles) and meshed again while that
#: lowers their number (each round costs a core run).
CURVED_REPAIR_ROUNDS = 2
#: With RemeshSurface and tet10: how many times the surface is remeshed finer around tets that
#: the curved mid-nodes would invert before the pipeline gives up with the error.
LOCAL_REFINEMENT_ROUNDS = 3


def elements_inverted_by_projection(mesh, moved):
    """Indices of the tets with a moved node that are inverted or (tet10) have a non-positive
    Jacobian determinant at a node or the centroid (double precision)."""
    if len(moved) == 0:
        return np.zeros(0, dtype=np.int64)
    is_moved = np.zeros(len(mesh.points), dtype=bool)
    is_moved[moved] = True
    touched = np.nonzero(is_moved[mesh.tets].any(axis=1))[0]
    t = mesh.tets[touched]
    p = mesh.points
    a, b, c, d = (p[t[:, i]] for i in range(4))
    bad = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) <= 0
    if t.shape[1] == 10:
        bad |= (tet10_jacobians(p, t) <= 0).any(axis=1)
    return touched[bad]


def refinement_points(mesh, tets, min_size=0.0):
    """Size points ``x, y, z, s`` (for ``surface_remesh.remesh_surface``) that make the surface
    around ``tets`` half as fine as their longest edge (never below ``min_size``)."""
    corners = mesh.points[mesh.tets[tets, :4]]  # (k, 4, 3)
    longest = np.zeros(len(tets))
    for i in range(4):
        for j in range(i + 1, 4):
            longest = np.maximum(longest, np.linalg.norm(corners[:, i] - corners[:, j], axis=1))
    size = np.maximum(0.5 * longest, min_size)
    return np.column_stack([corners.mean(axis=1), size])


def check_elements_after_projection(mesh, moved, faces, tags, face_names, min_dihedral=None,
                                    bad=None):
    """Raise InternalError if a tet with a moved node is inverted or (tet10) has a non-positive
    Jacobian determinant at a node or the centroid. The message names the tet and CAD face.

    This happens when a tet next to a curved face is thinner than the distance its mid-nodes
    move (the chord sag): flat tets (dihedral angles near 0 or 180 degrees) that only quality
    refinement of the core removes; ``min_dihedral`` (degrees) is quoted in the message.
    ``bad``: the result of :func:`elements_inverted_by_projection` if the caller has it."""
    if bad is None:
        bad = elements_inverted_by_projection(mesh, moved)
    if len(bad):
        e = int(bad[0])
        node_set = set(mesh.tets[e].tolist())
        where = sorted({face_names[g] for f, g in zip(faces.tolist(), tags.tolist())
                        if set(f) <= node_set})
        at = " (at %s)" % ", ".join(where) if where else ""
        if mesh.tets.shape[1] == 10:
            flat = ("; the mesh's worst dihedral angle is %.3g degrees: elements next to the "
                    "curved face are thinner than the distance their mid-nodes move onto it"
                    % min_dihedral) if min_dihedral is not None else ""
            raise CurvedElementsInverted(
                "placing the tet10 mid-nodes on the curved CAD faces would invert %d element(s), "
                "first tet %d%s%s" % (len(bad), e, at, flat), len(bad),
                ". No mesh was made (mid-nodes left off the CAD face would not be found by the "
                "constraints). ElementOrder 1st meshes this shape (its corner nodes are on the "
                "CAD faces)")
        flat = ("; the mesh's worst dihedral angle is %.3g degrees" % min_dihedral
                if min_dihedral is not None else "")
        raise InternalError(
            "moving the boundary nodes added by the size refinement onto the curved CAD faces "
            "would invert %d element(s), first tet %d%s%s: the tessellation is farther from the "
            "CAD surface there than those elements are thick. No mesh was made (nodes left off "
            "the CAD face would not be found by the constraints). A smaller LinearDeflection "
            "(a tessellation closer to the CAD faces), a larger CharacteristicLengthMax, or "
            "CharacteristicLengthMax 0 (no boundary nodes added) avoids it"
            % (len(bad), e, at, flat))
