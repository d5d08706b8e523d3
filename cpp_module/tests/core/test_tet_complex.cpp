// SPDX-License-Identifier: LGPL-2.1-or-later
// The tet complex of Steiner point removal (tet_complex.h), on small complexes built here: the
// Delaunay tetrahedralization of a cube's corners and points inside it, and a cube coned from an
// inner point with a Steiner point on one face. After every edit that succeeds the complex is
// valid (positive tets, faces shared by two tets with opposite orientations, the faces of one tet
// equal to the surface faces) and covers the same volume, exactly; an edit that fails changes
// nothing.
#include <gtest/gtest.h>

#include <gmpxx.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "bsptet/core/point_delaunay.h"
#include "bsptet/core/tet_complex.h"
#include "bsptet/numerics/implicit_geometry.h"
#include "bsptet/numerics/splitmix.h"

using namespace bsptet;

namespace {

using Face = std::array<Index, 3>;
using Tet = std::array<Index, 4>;

const std::vector<Vec3> kCube = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                 {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};

ImplicitGeometry make_geo(const std::vector<Vec3>& pts) {
  ImplicitGeometry geo(pts);
  for (Index i = 0; i < geo.num_explicit(); ++i) geo.add_explicit_vertex(i);
  return geo;
}

/// The rotation of f that starts at its smallest id (orientation kept).
Face canonical(Face f) {
  std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
  return f;
}

/// The four outward faces of a positive tet (types.h).
std::array<Face, 4> outward(const Tet& t) {
  return {{{t[0], t[2], t[1]}, {t[0], t[1], t[3]}, {t[0], t[3], t[2]}, {t[1], t[2], t[3]}}};
}

/// 6 times the complex's volume, exactly (every vertex here is an explicit double point).
mpq_class six_volume(ImplicitGeometry& geo, const std::vector<Tet>& tets) {
  mpq_class sum = 0;
  for (const Tet& t : tets) {
    Vec3 p[4];
    for (int i = 0; i < 4; ++i) {
      EXPECT_TRUE(geo.is_explicit(t[i]));
      p[i] = geo.rounded(t[i]);
    }
    mpq_class u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
      u[k] = mpq_class(p[1][k]) - mpq_class(p[0][k]);
      v[k] = mpq_class(p[2][k]) - mpq_class(p[0][k]);
      w[k] = mpq_class(p[3][k]) - mpq_class(p[0][k]);
    }
    sum += u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
  }
  return sum;
}

/// What breaks the header's validity (empty: a valid complex).
std::vector<std::string> problems(const TetComplex& mesh, ImplicitGeometry& geo) {
  std::vector<std::string> out;
  auto ids = [](const auto& f) {
    std::string s;
    for (Index v : f) s += " " + std::to_string(v);
    return s;
  };
  const std::vector<Tet> tets = mesh.alive_tets();
  std::map<Face, int> oriented;  // canonical oriented face -> count
  for (const Tet& t : tets) {
    if (geo.orient3d(t[0], t[1], t[2], t[3]) != Sign::kPositive) out.push_back("tet" + ids(t) + " not positive");
    for (const Face& f : outward(t)) ++oriented[canonical(f)];
  }
  std::set<Face> once;
  for (const auto& [f, n] : oriented) {
    if (n > 1) out.push_back("face" + ids(f) + " on the same side of two tets");
    if (!oriented.count(canonical({f[0], f[2], f[1]}))) once.insert(f);
  }
  std::set<Face> surface;
  for (const auto& [f, label] : mesh.alive_faces())
    if (!surface.insert(canonical(f)).second) out.push_back("surface face" + ids(f) + " twice");
  for (const Face& f : once)
    if (!surface.count(f)) out.push_back("face" + ids(f) + " of one tet is not a surface face");
  for (const Face& f : surface)
    if (!once.count(f)) out.push_back("surface face" + ids(f) + " is not the face of one tet");
  return out;
}

