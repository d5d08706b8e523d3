// SPDX-License-Identifier: LGPL-2.1-or-later
// The seed's flips (seed_flips.h) on small tetrahedralizations built here: two tets glued on a
// face (the 2-3 flip and back with recover_face), an octahedron split by its vertical axis (the
// 4-4 flip of planar_flip), and the Delaunay tetrahedralization of a cube's corners and points
// inside it (every pair of points asked for as an edge). After every call the tets are all
// positive (exact orient3d), each face is shared by at most two tets with opposite orientations,
// the hull faces and the volume (exact) are those of the start, protected triangles and edges
// stay, and result() gives the neighbours of the tets it returns.
#include <gtest/gtest.h>

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <vector>

#include "bsptet/core/point_delaunay.h"
#include "bsptet/core/seed_flips.h"
#include "bsptet/numerics/implicit_geometry.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/numerics/splitmix.h"

using namespace bsptet;

namespace {

using Tet = std::array<Index, 4>;
using Face = std::array<Index, 3>;

// The vertices' points and the tets, made positive (two corners swapped where orient3d < 0).
struct Tets {
  std::vector<Vec3> pts;
  std::vector<Tet> tets;
  Tets(std::vector<Vec3> p, std::vector<Tet> t) : pts(std::move(p)), tets(std::move(t)) {
    for (Tet& q : tets)
      if (orient3d(pts[q[0]], pts[q[1]], pts[q[2]], pts[q[3]]) != Sign::kPositive) std::swap(q[0], q[1]);
  }
  auto point_of() const {
    return [this](Index v) { return pts[static_cast<std::size_t>(v)]; };
  }
};

Face sorted(Face f) {
  std::sort(f.begin(), f.end());
  return f;
}
Face face_of(const Tet& q, int k) {
  return {q[kTetOppositeFace[k][0]], q[kTetOppositeFace[k][1]], q[kTetOppositeFace[k][2]]};
}

mpq_class volume6(const std::vector<Vec3>& pts, const std::vector<Tet>& tets) {
  mpq_class sum = 0;
  for (const Tet& q : tets) {
    const Vec3 &a = pts[q[0]], &b = pts[q[1]], &c = pts[q[2]], &d = pts[q[3]];
    const mpq_class bx = mpq_class(b.x) - a.x, by = mpq_class(b.y) - a.y, bz = mpq_class(b.z) - a.z;
    const mpq_class cx = mpq_class(c.x) - a.x, cy = mpq_class(c.y) - a.y, cz = mpq_class(c.z) - a.z;
    const mpq_class dx = mpq_class(d.x) - a.x, dy = mpq_class(d.y) - a.y, dz = mpq_class(d.z) - a.z;
    sum += bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
  }
  return sum;
}

/// The faces of one tet only (sorted), after checking that every tet is positive and every face
/// is shared by at most two tets, with opposite orientations (a face's two tets see it with
/// opposite orientations exactly when each lists it as kTetOppositeFace of a positive tet).
std::set<Face> hull_checked(const std::vector<Vec3>& pts, const std::vector<Tet>& tets) {
  std::map<Face, std::vector<Face>> seen;  // sorted face -> the oriented faces of its tets
  for (const Tet& q : tets) {
    EXPECT_EQ(orient3d(pts[q[0]], pts[q[1]], pts[q[2]], pts[q[3]]), Sign::kPositive);
    for (int k = 0; k < 4; ++k) seen[sorted(face_of(q, k))].push_back(face_of(q, k));
  }
  std::set<Face> hull;
  for (const auto& [key, oriented] : seen) {
    EXPECT_LE(oriented.size(), 2u);
    if (oriented.size() == 1) hull.insert(key);
    if (oriented.size() == 2) {
      // Opposite orientations: the second is an odd permutation of the first.
      Face a = oriented[0], b = oriented[1];
      std::rotate(b.begin(), std::find(b.begin(), b.end(), a[0]), b.end());
      EXPECT_EQ(b[1], a[2]);
      EXPECT_EQ(b[2], a[1]);
    }
  }
  return hull;
}

/// The neighbours as PointDelaunay::nb: the tet across the face opposite corner k, -1 on the hull.
std::vector<std::array<Index, 4>> neighbours(const std::vector<Tet>& tets) {
  std::map<Face, std::vector<Index>> at;
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (int k = 0; k < 4; ++k) at[sorted(face_of(tets[t], k))].push_back(static_cast<Index>(t));
  std::vector<std::array<Index, 4>> nb(tets.size());
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      const auto& l = at[sorted(face_of(tets[t], k))];
      nb[t][k] = l.size() < 2 ? -1 : (l[0] == static_cast<Index>(t) ? l[1] : l[0]);
    }
  return nb;
}

