// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: the size field (see size_field.h).
#include "bsptet/cad/size_field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <BRepAdaptor_Curve.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepLProp_CLProps.hxx>
#include <BRepLProp_SLProps.hxx>
#include <BRepTools.hxx>
#include <GeomAbs_SurfaceType.hxx>
#include <TopoDS.hxx>

#include "bsptet/numerics/errors.h"

namespace bsptet::cad {
namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNarrowFaceFactor = 2;

void check_option(double value, const char* name) {
  if (!std::isfinite(value) || value < 0) {
    std::ostringstream what;
    what << "option " << name << " must be a finite number >= 0, got " << value;
    throw InputError(ErrorCode::kBadArgument, "size_field", -1, what.str());
  }
}

/// Largest principal curvature of an analytic face (its smallest radius); -1 for other surfaces.
double analytic_face_curvature(const TopoDS_Face& face) {
  BRepAdaptor_Surface surface(face, /*restriction=*/true);
  switch (surface.GetType()) {
    case GeomAbs_Plane:
      return 0;
    case GeomAbs_Cylinder:
      return 1.0 / surface.Cylinder().Radius();
    case GeomAbs_Sphere:
      return 1.0 / surface.Sphere().Radius();
    case GeomAbs_Torus:
      return 1.0 / surface.Torus().MinorRadius();
    default:
      return -1;
  }
}

}  // namespace

SizeField::SizeField(const CadModel& model, const SizeOptions& options) {
  check_option(options.size, "size");
  check_option(options.min_size, "min_size");
  check_option(options.points_per_circle, "points_per_circle");
  check_option(options.grading, "grading");
  const double diagonal = model.diagonal();
  size_ = options.size > 0 ? options.size : diagonal / 20;
  min_size_ = options.min_size > 0 ? std::min(options.min_size, size_) : size_ / 50;
  min_size_given_ = options.min_size > 0;
  grading_ = options.grading > 0 ? options.grading : 0.3;
  points_per_circle_ = options.points_per_circle;
  face_size_.assign(static_cast<std::size_t>(model.num_faces()), size_);
  local_curvature_.assign(static_cast<std::size_t>(model.num_faces()), 0);
  for (int f = 0; f < model.num_faces(); ++f) {
    double s = size_;
    const auto it = options.size_by_face.find(f);
    if (it != options.size_by_face.end() && it->second > 0) s = std::min(s, it->second);
    // Narrow faces (a thread's flank, a small fillet or chamfer strip): at most twice the face's
    // mean width 2 A / P, so that its triangles span the width in one or two steps instead of
    // needles across a twisted strip.
    {
      GProp_GProps area, length;
      BRepGProp::SurfaceProperties(model.faces(f + 1), area);
      BRepGProp::LinearProperties(model.faces(f + 1), length);
      if (area.Mass() > 0 && length.Mass() > 0) s = std::min(s, kNarrowFaceFactor * 2 * area.Mass() / length.Mass());
    }
    if (points_per_circle_ > 0) {
      const double k = analytic_face_curvature(TopoDS::Face(model.faces(f + 1)));
      if (k > 0) s = std::min(s, kTwoPi / (k * points_per_circle_));
      local_curvature_[static_cast<std::size_t>(f)] = k < 0;
    }
    face_size_[static_cast<std::size_t>(f)] = clamp(s);
  }
}

double local_curvature_size(const BRepAdaptor_Surface& surface, double u, double v, double points_per_circle) {
  if (points_per_circle <= 0) return kInf;
  BRepLProp_SLProps props(surface, u, v, 2, 1e-9);
  if (!props.IsCurvatureDefined()) return kInf;
  const double k = std::max(std::abs(props.MaxCurvature()), std::abs(props.MinCurvature()));
  return k > 0 && std::isfinite(k) ? kTwoPi / (k * points_per_circle) : kInf;
}

double SizeField::clamp(double s) const { return std::max(min_size_, std::min(size_, s)); }

double SizeField::short_edge_size(double length) const {
  if (min_size_given_ || !(length < min_size_)) return clamp(length);
  return std::max(length, 0.1 * min_size_);
}

double SizeField::curve_curvature_size(const BRepAdaptor_Curve& curve, double t) const {
  if (points_per_circle_ <= 0) return kInf;
  switch (curve.GetType()) {
    case GeomAbs_Line:
      return kInf;
    case GeomAbs_Circle:
      return kTwoPi * curve.Circle().Radius() / points_per_circle_;
    default:
      break;
  }
  BRepLProp_CLProps props(curve, t, 2, 1e-9);
  if (!props.IsTangentDefined()) return kInf;
  const double k = std::abs(props.Curvature());
  return k > 0 && std::isfinite(k) ? kTwoPi / (k * points_per_circle_) : kInf;
}

}  // namespace bsptet::cad