void expect_valid(const TetComplex& mesh, ImplicitGeometry& geo) {
  EXPECT_EQ(problems(mesh, geo), std::vector<std::string>{});
}

/// The complex of the Delaunay tetrahedralization of `pts` (the first 8 are the cube's corners,
/// the input points; the others lie strictly inside), its hull triangles as the input surface.
struct DelaunayComplex {
  explicit DelaunayComplex(const std::vector<Vec3>& pts) : geo(make_geo(pts)) {
    std::vector<Index> order(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) order[i] = static_cast<Index>(i);
    PointDelaunay del;
    EXPECT_TRUE(delaunay_explicit_points(geo, order, del));
    for (std::size_t i = 0; i < 8; ++i) surface.xyz.insert(surface.xyz.end(), {pts[i].x, pts[i].y, pts[i].z});
    std::vector<Face> hull;
    for (std::size_t t = 0; t < del.tets.size(); ++t)
      for (int k = 0; k < 4; ++k)
        if (del.nb[t][k] < 0) {
          // kTetOppositeFace[k] has the tet on its positive side: reversed, it faces outward.
          const Face in{del.tets[t][kTetOppositeFace[k][0]], del.tets[t][kTetOppositeFace[k][1]],
                        del.tets[t][kTetOppositeFace[k][2]]};
          hull.push_back({in[0], in[2], in[1]});
        }
    for (const Face& f : hull) {
      for (Index v : f) EXPECT_LT(v, 8) << "a hull vertex that is not a corner";
      surface.tri.insert(surface.tri.end(), f.begin(), f.end());
      tri_plane.push_back(geo.add_plane(f[0], f[1], f[2]));
    }
    mesh = std::make_unique<TetComplex>(geo, surface, tri_plane);
    for (const Tet& t : del.tets) mesh->add_tet(t);
    for (std::size_t i = 0; i < hull.size(); ++i) mesh->add_face(hull[i], static_cast<Index>(i));
  }
  ImplicitGeometry geo;
  SurfaceMesh surface;
  std::vector<Index> tri_plane;
  std::unique_ptr<TetComplex> mesh;
};

/// The cube's corners and `n` points strictly inside it (deterministic).
std::vector<Vec3> cube_with_inner_points(int n, std::uint64_t seed) {
  std::vector<Vec3> pts = kCube;
  for (int i = 0; i < n; ++i) {
    Vec3 p;
    double* c[3] = {&p.x, &p.y, &p.z};
    for (double* x : c) *x = 0.05 + 0.9 * static_cast<double>(splitmix64(seed) >> 11) * 0x1.0p-53;
    pts.push_back(p);
  }
  return pts;
}

/// Every edge of the complex, (smaller id, larger id), sorted.
std::vector<std::pair<Index, Index>> edges(const TetComplex& mesh) {
  std::set<std::pair<Index, Index>> out;
  for (const Tet& t : mesh.alive_tets())
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) out.insert({std::min(t[i], t[j]), std::max(t[i], t[j])});
  return {out.begin(), out.end()};
}

bool has_edge(const TetComplex& mesh, Index a, Index b) {
  for (const Tet& t : mesh.alive_tets())
    if (std::count(t.begin(), t.end(), a) && std::count(t.begin(), t.end(), b)) return true;
  return false;
}

}  // namespace

TEST(TetComplex, DelaunayOfACubeIsValid) {
  DelaunayComplex d(cube_with_inner_points(20, 7));
  expect_valid(*d.mesh, d.geo);
  EXPECT_EQ(six_volume(d.geo, d.mesh->alive_tets()), 6);
  for (Index v = 0; v < 8; ++v) EXPECT_FALSE(d.mesh->labels(v).empty()) << "corner " << v;
  for (Index v = 8; v < 28; ++v) {
    EXPECT_TRUE(d.mesh->used(v));
    EXPECT_TRUE(d.mesh->labels(v).empty()) << "inner point " << v;
  }
  // Neighbours: input points first, then by id, each once.
  const std::vector<Index> nb = d.mesh->neighbours(20);
  EXPECT_TRUE(std::is_sorted(nb.begin(), nb.end()));
  EXPECT_TRUE(std::adjacent_find(nb.begin(), nb.end()) == nb.end());
}

