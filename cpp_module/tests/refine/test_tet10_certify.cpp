// SPDX-License-Identifier: LGPL-2.1-or-later
// Validity of 10-node tets (tet10.h): the Bezier coefficients of det J against a direct
// evaluation from the C3D10 shape functions, straight tets, invalid and strongly curved elements,
// soundness under rounding (exact rational arithmetic), and make_second_order through the driver.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <vector>

#include "bsptet/mesh/mesh_check.h"
#include "bsptet/core/mesher.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/tet10.h"

using namespace bsptet;

namespace {

constexpr int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};  // m12 m23 m31 m14 m24 m34

// det J at barycentric point L = (1 - r - s - t, r, s, t), from the gradients of the C3D10 shape
// functions N1 = L0 (2 L0 - 1), ..., N5 = 4 L0 r (m12), N6 = 4 r s (m23), N7 = 4 s L0 (m31),
// N8 = 4 L0 t (m14), N9 = 4 r t (m24), N10 = 4 s t (m34). T: double or mpq_class.
template <class T>
T direct_jacobian(const double* x, const T L[4]) {
  const T& l0 = L[0];
  const T& r = L[1];
  const T& s = L[2];
  const T& t = L[3];
  const T a0 = 4 * l0 - 1;
  // dN/d(r, s, t) for the 10 nodes.
  const T g[10][3] = {{-a0, -a0, -a0},
                      {4 * r - 1, 0, 0},
                      {0, 4 * s - 1, 0},
                      {0, 0, 4 * t - 1},
                      {4 * (l0 - r), -4 * r, -4 * r},
                      {4 * s, 4 * r, 0},
                      {-4 * s, 4 * (l0 - s), -4 * s},
                      {-4 * t, -4 * t, 4 * (l0 - t)},
                      {4 * t, 0, 4 * r},
                      {0, 4 * t, 4 * s}};
  T J[3][3];  // J[a][c] = d x_c / d (r, s, t)_a
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c) {
      J[a][c] = 0;
      for (int n = 0; n < 10; ++n) J[a][c] += g[n][a] * T(x[3 * n + c]);
    }
  return J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
         J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
}

double direct_jacobian(const double* x, const double L0, double r, double s, double t) {
  const double L[4] = {L0, r, s, t};
  return direct_jacobian<double>(x, L);
}

// sum_a c_a 3!/a! L^a.
double bezier_value(const double c[20], const double L[4]) {
  double v = 0;
  for (int p = 0; p < 20; ++p) {
    double term = c[p];
    for (int i = 0; i < 4; ++i) {
      const int a = kCubicMultiIndex[p][i];
      term *= std::pow(L[i], a);
      if (a == 2) term /= 2;
      if (a == 3) term /= 6;
    }
    v += 6 * term;
  }
  return v;
}

// A tet10 with the given corners and straight mid-nodes (rounded midpoints).
void straight_tet10(const double v[4][3], double* x) {
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) x[3 * k + c] = v[k][c];
  for (int e = 0; e < 6; ++e)
    for (int c = 0; c < 3; ++c) x[3 * (4 + e) + c] = 0.5 * (v[kEdge[e][0]][c] + v[kEdge[e][1]][c]);
}

double straight_det(const double* x) {
  const double e[3][3] = {{x[3] - x[0], x[4] - x[1], x[5] - x[2]},
                          {x[6] - x[0], x[7] - x[1], x[8] - x[2]},
                          {x[9] - x[0], x[10] - x[1], x[11] - x[2]}};
  return e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
         e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
}

// The tests' seed: FEMBSPTET_SEED overrides it; printed so a failure can be replayed.
std::uint64_t test_seed(std::uint64_t fallback) {
  const char* s = std::getenv("FEMBSPTET_SEED");
  const std::uint64_t seed = s ? std::strtoull(s, nullptr, 10) : fallback;
  std::printf("seed %llu (FEMBSPTET_SEED)\n", static_cast<unsigned long long>(seed));
  return seed;
}

