// Differential tests of the filtered predicates against the exact ones, on random, near-degenerate
// (one ulp, 2^-45 perturbations) and extreme-scale inputs. Seeds are printed and fixed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "bsptet/exact_float.h"
#include "bsptet/predicates.h"

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
  int zeros = 0, nonzeros = 0, refused = 0;
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
    Sign got;
    if (!orient3d_expansion(p[0], p[1], p[2], p[3], got)) {
      ++refused;
      continue;
    }
    const Sign want = orient3d_exact(p[0], p[1], p[2], p[3]);
    ASSERT_EQ(got, want) << "iteration " << it << " seed " << seed;
    (want == Sign::kZero ? zeros : nonzeros) += 1;
  }
  EXPECT_GT(zeros, 10000);
  EXPECT_GT(nonzeros, 10000);
  EXPECT_LT(refused, 100);  // a subnormal coordinate (the ulp step off 0), refused by design
  Sign out;
  EXPECT_FALSE(orient3d_expansion({1e-70, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, out));
  EXPECT_FALSE(orient3d_expansion({1e70, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, out));
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
