# SPDX-License-Identifier: LGPL-2.1-or-later
"""Meshing with the BspTet mesher object, and what scripts call (``import FemBspTet``):

    obj = FemBspTet.make_mesher(doc, part, CharacteristicLengthMax=500)
    FemBspTet.run_mesher(obj)                       # synchronous; raises on failure
    femmesh = FemBspTet.mesh_shape(shape, max_size=500, order=2)
    FemBspTet.export_mesh(obj, "part.inp")          # .inp .unv .vtk .vtu .med .z88

A failed run leaves the object's previous ``FemMesh`` as it was; only ``MeshStatus`` says what
went wrong. The task panel runs the same pipeline in a worker process
(:mod:`FemBspTet.freecad.mesh_worker`) and hands the result to :func:`apply_result` on the GUI thread.
"""

import json
import os


from ..compare.at_size import compare_at_size, SizeRow
from ..fem.mesh_pipeline import (dimension_of, FACE_GROUP_PREFIX, mesh_cad_shape, MeshParameters,
                                 PROPERTY_OF,
                                 removed_parameter_message, REMOVED_PARAMETERS)
from ..kernel.errors import InputError
from .femmesh import tetmesh_to_femmesh, triangles_to_femmesh, write_femmesh
from .mesher_object import DIMENSION_OF, source_of, source_property

#: Extensions :func:`export_mesh` writes (FreeCAD's own writers, SMESH conventions converted).
EXPORT_FORMATS = (".inp", ".unv", ".vtk", ".vtu", ".med", ".z88")


def parameters_from_object(obj):
    """:class:`MeshParameters` from the mesher object's properties (validated)."""
    return MeshParameters(
        max_size=float(obj.CharacteristicLengthMax.Value),
        min_size=float(obj.CharacteristicLengthMin.Value),
        order=1 if obj.ElementOrder == "1st" else 2,
        face_groups=bool(obj.FaceGroups),
        compare_peers=bool(obj.CompareWithPeers),
        dimension=dimension_of(shape_of(obj), DIMENSION_OF[obj.ElementDimension]),
        workers=int(getattr(obj, "Workers", 0)),
    ).validate()


def shape_of(obj):
    """The shape to mesh: the ``Shape`` of the object ``obj`` links to (property ``Shape`` on
    FreeCAD 1.x, ``Part`` on 0.20/0.21). InputError if there is none."""
    part = source_of(obj)
    if part is None:
        raise InputError("no solid is set: select the solid to mesh (property %s)"
                         % source_property(obj), where=obj.Label)
    shape = getattr(part, "Shape", None)
    if shape is None or shape.isNull():
        raise InputError("%s has no shape to mesh" % part.Label, where=obj.Label)
    return shape


def run_mesher(obj, progress=None, cancel=None):
    """Mesh the mesher object ``obj`` now, in this thread. Returns the MeshResult.

    progress(stage, fraction) and cancel() as in :func:`mesh_pipeline.mesh_cad_shape`.
    On failure the previous FemMesh stays, ``obj.MeshStatus`` says why, and the error
    (InputError, MeshingCancelled, InternalError; the message names the object) is raised.
    """
    try:
        params = parameters_from_object(obj)
        result = mesh_cad_shape(shape_of(obj), params, progress=progress, cancel=cancel,
                                compare=compare_at_size,
                                source=obj.Label)
    except Exception as e:  # every failure is recorded; the error itself goes on up
        record_failure(obj, e)
        raise
    apply_result(obj, result)
    return result


def record_failure(obj, error):
    """Say in ``obj.MeshStatus`` why the last run failed (the mesh itself is left alone)."""
    obj.MeshStatus = "failed: %s" % error


def femmesh_of(result, face_groups):
    """The ``Fem.FemMesh`` of a MeshResult (SMESH conventions; if ``face_groups``, the boundary
    triangles as faces and per CAD face a face group and a node group ``BspTet_Face<k>``)."""

    if len(result.mesh.tets) == 0:  # 2D: the triangles are the elements, grouped per CAD face
        return triangles_to_femmesh(result.mesh.points, result.groups(),
                                    group_prefix=FACE_GROUP_PREFIX, source=result.mesh.source)
    return tetmesh_to_femmesh(result.mesh, result.groups() if face_groups else None,
                              group_prefix=FACE_GROUP_PREFIX)


