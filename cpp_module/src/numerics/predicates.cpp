// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/numerics/predicates.h"

#include <cmath>
#include <limits>

#include "bsptet/numerics/exact_float.h"

namespace bsptet {

namespace {

constexpr double kUnitRoundoff = 1.1102230246251565e-16;  // 2^-53
// Forward error bounds of the straightforward floating-point evaluations below, relative to the
// permanent (the same expression with absolute values). Shewchuk (1997) proves (7 + 56u)u for
// orient3d and (3 + 16u)u for orient2d; we use slightly larger round constants.
constexpr double kOrient3dBound = 8.0 * kUnitRoundoff;
constexpr double kOrient2dBound = 4.0 * kUnitRoundoff;
// The lifted determinants below have depth 10 (det4) and 9 (det3) in rounded operations (the
// coordinate differences included); the standard bound gamma_n * permanent, with the permanent
// itself rounded over at most 10 operations, stays under 11u; 16u leaves room (kLiftedBoundUnits;
// u is the unit roundoff of the type they are evaluated in: double, or x87 extended).
constexpr double kLiftedBoundUnits = 16.0;
// Below this magnitude products may have underflowed and the relative bound no longer holds.
constexpr double kUnderflowGuard = 1e-280;

// Unit roundoff of the extended filters: 2^-64, that of a 64-bit significand (x87); for a wider
// long double (quad) it is larger than the true one, so the bound stays sound.
constexpr long double kExtendedUnitRoundoff = 0x1p-64L;
// True when long double has its 64-bit significand at run time (the extended filters' bounds
// need it: x87 precision control lowered by other code, or valgrind's emulation, lose it).
bool extended_precision_works() {
  if (std::numeric_limits<long double>::digits < 64) return false;
  volatile long double one = 1.0L;
  return one + 0x1p-63L != one;
}

Sign sign_of(double v) { return v > 0 ? Sign::kPositive : (v < 0 ? Sign::kNegative : Sign::kZero); }
Sign sign_of(int v) { return v > 0 ? Sign::kPositive : (v < 0 ? Sign::kNegative : Sign::kZero); }

// Picks the 2D coordinates kept when dropping `axis`, in cyclic order (see predicates.h).
inline void kept_axes(int axis, int& u, int& v) {
  u = (axis + 1) % 3;
  v = (axis + 2) % 3;
}

// Exactness certificates (coplanar and collinear inputs, whose determinants are exactly
// zero, defeat every filter; on CAD tessellations most of them are on a coarse grid where every
// operation of the double evaluation is exact). Each helper computes one operation in doubles and
// says whether the result is exact: a difference by Knuth's TwoSum error term (exact with
// subnormals; no overflow allowed), a product by its fma residual (exact when the operands are far
// from underflow or one is zero). When every operation is exact the double result is the exact
// value, and its sign is the sign of the determinant.
// Knuth's TwoSum: x + y == a + b exactly, x = fl(a + b) (any finite operands, subnormals too).
inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a, av = x - bv;
  y = (a - av) + (b - bv);
}
// TwoProduct: x + y == a * b exactly when the residual y does not underflow.
inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}
inline bool exact_diff(double a, double b, double& out) {
  double err;
  two_sum(a, -b, out, err);
  return std::isfinite(out) && err == 0;
}
inline bool exact_prod(double a, double b, double& out) {
  double err;
  two_product(a, b, out, err);
  if (a == 0 || b == 0) return true;
  constexpr double kTiny = 0x1p-400;  // both above: the residual is a multiple of 2^-904, representable
  if (!std::isfinite(out) || std::fabs(a) < kTiny || std::fabs(b) < kTiny) return false;
  return err == 0;
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

// sign(det[B, C, D]) of exact differences B = b - a, ... when its double evaluation is exact;
// false otherwise.
bool det3_exact_in_doubles(const Vec3& B, const Vec3& C, const Vec3& D, Sign& out) {
  const double bx = B.x, by = B.y, bz = B.z, cx = C.x, cy = C.y, cz = C.z, dx = D.x, dy = D.y, dz = D.z;
  double m1, m2, m3, m4, m5, m6, n1, n2, n3, t1, t2, t3, s12, det;
  if (!exact_prod(cy, dz, m1) || !exact_prod(cz, dy, m2) || !exact_prod(cx, dz, m3) || !exact_prod(cz, dx, m4) ||
      !exact_prod(cx, dy, m5) || !exact_prod(cy, dx, m6) || !exact_diff(m1, m2, n1) || !exact_diff(m3, m4, n2) ||
      !exact_diff(m5, m6, n3) || !exact_prod(bx, n1, t1) || !exact_prod(by, n2, t2) || !exact_prod(bz, n3, t3) ||
      !exact_diff(t1, t2, s12) || !exact_diff(s12, -t3, det))
    return false;
  out = sign_of(det);
  return true;
}

// ---- Floating-point expansions (Priest; Shewchuk 1997) -------------------------------------
// An expansion is a sum of doubles, stored by increasing magnitude, no two overlapping; its sign
// is the sign of its last (largest) component. TwoSum is exact for any finite operands (with
// subnormals); TwoProduct (fma residual) is exact when the product's residual does not underflow,
// which orient3d_expansion guarantees by its range check. Zero components are dropped, so an
// expansion equal to zero is the single component 0. (two_sum, two_product: above.)
// h = e + b (h may not alias e). Returns h's length.
int grow_expansion(const double* e, int n, double b, double* h) {
  double q = b;
  int k = 0;
  for (int i = 0; i < n; ++i) {
    double hh;
    two_sum(q, e[i], q, hh);
    if (hh != 0) h[k++] = hh;
  }
  if (q != 0 || k == 0) h[k++] = q;
  return k;
}
// h = e + f, by growing e with each component of f (small expansions only). h must hold n + m
// components and may not alias e or f; `tmp` is scratch of the same size.
int expansion_sum(const double* e, int n, const double* f, int m, double* h, double* tmp) {
  int len = n;
  for (int i = 0; i < n; ++i) h[i] = e[i];
  for (int j = 0; j < m; ++j) {
    len = grow_expansion(h, len, f[j], tmp);
    for (int i = 0; i < len; ++i) h[i] = tmp[i];
  }
  return len;
}
// h = e * b. h must hold 2n components and may not alias e.
int scale_expansion(const double* e, int n, double b, double* h) {
  double q, hh;
  int k = 0;
  two_product(e[0], b, q, hh);
  if (hh != 0) h[k++] = hh;
  for (int i = 1; i < n; ++i) {
    double p1, p0, sum;
    two_product(e[i], b, p1, p0);
    two_sum(q, p0, sum, hh);
    if (hh != 0) h[k++] = hh;
    two_sum(p1, sum, q, hh);
    if (hh != 0) h[k++] = hh;
  }
  if (q != 0 || k == 0) h[k++] = q;
  return k;
}
// a * b - c * d exactly, as an expansion of at most 4 components.
int two_by_two(double a, double b, double c, double d, double* h) {
  double p[2], q[2], tmp[4];
  two_product(a, b, p[1], p[0]);
  two_product(c, d, q[1], q[0]);
  q[0] = -q[0], q[1] = -q[1];
  return expansion_sum(p, 2, q, 2, h, tmp);
}
// The 2x2 minor p.x * q.y - q.x * p.y as an expansion of at most 4 components.
int minor_xy(const Vec3& p, const Vec3& q, double* h) { return two_by_two(p.x, q.y, q.x, p.y, h); }

}  // namespace

