# SPDX-License-Identifier: LGPL-2.1-or-later
"""A tet mesh checked against the CAD part it was made for, whoever made it (ours, Gmsh, Netgen):

    report = check_against_cad("part.step", read_tet_mesh("part.inp"))
    report["valid"], report["on_cad"], report["max_distance"], report["messages"]

* The mesh itself, exactly (:func:`FemBspTet.kernel.core.check_mesh` with the mesh's own boundary as the
  reference): positive corner tets, conforming faces, a closed boundary; for tet10 the Jacobian
  certified positive over every element (:func:`FemBspTet.kernel.core.certify_tet10`).
* Its boundary on the CAD: every boundary node (corners and, for tet10, the mid-nodes of the
  boundary triangles' edges) within its CAD face's tolerance (OpenCASCADE's
  ``BRep_Tool::Tolerance``, what FreeCAD's ``getNodesByFace`` compares with) of that face. The
  face of a node is the one its file names when the file carries face tags (our ``.msh``,
  ``.vtu``, ``.mesh``; a node on several faces is measured to the nearest of them), else the
  nearest face of the part (``cpp_module/include/bsptet/cad/cad_distance.h``).

Solids that touch without sharing a CAD face have coincident, distinct nodes where they touch; the
exact check of the whole mesh reports those faces as crossing: check such a mesh per solid.
"""

import numpy as np

from ..io.volume_io import triangle_midnodes, triangle_tags_in_file
from ..kernel.core import boundary_surface, certify_tet10, check_mesh, native_cad
from ..kernel.mesh_types import TetMesh

def _boundary_nodes(mesh, triangles):
    """Corner nodes of ``triangles`` and, for tet10, the mid-nodes of their edges; with, per
    node, the rows of ``triangles`` it belongs to (one of them)."""
    nodes = [triangles.ravel()]
    rows = [np.repeat(np.arange(len(triangles)), 3)]
    if mesh.tets.shape[1] == 10:
        nodes.append(triangle_midnodes(mesh.tets, len(mesh.points), triangles).T.ravel())
        rows.append(np.tile(np.arange(len(triangles)), 3))
    return np.concatenate(nodes), np.concatenate(rows)


def check_against_cad(cad_path, mesh: TetMesh, max_messages=20):
    """The report described in the module doc: the keys of :func:`core.check_mesh` (``valid`` is
    the mesh's own exact validity) and ``tet10_certified`` / ``tet10_not_certified`` (tet10),
    ``boundary_nodes``, ``off_cad_nodes`` (farther than their face's tolerance), ``max_distance``
    with its ``max_distance_face`` (1-based, FreeCAD's Face<n>) and ``max_distance_tolerance``,
    ``faces_tagged`` (nodes measured to the face their file names), ``on_cad`` and
    ``messages``."""

    boundary = boundary_surface(mesh)
    report = check_mesh(boundary, TetMesh(mesh.points, mesh.tets, source=mesh.source),
                        max_messages=max_messages)
    messages = list(report.get("messages", []))
    if mesh.tets.shape[1] == 10:
        cert = certify_tet10(mesh)
        report["tet10_certified"] = int(cert["certified"])
        report["tet10_not_certified"] = int(cert["invalid"]) + int(cert["undecided"])
        if report["tet10_not_certified"]:
            report["valid"] = False
            bad = np.flatnonzero(np.asarray(cert["status"]) != 0)[:5].tolist()
            messages.append(f"{report['tet10_not_certified']} tet10 elements are not certified "
                            f"valid (Jacobian not proved positive), first: tets {bad}")
    triangles = boundary.triangles
    nodes, rows = _boundary_nodes(mesh, triangles)
    tags = triangle_tags_in_file(mesh, triangles)[rows]
    # one measurement per node: its file's face if the file names one (the smallest tag seen)
    order = np.lexsort((np.where(tags < 0, np.iinfo(np.int64).max, tags), nodes))
    nodes, tags = nodes[order], tags[order]
    first = np.concatenate([[True], nodes[1:] != nodes[:-1]])
    nodes, tags = nodes[first], tags[first]
    distance, face, tolerance = native_cad().cad_face_distances(
        str(cad_path), np.ascontiguousarray(mesh.points[nodes]), tags.astype(np.int32))
    distance, face = np.asarray(distance), np.asarray(face)
    limit = np.asarray(tolerance)[face]
    off = distance > limit
    worst = int(np.argmax(distance)) if len(distance) else -1
    report.update(
        boundary_nodes=int(len(nodes)), faces_tagged=int((tags >= 0).sum()),
        off_cad_nodes=int(off.sum()),
        max_distance=float(distance[worst]) if worst >= 0 else 0.0,
        max_distance_face=int(face[worst]) + 1 if worst >= 0 else 0,
        max_distance_tolerance=float(limit[worst]) if worst >= 0 else 0.0,
        on_cad=not off.any())
    if off.any():
        first_off = np.flatnonzero(off)[:5]
        messages.append(
            f"{int(off.sum())} of {len(nodes)} boundary nodes are farther from their CAD face than "
            "its tolerance; first: " + "; ".join(
                f"node {int(nodes[i])} at {distance[i]:.3g} from Face{int(face[i]) + 1} "
                f"(tolerance {limit[i]:.3g})" for i in first_off))
    report["messages"] = messages[:max_messages]
    return report
