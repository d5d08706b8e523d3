// SPDX-License-Identifier: LGPL-2.1-or-later
// Differential tests of the filtered predicates against the exact ones, on random, near-degenerate
// (one ulp, 2^-45 perturbations) and extreme-scale inputs. Seeds are printed and fixed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "bsptet/numerics/exact_float.h"
#include "bsptet/numerics/predicates.h"

using namespace bsptet;

TEST(ExactFloat, ConvertsAndMultipliesExactly) {
  const ExactFloat a(0.1), b(3.0);
  // 0.1 * 3 in exact arithmetic is not 0.30000000000000004 nor 0.3: compare against sums.
  EXPECT_EQ(a * b, a + a + a);
  EXPECT_NE(a * b, ExactFloat(0.3));
  EXPECT_EQ((ExactFloat(1e300) * ExactFloat(1e300)).sign(), 1);
  EXPECT_EQ((ExactFloat(4.9e-324) * ExactFloat(-4.9e-324)).sign(), -1);
  EXPECT_EQ((ExactFloat(1.0) - ExactFloat(1.0)).sign(), 0);
  EXPECT_DOUBLE_EQ(ExactFloat(-2.5).to_double(), -2.5);
}

TEST(Orient3d, SignConvention) {
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0}, up{0, 0, 1}, down{0, 0, -1}, on{0.3, 0.3, 0};
  EXPECT_EQ(orient3d(a, b, c, up), Sign::kPositive);
  EXPECT_EQ(orient3d(a, b, c, down), Sign::kNegative);
  EXPECT_EQ(orient3d(a, b, c, on), Sign::kZero);
  EXPECT_EQ(orient3d(b, a, c, up), Sign::kNegative);
}

TEST(Orient2dProjected, SignMatchesNormalComponent) {
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};  // normal +z
  EXPECT_EQ(orient2d_projected(a, b, c, 2), Sign::kPositive);
  const Vec3 p{0, 0, 0}, q{0, 1, 0}, r{0, 0, 1};  // normal +x
  EXPECT_EQ(orient2d_projected(p, q, r, 0), Sign::kPositive);
  const Vec3 s{0, 0, 0}, t{0, 0, 1}, u{1, 0, 0};  // normal +y
  EXPECT_EQ(orient2d_projected(s, t, u, 1), Sign::kPositive);
}

TEST(Orient3d, OneUlpOffThePlane) {
  // A point exactly on the plane x + y + z = 1 and its one-ulp neighbours.
  const Vec3 a{1, 0, 0}, b{0, 1, 0}, c{0, 0, 1};
  const double x = 0.25, y = 0.5;
  const Vec3 on{x, y, 0.25};
  EXPECT_EQ(orient3d(a, b, c, on), Sign::kZero);
  const Vec3 above{x, y, std::nextafter(0.25, 1.0)};
  const Vec3 below{x, y, std::nextafter(0.25, 0.0)};
  EXPECT_EQ(orient3d(a, b, c, above), Sign::kPositive);  // the normal of (a, b, c) is +(1, 1, 1)
  EXPECT_EQ(orient3d(a, b, c, below), opposite(orient3d(a, b, c, above)));
  EXPECT_EQ(orient3d(a, b, c, above), orient3d_exact(a, b, c, above));
}