// sign(orient3d) by expansions, or false when a coordinate is outside [2^-200, 2^200] in
// magnitude (then a TwoProduct residual could underflow or a sum overflow: use ExactFloat).
// det[b - a, c - a, d - a] = -det4 with det4 the 4x4 determinant of rows (x, y, z, 1) of a, b, c,
// d; by Laplace expansion on the (x, y) columns, det4 = za A + zb B + zc C + zd D with the 2x2
// minors m_pq = xp yq - xq yp: A = m_bc - m_bd + m_cd, B = m_ad - m_ac - m_cd,
// C = m_ab - m_ad + m_bd, D = m_ac - m_ab - m_bc.
bool orient3d_expansion(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Sign& out) {
  for (const Vec3* p : {&a, &b, &c, &d})
    for (int k = 0; k < 3; ++k) {
      const double m = std::fabs((*p)[k]);
      if (m != 0 && !(m >= 0x1p-200 && m <= 0x1p200)) return false;
    }
  struct Minor {
    double e[4];
    int n;
  };
  Minor mab, mac, mad, mbc, mbd, mcd;
  mab.n = minor_xy(a, b, mab.e), mac.n = minor_xy(a, c, mac.e), mad.n = minor_xy(a, d, mad.e);
  mbc.n = minor_xy(b, c, mbc.e), mbd.n = minor_xy(b, d, mbd.e), mcd.n = minor_xy(c, d, mcd.e);
  double total[96], scratch[96];
  int total_len = 1;
  total[0] = 0;
  // total += z * (s1 m1 + s2 m2 + s3 m3), signs s = +1 or -1. Lengths: coefficient <= 12,
  // scaled <= 24, total <= 4 * 24.
  auto add_term = [&](const Minor& m1, double s1, const Minor& m2, double s2, const Minor& m3, double s3,
                      double z) {
    double t1[4], t2[4], t3[4], c12[8], coef[12], tmp[12], scaled[24], sum[96];
    for (int i = 0; i < m1.n; ++i) t1[i] = s1 * m1.e[i];
    for (int i = 0; i < m2.n; ++i) t2[i] = s2 * m2.e[i];
    for (int i = 0; i < m3.n; ++i) t3[i] = s3 * m3.e[i];
    const int n12 = expansion_sum(t1, m1.n, t2, m2.n, c12, tmp);
    const int nc = expansion_sum(c12, n12, t3, m3.n, coef, tmp);
    const int ns = scale_expansion(coef, nc, z, scaled);
    const int nt = expansion_sum(total, total_len, scaled, ns, sum, scratch);
    for (int i = 0; i < nt; ++i) total[i] = sum[i];
    total_len = nt;
  };
  add_term(mbc, 1, mbd, -1, mcd, 1, a.z);   // A = m_bc - m_bd + m_cd
  add_term(mad, 1, mac, -1, mcd, -1, b.z);  // B = m_ad - m_ac - m_cd
  add_term(mab, 1, mad, -1, mbd, 1, c.z);   // C = m_ab - m_ad + m_bd
  add_term(mac, 1, mab, -1, mbc, -1, d.z);  // D = m_ac - m_ab - m_bc
  out = sign_of(-total[total_len - 1]);
  return true;
}

