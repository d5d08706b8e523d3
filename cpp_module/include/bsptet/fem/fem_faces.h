// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet FEM pipeline, 2D: the CAD faces of a model as a triangle FEM mesh (shell and plane
// analyses: CalculiX S3/S6, CPS3/CPS6), as FreeCAD's Gmsh mesher gives for a Face or a Shell.
//
//   FemMesh mesh_cad_faces(const cad::CadModel& model, const FemOptions& options, FemStats* stats)
//
// Stages: every CAD edge, then every CAD face meshed once at the size field (cad/cad_surface.h,
// the same surface mesher as the volume path's stage 1); for order 2, one mid-node per triangle
// edge, put on the CAD:
//  * an edge between triangles of two faces: on their common CAD edge (cad_projection.h hook);
//  * an edge inside one face (a seam included): on that face; when the face's nearest point lies
//    outside its trimming (cad_projection.h) the mid-node stays on the chord;
//  * an edge of one triangle only (the free border of a Face or an open Shell): on the CAD edge
//    its nodes lie on (a node inside an edge names it; two CAD vertices name the edge joining
//    them, the nearest one when several do).
// A curved 6-node triangle is kept only when the normal component of its Jacobian, relative to
// its straight triangle's normal, has positive Bezier coefficients (so it is positive over the
// whole element: the element neither folds nor degenerates); otherwise its mid-nodes go back on
// their chords, and so on until every curved triangle passes (mid-nodes only ever go back, so this
// ends). The coefficients are computed in floating point: a check of shape, not an exact proof.
//
// Output: FemMesh with no tets (mesh.tet empty), `tri` every CAD face's triangles once (n1 n2 n3,
// then m12 m23 m31 for order 2) oriented as the shape orients each face, `tri_face` their faces.
// Node order: the CAD surface nodes (cad_surface.h order), then the mid-nodes in the order their
// edges are first met (triangle order, edge order). Deterministic.
#pragma once

#include "bsptet/cad/cad_model.h"
#include "bsptet/fem/fem_mesh.h"

namespace bsptet::fem {

/// Meshes every CAD face of `model` (read with cad::CadContent::kFaces) as above. FemOptions'
/// volume options (optimize_rounds) are unused. Sets `stats` surface_nodes, surface_triangles,
/// midnodes_projected, midnodes_straightened, nodes, boundary_triangles (all triangles), size,
/// min_size, seconds_surface, seconds_total. Throws as mesh_cad_model.
FemMesh mesh_cad_faces(const cad::CadModel& model, const FemOptions& options, FemStats* stats = nullptr);

}  // namespace bsptet::fem
