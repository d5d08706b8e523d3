# SPDX-License-Identifier: LGPL-2.1-or-later
"""The BspTet mesher document object, made the way the FreeCAD version at hand makes its Gmsh and
Netgen mesh objects, with proxy type ``Fem::FemMeshBspTet``.

    obj = make_mesher(doc, part, CharacteristicLengthMax=500, ElementOrder="2nd")
    FemBspTet.run_mesher(obj)            # meshes it (mesher_tools); recompute never meshes

* C++ type: ``Fem::FemMeshShapeBaseObjectPython`` on FreeCAD 1.x, whose built-in ``Shape`` link
  (global scope) names the solid the mesh is made from; ``Fem::FemMeshObjectPython`` on FreeCAD
  0.20/0.21 (which have no shape-based mesh type), with our own ``Part`` link. Either way
  CalculiX, Z88 and Mystran take the object as the analysis mesh, and FEM's writers find the
  solid (they read ``mesh_obj.Shape``, else ``mesh_obj.Part``). :func:`source_of` and
  :func:`set_source` read and set the link whatever its name. The proxy's ``Type`` is
  ``Fem::FemMeshBspTet``: FEM never mistakes it for Gmsh.
* Files made with 0.20/0.21 (``Fem::FemMeshObjectPython`` with ``Part``) open on 1.x: on restore
  their ``Part`` link becomes a ``Shape`` link (global scope), as FreeCAD 1.x's own Gmsh object
  migrates its older files. Such a file still opens on 0.20/0.21, which read either link.
* Parameters mean what FemMeshGmsh's mean where the names are the same
  (``CharacteristicLengthMax``/``Min``: 0 = automatic; ``ElementOrder`` "1st"/"2nd").
* Results (read-only in the property editor) are set by ``mesher_tools.apply_result``.
* Saved files store ``module="FemBspTet.freecad.mesher_object" class="MeshBspTet"``: never rename
  them (files of earlier versions store ``FemBspTet.mesher_object``, kept as a thin module).
  Properties are added only if missing, from ``__init__`` and from ``onDocumentRestored`` (files
  of older versions gain new properties with their defaults). The parameters of the former
  tessellation pipeline (``LinearDeflection``, ``AngularDeflection``, ``QualityBound``,
  ``ThicknessRatio``, ``AllowBoundarySteiner``, ``RemeshSurface``, ``StraightenMidNodes``) are
  removed from restored objects: FreeCAD restores dynamic properties from the file whether or
  not the proxy knows them, so the files open as before, and nothing reads those values.
"""

from ..fem.mesh_pipeline import REMOVED_BECAUSE, removed_parameter_message, REMOVED_PARAMETERS
from ..kernel.errors import InputError
from ..kernel.freecad_env import import_freecad
from .preferences import object_defaults

#: Proxy type (``femutils.type_of_obj``).
PROXY_TYPE = "Fem::FemMeshBspTet"
#: C++ type of the document object on FreeCAD 1.x: a FEM mesh with a built-in ``Shape`` link.
SHAPE_OBJECT_TYPE = "Fem::FemMeshShapeBaseObjectPython"
#: C++ type of the document object on FreeCAD 0.20/0.21 (no shape-based type), with ``Part``.
OBJECT_TYPE = "Fem::FemMeshObjectPython"
#: The link to the solid: FreeCAD 1.x's built-in one, and ours on 0.20/0.21.
SHAPE_LINK = "Shape"
PART_LINK = "Part"

#: ElementDimension's choices, as FreeCAD's Gmsh object names them, and MeshParameters.dimension.
DIMENSIONS = ("From Shape", "2D", "3D")
DIMENSION_OF = {"From Shape": 0, "2D": 2, "3D": 3}

#: Property groups (FreeCAD's property editor splits camel case: short plain words fit its column).
PARAMS_GROUP = "Mesh Params"
RESULTS_GROUP = "Mesh Results"
#: Groups of earlier versions, renamed on restore.
FORMER_GROUPS = ("BspTet Mesh Params", "BspTet Mesh Results")