// sign(det[u, v, w]) (rows) by expansions, or false when a nonzero entry is outside
// [2^-200, 2^200] in magnitude (a TwoProduct residual could underflow). Each 2x2 minor of v, w is
// an expansion of 4 components, scaled by u's entry (8), summed (24): for exact differences of
// nearby points (Sterbenz's lemma) on one plane or sphere, far cheaper than the 4x4 form of
// orient3d_expansion.
bool det3_expansion(const Vec3& u, const Vec3& v, const Vec3& w, Sign& out) {
  for (const Vec3* p : {&u, &v, &w})
    for (int k = 0; k < 3; ++k) {
      const double m = std::fabs((*p)[k]);
      if (m != 0 && !(m >= 0x1p-200 && m <= 0x1p200)) return false;
    }
  double m1[4], m2[4], m3[4], s1[8], s2[8], s3[8], s12[16], tmp[24], total[24];
  const int n1 = two_by_two(v.y, w.z, v.z, w.y, m1), n2 = two_by_two(v.z, w.x, v.x, w.z, m2),
            n3 = two_by_two(v.x, w.y, v.y, w.x, m3);
  const int l1 = scale_expansion(m1, n1, u.x, s1), l2 = scale_expansion(m2, n2, u.y, s2),
            l3 = scale_expansion(m3, n3, u.z, s3);
  const int l12 = expansion_sum(s1, l1, s2, l2, s12, tmp);
  const int lt = expansion_sum(s12, l12, s3, l3, total, tmp);
  out = sign_of(total[lt - 1]);
  return true;
}

