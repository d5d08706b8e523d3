// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the geometric predicates on double coordinates. The only sign authority for
// double inputs: a floating-point filter with a proven error bound decides when it can; otherwise
// the sign is computed exactly (orient3d: floating-point expansions, ExactFloat outside their safe
// range; orient2d: ExactFloat). Results are exact for every finite input.
//
// Sign conventions (stated once):
//  * orient3d(a, b, c, d) = sign(det[b - a, c - a, d - a]). POSITIVE when d lies on the side into
//    which the right-hand normal (b - a) x (c - a) points; a positively oriented tet (a, b, c, d)
//    has orient3d > 0. ZERO when the four points are coplanar.
//  * orient2d(a, b, c) = sign((b - a) x (c - a)) on the 2D coordinates: POSITIVE when a, b, c turn
//    counter-clockwise.
//  * orient2d_projected(a, b, c, axis) drops coordinate `axis` (0 = x, 1 = y, 2 = z) and applies
//    orient2d to the remaining pair in cyclic order: (y, z) for axis 0, (z, x) for 1, (x, y) for 2,
//    so that a triangle with normal n projects positively exactly when n[axis] > 0.
#pragma once

#include "bsptet/numerics/vec3.h"

namespace bsptet {

enum class Sign : int { kNegative = -1, kZero = 0, kPositive = 1 };

inline int to_int(Sign s) { return static_cast<int>(s); }
inline Sign opposite(Sign s) { return static_cast<Sign>(-static_cast<int>(s)); }

Sign orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
Sign orient2d_projected(const Vec3& a, const Vec3& b, const Vec3& c, int axis);

/// Exact-only versions (no filter), for differential tests of the filters.
Sign orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
Sign orient2d_projected_exact(const Vec3& a, const Vec3& b, const Vec3& c, int axis);
/// The exact sign of orient3d by floating-point expansions (no GMP; what orient3d uses when its
/// filter fails); false, and `out` unset, when a nonzero coordinate's magnitude is outside
/// [2^-200, 2^200] (orient3d then uses orient3d_exact).
bool orient3d_expansion(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Sign& out);
/// The exact sign of orient3d by expansions of the differences b - a, c - a, d - a (tried before
/// orient3d_expansion: far cheaper); false, and `out` unset, when a difference is not exact in
/// doubles or a nonzero one's magnitude is outside [2^-200, 2^200].
bool orient3d_differences_expansion(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Sign& out);
/// The exact sign of det[u, v, w] (rows) of double vectors by expansions; false, and `out` unset,
/// when a nonzero component's magnitude is outside [2^-200, 2^200].
bool det3_expansion(const Vec3& u, const Vec3& v, const Vec3& w, Sign& out);
/// out = p - q when every component's difference is exact in doubles (then true).
bool exact_difference(const Vec3& p, const Vec3& q, Vec3& out);

/// Filters for points known only approximately: each exact point lies within r (per coordinate)
/// of the given double point (a TPI vertex's rounded coordinates and its enclosing box). True,
/// and `out` set to the exact sign of orient3d / orient2d_projected of the exact points, when the
/// double evaluation and the input errors provably cannot change it; false otherwise (decide
/// exactly). With all r = 0 they are (slightly weaker) filters of orient3d / orient2d_projected.
bool orient3d_uncertain(const Vec3& a, double ra, const Vec3& b, double rb, const Vec3& c, double rc, const Vec3& d,
                        double rd, Sign& out);
bool orient2d_uncertain(const Vec3& a, double ra, const Vec3& b, double rb, const Vec3& c, double rc, int axis,
                        Sign& out);

/// Floating-point filters of the lifted determinants of ImplicitGeometry::lifted_det3 / lifted_det2
/// (unperturbed), for double points: lifted_det3 is sign det4 over the rows a..d of
/// (p - e, |p - e|^2); lifted_det2 is sign det3 over the rows a..c of ((p - d) projected by
/// `axis` as orient2d_projected, |p - d|^2). True, and `out` set, when the double evaluation's
/// proven error bound certifies the sign; false (out unset) when the caller must decide exactly.
bool lifted_det3_filter(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e, Sign& out);
bool lifted_det2_filter(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int axis, Sign& out);
/// lifted_det3_filter evaluated in x87 extended precision (64-bit significand, its own proven
/// bound): about 2^11 times tighter, so it certifies most points rounded onto a common sphere or
/// circle (a CAD cylinder's rings, a cube-sphere), where the double filter fails, at a fraction
/// of the exact computation's cost.
bool lifted_det3_filter_extended(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e,
                                 Sign& out);
/// lifted_det2_filter in x87 extended precision (points rounded onto one circle: a CAD plane's
/// round holes).
bool lifted_det2_filter_extended(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int axis, Sign& out);
/// The same determinants (unperturbed) for approximately known points, as orient3d_uncertain:
/// p[0..3] (lifted_det3; p[0..2] for lifted_det2) within rp[i] of the exact points, e (the last
/// row: e for lifted_det3, d for lifted_det2) within re.
bool lifted_det3_uncertain(const Vec3* p, const double* rp, const Vec3& e, double re, Sign& out);
bool lifted_det2_uncertain(const Vec3* p, const double* rp, const Vec3& e, double re, int axis, Sign& out);

}  // namespace bsptet
