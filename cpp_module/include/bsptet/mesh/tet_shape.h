// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage: shape measures of one tetrahedron, in double precision. They only rank
// candidate meshes (which flip, which position is better); they never decide validity, which is
// the exact orient3d of predicates.h.
#pragma once

#include "bsptet/mesh/types.h"

namespace bsptet {

/// Smallest of the six dihedral angles of tet (a, b, c, d), in degrees. For a positively oriented
/// tet it lies in (0, 70.53], 70.53 being the regular tet's; slivers, caps and wedges come near 0.
/// For a flat or inverted tet the value is meaningless (callers decide orientation first).
double tet_min_dihedral_deg(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Circumradius / shortest edge of tet (a, b, c, d): 0.612 for the regular tet, large for needles,
/// caps and wedges; infinite for a flat tet.
double tet_radius_edge_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Circumcentre of tet (a, b, c, d) into `center` and the squared circumradius into `radius2`;
/// false (outputs untouched) for a flat tet or a non-finite result.
bool tet_circumsphere(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Vec3* center, double* radius2);

/// Squared distance between two points.
double squared_distance(const Vec3& a, const Vec3& b);

}  // namespace bsptet