bool exact_difference(const Vec3& p, const Vec3& q, Vec3& out) {
  return exact_diff(p.x, q.x, out.x) && exact_diff(p.y, q.y, out.y) && exact_diff(p.z, q.z, out.z);
}

bool orient3d_differences_expansion(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Sign& out) {
  Vec3 B, C, D;
  return exact_difference(b, a, B) && exact_difference(c, a, C) && exact_difference(d, a, D) &&
         det3_expansion(B, C, D, out);
}

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
  // Differences exact in doubles (nearby points): the evaluation itself if exact, else their
  // expansions; otherwise the 4x4 expansions of the coordinates.
  Vec3 B, C, D;
  if (exact_difference(b, a, B) && exact_difference(c, a, C) && exact_difference(d, a, D) &&
      (det3_exact_in_doubles(B, C, D, certified) || det3_expansion(B, C, D, certified)))
    return certified;
  if (orient3d_expansion(a, b, c, d, certified)) return certified;
  return orient3d_exact(a, b, c, d);
}

namespace {
// |U_k - u_k| for the computed difference u_k = fl(B_k - A_k) of approximations A, B within ra,
// rb of the exact points: (ra + rb) + u |B_k - A_k|, with |B_k - A_k| <= |u_k| (1 + 2u), computed
// and then inflated so that its own rounding cannot make it smaller than the bound.
inline double difference_error(double ra, double rb, double uk) {
  return ((ra + rb) + 0x1p-52 * std::fabs(uk)) * (1 + 0x1p-50);
}
}  // namespace

bool orient3d_uncertain(const Vec3& a, double ra, const Vec3& b, double rb, const Vec3& c, double rc, const Vec3& d,
                        double rd, Sign& out) {
  const double u[3] = {b.x - a.x, b.y - a.y, b.z - a.z}, v[3] = {c.x - a.x, c.y - a.y, c.z - a.z},
               w[3] = {d.x - a.x, d.y - a.y, d.z - a.z};
  double au[3], av[3], aw[3], bu[3], bv[3], bw[3];  // |x| and |x| + its error bound
  for (int k = 0; k < 3; ++k) {
    au[k] = std::fabs(u[k]), av[k] = std::fabs(v[k]), aw[k] = std::fabs(w[k]);
    bu[k] = au[k] + difference_error(ra, rb, u[k]);
    bv[k] = av[k] + difference_error(ra, rc, v[k]);
    bw[k] = aw[k] + difference_error(ra, rd, w[k]);
  }
  const double det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                     u[2] * (v[0] * w[1] - v[1] * w[0]);
  auto perm = [](const double* x, const double* y, const double* z) {
    return x[0] * (y[1] * z[2] + y[2] * z[1]) + x[1] * (y[0] * z[2] + y[2] * z[0]) + x[2] * (y[0] * z[1] + y[1] * z[0]);
  };
  const double p0 = perm(au, av, aw), p1 = perm(bu, bv, bw);
  // |det(exact) - det| <= (P1 - P0) (input errors; det is multilinear) + 8u P0 (evaluation), with
  // P0, P1 the permanents without and with the errors, each computed within 6u; the last terms
  // cover the rounding of this bound's own three operations (each <= u P1).
  const double bound = p1 * (1 + 12 * kUnitRoundoff) - p0 * (1 - 16 * kUnitRoundoff);
  if (!(std::isfinite(p1) && std::isfinite(det) && p1 > kUnderflowGuard && std::fabs(det) > bound)) return false;
  out = sign_of(det);
  return true;
}