// A random positive tet with edges about 1 (centre near `centre`), its mid-nodes moved by up to
// `bend` times the edge length in random directions.
void random_tet10(std::mt19937_64& rng, double bend, double centre, double* x) {
  std::uniform_real_distribution<double> u(-1, 1);
  double v[4][3];
  do {
    for (auto& p : v)
      for (double& c : p) c = centre + u(rng);
  } while (std::fabs(straight_det(&v[0][0])) < 0.05);
  if (straight_det(&v[0][0]) < 0)
    for (int c = 0; c < 3; ++c) std::swap(v[0][c], v[1][c]);
  straight_tet10(v, x);
  for (int e = 0; e < 6; ++e) {
    const double* a = v[kEdge[e][0]];
    const double* b = v[kEdge[e][1]];
    const double len = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    for (int c = 0; c < 3; ++c) x[3 * (4 + e) + c] += bend * len * u(rng) / std::sqrt(3.0);
  }
}

// A uniformly random barycentric point.
void random_bary(std::mt19937_64& rng, double L[4]) {
  std::exponential_distribution<double> ex(1.0);
  double sum = 0;
  for (int i = 0; i < 4; ++i) sum += (L[i] = ex(rng));
  for (int i = 0; i < 4; ++i) L[i] /= sum;
}

// The smallest det J on a lattice of spacing 1/n over the tet.
double lattice_min_jacobian(const double* x, int n) {
  double best = INFINITY;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j)
      for (int k = 0; i + j + k <= n; ++k)
        best = std::min(best, direct_jacobian(x, static_cast<double>(n - i - j - k) / n, static_cast<double>(i) / n,
                                              static_cast<double>(j) / n, static_cast<double>(k) / n));
  return best;
}

}  // namespace

TEST(Tet10Certify, BezierPolynomialIsTheJacobianDeterminant) {
  std::mt19937_64 rng(test_seed(20240611));
  for (int trial = 0; trial < 200; ++trial) {
    double x[30];
    random_tet10(rng, trial % 2 ? 0.4 : 0.05, trial % 3 == 0 ? 1000.0 : 0.0, x);
    double c[20];
    tet10_jacobian_bezier(x, c);
    double scale = 0;
    for (double v : c) scale = std::max(scale, std::fabs(v));
    // The corner coefficients are the values at the corners.
    EXPECT_NEAR(c[0], direct_jacobian(x, 1, 0, 0, 0), 1e-10 * scale);
    EXPECT_NEAR(c[10], direct_jacobian(x, 0, 1, 0, 0), 1e-10 * scale);
    EXPECT_NEAR(c[16], direct_jacobian(x, 0, 0, 1, 0), 1e-10 * scale);
    EXPECT_NEAR(c[19], direct_jacobian(x, 0, 0, 0, 1), 1e-10 * scale);
    for (int k = 0; k < 20; ++k) {
      double L[4];
      random_bary(rng, L);
      const double direct = direct_jacobian<double>(x, L);
      ASSERT_NEAR(bezier_value(c, L), direct, 1e-10 * std::max(scale, std::fabs(direct))) << "trial " << trial;
    }
  }
}

