// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage: second-order (10-node) tets from a linear RefineMesh, and the
// certificate of their validity.
//
// One mid-node per edge. Interior edges: the rounded midpoint. Boundary edges: the rounded
// midpoint passed through the projection hook (point, tag, other tag) with the tags of the edge's
// two parent input triangles (other tag -1 when both have the same tag), so that mid-nodes lie on
// the true curved surface; without a hook they stay at the midpoint (on the facet up to rounding).
// Every tet must be certified valid (certify_tet10: det J > 0 over the whole element, proved with
// Bezier bounds and rounding-error bounds). A curved tet that is not certified is mended, in
// this order:
//  1. Mid-node relaxation: its mid-nodes move (then also those of the tets that share one with
//     it) to lower the shortfall of the elements' scaled Bezier coefficients (c_a over 6 times the
//     straight volume) below 0.1, by Levenberg-Marquardt steps: an interior edge's mid-node
//     anywhere (the interior edges then follow the boundary's curvature), a hook-placed
//     mid-node along its CAD face (in its edge's plane and the face triangle's, then put back on
//     the face by the hook) or along its CAD edge (along the chord, then back on the edge by the
//     hook), so it stays on the CAD geometry. Mid-nodes on faces kept as input
//     (RefineMesh::set_fixed_tags: faces shared with another solid) do not move. The moves are
//     kept when the tet is then certified and no tet around that was certified stops being so.
//     What this mends: an interior apex too close to a curved face (the interior mid-nodes bend
//     with it) and a needle face whose curved long edge tilts past its short one at a corner (the
//     mid-node slides along the CAD edge, which changes the tangent there).
//  2. A new interior point (RefineMesh::insert_point, the tet in its cavity) for each tet the
//     relaxation leaves invalid, then the lift again (at most 3 rounds): a tet with two boundary
//     faces on two tangent-continuous CAD faces has its three corner tangents in one plane
//     whatever its mid-nodes on the surface; the point gives it interior edges.
//  3. Last resort: the mid-nodes of the tets still not certified go back on their chords
//     (repeatedly, until every tet that still has a curved mid-node is certified), leaving those
//     boundary mid-nodes off the CAD face; SecondOrderStats::straightened counts them.
// Node order: types.h (n1..n4 m12 m23 m31 m14 m24
// m34); the linear points first, then the mid-nodes in sorted edge order.
//
// Validity of a 10-node tet (after Johnen, Remacle and Geuzaine, "Geometrical validity of
// curvilinear finite elements", J. Comput. Phys. 2013). On the reference tet (r, s, t) with
// barycentric coordinates L = (1 - r - s - t, r, s, t), the map x(L) is quadratic, so
// det J = det[dx/dr, dx/ds, dx/dt] is a cubic polynomial in L. Written in the cubic Bernstein
// basis B_a(L) = 3! / (a0! a1! a2! a3!) L0^a0 L1^a1 L2^a2 L3^a3 (20 multi-indices a, |a| = 3):
// det J(L) = sum_a c_a B_a(L). The B_a are non-negative and sum to 1 on the tet, so
// min_a c_a <= det J <= max_a c_a there, and the four corner coefficients c_(3e_i) are the values
// at the corners. Subdividing the tet (the same polynomial's coefficients on a sub-tet) makes the
// coefficients converge to the values, so the bound tightens where it is needed.
// Derivation of c: the Bezier control points of x are P_ii = n_i and P_ij = 2 m_ij - (n_i + n_j)/2;
// dx/dr etc. are linear with control vectors D_a[b] = 2 (P_ab - P_0b) (a = 1, 2, 3; b = 0..3), so
// det J = sum_{i,j,k} det(D_1[i], D_2[j], D_3[k]) L_i L_j L_k and c_a is the mean of the
// determinants over the ordered triples (i, j, k) with e_i + e_j + e_k = a. For a straight tet
// every c_a is det[n2 - n1, n3 - n1, n4 - n1] = 6 * volume.
#pragma once

#include <cstdint>

#include "bsptet/refine/refine_mesh.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

struct SecondOrderStats {
  std::int64_t midnodes = 0;
  std::int64_t projected = 0;     ///< boundary mid-nodes the hook placed
  std::int64_t straightened = 0;  ///< of which put back on the chord (a curved tet was not
                                  ///< certified; only mid-nodes the hook had moved off the chord count)
  std::int64_t not_certified = 0;  ///< curved tets found not certified (each straightened)
  std::int64_t curved_tets = 0;    ///< tets left with a curved mid-node, each certified
  std::int64_t relax_tried = 0;    ///< tets not certified once projected, given to the relaxation
  std::int64_t relaxed = 0;        ///< of which certified by moving interior mid-nodes
  std::int64_t interior_moved = 0;  ///< interior mid-nodes left off their chords
  std::int64_t surface_moved = 0;   ///< boundary mid-nodes moved along their CAD face or edge
  std::int64_t points_inserted = 0;  ///< interior points added to the linear mesh for curving
};

