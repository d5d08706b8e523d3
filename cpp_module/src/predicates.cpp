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
  return orient2d_projected_exact(a, b, c, axis);
}

}  // namespace bsptet
