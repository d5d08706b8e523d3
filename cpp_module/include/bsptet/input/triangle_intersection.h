// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: exact intersection tests between closed segments and closed triangles whose
// corners are doubles. Every decision is a sign of orient3d / orient2d_projected (predicates.h), so
// the answers are exact for every finite input; there is no tolerance anywhere.
//
// "Closed" means boundaries count: a segment that only touches a triangle's edge or corner meets
// it. Triangles must not be degenerate (their three corners not collinear) and segments must have
// two distinct end points; the functions do not check this (surface_check.cpp does, first).
#pragma once

#include <array>

#include "bsptet/mesh/types.h"

namespace bsptet {

/// True when the closed segment [p, q] and the closed triangle (a, b, c) have a point in common.
/// Preconditions: p != q; a, b, c not collinear.
bool segment_meets_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c);

/// How a segment meets a triangle, for ray casting (surface_check.cpp counts crossings).
enum class SegmentTriangleContact {
  kNone,      ///< no common point
  kCrossing,  ///< the segment passes through the triangle's interior, neither end point on its plane
  kDegenerate ///< any other contact: an end point on the plane, through an edge or a corner, coplanar
};
/// Classifies the contact of the closed segment [p, q] with the closed triangle (a, b, c).
/// Preconditions as for segment_meets_triangle.
SegmentTriangleContact classify_segment_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                                 const Vec3& c);

/// One triangle of a surface for triangles_intersect: its three vertex ids and their points.
/// Equal ids mean the same vertex; callers merge points with equal coordinates first, so distinct
/// ids have distinct points.
struct IndexedTriangle {
  std::array<Index, 3> id;
  std::array<Vec3, 3> p;
};

/// True when the two closed triangles share a point that is not in the simplex spanned by their
/// shared vertices: for triangles sharing no vertex, any contact; sharing one vertex, any common
/// point other than that vertex; sharing an edge, an overlap beyond that edge (a fold: coplanar,
/// both on one side of it). Two triangles with the same three vertices always intersect.
/// This is the self-intersection test of a triangle surface. Preconditions: both triangles non
/// degenerate; distinct ids have distinct points.
bool triangles_intersect(const IndexedTriangle& s, const IndexedTriangle& t);

}  // namespace bsptet
