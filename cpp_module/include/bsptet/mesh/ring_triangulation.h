// SPDX-License-Identifier: LGPL-2.1-or-later
// Edge removal's combinatorial half, shared by the core's Steiner removal (core/tet_complex.h),
// the Delaunay seed's flips (core/seed_flips.h) and the quality stage (refine/refine_mesh.h):
// the best triangulation of the polygon of the ring of vertices around an edge (u, v).
//
// Removing edge (u, v) replaces the n tets around it by 2 (n - 2): a triangulation of the ring
// polygon p_0 .. p_{n-1}, each of its triangles joined to u and to v (Shewchuk's n-to-2(n-2)
// flip; a 3-2 flip is n = 3). Which triangles are allowed and how good they are is the caller's
// (its exact orientation tests, its quality measure); this file only searches, by dynamic
// programming over the sub-polygons p_i .. p_j (i < j; the polygon itself is (0, n - 1)): a
// sub-polygon is triangulated by a triangle (i, k, j), i < k < j, and the sub-polygons (i, k) and
// (k, j); a sub-polygon of two vertices (j = i + 1) is an edge of the polygon and needs nothing.
//
// Contract:
//  * Score: a triangulation's score is the smallest of its triangles' scores (bottleneck). best(i,
//    j) is the highest score of a triangulation of (i, j) that is above `floor`, or kNone when no
//    triangulation is above it; apex(i, j) is its triangle's apex k, the lowest k among equals.
//    With scores 1 (allowed) and kNone (not allowed) and floor 0 this is the first allowed
//    triangulation in apex order.
//  * triangle(i, k, j, bar) returns the score of triangle (i, k, j), or any value <= bar when it
//    is not above bar (so the caller may stop measuring early), kNone when not allowed. It is
//    called only when both sub-polygons (i, k) and (k, j) are above the best found so far for
//    (i, j), at most once per (i, k, j).
//  * diagonal(i, j) says whether the diagonal (i, j) may be an edge (e.g. is not a mesh edge
//    yet); it is asked only of sub-polygons that have a triangulation above `floor`, never of
//    (0, n - 1) or of polygon edges.
//  * enough: once a sub-polygon's best reaches it, larger apexes are not tried (1 for the
//    first allowed triangulation; +infinity for the optimum).
//  * Sub-polygons are solved on demand (memoized), so only those the answer needs are measured.
//  * At most kMaxRingVertices vertices. Deterministic.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>

namespace bsptet {

/// The most vertices a RingTriangulation takes.
constexpr int kMaxRingVertices = 16;

template <class Triangle, class Diagonal>
class RingTriangulation {
 public:
  static constexpr double kNone = -1;

  RingTriangulation(int n, double floor, double enough, Triangle triangle, Diagonal diagonal)
      : n_(n), floor_(floor), enough_(enough), triangle_(triangle), diagonal_(diagonal) {
    known_.fill(0);
  }

  int size() const { return n_; }

  /// See the contract; +infinity for a polygon edge (j = i + 1).
  double best(int i, int j) {
    if (j == i + 1) return std::numeric_limits<double>::infinity();
    const std::size_t at = index(i, j);
    if (known_[at]) return best_[at];
    double b = floor_;
    int choice = -1;
    for (int k = i + 1; k < j && b < enough_; ++k) {
      const double left = best(i, k);
      if (left <= b) continue;
      const double right = best(k, j);
      if (right <= b) continue;
      const double q = std::min(std::min(left, right), triangle_(i, k, j, b));
      if (q > b) b = q, choice = k;
    }
    if (choice >= 0 && !(i == 0 && j == n_ - 1) && !diagonal_(i, j)) choice = -1;
    known_[at] = 1;
    best_[at] = choice < 0 ? kNone : b;
    apex_[at] = static_cast<signed char>(choice);
    return best_[at];
  }

  /// The apex of (i, j)'s best triangulation; call best(i, j) first (and only when it is not kNone).
  int apex(int i, int j) const { return apex_[index(i, j)]; }

  /// Calls f(i, k, j) for every triangle of (i, j)'s best triangulation, each before those of
  /// its sub-polygons, the left one (i, k) first, or the right one (k, j) with right_first (the
  /// order the caller's tets are made in); best(i, j) must not be kNone.
  template <class F>
  void for_each_triangle(int i, int j, F&& f, bool right_first = false) const {
    if (j - i < 2) return;
    const int k = apex(i, j);
    f(i, k, j);
    for_each_triangle(right_first ? k : i, right_first ? j : k, f, right_first);
    for_each_triangle(right_first ? i : k, right_first ? k : j, f, right_first);
  }

 private:
  static std::size_t index(int i, int j) { return static_cast<std::size_t>(i * kMaxRingVertices + j); }

  int n_;
  double floor_, enough_;
  Triangle triangle_;
  Diagonal diagonal_;
  std::array<char, kMaxRingVertices * kMaxRingVertices> known_;
  std::array<double, kMaxRingVertices * kMaxRingVertices> best_;
  std::array<signed char, kMaxRingVertices * kMaxRingVertices> apex_;
};

template <class Triangle, class Diagonal>
RingTriangulation<Triangle, Diagonal> make_ring_triangulation(int n, double floor, double enough, Triangle triangle,
                                                             Diagonal diagonal) {
  return RingTriangulation<Triangle, Diagonal>(n, floor, enough, triangle, diagonal);
}

}  // namespace bsptet
