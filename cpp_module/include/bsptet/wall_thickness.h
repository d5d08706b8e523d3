// FemBspTet quality stage, sizing: the local thickness of a solid's wall at a point of its surface.
//
//   WallThickness walls(surface, reach);
//   double t = walls.at(p, outward_normal, own_triangles);
//
// The thickness at a surface point p with outward unit normal n is the distance from p to the
// nearest input triangle f that faces p from across the solid: f's outward unit normal m opposes
// n (m . n < -1/2, an angle of more than 120 degrees between them) and the point q of f nearest
// to p lies on p's inner side ((q - p) . n < 0) with p on f's inner side ((p - q) . m < 0). A
// plate of thickness t gives t on both faces; the gap of a slot (air between two facing walls)
// does not count (q lies outward of p); neighbouring triangles of a smooth surface do not count
// (their normals are close to n). Triangles listed in `own` (those p lies on) are skipped. Only
// triangles within `reach` of p are looked at: the answer is infinity when none qualifies there.
//
// A sizing heuristic in doubles (no topological decision depends on it): the quality stage lowers
// its target size across thin walls to a multiple of this (RefineOptions::thickness_ratio), where
// tets of the asked size would span the wall flat.
//
// Lookups go through a uniform grid of cells at least `reach` wide (at most 256 per axis of the
// bounding box), so a query visits at most 8 cells. Deterministic.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "bsptet/types.h"

namespace bsptet {

class WallThickness {
 public:
  /// `surface`: closed, outward oriented (types.h). `reach` > 0 and finite: the largest thickness
  /// of interest.
  WallThickness(const SurfaceMesh& surface, double reach);

  /// Thickness at point p (on the surface) with outward unit normal n, skipping the triangles in
  /// `own` (sorted or not; small). Infinity when no opposing triangle is within reach.
  double at(const Vec3& p, const Vec3& n, const std::vector<Index>& own) const;

  /// Unit outward normal of input triangle t (zero for a degenerate triangle).
  const Vec3& normal(Index t) const { return normal_[static_cast<std::size_t>(t)]; }

 private:
  std::int64_t cell_key(std::int64_t i, std::int64_t j, std::int64_t k) const;
  const SurfaceMesh& s_;
  double reach_;
  double origin_[3] = {0, 0, 0};
  double cell_ = 1;
  std::int64_t dims_[3] = {1, 1, 1};
  std::vector<Vec3> normal_;
  std::unordered_map<std::int64_t, std::vector<Index>> cells_;
  mutable std::vector<std::uint32_t> seen_;
  mutable std::uint32_t stamp_ = 0;
};

/// Squared distance from p to the closed triangle (a, b, c), and the nearest point in `q`.
double point_triangle_squared_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3* q);

}  // namespace bsptet