bool orient2d_uncertain(const Vec3& a, double ra, const Vec3& b, double rb, const Vec3& c, double rc, int axis,
                        Sign& out) {
  int ku = 0, kv = 0;
  kept_axes(axis, ku, kv);
  const double bu = b[ku] - a[ku], bv = b[kv] - a[kv], cu = c[ku] - a[ku], cv = c[kv] - a[kv];
  const double l = bu * cv, r = bv * cu, det = l - r;
  const double p0 = std::fabs(bu) * std::fabs(cv) + std::fabs(bv) * std::fabs(cu);
  const double p1 = (std::fabs(bu) + difference_error(ra, rb, bu)) * (std::fabs(cv) + difference_error(ra, rc, cv)) +
                    (std::fabs(bv) + difference_error(ra, rb, bv)) * (std::fabs(cu) + difference_error(ra, rc, cu));
  // As orient3d_uncertain: P0, P1 within 3u, evaluation error <= 3u P0.
  const double bound = p1 * (1 + 8 * kUnitRoundoff) - p0 * (1 - 10 * kUnitRoundoff);
  if (!(std::isfinite(p1) && std::isfinite(det) && p1 > kUnderflowGuard && std::fabs(det) > bound)) return false;
  out = sign_of(det);
  return true;
}

bool lifted_det3_uncertain(const Vec3* p, const double* rp, const Vec3& e, double re, Sign& out) {
  double d[4][3], ad[4][3], bd[4][3], la[4], lb[4];
  for (int i = 0; i < 4; ++i) {
    const double di[3] = {p[i].x - e.x, p[i].y - e.y, p[i].z - e.z};
    la[i] = lb[i] = 0;
    for (int k = 0; k < 3; ++k) {
      d[i][k] = di[k];
      ad[i][k] = std::fabs(di[k]);
      bd[i][k] = ad[i][k] + difference_error(rp[i], re, di[k]);
      la[i] += di[k] * di[k];
      lb[i] += bd[i][k] * bd[i][k];
    }
  }
  // det3 over (x, y, z) of rows (i, j, k), and its permanent over the given magnitudes.
  auto det3r = [&](int i, int j, int k) {
    return d[i][0] * (d[j][1] * d[k][2] - d[j][2] * d[k][1]) - d[i][1] * (d[j][0] * d[k][2] - d[j][2] * d[k][0]) +
           d[i][2] * (d[j][0] * d[k][1] - d[j][1] * d[k][0]);
  };
  auto perm3 = [](const double (*x)[3], int i, int j, int k) {
    return x[i][0] * (x[j][1] * x[k][2] + x[j][2] * x[k][1]) + x[i][1] * (x[j][0] * x[k][2] + x[j][2] * x[k][0]) +
           x[i][2] * (x[j][0] * x[k][1] + x[j][1] * x[k][0]);
  };
  // Laplace expansion on the lift column: cofactor signs -, +, -, + for rows 0..3.
  const double det = ((la[1] * det3r(0, 2, 3) - la[0] * det3r(1, 2, 3)) + la[3] * det3r(0, 1, 2)) - la[2] * det3r(0, 1, 3);
  const double pa = ((la[1] * perm3(ad, 0, 2, 3) + la[0] * perm3(ad, 1, 2, 3)) + la[3] * perm3(ad, 0, 1, 2)) +
                    la[2] * perm3(ad, 0, 1, 3);
  const double pb = ((lb[1] * perm3(bd, 0, 2, 3) + lb[0] * perm3(bd, 1, 2, 3)) + lb[3] * perm3(bd, 0, 1, 2)) +
                    lb[2] * perm3(bd, 0, 1, 3);
  // Per term, |L M - l m| <= Lb Mb - La Ma (|L - l| <= Lb - La, |M - m| <= Mb - Ma, |M| <= Mb);
  // so the input errors move det by at most Pb - Pa, the evaluation by at most 16u Pa (as in
  // lifted_det3_filter); Pa and Pb are computed within 10u, this bound's own rounding within 3u Pb.
  const double bound = pb * (1 + 16 * kUnitRoundoff) - pa * (1 - 28 * kUnitRoundoff);
  if (!(std::isfinite(pb) && std::isfinite(det) && pb > kUnderflowGuard && std::fabs(det) > bound)) return false;
  out = sign_of(det);
  return true;
}