#: (type, name, group, tooltip, default) of every parameter property.
PARAMETER_PROPERTIES = (
    ("App::PropertyLink", PART_LINK, "FEM Mesh", "The solid (Part) the mesh is made from", None),
    ("App::PropertyLength", "CharacteristicLengthMax", PARAMS_GROUP,
     "Largest element size (0 = automatic: the bounding-box diagonal / 20). Curved faces and "
     "edges get smaller elements (12 per full circle)", 0.0),
    ("App::PropertyLength", "CharacteristicLengthMin", PARAMS_GROUP,
     "Smallest element size (0 = automatic: CharacteristicLengthMax / 50)", 0.0),
    ("App::PropertyEnumeration", "ElementDimension", PARAMS_GROUP,
     "3D: the solids as tetrahedra; 2D: every face as triangles (shell and plane analyses); "
     "From Shape: 3D if the shape holds a solid, else 2D (a Face or a Shell)",
     (DIMENSIONS, "From Shape")),
    ("App::PropertyEnumeration", "ElementOrder", PARAMS_GROUP,
     "1st: 4-node tetrahedra (3-node triangles in 2D); 2nd: 10-node tetrahedra (6-node "
     "triangles), boundary mid-nodes on the CAD faces", (("1st", "2nd"), "2nd")),
    ("App::PropertyBool", "FaceGroups", PARAMS_GROUP,
     "Add the boundary triangles as faces (tria6 for 2nd order), and a face group and a node "
     "group per CAD face (BspTet_Face1, ...)", True),
    ("App::PropertyBool", "CompareWithPeers", PARAMS_GROUP,
     "Also mesh the part at the same size with TetGen (tetgen -pq with the matching volume "
     "bound, on this mesh's surface), Gmsh and Netgen (on the CAD part, where installed) and "
     "show their counts, angles and times", True),
    ("App::PropertyInteger", "Workers", PARAMS_GROUP,
     "Solids meshed at the same time, one processor core each (0 = every core); a part of one "
     "big solid is cut in two or three pieces first; the mesh is the same for any value", 0),
)

#: (type, name, tooltip) of every read-only result property.
RESULT_PROPERTIES = (
    ("App::PropertyString", "MeshStatus", "Outcome of the last meshing run"),
    ("App::PropertyInteger", "Nodes", "Nodes of the mesh"),
    ("App::PropertyInteger", "Tetrahedra", "Tetrahedra of the mesh"),
    ("App::PropertyInteger", "Triangles", "Triangles of a 2D mesh (its elements)"),
    ("App::PropertyInteger", "SteinerPoints",
     "Corner nodes the volume mesher added to the CAD surface mesh's nodes"),
    ("App::PropertyInteger", "BoundarySteinerPoints",
     "Of those, the ones on the CAD faces (refinement of the surface)"),
    ("App::PropertyFloat", "MinDihedralAngle", "Smallest dihedral angle (degrees)"),
    ("App::PropertyFloat", "MedianTetMinDihedralAngle",
     "Median over the tetrahedra of each one's smallest dihedral angle (degrees)"),
    ("App::PropertyFloat", "MaxRadiusEdgeRatio", "Largest radius-edge ratio"),
    ("App::PropertyFloat", "MeshingTime", "Seconds of the last run (CAD to mesh)"),
    ("App::PropertyStringList", "MeshNotes", "What the mesher could not do as asked, warnings"),
    ("App::PropertyStringList", "Comparison",
     "The same part at the same size: this mesh, TetGen's, Gmsh's and Netgen's (nodes, "
     "tetrahedra, smallest and median per-tet smallest dihedral angle, seconds)"),
    ("App::PropertyString", "ComparisonData", "The comparison's rows as JSON (the task panel's "
     "table)"),
)
#: Result properties of earlier versions (a comparison with an unsized tetgen -pY), removed on
#: restore.
FORMER_RESULTS = ("TetGenCommand", "TetGenNodes", "TetGenTetrahedra", "TetGenSteinerPoints",
                  "TetGenBoundarySteinerPoints", "TetGenMinDihedralAngle",
                  "TetGenMaxRadiusEdgeRatio", "TetGenTime", "TetGenPeakMemory", "TetGenValid")