TEST(TetComplex, EdgeRemovalFlipsKeepValidityAndVolume) {
  int flipped = 0, refused = 0;
  for (std::uint64_t seed : {1, 2, 3}) {
    DelaunayComplex d(cube_with_inner_points(25, seed));
    TetComplex& mesh = *d.mesh;
    for (const auto& [v, x] : edges(mesh)) {
      if (!has_edge(mesh, v, x)) continue;  // gone with an earlier flip
      const std::vector<Tet> before = mesh.alive_tets();
      int around = 0;
      for (const Tet& t : before) around += std::count(t.begin(), t.end(), v) && std::count(t.begin(), t.end(), x);
      if (mesh.remove_edge(v, x)) {
        ++flipped;
        const std::vector<Tet> after = mesh.alive_tets();
        EXPECT_EQ(after.size(), before.size() - around + 2 * (around - 2)) << "an n-to-2(n-2) flip";
        EXPECT_FALSE(has_edge(mesh, v, x));
        expect_valid(mesh, d.geo);
        EXPECT_EQ(six_volume(d.geo, after), 6);
      } else {
        ++refused;
        EXPECT_EQ(mesh.alive_tets(), before) << "a refused flip changed the complex";
      }
    }
  }
  EXPECT_GT(flipped, 0);
  EXPECT_GT(refused, 0);  // hull edges, and rings that are not convex
}

TEST(TetComplex, InteriorSteinerPointsGoByCollapseConeAndRetetrahedralization) {
  DelaunayComplex d(cube_with_inner_points(12, 11));
  TetComplex& mesh = *d.mesh;
  int collapsed = 0, coned = 0, refilled = 0, refused = 0;
  auto check = [&](bool ok, const std::vector<Tet>& before, Index v, int& count) {
    if (ok) {
      ++count;
      EXPECT_FALSE(mesh.used(v)) << "point " << v << " still there";
      expect_valid(mesh, d.geo);
      EXPECT_EQ(six_volume(d.geo, mesh.alive_tets()), 6);
    } else {
      ++refused;
      EXPECT_EQ(mesh.alive_tets(), before);
    }
  };
  for (Index v = 8; v < 20; ++v) {
    // Collapse onto each neighbour (an inner point may go anywhere: the support rule allows it).
    for (Index u : mesh.neighbours(v)) {
      if (!mesh.used(v)) break;
      ASSERT_TRUE(mesh.may_move_onto(v, mesh.labels(v), u));
      const std::vector<Tet> before = mesh.alive_tets();
      check(mesh.try_substitute(v, u), before, v, collapsed);
    }
    for (Index u : mesh.used(v) ? mesh.neighbours(v) : std::vector<Index>{}) {
      if (!mesh.used(v)) break;
      const std::vector<Tet> before = mesh.alive_tets();
      check(mesh.cone_from_vertex(v, u, 6, 400), before, v, coned);
    }
    if (mesh.used(v)) {
      for (int layers = 0; layers <= 5 && mesh.used(v); ++layers) {
        std::size_t steps = 5000;
        const std::vector<Tet> before = mesh.alive_tets();
        check(mesh.retetrahedralize(v, layers, 120, steps), before, v, refilled);
      }
    }
  }
  EXPECT_GT(collapsed, 0);
  EXPECT_GT(refused, 0);
  // An edit removes its point, and a cone or a refill may take inner points inside its cavity too.
  int left = 0;
  for (Index v = 8; v < 20; ++v) left += mesh.used(v);
  EXPECT_LE(collapsed + coned + refilled, 12 - left);
  EXPECT_LT(left, 12);
  EXPECT_GT(mesh.work, 0);
}

