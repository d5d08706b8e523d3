// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: how far points are from a model's faces, for checking a mesh against its
// CAD (`fembsptet check PART.step MESH`), whoever made the mesh.
//
//   FaceDistances d = distances_to_faces(model, points, faces);   // faces[i] = -1: the nearest
//
// A point with a known face (0-based, as CadModel numbers them) is measured to that bounded face;
// one with face -1 to every face whose bounding box could hold a nearer point, and the nearest
// wins. A distance is the smaller of BRepExtrema_DistShapeShape's (what FreeCAD's distToShape
// gives) and the projection's onto the trimmed surface (cad_projection.h): both are distances to
// real points of the face, and BRepExtrema alone can stop at a local minimum on a B-spline face.
// Model units.
#pragma once

#include <vector>

#include "bsptet/cad/cad_model.h"
#include "bsptet/mesh/types.h"

namespace bsptet::cad {

struct FaceDistances {
  std::vector<double> distance;  ///< per point
  std::vector<int> face;         ///< per point: the face measured to (the nearest when not given)
  std::vector<double> face_tolerance;  ///< per face of the model: BRep_Tool::Tolerance
};

/// `faces` is empty (every point searched) or has one entry per point (-1: search). Throws
/// InputError for a face index outside the model, MeshingError if OpenCASCADE cannot measure.
FaceDistances distances_to_faces(const CadModel& model, const std::vector<Vec3>& points,
                                 const std::vector<int>& faces);

}  // namespace bsptet::cad