#: A parameter of earlier versions whose value carries over to its successor on restore.
RENAMED_PARAMETERS = {"CompareWithTetGen": "CompareWithPeers"}
#: Hidden in the property editor.
HIDDEN_RESULTS = ("ComparisonData",)


def object_type(doc):
    """The C++ type of a new mesher object in ``doc``'s FreeCAD (``Fem`` imported)."""
    return SHAPE_OBJECT_TYPE if SHAPE_OBJECT_TYPE in doc.supportedTypes() else OBJECT_TYPE


def source_property(obj):
    """Name of the link to the solid to mesh: ``Shape`` on FreeCAD 1.x objects (and on 0.20/0.21
    objects a 1.x version saved), else ``Part``."""
    if SHAPE_LINK in obj.PropertiesList and \
            obj.getTypeIdOfProperty(SHAPE_LINK).startswith("App::PropertyLink"):
        return SHAPE_LINK
    return PART_LINK


def source_of(obj):
    """The document object with the solid the mesher object meshes, or None."""
    return getattr(obj, source_property(obj), None)


def set_source(obj, part):
    """Link the mesher object to the document object ``part`` (or None) holding the solid."""
    setattr(obj, source_property(obj), part)


def _migrate_part_to_shape(obj):
    """On FreeCAD 1.x objects of 0.20/0.21 files: the ``Part`` link becomes a ``Shape`` link of
    global scope (what FreeCAD 1.x's mesh objects have). Returns True if it did."""
    if SHAPE_OBJECT_TYPE not in obj.Document.supportedTypes():
        return False  # FreeCAD 0.20/0.21: Part is the link
    if PART_LINK not in obj.PropertiesList or SHAPE_LINK in obj.PropertiesList:
        return False
    part = obj.getPropertyByName(PART_LINK)
    obj.setPropertyStatus(PART_LINK, "-LockDynamic")
    obj.removeProperty(PART_LINK)
    obj.addProperty("App::PropertyLinkGlobal", SHAPE_LINK, "FEM Mesh",
                    "The solid (Part) the mesh is made from")
    obj.Shape = part
    return True


def add_properties(obj):
    """Add every missing property of the mesher object; on objects of older files also remove
    the parameters of the former tessellation pipeline (``mesh_pipeline.REMOVED_PARAMETERS``)
    and the former comparison's results, carry renamed parameters over and move properties out
    of former groups. Used on creation and to upgrade restored objects. Returns the names of
    the parameters removed."""

    removed = [name for name in REMOVED_PARAMETERS.values() if name in obj.PropertiesList]
    for name in removed:
        obj.removeProperty(name)
    for name in FORMER_RESULTS:
        if name in obj.PropertiesList:
            obj.removeProperty(name)
    carried = {new: getattr(obj, old) for old, new in RENAMED_PARAMETERS.items()
               if old in obj.PropertiesList}
    for old in RENAMED_PARAMETERS:
        if old in obj.PropertiesList:
            obj.removeProperty(old)
    existing = set(obj.PropertiesList)
    for kind, name, group, tip, default in PARAMETER_PROPERTIES:
        if name == PART_LINK and source_property(obj) == SHAPE_LINK:
            continue
        if name in existing:
            _move_to_group(obj, name, group)
            continue
        obj.addProperty(kind, name, group, tip)
        if kind == "App::PropertyEnumeration":  # default: (choices, chosen)
            setattr(obj, name, list(default[0]))
            setattr(obj, name, default[1])
        elif default is not None:
            setattr(obj, name, carried.get(name, default))
    for kind, name, tip in RESULT_PROPERTIES:
        if name not in existing:
            obj.addProperty(kind, name, RESULTS_GROUP, tip)
        _move_to_group(obj, name, RESULTS_GROUP)
        obj.setEditorMode(name, 2 if name in HIDDEN_RESULTS else 1)  # hidden / read-only
    return removed