namespace {

/// The unit cube, the diagonals of its faces x = 1, y = 1 and z = 1 through corner 7 and of the
/// others through corner 0, coned from the inner point 9; point 8 = (0.25, 0.5, 0) is a Steiner
/// point inside input triangle 0, (0, 2, 3) of the face z = 0, which is split in three around it.
struct ConedCube {
  explicit ConedCube(const Vec3& inner) : geo(make_geo(points(inner))) {
    surface.xyz.clear();
    for (int i = 0; i < 8; ++i) surface.xyz.insert(surface.xyz.end(), {kCube[i].x, kCube[i].y, kCube[i].z});
    const std::vector<Face> tris = {
        {0, 2, 3}, {0, 3, 1},  // z = 0, normal -z
        {4, 5, 7}, {4, 7, 6},  // z = 1
        {0, 1, 5}, {0, 5, 4},  // y = 0
        {2, 6, 7}, {2, 7, 3},  // y = 1
        {0, 4, 6}, {0, 6, 2},  // x = 0
        {1, 3, 7}, {1, 7, 5},  // x = 1
    };
    for (const Face& f : tris) {
      surface.tri.insert(surface.tri.end(), f.begin(), f.end());
      tri_plane.push_back(geo.add_plane(f[0], f[1], f[2]));
    }
    mesh = std::make_unique<TetComplex>(geo, surface, tri_plane);
    std::vector<std::pair<Face, Index>> faces = {{{0, 2, 8}, 0}, {{2, 3, 8}, 0}, {{3, 0, 8}, 0}};
    for (std::size_t t = 1; t < tris.size(); ++t) faces.push_back({tris[t], static_cast<Index>(t)});
    for (const auto& [f, label] : faces) {
      mesh->add_tet({f[0], f[2], f[1], 9});
      mesh->add_face(f, label);
    }
  }
  static std::vector<Vec3> points(const Vec3& inner) {
    std::vector<Vec3> pts = kCube;
    pts.push_back({0.25, 0.5, 0});
    pts.push_back(inner);
    return pts;
  }
  ImplicitGeometry geo;
  SurfaceMesh surface;
  std::vector<Index> tri_plane;
  std::unique_ptr<TetComplex> mesh;
};

}  // namespace

TEST(TetComplex, ConedCubeIsValid) {
  ConedCube c({0.5, 0.5, 0.5});
  expect_valid(*c.mesh, c.geo);
  EXPECT_EQ(six_volume(c.geo, c.mesh->alive_tets()), 6);
  EXPECT_EQ(c.mesh->labels(8), std::vector<Index>{0});
  EXPECT_TRUE(c.mesh->labels(9).empty());
}

TEST(TetComplex, TheValidityCheckSeesAHoleAndAFlippedTet) {
  ConedCube c({0.5, 0.5, 0.5});
  c.mesh->kill_tet(c.mesh->star(7)[0]);
  std::vector<std::string> p = problems(*c.mesh, c.geo);
  EXPECT_EQ(p.size(), 4u);  // the dead tet's 3 inner faces, and its surface face
  ConedCube d({0.5, 0.5, 0.5});
  const Tet t = d.mesh->tet(0);
  d.mesh->add_tet({t[1], t[0], t[2], t[3]});
  p = problems(*d.mesh, d.geo);
  ASSERT_FALSE(p.empty());
  EXPECT_NE(p[0].find("not positive"), std::string::npos) << p[0];
}

