// SPDX-License-Identifier: LGPL-2.1-or-later
// A TPI vertex must behave exactly like the explicit point at the same place. Three axis-aligned
// planes through grid points meet at a grid point; oblique planes through grid points then pass
// exactly through many of them (exact zeros), which exercises the filter and the exact fallback.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "bsptet/numerics/implicit_geometry.h"

using namespace bsptet;

TEST(ImplicitGeometry, TpiVertexMatchesExplicitPoint) {
  const unsigned seed = 99u;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> G(-4, 4);
  int zeros = 0, total = 0;
  for (int it = 0; it < 300; ++it) {
    const double s = (it % 3 == 0) ? 0.1 : (it % 3 == 1 ? 1e-7 : 3e5);  // 0.1 is not dyadic
    const double a = G(rng) * s, b = G(rng) * s, c = G(rng) * s;
    std::vector<Vec3> pts = {
        {a, 0, 0}, {a, 1, 0}, {a, 0, 1},   // x = a
        {0, b, 0}, {0, b, 1}, {1, b, 0},   // y = b
        {0, 0, c}, {1, 0, c}, {0, 1, c},   // z = c
        {a, b, c},                          // the same point, explicit
    };
    for (int k = 0; k < 9; ++k) pts.push_back({G(rng) * s, G(rng) * s, G(rng) * s});
    ImplicitGeometry geo(pts);
    for (Index i = 0; i < geo.num_explicit(); ++i) geo.add_explicit_vertex(i);
    const Index px = geo.add_plane(0, 1, 2), py = geo.add_plane(3, 4, 5), pz = geo.add_plane(6, 7, 8);
    const Index tpi = geo.add_tpi_vertex(px, py, pz);
    const Vec3 r = geo.rounded(tpi);
    if (s != 0.1) {  // exactly representable: rounding is exact
      EXPECT_EQ(r.x, a);
      EXPECT_EQ(r.y, b);
      EXPECT_EQ(r.z, c);
    }
    // Oblique planes through (a, b, c) and two random points, and through three random points.
    for (int k = 10; k + 1 < 19; ++k) {
      for (const auto& def : {std::array<Index, 3>{9, k, k + 1}, std::array<Index, 3>{k, k + 1, (k + 2 - 10) % 9 + 10}}) {
        const Vec3 &p = pts[def[0]], &q = pts[def[1]], &w = pts[def[2]];
        if (orient2d_projected(p, q, w, 0) == Sign::kZero && orient2d_projected(p, q, w, 1) == Sign::kZero &&
            orient2d_projected(p, q, w, 2) == Sign::kZero)
          continue;  // collinear: not a plane
        const Index pl = geo.add_plane(def[0], def[1], def[2]);
        const Sign implicit = geo.side(pl, tpi);
        const Sign explicit_sign = orient3d(p, q, w, pts[9]);
        ASSERT_EQ(implicit, explicit_sign) << "iteration " << it << " seed " << seed;
        zeros += implicit == Sign::kZero;
        ++total;
      }
    }
  }
  EXPECT_GT(zeros, total / 4) << "the test must exercise exact zeros";
}

TEST(ImplicitGeometry, Orient2dOfTpiVerticesMatchesExplicit) {
  // Vertices on the plane z = 0.3 (not dyadic) given as TPIs of x = i, y = j, z = 0.3.
  std::vector<Vec3> pts = {{0, 0, 0.3}, {1, 0, 0.3}, {0, 1, 0.3}};
  for (int i = 0; i < 3; ++i) pts.insert(pts.end(), {{double(i), 0, 0}, {double(i), 1, 0}, {double(i), 0, 1}});
  for (int j = 0; j < 3; ++j) pts.insert(pts.end(), {{0, double(j), 0}, {0, double(j), 1}, {1, double(j), 0}});
  ImplicitGeometry geo(pts);
  for (Index i = 0; i < geo.num_explicit(); ++i) geo.add_explicit_vertex(i);
  const Index pz = geo.add_plane(0, 1, 2);
  Index px[3], py[3];
  for (int i = 0; i < 3; ++i) px[i] = geo.add_plane(3 + 3 * i, 4 + 3 * i, 5 + 3 * i);
  for (int j = 0; j < 3; ++j) py[j] = geo.add_plane(12 + 3 * j, 13 + 3 * j, 14 + 3 * j);
  Index v[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) v[i][j] = geo.add_tpi_vertex(px[i], py[j], pz);
  EXPECT_EQ(geo.orient2d(v[0][0], v[1][0], v[0][1], 2), Sign::kPositive);
  EXPECT_EQ(geo.orient2d(v[0][0], v[0][1], v[1][0], 2), Sign::kNegative);
  EXPECT_EQ(geo.orient2d(v[0][0], v[1][1], v[2][2], 2), Sign::kZero);  // collinear on the diagonal
  EXPECT_EQ(geo.orient2d(v[0][0], v[1][0], v[2][0], 2), Sign::kZero);
  EXPECT_EQ(geo.side(pz, v[2][1]), Sign::kZero);
}

