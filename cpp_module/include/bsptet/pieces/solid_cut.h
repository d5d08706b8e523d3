// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: cutting a solid in two along caps of its own vertices and points of their own, for the
// out-of-core mode (out_of_core.h), which meshes the pieces one after the other.
//
//   SolidCut cut = cut_solid(xyz, tri, axis, threshold);   // cut.ok: cut.below, cut.above
//
// Contract:
//  * `tri` (#T by 3, indices into the #P by 3 `xyz`) is a closed oriented surface (types.h); only
//    the vertices it uses matter.
//  * A triangle is BELOW when the sum of its three corners' `axis` coordinates (summed in doubles,
//    in corner order: a deterministic rule, not a geometric decision) is < `threshold`, else
//    ABOVE; each triangle around a vertex of `forced` then starts on the side given with it (later
//    entries win: how the caller moves the cut away from where a cap crossed the surface); then
//    smoothed, in rounds until nothing changes (at most 16): a triangle with two or
//    three edges to the other side joins it (a spike of the boundary would make a cap triangle
//    equal to it), and where the boundary passes a vertex more than once all the vertex's
//    triangles join the side that has at least half of them. The edges between a below and an
//    above triangle, directed as in their below triangle, must then form disjoint simple loops
//    (a vertex on two of them, or twice on one, refuses the cut).
//  * Each loop is closed by a CAP: the loop, reversed, projected along `axis`
//    (orient2d_projected's convention, predicates.h), triangulated by exact ear clipping, made
//    Delaunay in the projection by Lawson flips where the in-circle filter is certain, then given
//    points of its own: a grid of spacing twice the loop's mean projected edge (cells along the
//    loop left empty), each inserted where it falls strictly inside a triangle (Delaunay
//    insertion in the projection; polygon edges are never flipped), placed at `threshold` / 3
//    along `axis`. The loop's triangles keep the loop's own 3D vertices. A loop whose reversed
//    projection does not turn counter-clockwise (a hole of the cross-section, a fold) or that no
//    ear clipping finishes refuses the cut. The flips and the points are for shape only: any
//    triangulation is as valid, and the caller checks the result.
//  * cut.below = the below triangles and the caps; cut.above = the above triangles and the caps
//    reversed. As 2-chains below + above = the input, so where both are valid closed surfaces
//    (check_surface, surface_check.h) their solids are the input's solid split along the caps:
//    disjoint interiors, common boundary the caps. NOTHING HERE IS TRUSTED: a cap may cross the
//    surface where it is nearly parallel to the cut, or its lifted triangles may meet; the caller
//    checks both pieces exactly and drops the cut when either fails.
//  * The new points are doubles chosen here (no rounding of anything computed): cut.new_points,
//    numbered after the #P input points (the caller appends them to xyz).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "bsptet/mesh/types.h"

namespace bsptet {

struct SolidCut {
  bool ok = false;
  std::string reason;              ///< why the cut was refused (when !ok), for people
  std::vector<Index> below, above;  ///< #T by 3 each, indices into xyz
  /// Per triangle of below / above: its index in the input `tri`, or -1 for a cap triangle.
  std::vector<Index> below_source, above_source;
  /// The caps' own points (#N by 3); in below / above they are numbered #P, #P + 1, ...
  std::vector<double> new_points;
  std::int64_t loops = 0, cap_triangles = 0, cap_points = 0, cap_flips = 0;
};

/// The adjacency of a closed triangle list that cut_solid needs, the same for every cut of it:
/// made once per piece when several cuts are tried.
struct SolidTopology {
  explicit SolidTopology(const std::vector<Index>& tri);
  /// The triangle holding the directed edge u -> v, or -1.
  Index triangle_of(Index u, Index v) const;
  std::vector<std::array<Index, 3>> edges;        ///< (u, v, triangle) per directed edge, sorted by (u, v, triangle)
  std::vector<Index> edge_start;                  ///< vertex u's edges (and corners) start at edge_start[u]
  std::vector<Index> across;                      ///< as edge_neighbours
  std::vector<std::pair<Index, Index>> corners;  ///< (vertex, triangle), sorted: each vertex's fan
};

/// See the contract above. Never throws on geometry (a refused cut has ok = false and a reason).
/// `topology`: SolidTopology(tri), or null to have it made here.
SolidCut cut_solid(const std::vector<double>& xyz, const std::vector<Index>& tri, int axis, double threshold,
                   const std::vector<std::pair<Index, char>>& forced = {}, const SolidTopology* topology = nullptr);

/// For each corner i of `tri` (#T by 3): the triangle across the edge from corner i to the next
/// corner of its triangle (the one holding that edge reversed), or -1.
std::vector<Index> edge_neighbours(const std::vector<Index>& tri);

/// The corner sum cut_solid compares with its threshold, for choosing thresholds.
inline double corner_sum(const std::vector<double>& xyz, const Index* t, int axis) {
  return xyz[3 * static_cast<std::size_t>(t[0]) + axis] + xyz[3 * static_cast<std::size_t>(t[1]) + axis] +
         xyz[3 * static_cast<std::size_t>(t[2]) + axis];
}

}  // namespace bsptet
