// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: points put onto the CAD faces and edges of a model, the projection hook of
// the quality stage (mesh/projection_hook.h ProjectionHook) backed by OpenCASCADE.
//
//   ProjectionHook hook = make_projection_hook(model);   // hook(point, face, other_face)
//   double d = distance_to_face(model, face, point);       // to the bounded face (tests)
//
// The hook's contract (tags are CAD face indices, 0-based, cad_model.h):
//  * other_face -1 or equal to face: the point goes onto that face. OpenCASCADE's nearest point
//    of the face's untrimmed surface (GeomAPI_ProjectPointOnSurf over the face's (u, v) bounds) is
//    the answer when its (u, v) lies inside the trimmed face (BRepTopAdaptor_FClass2d, IN or ON).
//    When it lies outside the trimming, the point sits in the sliver between a chord of the
//    surface mesh and a curved CAD edge; its nearest point of the bounded face is on that edge,
//    where a mesh vertex meant to be inside the face would make a flat triangle with three
//    corners on the edge. The hook then returns three NaNs: the quality stage refuses such a
//    point (the split does not happen; a tet10 mid-node stays on its chord). to_face() gives the
//    nearest point of the bounded face in every case.
//  * two different faces: the point belongs on their common CAD edge; it goes to the nearest
//    point of the nearest edge the two faces share (GeomAPI_ProjectPointOnCurve within the edge's
//    parameter range, or an end of the edge). Faces without a common edge (not expected from the
//    surface mesher): their nearest common CAD vertex, else the nearer of the two face points.
// Per face and per edge the OpenCASCADE objects (surface projector with its sampling grid, face
// classifier, curve projector) are built on first use and kept: later calls only run the search.
//
// A hook holds its own caches (shared by the copies of one std::function), never global state;
// it is not thread-safe: one hook per thread. The model must outlive the hook.
// Distances here place points on curved geometry; they decide nothing about mesh topology, which
// the quality stage decides exactly.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "bsptet/cad/cad_model.h"
#include "bsptet/mesh/projection_hook.h"
#include "bsptet/mesh/types.h"

namespace bsptet::cad {

/// Counts of what a projector did (for benchmarks and tests).
struct ProjectionStats {
  std::int64_t face_calls = 0;       ///< points put onto one face
  std::int64_t edge_calls = 0;       ///< points put onto the common edge of two faces
  /// Face points whose nearest surface point within the face's (u, v) bounds lies outside the
  /// trimmed face, or that have none there (the nearest point of the bounded face answered).
  std::int64_t outside_trim = 0;
  std::int64_t face_fallbacks = 0;   ///< OpenCASCADE failed on the surface: the bounded face answered
  std::int64_t no_common_edge = 0;   ///< two faces without a common edge (vertex or face used)
};

/// Projection onto the faces and edges of one model; see the file comment. Not thread-safe.
class CadProjector {
 public:
  /// Keeps a reference to `model` (it must outlive the projector). Builds the face-pair to
  /// common-edge table; everything per face or edge is built on first use.
  explicit CadProjector(const CadModel& model);
  ~CadProjector();
  CadProjector(const CadProjector&) = delete;
  CadProjector& operator=(const CadProjector&) = delete;

  /// The hook's answer (file comment): NaNs for a face point outside the trimmed face.
  /// Throws InputError for a face index out of range.
  Vec3 operator()(const Vec3& point, std::int32_t face, std::int32_t other_face);
  /// Nearest point of the bounded face `face` (0-based). `inside` (optional) receives whether the
  /// surface's own nearest point lay inside the trimmed face (false: the bounded-face search
  /// answered).
  Vec3 to_face(const Vec3& point, int face, bool* inside = nullptr);
  /// Nearest point of the bounded edge `edge` (0-based; a degenerated edge: its vertex).
  Vec3 to_edge(const Vec3& point, int edge);
  /// Non-degenerated edges shared by faces a and b (0-based, increasing); empty when none.
  const std::vector<int>& common_edges(int a, int b) const;

  const ProjectionStats& stats() const { return stats_; }

 private:
  struct FaceData;
  struct EdgeData;
  FaceData& face_data(int face);
  EdgeData& edge_data(int edge);
  Vec3 to_two_faces(const Vec3& point, int a, int b);

  const CadModel& model_;
  std::vector<std::unique_ptr<FaceData>> faces_;
  std::vector<std::unique_ptr<EdgeData>> edges_;
  std::map<std::pair<int, int>, std::vector<int>> common_edges_;
  std::vector<std::vector<int>> face_vertices_;  ///< sorted vertex indices per face
  ProjectionStats stats_;
};

/// The quality stage's hook for `model`: a CadProjector shared by the copies of the returned
/// function. `projector` (optional) receives it, to read its stats afterwards.
ProjectionHook make_projection_hook(const CadModel& model, std::shared_ptr<CadProjector>* projector = nullptr);

/// Distance from `point` to the bounded face `face` (0-based), by BRepExtrema_DistShapeShape:
/// what FreeCAD's FemMesh.getNodesByFace compares with the face's tolerance. Slow (a full
/// extrema search per call): for tests and reports.
double distance_to_face(const CadModel& model, int face, const Vec3& point);

/// BRep_Tool::Tolerance of face `face` (0-based), model units.
double face_tolerance(const CadModel& model, int face);

}  // namespace bsptet::cad