TEST(ImplicitGeometry, Orient3dWithTpiVerticesMatchesExplicit) {
  // TPI vertices of axis planes through grid points (x = i, y = j, z = k * 0.1): orient3d of any
  // four of them, implicit or explicit, must agree, including the many exact zeros of a grid.
  const unsigned seed = 7u;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::vector<Vec3> pts;
  for (int i = 0; i < 3; ++i) pts.insert(pts.end(), {{i * 0.1, 0, 0}, {i * 0.1, 1, 0}, {i * 0.1, 0, 1}});
  for (int j = 0; j < 3; ++j) pts.insert(pts.end(), {{0, j * 0.1, 0}, {0, j * 0.1, 1}, {1, j * 0.1, 0}});
  for (int k = 0; k < 3; ++k) pts.insert(pts.end(), {{0, 0, k * 0.1}, {1, 0, k * 0.1}, {0, 1, k * 0.1}});
  const std::size_t first_grid = pts.size();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) pts.push_back({i * 0.1, j * 0.1, k * 0.1});
  ImplicitGeometry geo(pts);
  for (Index i = 0; i < geo.num_explicit(); ++i) geo.add_explicit_vertex(i);
  Index pl[3][3];
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < 3; ++i) pl[a][i] = geo.add_plane(9 * a + 3 * i, 9 * a + 3 * i + 1, 9 * a + 3 * i + 2);
  std::vector<Index> tpi(27), expl(27);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        tpi[9 * i + 3 * j + k] = geo.add_tpi_vertex(pl[0][i], pl[1][j], pl[2][k]);
        expl[9 * i + 3 * j + k] = static_cast<Index>(first_grid) + 9 * i + 3 * j + k;
      }
  std::uniform_int_distribution<int> G(0, 26), B(0, 1);
  int zeros = 0;
  for (int it = 0; it < 2000; ++it) {
    const int q[4] = {G(rng), G(rng), G(rng), G(rng)};
    Index v[4];
    for (int m = 0; m < 4; ++m) v[m] = B(rng) ? tpi[q[m]] : expl[q[m]];
    // The explicit grid points are the rounded values of 0.1 multiples, the TPIs the same planes'
    // exact intersections: both are the same points, as the planes pass through the grid doubles.
    const Sign want = orient3d(pts[first_grid + q[0]], pts[first_grid + q[1]], pts[first_grid + q[2]],
                               pts[first_grid + q[3]]);
    ASSERT_EQ(geo.orient3d(v[0], v[1], v[2], v[3]), want) << "iteration " << it;
    zeros += want == Sign::kZero;
  }
  EXPECT_GT(zeros, 100);
  EXPECT_LT(zeros, 1900);
}

// side_of_box is a filter: when it decides, every vertex inside the box is strictly on that side
// (checked against the exact side() of explicit and TPI vertices in the box), and it never decides
// for a box the plane passes through. Boxes from TPI vertices' own interval boxes, as BspComplex
// builds them for its faces.
TEST(ImplicitGeometry, SideOfBoxNeverContradictsExactSide) {
  const unsigned seed = 4242u;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  int decided = 0, undecided = 0;
  for (int it = 0; it < 400; ++it) {
    const double scale = it % 2 ? 1e-3 : 1e3;
    std::vector<Vec3> pts;
    for (int k = 0; k < 15; ++k) pts.push_back({U(rng) * scale, U(rng) * scale, U(rng) * scale});
    ImplicitGeometry geo(pts);
    for (Index i = 0; i < geo.num_explicit(); ++i) geo.add_explicit_vertex(i);
    std::vector<Index> planes;
    for (int k = 0; k < 5; ++k) planes.push_back(geo.add_plane(3 * k, 3 * k + 1, 3 * k + 2));
    // Vertices: some explicit points and the TPI vertices of plane triples.
    std::vector<Index> verts = {0, 4, 8};
    for (int a = 0; a < 5; ++a)
      for (int b = a + 1; b < 5; ++b)
        for (int c = b + 1; c < 5; ++c) verts.push_back(geo.add_tpi_vertex(planes[a], planes[b], planes[c]));
    // Boxes over a few vertices each (a face's box).
    for (std::size_t start = 0; start + 3 <= verts.size(); start += 2) {
      double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
      bool ok = true;
      for (std::size_t i = start; i < start + 3; ++i) {
        const auto* b = geo.vertex_box(verts[i]);
        if (!b) {
          ok = false;
          break;
        }
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], (*b)[k].lo()), hi[k] = std::max(hi[k], (*b)[k].hi());
      }
      if (!ok) continue;
      const std::array<Interval, 3> box = {Interval(lo[0], hi[0]), Interval(lo[1], hi[1]), Interval(lo[2], hi[2])};
      for (Index pl : planes) {
        const Sign bs = geo.side_of_box(pl, box);
        if (bs == Sign::kZero) {
          ++undecided;
          continue;
        }
        ++decided;
        for (std::size_t i = start; i < start + 3; ++i)
          ASSERT_EQ(geo.side(pl, verts[i]), bs) << "iteration " << it << " seed " << seed;
      }
    }
  }
  std::printf("decided %d, undecided %d\n", decided, undecided);
  EXPECT_GT(decided, 100) << "the filter must decide often enough to matter";
  EXPECT_GT(undecided, 100) << "the test must include boxes the plane passes through";
}