TEST(Tet10Certify, StraightTetCoefficientsAreSixTimesItsVolume) {
  const double v[4][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}, {0, 0, 5}};  // volume 5
  double x[30];
  straight_tet10(v, x);
  double c[20];
  tet10_jacobian_bezier(x, c);
  for (double ci : c) EXPECT_EQ(ci, 30.0);  // exact: every operation is on small integers
  double bound = 0;
  EXPECT_EQ(certify_tet10(x, 6, &bound), Tet10Validity::kCertified);
  EXPECT_LE(bound, 30.0);
  EXPECT_GT(bound, 30.0 * (1 - 1e-12));  // the rounding-error bound, tiny
  EXPECT_NEAR(tet10_min_scaled_jacobian(x), 1.0, 1e-14);
  // Random straight tets, far from the origin too: every coefficient is 6 * volume.
  std::mt19937_64 rng(test_seed(7));
  for (int trial = 0; trial < 100; ++trial) {
    double y[30];
    random_tet10(rng, 0, trial % 2 ? 0.0 : 1e4, y);
    const double six_v = straight_det(y);
    tet10_jacobian_bezier(y, c);
    for (double ci : c) EXPECT_NEAR(ci, six_v, 1e-8 * six_v) << "trial " << trial;
    EXPECT_EQ(certify_tet10(y, 0), Tet10Validity::kCertified);
  }
  // A negative straight tet is invalid at once, with a bound near its -6 * volume.
  const double w[4][3] = {{2, 0, 0}, {0, 0, 0}, {0, 3, 0}, {0, 0, 5}};
  straight_tet10(w, x);
  EXPECT_EQ(certify_tet10(x, 6, &bound), Tet10Validity::kInvalid);
  EXPECT_NEAR(bound, -30.0, 1e-11);
}

TEST(Tet10Certify, MidNodeAcrossTheOppositeFaceIsInvalid) {
  const double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int e = 0; e < 6; ++e) {
    double x[30];
    straight_tet10(v, x);
    // Mid-node e goes from its edge's first corner through the centroid of the face opposite
    // that corner, to 2.5 times that distance (well beyond the face).
    const int a = kEdge[e][0];
    const double* opposite_corner = v[a];
    for (int c = 0; c < 3; ++c) {
      const double centroid_of_face = (v[0][c] + v[1][c] + v[2][c] + v[3][c] - opposite_corner[c]) / 3;
      x[3 * (4 + e) + c] = opposite_corner[c] + 2.5 * (centroid_of_face - opposite_corner[c]);
    }
    double bound = 0;
    EXPECT_EQ(certify_tet10(x, 6, &bound), Tet10Validity::kInvalid) << "edge " << e;
    EXPECT_LE(bound, 0);
    EXPECT_LT(tet10_min_scaled_jacobian(x), 0);
  }
  // The 10-node tet of the old Tet10 test: m12 pulled to x = -20.
  const double w[4][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}, {0, 0, 5}};
  double x[30];
  straight_tet10(w, x);
  x[3 * 4] = -20;
  EXPECT_EQ(certify_tet10(x), Tet10Validity::kInvalid);
}

// Positive at the 15 points the old check sampled (corners, edge midpoints, face centroids, the
// centroid) and at CalculiX's 4 integration points, yet negative elsewhere: found by a random
// search over perturbed tets, pinned at full precision.
TEST(Tet10Certify, InvalidBetweenTheOldSamplePointsIsFound) {
  const double x[30] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1,  // the unit corner tet
                        0.13059508759676752, -0.085003519624771248, -0.084497136796046451,
                        0.69281312481190271, 0.86929999756397147, -0.052420446045245539,
                        -0.086810685702064877, 0.37258677586773048, -0.22993152192300706,
                        0.18505633132600885, -0.39458350905783418, 0.48246972002118149,
                        0.48256262646490733, 0.39749750289732733, 0.41377721952711288,
                        -0.36316577911790054, 0.87953605868568929, 0.86840498783411735};
  const double samples[15][4] = {
      {1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1},
      {.5, .5, 0, 0}, {0, .5, .5, 0}, {.5, 0, .5, 0}, {.5, 0, 0, .5}, {0, .5, 0, .5}, {0, 0, .5, .5},
      {1. / 3, 1. / 3, 1. / 3, 0}, {1. / 3, 1. / 3, 0, 1. / 3}, {1. / 3, 0, 1. / 3, 1. / 3}, {0, 1. / 3, 1. / 3, 1. / 3},
      {.25, .25, .25, .25}};
  for (const auto& s : samples) EXPECT_GT(direct_jacobian<double>(x, s), 0);
  const double a = 0.1381966011250105, b = 0.5854101966249685;  // C3D10's 4-point rule
  for (int k = 0; k < 4; ++k) {
    double L[4] = {a, a, a, a};
    L[k] = b;
    EXPECT_GT(direct_jacobian<double>(x, L), 0);
  }
  EXPECT_LT(lattice_min_jacobian(x, 40), 0);
  double bound = 0;
  EXPECT_EQ(certify_tet10(x, 6, &bound), Tet10Validity::kInvalid);
  EXPECT_LE(bound, 0);
}

