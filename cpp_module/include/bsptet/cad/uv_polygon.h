// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: triangulating a face's boundary polygon in its parameter plane.
//
//   std::vector<std::array<int, 3>> triangulate_polygon(uv, loops)
//
// `uv` holds #P points (u, v). loops[0] is the outer boundary, counter-clockwise (positive area);
// loops[1..] are holes, clockwise; each loop lists point indices in order, its first point not
// repeated at the end. Points of different loops and of one loop are distinct (a point may appear
// once in all loops). Holes are joined to the outer boundary by bridges (a segment to a visible
// vertex), then ears are cut. Every decision is an exact orient2d on the doubles.
//
// Returns #T triangles, counter-clockwise, covering the polygon (T = P - 2 + 2 * holes). Throws
// std::runtime_error when the loops are not a simple polygon with holes (an ear cannot be found
// or a hole has no visible bridge); the caller names the CAD face.
#pragma once

#include <array>
#include <vector>

namespace bsptet::cad {

using Uv = std::array<double, 2>;

std::vector<std::array<int, 3>> triangulate_polygon(const std::vector<Uv>& uv, const std::vector<std::vector<int>>& loops);

/// Exact sign of the turn a -> b -> c in the (u, v) plane: +1 counter-clockwise, -1 clockwise, 0 collinear.
int uv_orient(const Uv& a, const Uv& b, const Uv& c);

/// Whether the closed segments ab and cd share a point (crossing or touching), exact.
bool uv_segments_meet(const Uv& a, const Uv& b, const Uv& c, const Uv& d);

}  // namespace bsptet::cad