// orient3d of three vertices on one known plane and a fourth (side x orient2d in the plane) must
// agree with the 4 x 4 homogeneous determinant: the same points are built a second time with
// distinct plane ids for the common plane (same defining points), so no three share a known plane
// and the general exact path decides. Fourth points near the plane make the filters fail.
TEST(ImplicitGeometry, Orient3dThroughACommonPlaneMatchesTheGeneralPath) {
  const unsigned seed = 2027u;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  int decided_by_exact = 0, zeros = 0;
  for (int it = 0; it < 300; ++it) {
    std::vector<Vec3> pts;
    for (int k = 0; k < 3; ++k) pts.push_back({U(rng), U(rng), U(rng)});  // P
    for (int k = 0; k < 16; ++k) pts.push_back({U(rng), U(rng), U(rng)});  // others
    // P': through P's first two points and a point very near P (or on it: an exact zero).
    const Vec3 &p0 = pts[0], &p1 = pts[1], &p2 = pts[2];
    const double t = U(rng), e = 1e-13 * U(rng);
    pts.push_back({p0.x + t * (p2.x - p0.x) + e, p0.y + t * (p2.y - p0.y) - e, p0.z + t * (p2.z - p0.z)});
    Sign first[4];  // pass 0's signs (a known common plane), per vertex order
    for (int pass = 0; pass < 2; ++pass) {
      ImplicitGeometry geo(pts);
      for (Index i = 0; i < geo.num_explicit(); ++i) geo.add_explicit_vertex(i);
      std::vector<Index> q;
      for (int k = 0; k < 5; ++k) q.push_back(geo.add_plane(3 + 3 * k, 4 + 3 * k, 5 + 3 * k));
      const Index pa = geo.add_plane(0, 1, 2);
      const Index pb = pass == 0 ? pa : geo.add_plane(0, 1, 2), pc = pass == 0 ? pa : geo.add_plane(0, 1, 2);
      // Every third run the fourth point is on P itself, through a plane id of its own (an exact
      // zero the known-plane lists do not give away).
      const Index pnear = it % 3 == 0 ? geo.add_plane(0, 1, 2) : geo.add_plane(0, 1, 19);
      const Index v1 = geo.add_tpi_vertex(pa, q[0], q[1]), v2 = geo.add_tpi_vertex(pb, q[1], q[2]),
                  v3 = geo.add_tpi_vertex(pc, q[2], q[3]), w = geo.add_tpi_vertex(pnear, q[3], q[4]);
      const std::array<std::array<Index, 4>, 4> orders = {
          {{v1, v2, v3, w}, {v1, v2, w, v3}, {w, v1, v2, v3}, {v2, w, v3, v1}}};
      for (int o = 0; o < 4; ++o) {
        const Sign s = geo.orient3d(orders[o][0], orders[o][1], orders[o][2], orders[o][3]);
        if (pass == 0) {
          first[o] = s;
        } else {
          ASSERT_EQ(s, first[o]) << "iteration " << it << " order " << o << " seed " << seed;
          zeros += s == Sign::kZero;
        }
      }
      if (pass == 1) decided_by_exact += geo.exact_fallbacks() > 0;
    }
  }
  std::printf("runs with exact fallbacks %d, zeros %d\n", decided_by_exact, zeros);
  EXPECT_GT(decided_by_exact, 100) << "the filters must fail often enough to test the exact paths";
  EXPECT_GT(zeros, 100);
}