TEST(Tet10Certify, StronglyCurvedValidElementsAreCertifiedBySubdivision) {
  // A tet on a sphere of radius 1: corners 1..3 on the sphere (a face spanning 60 degrees of
  // arc), corner 4 at the centre; the face's mid-nodes projected onto the sphere.
  const double kPi = 3.14159265358979323846;
  auto on_sphere = [](double theta, double phi, double* p) {
    p[0] = std::sin(theta) * std::cos(phi), p[1] = std::sin(theta) * std::sin(phi), p[2] = std::cos(theta);
  };
  double v[4][3];
  on_sphere(kPi / 6, 0, v[0]);
  on_sphere(kPi / 6, 2 * kPi / 3, v[1]);
  on_sphere(kPi / 6, 4 * kPi / 3, v[2]);
  v[3][0] = v[3][1] = 0, v[3][2] = -0.2;
  // Orient positively.
  if (straight_det(&v[0][0]) < 0)
    for (int c = 0; c < 3; ++c) std::swap(v[0][c], v[1][c]);
  double x[30];
  straight_tet10(v, x);
  for (int e : {0, 1, 2}) {  // m12 m23 m31: the curved face
    double* m = x + 3 * (4 + e);
    const double r = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    for (int c = 0; c < 3; ++c) m[c] /= r;
  }
  double bound = 0;
  EXPECT_EQ(certify_tet10(x, 6, &bound), Tet10Validity::kCertified);
  const double lattice = lattice_min_jacobian(x, 60);
  EXPECT_GT(bound, 0);
  EXPECT_LE(bound, lattice);
  const double scaled = tet10_min_scaled_jacobian(x, 1e-4);
  EXPECT_LE(scaled, lattice / straight_det(x));
  EXPECT_GT(scaled, lattice / straight_det(x) - 2e-4);

  // Two mid-nodes of the unit tet moved far off their edges (m12 to (0.375, -0.25, 0.5), m24 to
  // (1, 0, 0.625)): some Bezier coefficients of the element are negative, and of its first
  // eight sub-tets too, so it is undecided at depths 0 and 1; depth 2 certifies it.
  const double w[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  double y[30];
  straight_tet10(w, y);
  const double m12[3] = {0.375, -0.25, 0.5}, m24[3] = {1, 0, 0.625};
  std::copy(m12, m12 + 3, y + 3 * 4);
  std::copy(m24, m24 + 3, y + 3 * 8);
  double c[20];
  tet10_jacobian_bezier(y, c);
  EXPECT_LT(*std::min_element(c, c + 20), 0);
  EXPECT_EQ(certify_tet10(y, 0), Tet10Validity::kUndecided);
  EXPECT_EQ(certify_tet10(y, 1), Tet10Validity::kUndecided);
  EXPECT_EQ(certify_tet10(y, 2, &bound), Tet10Validity::kCertified);
  EXPECT_GT(bound, 0);
  EXPECT_LE(bound, lattice_min_jacobian(y, 60));
}

// A mid-node moved along its edge: det J at the far corner is (up to scale) 3 - 4 t with t the
// mid-node's place along the edge, so 0 at t = 0.75 and negative beyond.
TEST(Tet10Certify, MidNodeSlidingAlongItsEdge) {
  const double w[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  double y[30];
  straight_tet10(w, y);
  double bound = 0;
  y[3 * 4] = 0.7;  // m12 at 0.7 of the way from n1 to n2: still valid
  EXPECT_EQ(certify_tet10(y, 6, &bound), Tet10Validity::kCertified);
  EXPECT_NEAR(bound, 0.2, 1e-12);  // the value at corner n2
  // At 0.75 det J is exactly 0 at corner n2: never certified (the interval of that value
  // straddles 0, so it cannot be proved <= 0 either).
  y[3 * 4] = 0.75;
  EXPECT_NE(certify_tet10(y, 6, &bound), Tet10Validity::kCertified);
  EXPECT_LE(bound, 0);
  y[3 * 4] = 0.8;
  EXPECT_EQ(certify_tet10(y, 6, &bound), Tet10Validity::kInvalid);
  EXPECT_NEAR(bound, -0.2, 1e-12);
}

// Random strongly curved elements: a certified element's bound is below every sampled det J; an
// invalid one's bound is <= 0. Both outcomes occur.
TEST(Tet10Certify, BoundsAreConsistentWithSamplingOnRandomCurvedElements) {
  std::mt19937_64 rng(test_seed(99));
  int certified = 0, invalid = 0, undecided = 0;
  for (int trial = 0; trial < 300; ++trial) {
    double x[30];
    random_tet10(rng, 0.35, 0.0, x);
    double bound = 0;
    const Tet10Validity v = certify_tet10(x, 6, &bound);
    const double sampled = lattice_min_jacobian(x, 16);
    if (v == Tet10Validity::kCertified) {
      ++certified;
      EXPECT_GT(bound, 0);
      EXPECT_LE(bound, sampled) << "trial " << trial;
    } else if (v == Tet10Validity::kInvalid) {
      ++invalid;
      EXPECT_LE(bound, 0);
    } else {
      ++undecided;
    }
    if (sampled <= 0) EXPECT_NE(v, Tet10Validity::kCertified) << "trial " << trial;
  }
  std::printf("random curved tet10: %d certified, %d invalid, %d undecided\n", certified, invalid, undecided);
  EXPECT_GT(certified, 30);
  EXPECT_GT(invalid, 30);
  EXPECT_LT(undecided, 10);
}

// Rounding: nearly flat elements (corner 4 within 2^-46 or less of the plane of the others,
// mid-nodes nudged by an ulp) are certified only when det J is positive in exact rational
// arithmetic at the four corners and at sample points. The Bezier coefficients in plain double
// precision are all positive for some elements whose exact det J is not (the test counts them):
// the interval enclosure is what makes the certificate hold.
TEST(Tet10Certify, CertifiedIsTrueInExactArithmeticOnNearlyFlatElements) {
  std::mt19937_64 rng(test_seed(31337));
  std::uniform_real_distribution<double> u(-1, 1);
  int certified = 0, not_certified = 0, fooled_double = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    double v[4][3];
    for (int k = 0; k < 3; ++k)
      for (double& c : v[k]) c = u(rng);
    const double s = 0.3 + 0.2 * u(rng), t = 0.3 + 0.2 * u(rng);
    const double lift = std::ldexp(u(rng), -46 - static_cast<int>(trial % 10));
    double n[3] = {(v[1][1] - v[0][1]) * (v[2][2] - v[0][2]) - (v[1][2] - v[0][2]) * (v[2][1] - v[0][1]),
                   (v[1][2] - v[0][2]) * (v[2][0] - v[0][0]) - (v[1][0] - v[0][0]) * (v[2][2] - v[0][2]),
                   (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0])};
    for (int c = 0; c < 3; ++c)
      v[3][c] = v[0][c] + s * (v[1][c] - v[0][c]) + t * (v[2][c] - v[0][c]) + lift * n[c];
    double x[30];
    straight_tet10(v, x);
    for (int i = 12; i < 30; ++i) x[i] = std::nextafter(x[i], u(rng) > 0 ? 2.0 : -2.0);
    bool corners_positive = true;
    for (int k = 0; k < 4; ++k) {
      mpq_class L[4] = {0, 0, 0, 0};
      L[k] = 1;
      corners_positive = corners_positive && sgn(direct_jacobian<mpq_class>(x, L)) > 0;
    }
    double c[20];
    tet10_jacobian_bezier(x, c);
    fooled_double += *std::min_element(c, c + 20) > 0 && !corners_positive;
    if (certify_tet10(x, 4) != Tet10Validity::kCertified) {
      ++not_certified;
      continue;
    }
    ++certified;
    ASSERT_TRUE(corners_positive) << "trial " << trial;
    for (int k = 0; k < 4; ++k) {
      double b[4];
      random_bary(rng, b);
      mpq_class L[4] = {b[0], b[1], b[2], 0};
      L[3] = 1 - L[0] - L[1] - L[2];
      if (sgn(L[3]) < 0) continue;
      ASSERT_GT(sgn(direct_jacobian<mpq_class>(x, L)), 0) << "trial " << trial;
    }
  }
  std::printf("nearly flat tet10: %d certified, %d not; double coefficients all positive but an exact "
              "corner value not: %d\n", certified, not_certified, fooled_double);
  EXPECT_GT(certified, 20);
  EXPECT_GT(not_certified, 20);
  EXPECT_GT(fooled_double, 0);
}

