// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: the element size field on a CAD model.
//
// The size h at a point is the smallest of:
//  * `size`, the largest element size (FreeCAD's / Gmsh's CharacteristicLengthMax);
//  * the size asked for the CAD face (`size_by_face`), on that face and its edges;
//  * curvature: 2 pi R / points_per_circle where R is the smallest radius of curvature (a circle
//    of radius R gets points_per_circle segments): on a plane, cylinder, cone, sphere or torus
//    face, its smallest radius, over the whole face; on any other surface (B-spline, revolution,
//    offset...), the largest principal curvature at the point itself (local_curvature_size),
//    so that one tight spot does not fine the whole face; on an edge, the curve's curvature at
//    that parameter;
//  * narrow faces: at most twice the face's mean width 2 * area / perimeter (a thread flank, a
//    thin fillet or chamfer strip is crossed in one or two triangles, not by needles);
//  * gradation: sizes grow away from smaller ones by at most `grading` per unit length (along an
//    edge from its vertices, inside a face from its boundary nodes);
// and never below `min_size` (CharacteristicLengthMin), except at the ends of a CAD edge shorter
// than the automatic floor (short_edge_size): such an edge is one segment whatever the floor, and
// the sizes around it grade up from its length. Lengths in model units.
#pragma once

#include <map>
#include <vector>

#include "bsptet/cad/cad_model.h"

class BRepAdaptor_Curve;
class BRepAdaptor_Surface;

namespace bsptet::cad {

struct SizeOptions {
  /// Largest element size h (CharacteristicLengthMax); 0: automatic (diagonal / 20, then
  /// curvature as below).
  double size = 0;
  /// Smallest element size (CharacteristicLengthMin); 0: size / 50.
  double min_size = 0;
  /// Curvature: at most 2 pi R / points_per_circle; 0 turns curvature sizing off.
  double points_per_circle = 12;
  /// Growth of the size away from smaller sizes, per unit length (Netgen's grading is 0.3).
  double grading = 0.3;
  /// Size on given CAD faces (0-based face index), model units.
  std::map<int, double> size_by_face;
};

class SizeField {
 public:
  /// Samples every face's curvature. Throws InputError for a negative or non-finite option.
  SizeField(const CadModel& model, const SizeOptions& options);

  double size() const { return size_; }          ///< h (automatic one resolved)
  double min_size() const { return min_size_; }
  double grading() const { return grading_; }
  /// The size on face f (0-based): h, its size_by_face and its curvature size, at least min_size.
  double face_size(int f) const { return face_size_[static_cast<std::size_t>(f)]; }
  /// True when face f's curvature size varies over it (not an analytic surface): the face mesher
  /// then asks local_curvature_size at each node.
  bool face_has_local_curvature(int f) const { return local_curvature_[static_cast<std::size_t>(f)] != 0; }
  double points_per_circle() const { return points_per_circle_; }
  /// The curvature size of `curve` at parameter t (infinity on a straight piece or when off).
  double curve_curvature_size(const BRepAdaptor_Curve& curve, double t) const;
  /// Clamps a size to [min_size, size].
  double clamp(double s) const;
  /// The size at the ends of a CAD edge of this length: clamp(length) when min_size was given;
  /// else the length itself when it is below the automatic floor, but at least a tenth of that
  /// floor, so that the edges and faces around a short edge grade down to it instead of meeting
  /// it with needles. (Down to the length itself, Pump_Nut's 0.002 mm edges cost 40% more tets
  /// for the same worst angle; a quarter of the floor left it under 10 degrees.)
  double short_edge_size(double length) const;

 private:
  double size_ = 0, min_size_ = 0, grading_ = 0.3, points_per_circle_ = 12;
  bool min_size_given_ = false;
  std::vector<double> face_size_;
  std::vector<char> local_curvature_;
};

/// 2 pi / (k points_per_circle) for the largest principal curvature k of `surface` at (u, v);
/// infinity where the curvature is zero or undefined (a singular point) or points_per_circle is 0.
double local_curvature_size(const BRepAdaptor_Surface& surface, double u, double v, double points_per_circle);

}  // namespace bsptet::cad
