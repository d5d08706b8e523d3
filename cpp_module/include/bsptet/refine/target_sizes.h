// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage: the target edge length at each point of a RefineMesh, and the edge split
// that the size passes, the radius-edge pass and separate_face_tags share.
//
// Contract:
//  * Takes a RefineMesh and RefineOptions already checked (quality_refine.cpp, check_options); both
//    must outlive the field. Only split() changes the mesh; every other member reads it.
//  * compute() sets target(v) for every point v of the mesh: RefineOptions::size, lowered to the
//    size of the face tags around v (size_by_tag), to the mean edge of v's input triangles
//    (size_from_surface), to thickness_ratio times the wall's thickness at v (never below
//    floor()), then graded along mesh edges: target(w) <= target(v) + grading * |vw| (Dijkstra).
//    With raise_stuck, the targets around edges that split() could not split are raised to that
//    edge's length / split_ratio (decreasing by one unit per unit of distance from it).
//  * Targets are lengths in model units, > 0 or +infinity (no size); a point that compute() has
//    not seen (added since) has target `size` until set_target gives it one.
//  * floor() is the smallest length refinement works at (RefineOptions::min_size, or one eighth of
//    the smallest target after the first compute(), or 1e-3 of the bounding-box diagonal without
//    sizes); fixed after the first compute(). No edge shorter than 2 * floor() counts as long.
//  * split(u, v, min_quality, stats) splits edge (u, v) through RefineMesh::split_edge (valid mesh
//    after it either way), counts the outcome in `stats`, gives the new point the mean of u's and
//    v's targets, and remembers an edge that could not be split (for compute's raise_stuck).
//  * Deterministic: no randomness; the same calls in the same order give the same targets.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "bsptet/mesh/tet_shape.h"
#include "bsptet/mesh/types.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/wall_thickness.h"

namespace bsptet {

class TargetSizes {
 public:
  TargetSizes(RefineMesh& m, const RefineOptions& o) : m_(m), o_(o) {}

  /// The targets of every point (see the contract); `raise_stuck`: raise them around the edges
  /// that could not be split.
  void compute(bool raise_stuck = true);
  /// RefineOptions::min_size or its default (see the contract); 0 before the first compute().
  double floor() const { return floor_; }
  /// The targets by point index (compute, set_target).
  const std::vector<double>& targets() const { return target_; }

  double target(Index v) const {
    return static_cast<std::size_t>(v) < target_.size() ? target_[static_cast<std::size_t>(v)] : o_.size;
  }
  double edge_target(Index u, Index v) const { return std::min(target(u), target(v)); }
  double length(Index u, Index v) const { return std::sqrt(squared_distance(m_.point(u), m_.point(v))); }
  /// Longer than split_ratio * edge_target and than 2 * floor().
  bool is_long(Index u, Index v) const {
    const double l = length(u, v);
    return l > o_.split_ratio * edge_target(u, v) && l > 2 * floor_;
  }
  /// The grading rule at a new point x from the corners of the tet it was made in: the least of
  /// target(corner) + grading * |x - corner|, at most `size`. (The corners' mean instead gave a
  /// circumcentre deep inside a large tet its corners' small surface sizes: on a crankshaft the
  /// refinement made 89,000 points and the optimization collapsed 66,000 of them again.)
  double graded_target(const Vec3& x, const std::array<Index, 4>& corners) const {
    double t = o_.size;
    for (Index k : corners) t = std::min(t, target(k) + o_.grading * std::sqrt(squared_distance(x, m_.point(k))));
    return t;
  }
  void set_target(Index n, double t) {
    if (static_cast<std::size_t>(n) >= target_.size()) target_.resize(static_cast<std::size_t>(n) + 1, o_.size);
    target_[static_cast<std::size_t>(n)] = t;
  }

  /// Splits edge (u, v) (RefineMesh::split_edge with `min_quality`) and counts the outcome in
  /// `st`; true when it was split. See the contract.
  bool split(Index u, Index v, double min_quality, RefineStats& st);

 private:
  void compute_floor();
  void apply_wall_thickness();
  static double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b);
  void raise_lower(Index u, Index v);

  RefineMesh& m_;
  const RefineOptions& o_;
  std::vector<double> target_;
  struct Stuck {  ///< an edge that could not be split
    Vec3 a, b;
    double lo[3], hi[3];
    double reach;  ///< length / split_ratio
  };
  std::vector<Stuck> stuck_;
  double floor_ = 0;
  std::unique_ptr<WallThickness> walls_;  ///< thickness_ratio: the input's walls, built once
};

}  // namespace bsptet