// Coordinates scaled by 2^260 or 2^-260 are outside the range of the double-precision error
// bound, so the element goes straight to the interval evaluation: the same decisions, and the
// bound scales by 2^780 or 2^-780 (det J is cubic in the coordinates) up to the error bounds.
TEST(Tet10Certify, IntervalPathAgreesWithTheDoublePath) {
  std::mt19937_64 rng(test_seed(4242));
  int agree = 0, decided_by_subdivision = 0;
  for (int trial = 0; trial < 300; ++trial) {
    double x[30], big[30], small[30];
    random_tet10(rng, 0.2, 0.0, x);
    for (int i = 0; i < 30; ++i) big[i] = std::ldexp(x[i], 260), small[i] = std::ldexp(x[i], -260);
    double b = 0, b_big = 0, b_small = 0;
    const Tet10Validity v = certify_tet10(x, 6, &b);
    ASSERT_EQ(certify_tet10(big, 6, &b_big), v) << "trial " << trial;
    ASSERT_EQ(certify_tet10(small, 6, &b_small), v) << "trial " << trial;
    decided_by_subdivision += certify_tet10(x, 0) == Tet10Validity::kUndecided;
    if (v == Tet10Validity::kCertified) {
      // The same lowest coefficient; the double path's a-priori error bound is the wider one.
      EXPECT_NEAR(std::ldexp(b_big, -780), b, 1e-11) << "trial " << trial;  // det J is about 1
      EXPECT_NEAR(std::ldexp(b_small, 780), b, 1e-11) << "trial " << trial;
    }
    ++agree;
  }
  std::printf("scaled tet10: %d agree, %d of them needed subdivision\n", agree, decided_by_subdivision);
  EXPECT_GT(decided_by_subdivision, 5);
}