/// Checks result(): the alive tets are valid with the hull and volume of the start, and nb holds
/// their neighbours.
std::vector<Tet> checked_result(const SeedFlips& flips, const Tets& start) {
  std::vector<std::array<Index, 4>> nb = neighbours(start.tets);
  const std::vector<Tet> out = flips.result(nb);
  EXPECT_EQ(hull_checked(start.pts, out), hull_checked(start.pts, start.tets));
  EXPECT_EQ(volume6(start.pts, out), volume6(start.pts, start.tets));
  EXPECT_EQ(nb, neighbours(out));
  return out;
}

bool has_edge(const std::vector<Tet>& tets, Index a, Index b) {
  for (const Tet& q : tets)
    if (std::count(q.begin(), q.end(), a) && std::count(q.begin(), q.end(), b)) return true;
  return false;
}

// Two tets glued on face (0, 1, 2): apexes 3 (above) and 4 (below), segment 3-4 through the face.
Tets bipyramid() {
  return Tets({{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {1, 1, 0.5}, {1, 1, -0.5}}, {{0, 1, 2, 3}, {0, 1, 2, 4}});
}

// The octahedron of (+-1, 0, 0), (0, +-1, 0), (0, 0, +-1) as the four tets around its axis 4-5.
Tets octahedron() {
  return Tets({{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}},
              {{4, 5, 0, 1}, {4, 5, 1, 2}, {4, 5, 2, 3}, {4, 5, 3, 0}});
}

}  // namespace

TEST(SeedFlips, Flip23RecoversTheEdgeThroughAFace) {
  Tets start = bipyramid();
  std::vector<Tet> tets = start.tets;
  SeedFlips flips(tets, 5, start.point_of());
  EXPECT_FALSE(flips.has_edge(3, 4));
  EXPECT_TRUE(flips.has_face(0, 1, 2));
  EXPECT_TRUE(flips.recover_edge(3, 4, 64));
  EXPECT_TRUE(flips.has_edge(3, 4));
  EXPECT_FALSE(flips.has_face(0, 1, 2));
  EXPECT_EQ(flips.flips(), 1);
  const std::vector<Tet> out = checked_result(flips, start);
  EXPECT_EQ(out.size(), 3u);
  EXPECT_TRUE(has_edge(out, 3, 4));
}

TEST(SeedFlips, ProtectedTriangleBlocksTheFlipAndRecoverFaceFlipsBack) {
  {
    Tets start = bipyramid();
    std::vector<Tet> tets = start.tets;
    SeedFlips flips(tets, 5, start.point_of());
    flips.protect_triangle(2, 1, 0);
    EXPECT_FALSE(flips.recover_edge(3, 4, 64));
    EXPECT_EQ(flips.flips(), 0);
    EXPECT_TRUE(flips.has_face(0, 1, 2));
  }
  // The three tets around 3-4 (the 2-3 flip's result): a 3-2 flip makes (0, 1, 2) a face again.
  Tets three = bipyramid();
  {
    std::vector<Tet> tets = three.tets;
    SeedFlips flips(tets, 5, three.point_of());
    ASSERT_TRUE(flips.recover_edge(3, 4, 64));
    std::vector<std::array<Index, 4>> nb = neighbours(three.tets);
    three.tets = flips.result(nb);
  }
  std::vector<Tet> tets = three.tets;
  SeedFlips flips(tets, 5, three.point_of());
  EXPECT_TRUE(flips.recover_face(0, 2, 1));
  EXPECT_TRUE(flips.has_face(0, 1, 2));
  EXPECT_FALSE(flips.has_edge(3, 4));
  EXPECT_EQ(checked_result(flips, three).size(), 2u);
  EXPECT_TRUE(flips.recover_face(0, 1, 2));  // already a face: no flip
  EXPECT_EQ(flips.flips(), 1);
}

