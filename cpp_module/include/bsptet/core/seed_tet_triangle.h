// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: how a tet of the seed and an input triangle meet, for the seed's conflict lists
// (BspComplex::seed_delaunay, bsp_seed.cpp: a cell is split only by the triangles that cross its
// interior).
//
// Contract:
//  * Takes a positive tet (corners p, exact orient3d > 0, vertex ids pid) and a triangle (corners
//    q, vertex ids qid) as doubles; a shared id is a shared corner (they touch there).
//  * Returns 0 when the closed sets are disjoint, 1 when the triangle misses the tet's interior
//    (they may touch), 2 when it crosses the interior. Every answer is exact: separating axes
//    decide it (the tet's face planes and the triangle's plane by orient3d, then the 18 edge-pair
//    directions, first by rounded projections with certified error bounds, which only shortcut
//    what they prove, then exactly: intervals, expansions or ExactFloat). Conservative where it
//    counts: 2 only when no plane separates the triangle from the interior.
//  * Pure: no state, the same answer for the same arguments.
#pragma once

#include <array>

#include "bsptet/mesh/types.h"

namespace bsptet {

/// See the contract above.
int seed_tet_triangle_relation(const std::array<Vec3, 4>& p, const std::array<Index, 4>& pid,
                               const std::array<Vec3, 3>& q, const std::array<Index, 3>& qid);

}  // namespace bsptet