TEST(Tet10Certify, NonFiniteInputIsUndecided) {
  const double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  double x[30];
  straight_tet10(v, x);
  x[3 * 5 + 1] = NAN;
  double bound = 0;
  EXPECT_EQ(certify_tet10(x, 6, &bound), Tet10Validity::kUndecided);
  EXPECT_TRUE(std::isnan(bound));
  const double big[4][3] = {{0, 0, 0}, {1e200, 0, 0}, {0, 1e200, 0}, {0, 0, 1e200}};
  straight_tet10(big, x);  // finite, but 6 * volume overflows
  EXPECT_EQ(certify_tet10(x), Tet10Validity::kUndecided);
}

// The driver's tet10 on a coarse 12-gon prism whose side mid-nodes go onto the true cylinder of
// radius 10 (the 12-gon's chords sag by 0.34): every element of the output is certified.
TEST(Tet10Certify, MakeSecondOrderLeavesOnlyCertifiedElements) {
  const int n = 12;
  SurfaceMesh s;
  for (int z = 0; z < 2; ++z)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * 3.14159265358979323846 * i / n;
      s.xyz.insert(s.xyz.end(), {10 * std::cos(a), 10 * std::sin(a), 30.0 * z});
    }
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    s.tri.insert(s.tri.end(), {i, j, n + j, i, n + j, n + i});
    s.tag.insert(s.tag.end(), {0, 0});
  }
  for (int i = 1; i + 1 < n; ++i) {
    s.tri.insert(s.tri.end(), {n, n + i, n + i + 1, 0, i + 1, i});
    s.tag.insert(s.tag.end(), {1, 2});
  }
  const TetMesh core = tetrahedralize(s, MeshOptions{});
  RefineOptions o;
  o.size = 6;
  o.order = 2;
  o.projection = [](const Vec3& p, std::int32_t tag, std::int32_t other) {
    if (tag != 0 && other != 0) return p;  // on a cap: the rounded midpoint is on its plane
    const double r = std::hypot(p.x, p.y);
    return Vec3{10 * p.x / r, 10 * p.y / r, p.z};
  };
  RefineStats st;
  const TetMesh m = refine_quality(s, core, o, &st);
  ASSERT_EQ(m.nodes_per_tet, 10);
  int certified = 0;
  for (Index t = 0; t < m.num_tets(); ++t) {
    double x[30];
    for (int k = 0; k < 10; ++k)
      for (int c = 0; c < 3; ++c) x[3 * k + c] = m.xyz[static_cast<std::size_t>(3 * m.tet[static_cast<std::size_t>(10 * t + k)] + c)];
    certified += certify_tet10(x) == Tet10Validity::kCertified;
  }
  std::printf("prism tet10: %d tets, %lld mid-nodes projected, %lld straightened, %d certified\n",
              static_cast<int>(m.num_tets()), static_cast<long long>(st.midnodes_projected),
              static_cast<long long>(st.midnodes_straightened), certified);
  EXPECT_EQ(certified, m.num_tets());
  EXPECT_GT(st.midnodes_projected, 0);
}