/// Builds the 10-node mesh of `mesh`'s live tets. `hook` may be empty (then every mid-node is a
/// midpoint and nothing is mended). With a hook, interior points may be inserted into `mesh`
/// (step 2 above); the result's corners are then `mesh.to_tet_mesh()`'s after them.
TetMesh make_second_order(RefineMesh& mesh, const ProjectionHook& hook, SecondOrderStats* stats = nullptr);

/// The 20 multi-indices (a0, a1, a2, a3), a0 + a1 + a2 + a3 = 3, of the cubic Bernstein basis on
/// a tet, in the order of tet10_jacobian_bezier's coefficients (lexicographically decreasing).
inline constexpr int kCubicMultiIndex[20][4] = {
    {3, 0, 0, 0}, {2, 1, 0, 0}, {2, 0, 1, 0}, {2, 0, 0, 1}, {1, 2, 0, 0}, {1, 1, 1, 0}, {1, 1, 0, 1},
    {1, 0, 2, 0}, {1, 0, 1, 1}, {1, 0, 0, 2}, {0, 3, 0, 0}, {0, 2, 1, 0}, {0, 2, 0, 1}, {0, 1, 2, 0},
    {0, 1, 1, 1}, {0, 1, 0, 2}, {0, 0, 3, 0}, {0, 0, 2, 1}, {0, 0, 1, 2}, {0, 0, 0, 3}};

/// Bezier (Bernstein) coefficients of the Jacobian determinant of a 10-node tet, in double
/// precision (for reports and tests; certify_tet10 uses enclosures of them).
/// @param[in]  xyz30  10 nodes by 3 coordinates, types.h order
/// @param[out] out20  c_a for a = kCubicMultiIndex[0..19]: det J(L) = sum_a c_a 3!/a! L^a, with
///                    J the derivative with respect to the reference coordinates (r, s, t)
void tet10_jacobian_bezier(const double* xyz30, double* out20);

enum class Tet10Validity {
  kCertified,  ///< det J > 0 on the whole closed element, proved (rounding errors included)
  kInvalid,    ///< det J <= 0 at some point of the element, proved
  kUndecided   ///< neither within the subdivision depth (or non-finite input): treat as invalid
};

/// Certifies a 10-node tet: bounds det J from below by its Bezier coefficients. First the
/// element's 20 coefficients in double precision with an a-priori bound of their rounding error
/// (coordinates 0 or of magnitude in [2^-250, 2^250]): all proved positive, kCertified; a corner
/// value proved <= 0, kInvalid. Otherwise the coefficients as intervals that enclose the exact
/// ones (interval.h), on the element and then on sub-tets (8-way red refinement of the
/// barycentric domain, Bey's rule), only where the bound is not yet positive. A sub-tet corner
/// whose value is proved <= 0 makes the element kInvalid at once. A sub-tet is not split further
/// once it is `max_depth` levels down, or when the sign of det J at one of its corners is
/// undecided in interval arithmetic (within rounding of zero: no split can decide it); it is
/// then left undecided. kCertified when every leaf's coefficients are proved positive.
/// Cost: about 1 microsecond for an element the first test decides (most of a mesh), then about
/// 5 per sub-tet; at most 1 + 8 + ... + 8^max_depth sub-tets.
/// @param[in]  xyz30      10 nodes by 3 coordinates, types.h order (n1..n4 m12 m23 m31 m14 m24 m34)
/// @param[in]  max_depth  subdivision levels allowed (0: the element's own coefficients only)
/// @param[out] min_bound  optional. kCertified: a positive lower bound of min det J over the
///                        element. kInvalid: an upper bound (<= 0) of det J at a point of the
///                        element. kUndecided: the lowest lower bound found (<= 0; NaN for
///                        non-finite input or overflow)
Tet10Validity certify_tet10(const double* xyz30, int max_depth = 6, double* min_bound = nullptr);

/// The element's minimum scaled Jacobian, min det J / det J0 with J0 the Jacobian of the straight
/// tet on the same corners (6 * its volume): 1 for an undistorted element, <= 0 for an invalid one.
/// Returned as a lower bound of that minimum, refined (best-first subdivision) until it is within
/// `tolerance` of the smallest value of det J / det J0 sampled, or sub-tets reach `max_depth`.
/// The coefficients are interval lower bounds, but the quotient is not rounded outwards (a figure
/// for reports; certify_tet10 decides validity).
/// Returns -infinity when the straight tet is not positive (det J0 <= 0), NaN for non-finite input.
double tet10_min_scaled_jacobian(const double* xyz30, double tolerance = 1e-3, int max_depth = 8);

}  // namespace bsptet
