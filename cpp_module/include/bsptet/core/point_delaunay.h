// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the Delaunay tetrahedralization of explicit (double) points, the first step of
// the BSP's Delaunay seed (bsp_seed.cpp).
//
// The triangulation is the perturbed one of cell_delaunay.h (the lifting |v|^2 perturbed by the
// global vertex id): the same predicates decide it (orient3d on the doubles, the in-sphere sign of
// ImplicitGeometry::lifted_det3 and, on a hull plane, lifted_det2), and under them it is unique,
// so it equals delaunay_cell's on the same points as a set of tets. What differs is the cost
// (compared with cell_delaunay's builder): points as plain
// doubles in a flat array, the floating-point filters called directly (ImplicitGeometry only for
// the cases they cannot certify), the cavity's new tets linked by their edges without allocation,
// and the neighbours of every tet returned beside it.
//
// Sign conventions: as predicates.h (a positive tet has orient3d > 0); the face opposite corner i
// is kTetOppositeFace[i] (types.h), oriented so that its normal points into the tet.
#pragma once

#include <array>
#include <vector>

#include "bsptet/numerics/implicit_geometry.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

struct PointDelaunay {
  std::vector<std::array<Index, 4>> tets;  ///< positive (exact), vertex ids
  std::vector<std::array<Index, 4>> nb;    ///< tet across the face opposite corner i, -1 on the hull
};

/// Bowyer-Watson over `order` (distinct vertex ids of explicit points, not all coplanar), inserted
/// in that order (give a spatially sorted one: the walks stay short; the result does not depend on
/// it). Returns false (output unspecified) when an internal check fails (a walk that does not end,
/// a cavity that does not close, a non-positive tet); the caller then reports an internal error.
bool delaunay_explicit_points(ImplicitGeometry& geo, const std::vector<Index>& order, PointDelaunay& out);

}  // namespace bsptet