TEST(SeedFlips, PlanarEdgeRemovalReplacesTheCrossedDiagonal) {
  Tets start = octahedron();
  std::vector<Tet> tets = start.tets;
  SeedFlips flips(tets, 6, start.point_of());
  EXPECT_TRUE(flips.recover_edge(0, 2, 64));  // 0-2 crosses edge 4-5 in the plane y = 0
  EXPECT_TRUE(flips.has_edge(0, 2));
  EXPECT_FALSE(flips.has_edge(4, 5));
  const std::vector<Tet> out = checked_result(flips, start);
  EXPECT_EQ(out.size(), 4u);
}

TEST(SeedFlips, ProtectedEdgeIsNeverRemoved) {
  Tets start = octahedron();
  std::vector<Tet> tets = start.tets;
  SeedFlips flips(tets, 6, start.point_of());
  flips.protect_triangle(0, 4, 5);  // its edge 4-5 is the one 0-2 crosses
  EXPECT_FALSE(flips.recover_edge(0, 2, 64));
  EXPECT_FALSE(flips.recover_edge(2, 0, 64));
  EXPECT_TRUE(flips.has_edge(4, 5));
  EXPECT_TRUE(flips.has_face(0, 4, 5));
  EXPECT_EQ(flips.flips(), 0);
}

TEST(SeedFlips, EveryPairOfADelaunayCubeStaysATetrahedralization) {
  std::vector<Vec3> pts = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  std::uint64_t seed = 7;
  for (int i = 0; i < 24; ++i) {
    Vec3 p;
    for (double* x : {&p.x, &p.y, &p.z}) *x = 0.05 + 0.9 * static_cast<double>(splitmix64(seed) >> 11) * 0x1.0p-53;
    pts.push_back(p);
  }
  ImplicitGeometry geo(pts);
  for (Index i = 0; i < geo.num_explicit(); ++i) geo.add_explicit_vertex(i);
  std::vector<Index> order(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) order[i] = static_cast<Index>(i);
  PointDelaunay del;
  ASSERT_TRUE(delaunay_explicit_points(geo, order, del));
  const Tets start(pts, del.tets);
  ASSERT_EQ(neighbours(start.tets), del.nb);
  std::vector<Tet> tets = start.tets;
  const Index n = static_cast<Index>(pts.size());
  SeedFlips flips(tets, n, start.point_of());
  const Face f = *hull_checked(pts, start.tets).begin();  // a hull triangle, and its edges
  flips.protect_triangle(f[0], f[1], f[2]);
  int recovered = 0, missing = 0;
  for (Index a = 0; a < n; ++a)
    for (Index b = a + 1; b < n; ++b) {
      if (flips.has_edge(a, b)) continue;
      ++missing;
      const bool ok = flips.recover_edge(a, b, 8);
      EXPECT_EQ(ok, flips.has_edge(a, b));
      recovered += ok;
      EXPECT_TRUE(flips.has_face(f[0], f[1], f[2]));
      EXPECT_TRUE(flips.has_edge(f[0], f[1]) && flips.has_edge(f[1], f[2]) && flips.has_edge(f[0], f[2]));
    }
  EXPECT_GT(missing, 0);
  EXPECT_GT(recovered, 0);
  EXPECT_GT(flips.flips(), 0);
  checked_result(flips, start);
}