bool lifted_det2_uncertain(const Vec3* p, const double* rp, const Vec3& e, double re, int axis, Sign& out) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  double du[3], dv[3], au[3], av[3], bu[3], bv[3], la[3], lb[3];
  for (int i = 0; i < 3; ++i) {
    const double di[3] = {p[i].x - e.x, p[i].y - e.y, p[i].z - e.z};
    la[i] = lb[i] = 0;
    for (int k = 0; k < 3; ++k) {
      const double b = std::fabs(di[k]) + difference_error(rp[i], re, di[k]);
      la[i] += di[k] * di[k];
      lb[i] += b * b;
      if (k == u) du[i] = di[k], au[i] = std::fabs(di[k]), bu[i] = b;
      if (k == v) dv[i] = di[k], av[i] = std::fabs(di[k]), bv[i] = b;
    }
  }
  // det3 of rows (du, dv, l) expanded on the lift column: l0 m12 - l1 m02 + l2 m01 with the 2x2
  // minors m_ij = du_i dv_j - dv_i du_j.
  auto m = [&](int i, int j) { return du[i] * dv[j] - dv[i] * du[j]; };
  auto pm = [](const double* x, const double* y, int i, int j) { return x[i] * y[j] + y[i] * x[j]; };
  const double det = (la[0] * m(1, 2) - la[1] * m(0, 2)) + la[2] * m(0, 1);
  const double pa = (la[0] * pm(au, av, 1, 2) + la[1] * pm(au, av, 0, 2)) + la[2] * pm(au, av, 0, 1);
  const double pb = (lb[0] * pm(bu, bv, 1, 2) + lb[1] * pm(bu, bv, 0, 2)) + lb[2] * pm(bu, bv, 0, 1);
  // As lifted_det3_uncertain (evaluation depth 9: 16u; Pa, Pb within 8u).
  const double bound = pb * (1 + 14 * kUnitRoundoff) - pa * (1 - 26 * kUnitRoundoff);
  if (!(std::isfinite(pb) && std::isfinite(det) && pb > kUnderflowGuard && std::fabs(det) > bound)) return false;
  out = sign_of(det);
  return true;
}

namespace {
// lifted_det3_filter in the floating-point type T whose unit roundoff is `unit` (double: 2^-53;
// x87 extended long double: 2^-64). The evaluation has depth 10 in rounded operations, the
// coordinate differences included; its error stays under 11 unit times the permanent (itself
// rounded over at most 10 operations): 16 unit leaves room, in either format.
template <typename T>
bool lifted_det3_filter_in(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e, T unit,
                           Sign& out) {
  const Vec3* rows[4] = {&a, &b, &c, &d};
  T x[4], y[4], z[4], l[4];
  for (int i = 0; i < 4; ++i) {
    x[i] = T(rows[i]->x) - T(e.x), y[i] = T(rows[i]->y) - T(e.y), z[i] = T(rows[i]->z) - T(e.z);
    l[i] = x[i] * x[i] + y[i] * y[i] + z[i] * z[i];  // a sum of non-negative terms: its own permanent
  }
  using std::fabs;
  // 2x2 minors of the (x, y) columns and their permanents.
  auto m = [&](int i, int j) { return x[i] * y[j] - x[j] * y[i]; };
  auto pm = [&](int i, int j) { return fabs(x[i] * y[j]) + fabs(x[j] * y[i]); };
  const T m01 = m(0, 1), m02 = m(0, 2), m03 = m(0, 3), m12 = m(1, 2), m13 = m(1, 3), m23 = m(2, 3);
  const T p01 = pm(0, 1), p02 = pm(0, 2), p03 = pm(0, 3), p12 = pm(1, 2), p13 = pm(1, 3), p23 = pm(2, 3);
  // det3 of rows (i, j, k) over (x, y, z) = z_i m_jk - z_j m_ik + z_k m_ij.
  const T d123 = (z[1] * m23 - z[2] * m13) + z[3] * m12, d023 = (z[0] * m23 - z[2] * m03) + z[3] * m02,
          d013 = (z[0] * m13 - z[1] * m03) + z[3] * m01, d012 = (z[0] * m12 - z[1] * m02) + z[2] * m01;
  const T q123 = (fabs(z[1]) * p23 + fabs(z[2]) * p13) + fabs(z[3]) * p12,
          q023 = (fabs(z[0]) * p23 + fabs(z[2]) * p03) + fabs(z[3]) * p02,
          q013 = (fabs(z[0]) * p13 + fabs(z[1]) * p03) + fabs(z[3]) * p01,
          q012 = (fabs(z[0]) * p12 + fabs(z[1]) * p02) + fabs(z[2]) * p01;
  // Laplace expansion on the lift column (index 3): cofactor signs -, +, -, + for rows 0..3.
  const T det = ((l[1] * d023 - l[0] * d123) + l[3] * d012) - l[2] * d013;
  const T perm = ((l[1] * q023 + l[0] * q123) + l[3] * q012) + l[2] * q013;
  using std::isfinite;
  if (!(isfinite(perm) && perm > T(kUnderflowGuard) && fabs(det) > T(kLiftedBoundUnits) * unit * perm)) return false;
  out = det > 0 ? Sign::kPositive : (det < 0 ? Sign::kNegative : Sign::kZero);
  return true;
}
}  // namespace