TEST(Orient3d, FilterAgreesWithExact) {
  const unsigned seed = 20261122u;
  std::printf("seed %u\n", seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  std::uniform_int_distribution<int> scale_exp(-300, 300);
  int degenerate = 0;
  for (int it = 0; it < 200000; ++it) {
    const double s = std::ldexp(1.0, scale_exp(rng) % 60);
    const double shift = (it % 3 == 0) ? 1e6 : 0.0;
    Vec3 p[4];
    for (auto& v : p) v = {U(rng) * s + shift, U(rng) * s - shift, U(rng) * s};
    if (it % 4 == 1) {
      // d on the line through a and b (exactly when representable), or nudged by 2^-45.
      const double t = 0.5;
      p[3] = {p[0].x + t * (p[1].x - p[0].x), p[0].y + t * (p[1].y - p[0].y), p[0].z + t * (p[1].z - p[0].z)};
      if (it % 8 == 1) p[3].x += std::ldexp(p[3].x, -45);
    } else if (it % 4 == 2) {
      // Grid points: many exactly coplanar quadruples.
      for (auto& v : p) v = {std::round(U(rng) * 4) * s, std::round(U(rng) * 4) * s, std::round(U(rng) * 2) * s};
    } else if (it % 4 == 3) {
      p[3].z = std::nextafter(p[3].z, (it & 16) ? INFINITY : -INFINITY);
    }
    const Sign f = orient3d(p[0], p[1], p[2], p[3]);
    const Sign e = orient3d_exact(p[0], p[1], p[2], p[3]);
    ASSERT_EQ(f, e) << "iteration " << it << " seed " << seed;
    degenerate += e == Sign::kZero;
  }
  EXPECT_GT(degenerate, 1000) << "the test must exercise exact zeros";
}

// The expansion path alone against ExactFloat, on the inputs the filter cannot decide: points
// rounded onto generic planes (orient3d tiny but mostly not zero), exactly coplanar grid points
// far from the origin, and points one ulp off such planes.
TEST(Orient3d, ExpansionsAgreeWithExactFloat) {
  const unsigned seed = 20261123u;
  std::printf("seed %u\n", seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  std::uniform_int_distribution<int> scale_exp(-150, 150);
  int zeros = 0, nonzeros = 0, refused = 0, by_differences = 0;
  for (int it = 0; it < 100000; ++it) {
    const double s = std::ldexp(1.0, scale_exp(rng));
    const double shift = (it % 5 == 0) ? 1e7 * s : 0.0;
    Vec3 p[4];
    if (it % 3 == 0) {
      // Four points rounded onto the plane through three random ones.
      Vec3 q[3];
      for (auto& v : q) v = {U(rng) * s + shift, U(rng) * s, U(rng) * s - shift};
      for (int k = 0; k < 4; ++k) {
        const double u = U(rng), w = U(rng);
        p[k] = {q[0].x + u * (q[1].x - q[0].x) + w * (q[2].x - q[0].x),
                q[0].y + u * (q[1].y - q[0].y) + w * (q[2].y - q[0].y),
                q[0].z + u * (q[1].z - q[0].z) + w * (q[2].z - q[0].z)};
      }
    } else {
      // Integer points on the plane z = i x + j y + k (exactly coplanar), scaled by s.
      const double i = std::round(U(rng) * 3), j = std::round(U(rng) * 3), k = std::round(U(rng) * 50);
      for (auto& v : p) {
        const double x = std::round(U(rng) * 1000), y = std::round(U(rng) * 1000);
        v = {x * s + shift, y * s, (i * x + j * y + k) * s};
      }
      if (it % 3 == 2) p[3].y = std::nextafter(p[3].y, (it & 8) ? INFINITY : -INFINITY);
    }
    Sign got, from_differences;
    const Sign want = orient3d_exact(p[0], p[1], p[2], p[3]);
    if (orient3d_differences_expansion(p[0], p[1], p[2], p[3], from_differences)) {
      ASSERT_EQ(from_differences, want) << "differences, iteration " << it << " seed " << seed;
      ++by_differences;
    }
    if (!orient3d_expansion(p[0], p[1], p[2], p[3], got)) {
      ++refused;
      continue;
    }
    ASSERT_EQ(got, want) << "iteration " << it << " seed " << seed;
    (want == Sign::kZero ? zeros : nonzeros) += 1;
  }
  // The differences stage decides most of these (exact differences: no shift, or a shift
  // within Sterbenz's range), and is exact on every one it decides.
  EXPECT_GT(by_differences, 30000);
  EXPECT_GT(zeros, 10000);
  EXPECT_GT(nonzeros, 10000);
  EXPECT_LT(refused, 100);  // a subnormal coordinate (the ulp step off 0), refused by design
  Sign out;
  EXPECT_FALSE(orient3d_expansion({1e-70, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, out));
  EXPECT_FALSE(orient3d_expansion({1e70, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, out));
  EXPECT_FALSE(orient3d_differences_expansion({1e-70, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, out));
  EXPECT_FALSE(orient3d_differences_expansion({0, 0, 0}, {1e70, 0, 0}, {0, 1, 0}, {0, 0, 1}, out));
  EXPECT_FALSE(orient3d_differences_expansion({1, 0, 0}, {0x1p-60, 0, 0}, {0, 1, 0}, {0, 0, 1}, out));  // 1 - 2^-60 not exact
}

TEST(Orient3d, ExtremeMagnitudes) {
  for (double s : {1e-300, 1e-150, 1e-6, 1.0, 1e6, 1e150, 1e300}) {
    const Vec3 a{0, 0, 0}, b{s, 0, 0}, c{0, s, 0}, d{0, 0, s}, e{s / 4, s / 4, 0};
    EXPECT_EQ(orient3d(a, b, c, d), Sign::kPositive) << s;
    EXPECT_EQ(orient3d(a, b, c, e), Sign::kZero) << s;
    const Vec3 tiny{s / 4, s / 4, std::nextafter(0.0, 1.0)};
    EXPECT_EQ(orient3d(a, b, c, tiny), Sign::kPositive) << s;
  }
}

TEST(Orient2dProjected, FilterAgreesWithExact) {
  const unsigned seed = 7u;
  std::printf("seed %u\n", seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int it = 0; it < 100000; ++it) {
    Vec3 p[3];
    for (auto& v : p) v = {U(rng), U(rng), U(rng)};
    if (it % 2) p[2] = {(p[0].x + p[1].x) / 2, (p[0].y + p[1].y) / 2, (p[0].z + p[1].z) / 2};
    if (it % 4 == 3) p[2].y = std::nextafter(p[2].y, 2.0);
    for (int axis = 0; axis < 3; ++axis)
      ASSERT_EQ(orient2d_projected(p[0], p[1], p[2], axis), orient2d_projected_exact(p[0], p[1], p[2], axis))
          << "iteration " << it;
  }
}

namespace {

// The lifted determinants of lifted_det3_filter / lifted_det2_filter computed in ExactFloat: det4
// over the rows p[0..3] of (p - e, |p - e|^2), and det3 over the rows p[0..2] of ((p - d)
// projected by `axis`, |p - d|^2). Their signs (-1, 0, +1).
int exact_lifted_det3(const Vec3* p, const Vec3& e) {
  ExactFloat r[4][4];
  for (int i = 0; i < 4; ++i) {
    const ExactFloat dx = ExactFloat(p[i].x) - ExactFloat(e.x), dy = ExactFloat(p[i].y) - ExactFloat(e.y),
                     dz = ExactFloat(p[i].z) - ExactFloat(e.z);
    r[i][0] = dx, r[i][1] = dy, r[i][2] = dz, r[i][3] = dx * dx + dy * dy + dz * dz;
  }
  auto m = [&](int i, int j, int a, int b) { return r[i][a] * r[j][b] - r[i][b] * r[j][a]; };
  const ExactFloat det = m(0, 1, 0, 1) * m(2, 3, 2, 3) - m(0, 1, 0, 2) * m(2, 3, 1, 3) + m(0, 1, 0, 3) * m(2, 3, 1, 2) +
                         m(0, 1, 1, 2) * m(2, 3, 0, 3) - m(0, 1, 1, 3) * m(2, 3, 0, 2) + m(0, 1, 2, 3) * m(2, 3, 0, 1);
  return det.sign();
}
int exact_lifted_det2(const Vec3* p, const Vec3& d, int axis) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  ExactFloat r[3][3];
  for (int i = 0; i < 3; ++i) {
    const ExactFloat dd[3] = {ExactFloat(p[i].x) - ExactFloat(d.x), ExactFloat(p[i].y) - ExactFloat(d.y),
                              ExactFloat(p[i].z) - ExactFloat(d.z)};
    r[i][0] = dd[u], r[i][1] = dd[v], r[i][2] = dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2];
  }
  const ExactFloat det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) -
                         r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0]) +
                         r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
  return det.sign();
}
// Exactly cospherical points: (+-3, +-4, 0), (0, +-3, +-4), (+-4, 0, +-3) on the sphere of radius 5.
const Vec3 kCospherical[8] = {{3, 4, 0}, {-3, 4, 0}, {0, 3, 4}, {0, -3, 4}, {4, 0, 3}, {4, 0, -3}, {-4, 0, 3}, {0, 5, 0}};

}  // namespace