def _move_to_group(obj, name, group):
    if obj.getGroupOfProperty(name) in FORMER_GROUPS:
        obj.setGroupOfProperty(name, group)


class StatelessProxy:
    """Proxy serialisation with no state, for both pairs FreeCAD calls: __getstate__/__setstate__
    (0.20) and dumps/loads (newer versions). Everything lives in the object's properties."""

    def dumps(self):
        return None

    def loads(self, state):
        return None

    def __getstate__(self):
        return None

    def __setstate__(self, state):
        return None


class MeshBspTet(StatelessProxy):
    """Proxy of the mesher object. Holds no state of its own (everything is in properties)."""

    Type = PROXY_TYPE

    def __init__(self, obj):
        obj.Proxy = self
        add_properties(obj)

    def onDocumentRestored(self, obj):
        import FreeCAD

        if _migrate_part_to_shape(obj):
            FreeCAD.Console.PrintMessage(
                "FemBspTet: %s: the Part link of an older file is now the Shape link\n"
                % obj.Label)
        removed = add_properties(obj)
        if removed:
            FreeCAD.Console.PrintMessage(
                "FemBspTet: %s: removed the former mesher properties %s (%s)\n"
                % (obj.Label, ", ".join(removed), REMOVED_BECAUSE.split(";")[0]))

    def execute(self, obj):
        """Recompute never meshes (as FEM's Gmsh object): meshing is an explicit action."""
        return None


def is_mesher(obj):
    """True if ``obj`` is a BspTet mesher object."""
    return getattr(getattr(obj, "Proxy", None), "Type", None) == PROXY_TYPE


def make_mesher(doc, part=None, name="MeshBspTet", **properties):
    """Create a BspTet mesher object in ``doc`` for ``part`` (not meshed yet).

    doc:        a FreeCAD document.
    part:       the document object with the solid (``Part::Feature`` and the like), or None.
    name:       the object's name (FreeCAD makes it unique).
    properties: property values, e.g. ``CharacteristicLengthMax=500, ElementOrder="1st"``; the
                preferences (Edit > Preferences > FEM > BspTet) give the others.

    Returns the object. Raises InputError for an unknown property name or a bad value.
    """

    freecad = import_freecad()
    import Fem  # noqa: F401  (registers the Fem:: document object types)


    known = {p[1] for p in PARAMETER_PROPERTIES}
    removed = set(properties) & set(REMOVED_PARAMETERS.values())
    if removed:
        raise InputError("mesher property: " + removed_parameter_message(removed))
    renamed = sorted(set(properties) & set(RENAMED_PARAMETERS))
    if renamed:
        raise InputError("mesher property %s is called %s: use that name"
                         % (renamed[0], RENAMED_PARAMETERS[renamed[0]]))
    unknown = set(properties) - known
    if unknown:
        raise InputError("unknown mesher propert%s %s; the parameters are %s"
                         % ("y" if len(unknown) == 1 else "ies", ", ".join(sorted(unknown)),
                            ", ".join(sorted(known - {"Part"}))))
    obj = doc.addObject(object_type(doc), name)
    MeshBspTet(obj)
    values = dict(object_defaults())
    values.update(properties)
    if part is not None:
        values[PART_LINK] = part
    if PART_LINK in values:  # the solid's link is Shape on FreeCAD 1.x
        values[source_property(obj)] = values.pop(PART_LINK)
    try:
        for key, value in values.items():
            setattr(obj, key, value)
    except Exception as e:
        doc.removeObject(obj.Name)
        raise InputError("mesher property %s: %s" % (key, e)) from None
    if freecad.GuiUp:
        from ..gui.view_provider import VPMeshBspTet

        VPMeshBspTet(obj.ViewObject)
    return obj
