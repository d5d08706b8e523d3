#include "bsptet/predicates.h"

#include <cmath>

#include "bsptet/exact_float.h"

namespace bsptet {

namespace {

constexpr double kUnitRoundoff = 1.1102230246251565e-16;  // 2^-53
// Forward error bounds of the straightforward floating-point evaluations below, relative to the
// permanent (the same expression with absolute values). Shewchuk (1997) proves (7 + 56u)u for
// orient3d and (3 + 16u)u for orient2d; we use slightly larger round constants.
constexpr double kOrient3dBound = 8.0 * kUnitRoundoff;
constexpr double kOrient2dBound = 4.0 * kUnitRoundoff;
// Below this magnitude products may have underflowed and the relative bound no longer holds.
constexpr double kUnderflowGuard = 1e-280;

Sign sign_of(double v) { return v > 0 ? Sign::kPositive : (v < 0 ? Sign::kNegative : Sign::kZero); }
Sign sign_of(int v) { return v > 0 ? Sign::kPositive : (v < 0 ? Sign::kNegative : Sign::kZero); }

// Picks the 2D coordinates kept when dropping `axis`, in cyclic order (see predicates.h).
inline void kept_axes(int axis, int& u, int& v) {
  u = (axis + 1) % 3;
  v = (axis + 2) % 3;
}

// Exactness certificates (issue 7: coplanar and collinear inputs, whose determinants are exactly
// zero, defeat every filter; on CAD tessellations most of them are on a coarse grid where every
// operation of the double evaluation is exact). Each helper computes one operation in doubles and
// says whether the result is exact: a difference by Knuth's TwoSum error term (exact with
// subnormals; no overflow allowed), a product by its fma residual (exact when the operands are far
// from underflow or one is zero). When every operation is exact the double result is the exact
// value, and its sign is the sign of the determinant.
inline bool exact_diff(double a, double b, double& out) {
  out = a - b;
  if (!std::isfinite(out)) return false;
  const double bb = out - a;
  return (a - (out - bb)) + (-b - bb) == 0;
}
inline bool exact_prod(double a, double b, double& out) {
  out = a * b;
  if (a == 0 || b == 0) return true;
  constexpr double kTiny = 0x1p-400;  // both above: the residual is a multiple of 2^-904, representable
  if (!std::isfinite(out) || std::fabs(a) < kTiny || std::fabs(b) < kTiny) return false;
  return std::fma(a, b, -out) == 0;
}

// sign(orient2d) when its double evaluation is exact; false otherwise.
bool orient2d_exact_in_doubles(const Vec3& a, const Vec3& b, const Vec3& c, int u, int v, Sign& out) {
  double bu, bv, cu, cv, l, r;
  if (!exact_diff(b[u], a[u], bu) || !exact_diff(b[v], a[v], bv) || !exact_diff(c[u], a[u], cu) ||
      !exact_diff(c[v], a[v], cv) || !exact_prod(bu, cv, l) || !exact_prod(bv, cu, r))
    return false;
  out = l > r ? Sign::kPositive : (l < r ? Sign::kNegative : Sign::kZero);  // comparing is exact
  return true;
}

// sign(orient3d) when its double evaluation is exact; false otherwise.
bool orient3d_exact_in_doubles(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Sign& out) {
  double bx, by, bz, cx, cy, cz, dx, dy, dz;
  if (!exact_diff(b.x, a.x, bx) || !exact_diff(b.y, a.y, by) || !exact_diff(b.z, a.z, bz) ||
      !exact_diff(c.x, a.x, cx) || !exact_diff(c.y, a.y, cy) || !exact_diff(c.z, a.z, cz) ||
      !exact_diff(d.x, a.x, dx) || !exact_diff(d.y, a.y, dy) || !exact_diff(d.z, a.z, dz))
    return false;
  double m1, m2, m3, m4, m5, m6, n1, n2, n3, t1, t2, t3, s12, det;
  if (!exact_prod(cy, dz, m1) || !exact_prod(cz, dy, m2) || !exact_prod(cx, dz, m3) || !exact_prod(cz, dx, m4) ||
      !exact_prod(cx, dy, m5) || !exact_prod(cy, dx, m6) || !exact_diff(m1, m2, n1) || !exact_diff(m3, m4, n2) ||
      !exact_diff(m5, m6, n3) || !exact_prod(bx, n1, t1) || !exact_prod(by, n2, t2) || !exact_prod(bz, n3, t3) ||
      !exact_diff(t1, t2, s12) || !exact_diff(s12, -t3, det))
    return false;
  out = sign_of(det);
  return true;
}

}  // namespace

Sign orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  // det[b - a, c - a, d - a]
  const ExactFloat ax(a.x), ay(a.y), az(a.z);
  const ExactFloat bx = ExactFloat(b.x) - ax, by = ExactFloat(b.y) - ay, bz = ExactFloat(b.z) - az;
  const ExactFloat cx = ExactFloat(c.x) - ax, cy = ExactFloat(c.y) - ay, cz = ExactFloat(c.z) - az;
  const ExactFloat dx = ExactFloat(d.x) - ax, dy = ExactFloat(d.y) - ay, dz = ExactFloat(d.z) - az;
  const ExactFloat det = bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
  return sign_of(det.sign());
}

Sign orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double bx = b.x - a.x, by = b.y - a.y, bz = b.z - a.z;
  const double cx = c.x - a.x, cy = c.y - a.y, cz = c.z - a.z;
  const double dx = d.x - a.x, dy = d.y - a.y, dz = d.z - a.z;
  const double m1 = cy * dz, m2 = cz * dy, m3 = cx * dz, m4 = cz * dx, m5 = cx * dy, m6 = cy * dx;
  const double det = bx * (m1 - m2) - by * (m3 - m4) + bz * (m5 - m6);
  const double perm = std::fabs(bx) * (std::fabs(m1) + std::fabs(m2)) +
                      std::fabs(by) * (std::fabs(m3) + std::fabs(m4)) +
                      std::fabs(bz) * (std::fabs(m5) + std::fabs(m6));
  const double bound = kOrient3dBound * perm;
  if (std::isfinite(perm) && perm > kUnderflowGuard && std::fabs(det) > bound) return sign_of(det);
  Sign certified;
  if (orient3d_exact_in_doubles(a, b, c, d, certified)) return certified;
  return orient3d_exact(a, b, c, d);
}

Sign orient2d_projected_exact(const Vec3& a, const Vec3& b, const Vec3& c, int axis) {
  int u = 0, v = 0;
  kept_axes(axis, u, v);
  const ExactFloat au(a[u]), av(a[v]);
  const ExactFloat det = (ExactFloat(b[u]) - au) * (ExactFloat(c[v]) - av) -
                         (ExactFloat(b[v]) - av) * (ExactFloat(c[u]) - au);
  return sign_of(det.sign());
}

Sign orient2d_projected(const Vec3& a, const Vec3& b, const Vec3& c, int axis) {
  int u = 0, v = 0;
  kept_axes(axis, u, v);
  const double l = (b[u] - a[u]) * (c[v] - a[v]);
  const double r = (b[v] - a[v]) * (c[u] - a[u]);
  const double det = l - r;
  const double perm = std::fabs(l) + std::fabs(r);
  if (std::isfinite(perm) && perm > kUnderflowGuard && std::fabs(det) > kOrient2dBound * perm)
    return sign_of(det);
  Sign certified;
  if (orient2d_exact_in_doubles(a, b, c, u, v, certified)) return certified;
  return orient2d_projected_exact(a, b, c, axis);
}

}  // namespace bsptet