// make_second_order straight on the core's tets of a coarse hexagonal tube (radii 6 and 10,
// height 4): the inner wall is concave, so its mid-nodes go into the solid by the chords' sag
// (0.80), and many of the core's flat tets over it are invalid once curved. The lift mends them by
// moving mid-nodes (interior ones, and boundary ones along the cylinders through the hook) and,
// where that is not enough, interior points: every element certified, none straightened, and
// every boundary mid-node on its cylinder or plane.
TEST(Tet10Certify, MakeSecondOrderMendsCurvedConflictsWithoutStraightening) {
  const int n = 6;
  const double outer = 10, inner = 6;
  const double pi = 3.14159265358979323846;
  SurfaceMesh s;
  for (int z = 0; z < 2; ++z)
    for (double r : {outer, inner})
      for (int i = 0; i < n; ++i) {
        const double a = 2 * pi * i / n;
        s.xyz.insert(s.xyz.end(), {r * std::cos(a), r * std::sin(a), 4.0 * z});
      }
  auto v = [&](int z, int ring, int i) { return 2 * n * z + n * ring + (i % n); };
  for (int i = 0; i < n; ++i) {
    const int j = i + 1;
    s.tri.insert(s.tri.end(), {v(0, 0, i), v(0, 0, j), v(1, 0, j), v(0, 0, i), v(1, 0, j), v(1, 0, i)});  // outer
    s.tri.insert(s.tri.end(), {v(0, 1, i), v(1, 1, j), v(0, 1, j), v(0, 1, i), v(1, 1, i), v(1, 1, j)});  // inner
    s.tri.insert(s.tri.end(), {v(1, 0, i), v(1, 0, j), v(1, 1, j), v(1, 0, i), v(1, 1, j), v(1, 1, i)});  // top
    s.tri.insert(s.tri.end(), {v(0, 0, i), v(0, 1, j), v(0, 0, j), v(0, 0, i), v(0, 1, i), v(0, 1, j)});  // bottom
    s.tag.insert(s.tag.end(), {0, 0, 1, 1, 2, 2, 3, 3});
  }
  auto on_cylinder = [](const Vec3& p, double r) {
    const double d = std::hypot(p.x, p.y);
    return Vec3{r * p.x / d, r * p.y / d, p.z};
  };
  const ProjectionHook hook = [&](const Vec3& p, std::int32_t tag, std::int32_t other) {
    const std::int32_t t = other >= 0 && other < tag ? other : tag;  // a cylinder when one is
    if (t == 0) return on_cylinder(p, outer);
    if (t == 1) return on_cylinder(p, inner);
    return p;  // the planes: the rounded midpoint is on them
  };
  const TetMesh core = tetrahedralize(s, MeshOptions{});
  RefineMesh mesh(s, core, hook);
  SecondOrderStats st;
  const TetMesh m = make_second_order(mesh, hook, &st);
  ASSERT_EQ(m.nodes_per_tet, 10);
  std::printf("tube tet10: %d tets, %lld projected, %lld tets mended by moves, %lld points inserted, %lld straightened\n",
              static_cast<int>(m.num_tets()), static_cast<long long>(st.projected), static_cast<long long>(st.relaxed),
              static_cast<long long>(st.points_inserted), static_cast<long long>(st.straightened));
  EXPECT_GT(st.relax_tried, 0);  // the case this test is about
  EXPECT_EQ(st.straightened, 0);
  for (Index t = 0; t < m.num_tets(); ++t) {
    double x[30];
    for (int k = 0; k < 10; ++k)
      for (int c = 0; c < 3; ++c) x[3 * k + c] = m.xyz[static_cast<std::size_t>(3 * m.tet[static_cast<std::size_t>(10 * t + k)] + c)];
    EXPECT_EQ(certify_tet10(x), Tet10Validity::kCertified) << "tet " << t;
  }
  // Boundary mid-nodes (no point was added, so the boundary edges are the input's): on their
  // cylinder (tags 0 and 1: radii 10 and 5) and on their plane (tags 2 and 3: z = 4 and 0).
  std::map<std::array<Index, 2>, std::vector<std::int32_t>> edge_tags;
  for (Index f = 0; f < s.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Index a = s.tri[static_cast<std::size_t>(3 * f + k)], b = s.tri[static_cast<std::size_t>(3 * f + (k + 1) % 3)];
      edge_tags[{std::min(a, b), std::max(a, b)}].push_back(s.tag[static_cast<std::size_t>(f)]);
    }
  static const int kMid[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  std::int64_t checked = 0;
  for (Index t = 0; t < m.num_tets(); ++t) {
    const Index* q = &m.tet[static_cast<std::size_t>(10 * t)];
    for (int e = 0; e < 6; ++e) {
      const Index a = q[kMid[e][0]], b = q[kMid[e][1]];
      auto it = edge_tags.find({std::min(a, b), std::max(a, b)});
      if (it == edge_tags.end()) continue;
      const Vec3 p = m.point(q[4 + e]);
      for (std::int32_t tag : it->second) {
        if (tag <= 1) EXPECT_NEAR(std::hypot(p.x, p.y), tag == 0 ? outer : inner, 1e-12) << "tet " << t << " mid-node " << e;
        if (tag >= 2) EXPECT_EQ(p.z, tag == 2 ? 4.0 : 0.0) << "tet " << t << " mid-node " << e;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 0);
}