// The lifted (in-sphere / in-circle) filters against ExactFloat: random points, points on a
// common sphere (integer Pythagorean-like coordinates, exactly cospherical) moved by one ulp or
// 2^-45, and scales from 2^-300 to 2^300. A certified sign must be the exact one; a zero
// determinant must never be certified as non-zero.
TEST(LiftedFilters, AgreeWithExact) {
  const unsigned seed = 20261203u;
  std::printf("seed %u\n", seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  std::uniform_int_distribution<int> scale_exp(-300, 300), pick(0, 3);
  int certified = 0, zeros = 0, trials = 0;
  for (int it = 0; it < 40000; ++it) {
    Vec3 p[5];
    const int kind = it % 4;
    const double s = std::ldexp(1.0, kind == 3 ? scale_exp(rng) : 0);
    for (int i = 0; i < 5; ++i) {
      if (kind == 0) {
        p[i] = {U(rng), U(rng), U(rng)};
      } else {
        p[i] = kCospherical[(it * 7 + i * 3) % 8];
        if (i == 4 && kind == 2) p[i].x = std::nextafter(p[i].x, pick(rng) < 2 ? 10.0 : -10.0);
        if (i == 4 && kind == 1 && pick(rng) == 0) p[i].y += std::ldexp(1.0, -45);
      }
      p[i] = {p[i].x * s, p[i].y * s, p[i].z * s};
    }
    Sign f;
    ++trials;
    const int ex3 = exact_lifted_det3(p, p[4]);
    zeros += ex3 == 0;
    if (lifted_det3_filter(p[0], p[1], p[2], p[3], p[4], f)) {
      ++certified;
      ASSERT_EQ(static_cast<int>(f), ex3) << "it " << it;
    }
    if (lifted_det3_filter_extended(p[0], p[1], p[2], p[3], p[4], f)) ASSERT_EQ(static_cast<int>(f), ex3) << "it " << it;
    const int axis = it % 3;
    const int ex2 = exact_lifted_det2(p, p[3], axis);
    if (lifted_det2_filter(p[0], p[1], p[2], p[3], axis, f)) ASSERT_EQ(static_cast<int>(f), ex2) << "it " << it;
    if (lifted_det2_filter_extended(p[0], p[1], p[2], p[3], axis, f)) ASSERT_EQ(static_cast<int>(f), ex2) << "it " << it;
  }
  std::printf("lifted_det3: %d of %d certified, %d exact zeros\n", certified, trials, zeros);
  EXPECT_GT(zeros, 1000);           // the degenerate cases were really made
  EXPECT_GT(certified, trials / 5);  // and the filter decides the random quarter (the rest is built degenerate)
}

// The extended-precision lifted filter where the double one fails: five points rounded onto one
// sphere (a cube-sphere, a CAD sphere), four rounded onto a circle and a fifth near it (a CAD
// cylinder's ring), shifted and scaled. Every certified sign must be the exact one, and it must
// certify most of them (that is its purpose: the Delaunay seed of such surfaces went to GMP).
TEST(LiftedFilters, ExtendedPrecisionDecidesRoundedSpheres) {
  volatile long double one = 1.0L;
  if (one + 0x1p-63L == one) GTEST_SKIP() << "long double has no 64-bit significand here (valgrind?): the filter declines";
  const unsigned seed = 20261203u;
  std::printf("seed %u\n", seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1), angle(0, 6.283185307179586);
  std::uniform_int_distribution<int> scale_exp(-60, 60);
  int by_double = 0, by_extended = 0, nonzero = 0;
  for (int it = 0; it < 20000; ++it) {
    const double s = std::ldexp(1.0, scale_exp(rng)), shift = (it % 3 == 0) ? 100.0 : 0.0;
    Vec3 p[5];
    for (int i = 0; i < 5; ++i) {
      if (it % 2 == 0) {
        const double t = angle(rng), z = U(rng), r = std::sqrt(1 - z * z);
        p[i] = {r * std::cos(t), r * std::sin(t), z};
      } else {
        const double t = angle(rng);
        p[i] = i < 4 ? Vec3{std::cos(t), std::sin(t), 0.5} : Vec3{std::cos(t) * (1 + 1e-9 * U(rng)), std::sin(t), 0.5 + 1e-3 * U(rng)};
      }
      p[i] = {(p[i].x + shift) * s, p[i].y * s, (p[i].z - shift) * s};
    }
    const int want = exact_lifted_det3(p, p[4]);
    nonzero += want != 0;
    Sign f;
    if (lifted_det3_filter(p[0], p[1], p[2], p[3], p[4], f)) {
      ++by_double;
      ASSERT_EQ(static_cast<int>(f), want) << "it " << it;
    }
    if (lifted_det3_filter_extended(p[0], p[1], p[2], p[3], p[4], f)) {
      ++by_extended;
      ASSERT_EQ(static_cast<int>(f), want) << "it " << it;
    }
  }
  std::printf("certified: double %d, extended %d, of %d nonzero\n", by_double, by_extended, nonzero);
  EXPECT_LT(by_double, nonzero / 2);
  EXPECT_GT(by_extended, nonzero * 8 / 10);
  // The in-circle test on a plane: four points rounded onto one circle of a plane z = c (a CAD
  // plane's round hole), the fourth sometimes moved off it by a relative 1e-12.
  int by_double2 = 0, by_extended2 = 0, nonzero2 = 0;
  for (int it = 0; it < 20000; ++it) {
    const double s = std::ldexp(1.0, scale_exp(rng)), cx = (it % 3 == 0) ? 50.0 : 0.0, r = 1 + U(rng) * 0.5;
    Vec3 p[4];
    for (int i = 0; i < 4; ++i) {
      const double t = angle(rng), rr = (i == 3 && it % 2) ? r * (1 + 1e-12 * U(rng)) : r;
      p[i] = {(cx + rr * std::cos(t)) * s, rr * std::sin(t) * s, 0.75 * s};
    }
    const int want = exact_lifted_det2(p, p[3], 2);
    nonzero2 += want != 0;
    Sign f;
    if (lifted_det2_filter(p[0], p[1], p[2], p[3], 2, f)) {
      ++by_double2;
      ASSERT_EQ(static_cast<int>(f), want) << "it " << it;
    }
    if (lifted_det2_filter_extended(p[0], p[1], p[2], p[3], 2, f)) {
      ++by_extended2;
      ASSERT_EQ(static_cast<int>(f), want) << "it " << it;
    }
  }
  std::printf("in-circle certified: double %d, extended %d, of %d nonzero\n", by_double2, by_extended2, nonzero2);
  EXPECT_LT(by_double2, nonzero2 * 7 / 10);  // about half
  EXPECT_GT(by_extended2, nonzero2 * 8 / 10);
}

// The filters for approximately known points: the exact points p are doubles (so the exact sign
// is known), the filters see m = p moved by up to r in each coordinate (r from 0 to 1e-3 of the
// scale). A certified sign must be the exact sign of the p; coplanar / collinear p (exact zeros)
// must never be certified. Near-degenerate cases: a fourth point on the plane of three, moved one
// ulp; scales from 2^-300 to 2^300.
TEST(UncertainFilters, AgreeWithExactOfTheTruePoints) {
  const unsigned seed = 20261204u;
  std::printf("seed %u\n", seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1), U01(0, 1);
  std::uniform_int_distribution<int> scale_exp(-300, 300), kind_of(0, 3), rexp(-60, -10);
  int certified3 = 0, certified2 = 0, zeros = 0;
  for (int it = 0; it < 60000; ++it) {
    const int kind = kind_of(rng);
    const double s = std::ldexp(1.0, kind == 3 ? scale_exp(rng) : 0);
    Vec3 p[4];
    for (auto& q : p) q = {U(rng) * s, U(rng) * s, U(rng) * s};
    if (kind == 1 || kind == 2) {
      // d on the plane of a, b, c (exactly when it lands on doubles: take d = a + k (b - a) with
      // small integer k and exact differences), then maybe one ulp off.
      const double k = static_cast<double>(1 + it % 3);
      p[0] = {std::ldexp(std::round(U(rng) * 1024), -10) * s, std::ldexp(std::round(U(rng) * 1024), -10) * s,
              std::ldexp(std::round(U(rng) * 1024), -10) * s};
      p[1] = {p[0].x + std::ldexp(1.0, -3) * s, p[0].y, p[0].z + std::ldexp(1.0, -4) * s};
      p[3] = {p[0].x + k * (p[1].x - p[0].x), p[0].y + k * (p[1].y - p[0].y), p[0].z + k * (p[1].z - p[0].z)};
      if (kind == 2) p[3].y = std::nextafter(p[3].y, 10.0 * s);
    }
    const double r[4] = {kind_of(rng) == 0 ? 0.0 : std::ldexp(U01(rng), rexp(rng)) * s,
                         kind_of(rng) == 0 ? 0.0 : std::ldexp(U01(rng), rexp(rng)) * s,
                         kind_of(rng) == 0 ? 0.0 : std::ldexp(U01(rng), rexp(rng)) * s,
                         kind_of(rng) == 0 ? 0.0 : std::ldexp(U01(rng), rexp(rng)) * s};
    Vec3 m[4];
    for (int i = 0; i < 4; ++i) m[i] = {p[i].x + r[i] * U(rng), p[i].y + r[i] * U(rng), p[i].z + r[i] * U(rng)};
    // The perturbation itself rounds: recompute the radius that really holds.
    double rr[4];
    for (int i = 0; i < 4; ++i)
      rr[i] = std::max({std::fabs(m[i].x - p[i].x), std::fabs(m[i].y - p[i].y), std::fabs(m[i].z - p[i].z)});
    const Sign ex = orient3d_exact(p[0], p[1], p[2], p[3]);
    zeros += ex == Sign::kZero;
    Sign f;
    if (orient3d_uncertain(m[0], rr[0], m[1], rr[1], m[2], rr[2], m[3], rr[3], f)) {
      ++certified3;
      ASSERT_EQ(f, ex) << "it " << it;
    }
    const int axis = it % 3;
    const Sign ex2 = orient2d_projected_exact(p[0], p[1], p[3], axis);
    if (orient2d_uncertain(m[0], rr[0], m[1], rr[1], m[3], rr[3], axis, f)) {
      ++certified2;
      ASSERT_EQ(f, ex2) << "it " << it;
    }
  }
  std::printf("orient3d_uncertain certified %d, orient2d_uncertain %d, exact zeros %d of 60000\n", certified3,
              certified2, zeros);
  EXPECT_GT(zeros, 5000);
  EXPECT_GT(certified3, 20000);
  EXPECT_GT(certified2, 20000);
}

// The lifted filters for approximately known points, as above: exact double points (random, and
// exactly cospherical / cocircular ones moved by one ulp), seen within radii up to 2^-10 of them.
TEST(UncertainFilters, LiftedAgreeWithExactOfTheTruePoints) {
  const unsigned seed = 20261205u;
  std::printf("seed %u\n", seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1), U01(0, 1);
  std::uniform_int_distribution<int> kind_of(0, 3), rexp(-60, -10);
  int certified3 = 0, certified2 = 0, zeros = 0;
  for (int it = 0; it < 40000; ++it) {
    const int kind = it % 3;
    Vec3 p[5];
    for (int i = 0; i < 5; ++i) {
      p[i] = kind == 0 ? Vec3{U(rng), U(rng), U(rng)} : kCospherical[(it * 7 + i * 3) % 8];
      if (kind == 2 && i == 4) p[i].x = std::nextafter(p[i].x, 10.0);
    }
    double r[5];
    Vec3 m[5];
    for (int i = 0; i < 5; ++i) {
      const double ri = kind_of(rng) == 0 ? 0.0 : std::ldexp(U01(rng), rexp(rng));
      m[i] = {p[i].x + ri * U(rng), p[i].y + ri * U(rng), p[i].z + ri * U(rng)};
      r[i] = std::max({std::fabs(m[i].x - p[i].x), std::fabs(m[i].y - p[i].y), std::fabs(m[i].z - p[i].z)});
    }
    const Sign ex3 = static_cast<Sign>(exact_lifted_det3(p, p[4]));
    Sign f;
    zeros += ex3 == Sign::kZero;
    if (lifted_det3_uncertain(m, r, m[4], r[4], f)) {
      ++certified3;
      ASSERT_EQ(f, ex3) << "it " << it;
    }
    const int axis = it % 3;
    const Sign ex2 = static_cast<Sign>(exact_lifted_det2(p, p[3], axis));
    if (lifted_det2_uncertain(m, r, m[3], r[3], axis, f)) {
      ++certified2;
      ASSERT_EQ(f, ex2) << "it " << it;
    }
  }
  std::printf("lifted_det3_uncertain certified %d, lifted_det2_uncertain %d, exact zeros %d of 40000\n", certified3,
              certified2, zeros);
  EXPECT_GT(zeros, 5000);
  EXPECT_GT(certified3, 10000);
  EXPECT_GT(certified2, 10000);
}
