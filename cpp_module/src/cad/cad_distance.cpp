// SPDX-License-Identifier: LGPL-2.1-or-later
// Distances from points to a model's faces (cad/cad_distance.h).
#include "bsptet/cad/cad_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <Standard_Failure.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Pnt.hxx>

#include "bsptet/cad/cad_projection.h"
#include "bsptet/numerics/errors.h"

namespace bsptet::cad {
namespace {

struct Box {
  double lo[3], hi[3];
  /// Distance from `p` to the box (0 inside): no point of the face is nearer.
  double distance(const Vec3& p) const {
    const double c[3] = {p.x, p.y, p.z};
    double s = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = c[k] < lo[k] ? lo[k] - c[k] : (c[k] > hi[k] ? c[k] - hi[k] : 0.0);
      s += d * d;
    }
    return std::sqrt(s);
  }
};

/// The smaller of two distances to real points of the face (both bound the true distance from
/// above): BRepExtrema's (what FreeCAD's distToShape gives; it can stop at a local minimum on a
/// B-spline face) and the projection onto the trimmed surface (CadProjector::to_face).
double measure(const CadModel& model, CadProjector& projector, int face, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  try {
    const TopoDS_Vertex vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(p.x, p.y, p.z));
    BRepExtrema_DistShapeShape extrema(model.faces(face + 1), vertex);
    if (extrema.IsDone() && extrema.NbSolution() >= 1) best = extrema.Value();
  } catch (const Standard_Failure&) {
  }
  try {
    const Vec3 q = projector.to_face(p, face);
    const double dx = p.x - q.x, dy = p.y - q.y, dz = p.z - q.z;
    best = std::min(best, std::sqrt(dx * dx + dy * dy + dz * dz));
  } catch (const Error&) {
  }
  if (!std::isfinite(best))
    throw MeshingError(ErrorCode::kInternal, "cad_distance", face,
                       model.source + ": OpenCASCADE could not measure a distance to Face" + std::to_string(face + 1));
  return best;
}

}  // namespace

FaceDistances distances_to_faces(const CadModel& model, const std::vector<Vec3>& points,
                                 const std::vector<int>& faces) {
  const int nf = model.num_faces();
  if (!faces.empty() && faces.size() != points.size())
    throw InputError(ErrorCode::kBadArgument, "cad_distance", -1,
                     "one face per point (or none) is needed, got " + std::to_string(faces.size()) + " for " +
                         std::to_string(points.size()) + " points");
  FaceDistances out;
  out.distance.assign(points.size(), 0.0);
  out.face.assign(points.size(), -1);
  out.face_tolerance.resize(static_cast<std::size_t>(nf));
  std::vector<Box> boxes(static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    const TopoDS_Face& face = TopoDS::Face(model.faces(f + 1));
    out.face_tolerance[static_cast<std::size_t>(f)] = BRep_Tool::Tolerance(face);
    Bnd_Box b;
    BRepBndLib::Add(face, b);  // enlarged by the face's tolerance: it holds the face
    Box& box = boxes[static_cast<std::size_t>(f)];
    b.Get(box.lo[0], box.lo[1], box.lo[2], box.hi[0], box.hi[1], box.hi[2]);
  }
  CadProjector projector(model);
  std::vector<int> order(static_cast<std::size_t>(nf));
  std::vector<double> box_distance(static_cast<std::size_t>(nf));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    const int given = faces.empty() ? -1 : faces[i];
    if (given >= nf || given < -1)
      throw InputError(ErrorCode::kBadArgument, "cad_distance", static_cast<std::int64_t>(i),
                       "point " + std::to_string(i) + ": the model has no Face" + std::to_string(given + 1));
    if (given >= 0) {
      out.distance[i] = measure(model, projector, given, p);
      out.face[i] = given;
      continue;
    }
    // the faces by the distance to their boxes; stop once a box is farther than the best
    for (int f = 0; f < nf; ++f) box_distance[static_cast<std::size_t>(f)] = boxes[static_cast<std::size_t>(f)].distance(p);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      const double da = box_distance[static_cast<std::size_t>(a)], db = box_distance[static_cast<std::size_t>(b)];
      return da != db ? da < db : a < b;
    });
    double best = std::numeric_limits<double>::infinity();
    int best_face = -1;
    for (const int f : order) {
      if (box_distance[static_cast<std::size_t>(f)] > best) break;
      const double d = measure(model, projector, f, p);
      if (d < best) {
        best = d;
        best_face = f;
      }
    }
    out.distance[i] = best;
    out.face[i] = best_face;
  }
  return out;
}

}  // namespace bsptet::cad
