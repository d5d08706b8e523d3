// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage, sizing: the local thickness of a solid's wall at a point of its surface.
//
//   WallThickness walls(surface);
//   double t = walls.at(p, outward_normal, own_triangles, reach);
//
// The thickness at a surface point p with outward unit normal n is the distance from p to the
// nearest input triangle f that faces p from across the solid: f's outward unit normal m opposes
// n (m . n < -1/2, an angle of more than 120 degrees between them) and the point q of f nearest
// to p lies on p's inner side ((q - p) . n < 0) with p on f's inner side ((p - q) . m < 0). A
// plate of thickness t gives t on both faces; the gap of a slot (air between two facing walls)
// does not count (q lies outward of p); neighbouring triangles of a smooth surface do not count
// (their normals are close to n). Triangles listed in `own` (those p lies on) are skipped. Only
// triangles nearer than `reach` are looked at: the answer is infinity when none qualifies there.
//
// A sizing heuristic in doubles (no topological decision depends on it): the quality stage lowers
// its target size across thin walls to a multiple of this (RefineOptions::thickness_ratio), where
// tets of the asked size would span the wall flat.
//
// Lookups descend a bounding-box tree over the triangles (median splits, a few triangles per
// leaf), skipping boxes farther than the best distance found so far: a query costs about the
// number of triangles within `reach`, whatever the spread of triangle sizes. Degenerate triangles
// (zero normal) are left out. Deterministic; a query is not thread-safe (it marks `own`).
#pragma once

#include <cstdint>
#include <vector>

#include "bsptet/mesh/types.h"

namespace bsptet {

class WallThickness {
 public:
  /// `surface`: closed, outward oriented (types.h).
  explicit WallThickness(const SurfaceMesh& surface);

  /// Thickness at point p (on the surface) with outward unit normal n, skipping the triangles in
  /// `own` (small). Infinity when no opposing triangle is nearer than `reach`.
  double at(const Vec3& p, const Vec3& n, const std::vector<Index>& own, double reach) const;

  /// Unit outward normal of input triangle t (zero for a degenerate triangle).
  const Vec3& normal(Index t) const { return normal_[static_cast<std::size_t>(t)]; }

 private:
  struct Node {
    double lo[3], hi[3];
    Index first, count;  ///< leaf: tris_[first .. first + count); inner: count = -1, children
    Index left, right;   ///< (inner nodes)
  };
  Index build(Index first, Index count);
  const SurfaceMesh& s_;
  std::vector<Vec3> normal_;
  std::vector<Index> tris_;       ///< non-degenerate triangles, in tree order
  std::vector<Vec3> centroid_;    ///< per input triangle
  std::vector<Node> nodes_;
  mutable std::vector<std::uint32_t> seen_;
  mutable std::uint32_t stamp_ = 0;
};

/// Squared distance from p to the closed triangle (a, b, c), and the nearest point in `q`.
double point_triangle_squared_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3* q);

}  // namespace bsptet
