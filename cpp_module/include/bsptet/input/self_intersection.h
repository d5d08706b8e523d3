// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the self-intersections of a triangle surface, exactly.
//
//   pairs = find_self_intersections(surface, max_pairs, &complete)
//
// Broad phase: a bounding-volume hierarchy over the triangles' boxes (boxes of doubles, compared
// exactly, closed), traversed against itself. Narrow phase: triangles_intersect
// (triangle_intersection.h): any common point outside the simplex of the shared vertices.
// Deterministic: the hierarchy splits at medians with ties broken by triangle index.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "bsptet/mesh/types.h"

namespace bsptet {

/// The pairs (s, t), s < t, of triangles of `surface` that intersect, sorted. At most `max_pairs`
/// (>= 1) are returned; `complete` (optional) is set to false when the search stopped there.
/// Preconditions (surface_check.cpp establishes them): indices in range, finite coordinates, points
/// with equal coordinates merged into one index, no degenerate triangle.
std::vector<std::array<Index, 2>> find_self_intersections(const SurfaceMesh& surface, std::int64_t max_pairs,
                                                          bool* complete = nullptr);

}  // namespace bsptet
