// FemBspTet quality stage: second-order (10-node) tets from a linear RefineMesh.
//
// One mid-node per edge. Interior edges: the rounded midpoint. Boundary edges: the rounded
// midpoint passed through the projection hook (point, tag, other tag) with the tags of the edge's
// two parent input triangles (other tag -1 when both have the same tag), so that mid-nodes lie on
// the true curved surface; without a hook they stay at the midpoint (on the facet up to rounding).
// Curved tets are checked in double precision: the Jacobian determinant of the quadratic map must
// be positive at 15 points (corners, edge midpoints, face centroids, centroid). Mid-nodes of tets
// that fail are put back at the straight midpoint, repeatedly, until every tet passes (straight
// tets pass whenever the linear tet is positive). Node order: types.h (n1..n4 m12 m23 m31 m14 m24
// m34); the linear points first, then the mid-nodes in sorted edge order.
#pragma once

#include <cstdint>

#include "bsptet/refine_mesh.h"
#include "bsptet/types.h"

namespace bsptet {

struct SecondOrderStats {
  std::int64_t midnodes = 0;
  std::int64_t projected = 0;     ///< boundary mid-nodes the hook placed
  std::int64_t straightened = 0;  ///< of which put back on the chord (a curved tet was not valid;
                                  ///< only mid-nodes the hook had moved off the chord count)
};

/// Builds the 10-node mesh of `mesh`'s live tets. `hook` may be empty.
TetMesh make_second_order(RefineMesh& mesh, const ProjectionHook& hook, SecondOrderStats* stats = nullptr);

/// Smallest Jacobian determinant of a 10-node tet (nodes in types.h order, 30 coordinates) over
/// the 15 sample points; positive for a valid, positively oriented element.
double tet10_min_jacobian(const double* xyz30);

}  // namespace bsptet