bool lifted_det3_filter(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e, Sign& out) {
  return lifted_det3_filter_in<double>(a, b, c, d, e, kUnitRoundoff, out);
}

bool lifted_det3_filter_extended(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e,
                                 Sign& out) {
  // Where long double is double (MSVC, Apple arm64) the filter would repeat the double one:
  // decline. At run time the significand must be there too: code that lowers the x87 precision
  // control (or an emulator such as valgrind, which computes long double in double) would make
  // the bound unsound. Then decline (the caller decides exactly).
  if (!extended_precision_works()) return false;
  return lifted_det3_filter_in<long double>(a, b, c, d, e, kExtendedUnitRoundoff, out);
}

namespace {
// lifted_det2_filter in the floating-point type T with unit roundoff `unit` (see
// lifted_det3_filter_in: depth 9, the same bound).
template <typename T>
bool lifted_det2_filter_in(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int axis, T unit, Sign& out) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const Vec3* rows[3] = {&a, &b, &c};
  T r[3][3];
  for (int i = 0; i < 3; ++i) {
    const T dx = T(rows[i]->x) - T(d.x), dy = T(rows[i]->y) - T(d.y), dz = T(rows[i]->z) - T(d.z);
    const T dd[3] = {dx, dy, dz};
    r[i][0] = dd[u], r[i][1] = dd[v], r[i][2] = dx * dx + dy * dy + dz * dz;
  }
  using std::fabs;
  auto m = [&](int i, int j, int p, int q) { return r[i][p] * r[j][q] - r[i][q] * r[j][p]; };
  auto pm = [&](int i, int j, int p, int q) { return fabs(r[i][p] * r[j][q]) + fabs(r[i][q] * r[j][p]); };
  const T det = (r[0][0] * m(1, 2, 1, 2) - r[0][1] * m(1, 2, 0, 2)) + r[0][2] * m(1, 2, 0, 1);
  const T perm = (fabs(r[0][0]) * pm(1, 2, 1, 2) + fabs(r[0][1]) * pm(1, 2, 0, 2)) + fabs(r[0][2]) * pm(1, 2, 0, 1);
  using std::isfinite;
  if (!(isfinite(perm) && perm > T(kUnderflowGuard) && fabs(det) > T(kLiftedBoundUnits) * unit * perm)) return false;
  out = det > 0 ? Sign::kPositive : (det < 0 ? Sign::kNegative : Sign::kZero);
  return true;
}
}  // namespace

bool lifted_det2_filter(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int axis, Sign& out) {
  return lifted_det2_filter_in<double>(a, b, c, d, axis, kUnitRoundoff, out);
}

bool lifted_det2_filter_extended(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int axis, Sign& out) {
  if (!extended_precision_works()) return false;
  return lifted_det2_filter_in<long double>(a, b, c, d, axis, kExtendedUnitRoundoff, out);
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