TEST(TetComplex, SupportRuleKeepsASurfacePointInItsTriangle) {
  ConedCube c({0.5, 0.5, 0.5});
  TetComplex& mesh = *c.mesh;
  const std::vector<Index> lv = mesh.labels(8);
  for (Index u : {0, 2, 3}) EXPECT_TRUE(mesh.may_move_onto(8, lv, u)) << u;       // corners of triangle 0
  for (Index u : {1, 4, 5, 6, 7}) EXPECT_FALSE(mesh.may_move_onto(8, lv, u)) << u;
  EXPECT_FALSE(mesh.may_move_onto(0, mesh.labels(0), 8));  // input points never move
  // The collapse onto corner 3 gives back triangle 0 whole.
  ASSERT_TRUE(mesh.try_substitute(8, 3));
  EXPECT_FALSE(mesh.used(8));
  expect_valid(mesh, c.geo);
  EXPECT_EQ(six_volume(c.geo, mesh.alive_tets()), 6);
  std::vector<Face> zero;
  for (const auto& [f, label] : mesh.alive_faces())
    if (label == 0) zero.push_back(canonical(f));
  EXPECT_EQ(zero, std::vector<Face>{canonical({0, 2, 3})});
}

TEST(TetComplex, CollapseIsRefusedWhenATetWouldBeFlat) {
  ConedCube c({0.5, 0.5, 0.5});
  TetComplex& mesh = *c.mesh;
  const auto sig = mesh.signature(9, mesh.neighbours(9));
  // Corner 1 lies in the plane z = 0 of the faces around point 8, which do not contain it: the
  // cone from it over them is flat.
  const std::vector<Tet> before = mesh.alive_tets();
  EXPECT_FALSE(mesh.try_substitute(9, 1));
  EXPECT_EQ(mesh.alive_tets(), before);
  EXPECT_EQ(mesh.signature(9, mesh.neighbours(9)), sig) << "a refused edit changed nothing";
  // Every face in a plane through corner 7 contains it: the cone from 7 tiles the cube.
  ASSERT_TRUE(mesh.try_substitute(9, 7));
  EXPECT_FALSE(mesh.used(9));
  expect_valid(mesh, c.geo);
  EXPECT_EQ(six_volume(c.geo, mesh.alive_tets()), 6);
}

TEST(TetComplex, RelocateTakesASurfaceSteinerPointInside) {
  ConedCube c({0.5, 0.5, 0.5});
  TetComplex& mesh = *c.mesh;
  const Index vertices_before = c.geo.num_vertices();
  ASSERT_TRUE(mesh.relocate(8)) << mesh.why;
  EXPECT_FALSE(mesh.used(8));
  EXPECT_GT(c.geo.num_vertices(), vertices_before);  // the new double point
  expect_valid(mesh, c.geo);
  EXPECT_EQ(six_volume(c.geo, mesh.alive_tets()), 6);
  std::vector<Face> zero;
  for (const auto& [f, label] : mesh.alive_faces())
    if (label == 0) zero.push_back(canonical(f));
  EXPECT_EQ(zero, std::vector<Face>{canonical({0, 2, 3})}) << "triangle 0 re-triangulated without the point";
  for (Index v = 0; v < c.geo.num_vertices(); ++v)
    if (v >= 8 && mesh.used(v)) EXPECT_TRUE(mesh.labels(v).empty()) << "Steiner point " << v << " on the surface";
}

TEST(TetComplex, PushMovesAnInnerPointTowardsTheCentre) {
  // An inner point near corner 7: its clearance from its link is 0.1, the cube's centre has 0.5.
  ConedCube c({0.9, 0.9, 0.9});
  TetComplex& mesh = *c.mesh;
  ASSERT_TRUE(mesh.push(9));
  EXPECT_FALSE(mesh.used(9));
  expect_valid(mesh, c.geo);
  EXPECT_EQ(six_volume(c.geo, mesh.alive_tets()), 6);
  // At the centre already: nothing to gain, nothing changes.
  ConedCube centred({0.5, 0.5, 0.5});
  const std::vector<Tet> before = centred.mesh->alive_tets();
  EXPECT_FALSE(centred.mesh->push(9));
  EXPECT_EQ(centred.mesh->alive_tets(), before);
}
