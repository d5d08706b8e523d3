// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: back to doubles. Implicit vertices are rounded to the nearest doubles; input
// vertices are never rounded. Every tet is then re-checked exactly on the doubles; rounding that
// inverts or flattens a tet, or merges two points, is reported (local repair is not built yet).
#pragma once

#include <array>
#include <vector>

#include "bsptet/numerics/implicit_geometry.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

/// Builds the output mesh from tets over geometry vertex ids. Input points (vertex ids below
/// `num_input_points`) come first, in input order; unused ones are dropped. Throws MeshingError
/// if a rounded tet is not positively oriented.
TetMesh snap_round(ImplicitGeometry& geo, const std::vector<std::array<Index, 4>>& tets, Index num_input_points,
                   std::int64_t* steiner_points);

}  // namespace bsptet