def apply_result(obj, result, femmesh=None):
    """Set ``obj.FemMesh`` and the result properties from ``result`` (a MeshResult). Call on the
    GUI thread when the GUI is up. ``femmesh`` may be given if already built."""
    fem = femmesh if femmesh is not None else femmesh_of(result, bool(obj.FaceGroups))
    st = result.stats
    obj.FemMesh = fem
    obj.Nodes = int(len(result.mesh.points))
    obj.Tetrahedra = int(len(result.mesh.tets))
    obj.Triangles = 0 if len(result.mesh.tets) else int(len(result.boundary_faces))
    obj.SteinerPoints = int(st.get("steiner_points", 0))
    obj.BoundarySteinerPoints = int(st.get("boundary_steiner_points", 0))
    obj.MinDihedralAngle = float(st.get("min_dihedral_deg") or 0.0)
    obj.MaxRadiusEdgeRatio = float(st.get("max_radius_edge_ratio") or 0.0)
    obj.MeshingTime = float(st.get("seconds_total") or 0.0)
    obj.MedianTetMinDihedralAngle = float(st.get("median_tet_min_dihedral_deg") or 0.0)
    obj.MeshNotes = [str(n) for n in result.notes]
    obj.Comparison = [comparison_line(SizeRow.from_dict(r)) for r in result.comparison]
    obj.ComparisonData = json.dumps(result.comparison)
    if obj.Triangles:
        obj.MeshStatus = "meshed: %d nodes, %d %s" % (
            obj.Nodes, obj.Triangles, "tria6" if len(result.boundary_midnodes) else "tria3")
    else:
        obj.MeshStatus = "meshed: %d nodes, %d %s" % (
            obj.Nodes, obj.Tetrahedra, "tet10" if result.mesh.tets.shape[1] == 10 else "tet4")


def comparison_line(row):
    """One line of the ``Comparison`` property for a :class:`SizeRow`."""
    if row.status != "ok":
        return "%s (%s): %s, %s" % (row.mesher, row.command, row.status, row.message)
    return ("%s (%s): %d nodes, %d tetrahedra, smallest angle %.1f°, median per-tet smallest "
            "%.1f°, %.2f s" % (row.mesher, row.command, row.nodes, row.tets,
                               row.min_dihedral_deg, row.median_tet_min_dihedral_deg,
                               row.seconds))


def comparison_rows(obj):
    """The comparison's rows (:class:`SizeRow`) stored on the object, ours first; empty when it
    was not run."""
    try:
        return [SizeRow.from_dict(r) for r in json.loads(obj.ComparisonData or "[]")]
    except (ValueError, TypeError):
        return []


def mesh_shape(shape, **options):
    """Mesh a ``Part.Shape`` and return a ``Fem.FemMesh`` (SMESH conventions).

    options: MeshParameters fields (``max_size``, ``min_size``, ``order``, ``face_groups``) or
    the object's property names (``CharacteristicLengthMax``, ``CharacteristicLengthMin``,
    ``ElementOrder`` "1st"/"2nd", ``FaceGroups``). The former tessellation options
    (``LinearDeflection``, ``RemeshSurface``, ...) are refused with the reason. Raises
    InputError / InternalError with a message.
    """
    params = MeshParameters(compare_peers=False).to_dict()
    field_of = {prop: field for field, prop in PROPERTY_OF.items()}
    field_of.update({prop: field for field, prop in REMOVED_PARAMETERS.items()})
    removed = [key for key in options if field_of.get(key, key) in REMOVED_PARAMETERS]
    if removed:
        raise InputError(removed_parameter_message(removed))
    for key, value in options.items():
        field = field_of.get(key, key)
        if key == "ElementOrder":
            value = {"1st": 1, "2nd": 2}.get(value, value)
        params[field] = value
    params = MeshParameters.from_dict(params)
    result = mesh_cad_shape(shape, params)
    return femmesh_of(result, params.face_groups)


def export_mesh(obj, path):
    """Write the mesh of ``obj`` (any FEM mesh object) to ``path`` with FreeCAD's writer for its
    extension: .inp (CalculiX C3D4/C3D10), .unv, .vtk, .vtu, .med, .z88. Returns the path.
    Written to a temporary file and renamed: a failure leaves no partial file."""


    ext = os.path.splitext(os.fspath(path))[1].lower()
    if ext not in EXPORT_FORMATS:
        raise InputError("cannot export a mesh as %r; use one of %s"
                         % (ext or "(no extension)", " ".join(EXPORT_FORMATS)), where=path)
    fem = obj.FemMesh
    if fem.VolumeCount == 0:
        raise InputError("has no volume mesh to export: mesh it first", where=obj.Label)
    return write_femmesh(path, fem)
