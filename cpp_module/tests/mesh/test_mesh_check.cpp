// SPDX-License-Identifier: LGPL-2.1-or-later
// The checker accepts a valid Kuhn subdivision of a box and rejects every kind of damage.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "bsptet/mesh/mesh_check.h"
#include "bsptet/numerics/predicates.h"

using namespace bsptet;

namespace {

// Box [0,sx]x[0,sy]x[0,sz] with corners indexed i = x + 2y + 4z.
std::vector<double> box_points(double sx = 1, double sy = 1, double sz = 1) {
  std::vector<double> xyz;
  for (int i = 0; i < 8; ++i) {
    xyz.push_back((i & 1) ? sx : 0);
    xyz.push_back((i & 2) ? sy : 0);
    xyz.push_back((i & 4) ? sz : 0);
  }
  return xyz;
}

// Each face quad split along the diagonal from its lowest to its highest corner index (the
// diagonals of the Kuhn subdivision), oriented outward.
SurfaceMesh box_surface(double sx = 1, double sy = 1, double sz = 1) {
  SurfaceMesh s;
  s.xyz = box_points(sx, sy, sz);
  const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& q : quads) {
    // q is a cycle; find the min corner, the diagonal goes to the opposite corner of the cycle.
    const int k = static_cast<int>(std::min_element(q, q + 4) - q);
    const int a = q[k], b = q[(k + 1) % 4], c = q[(k + 2) % 4], d = q[(k + 3) % 4];
    for (int t : {a, b, c, a, c, d}) s.tri.push_back(t);
  }
  // Orient outward by the centroid test (the box is convex).
  const Vec3 center{sx / 2, sy / 2, sz / 2};
  for (Index t = 0; t < s.num_triangles(); ++t)
    if (orient3d(s.point(s.tri[3 * t]), s.point(s.tri[3 * t + 1]), s.point(s.tri[3 * t + 2]), center) ==
        Sign::kPositive)
      std::swap(s.tri[3 * t + 1], s.tri[3 * t + 2]);
  return s;
}

TetMesh kuhn_box(double sx = 1, double sy = 1, double sz = 1) {
  TetMesh m;
  m.xyz = box_points(sx, sy, sz);
  const int perms[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
  for (const auto& p : perms) {
    Index t[4] = {0, p[0], p[0] + p[1], 7};
    if (orient3d(m.point(t[0]), m.point(t[1]), m.point(t[2]), m.point(t[3])) == Sign::kNegative)
      std::swap(t[1], t[2]);
    m.tet.insert(m.tet.end(), t, t + 4);
  }
  return m;
}

}  // namespace

TEST(MeshCheck, AcceptsKuhnBox) {
  const MeshCheckReport r = check_mesh(box_surface(), kuhn_box());
  for (const auto& m : r.messages) ADD_FAILURE() << m;
  EXPECT_TRUE(r.valid);
  EXPECT_EQ(r.tets, 6);
  EXPECT_EQ(r.boundary_faces, 12);
  EXPECT_EQ(r.interior_faces, 6);
  EXPECT_TRUE(r.volume_equal);
  EXPECT_DOUBLE_EQ(r.tet_volume, 1.0);
  EXPECT_EQ(r.steiner_points, 0);
  EXPECT_NEAR(r.quality.min_dihedral_deg, 45.0, 1e-9);
  EXPECT_NEAR(r.quality.max_dihedral_deg, 90.0, 1e-9);
}

TEST(MeshCheck, AcceptsAtAnyScaleAndPlacement) {
  for (double s : {1e-6, 1e-3, 1.0, 1e6}) {
    SurfaceMesh surf = box_surface(3 * s, 0.1 * s, 7 * s);
    TetMesh mesh = kuhn_box(3 * s, 0.1 * s, 7 * s);
    for (std::size_t i = 0; i < surf.xyz.size(); ++i) surf.xyz[i] += 12345.678;
    for (std::size_t i = 0; i < mesh.xyz.size(); ++i) mesh.xyz[i] += 12345.678;
    const MeshCheckReport r = check_mesh(surf, mesh);
    EXPECT_TRUE(r.valid) << "scale " << s << ": " << (r.messages.empty() ? "" : r.messages[0]);
  }
}

TEST(MeshCheck, RejectsDroppedTet) {
  TetMesh m = kuhn_box();
  m.tet.erase(m.tet.begin() + 8, m.tet.begin() + 12);
  const MeshCheckReport r = check_mesh(box_surface(), m);
  EXPECT_FALSE(r.valid);
  EXPECT_GT(r.boundary_faces_off_surface + r.miscovered_triangles, 0);
  EXPECT_FALSE(r.volume_equal);
  EXPECT_FALSE(r.messages.empty());
}

TEST(MeshCheck, RejectsFlippedTet) {
  TetMesh m = kuhn_box();
  std::swap(m.tet[4 * 3 + 1], m.tet[4 * 3 + 2]);
  const MeshCheckReport r = check_mesh(box_surface(), m);
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.inverted_tets, 1);
  EXPECT_NE(r.messages[0].find("tet 3"), std::string::npos) << r.messages[0];
}

TEST(MeshCheck, RejectsDuplicatedTet) {
  TetMesh m = kuhn_box();
  m.tet.insert(m.tet.end(), m.tet.begin(), m.tet.begin() + 4);
  const MeshCheckReport r = check_mesh(box_surface(), m);
  EXPECT_FALSE(r.valid);
  EXPECT_GT(r.overshared_faces + r.same_orientation_faces, 0);
}

TEST(MeshCheck, RejectsPointMovedOffTheSurface) {
  // Move corner 7 outward by one ulp: faces on it leave their input triangles.
  SurfaceMesh s = box_surface();
  TetMesh m = kuhn_box();
  m.xyz[3 * 7] = std::nextafter(1.0, 2.0);
  const MeshCheckReport r = check_mesh(s, m);
  EXPECT_FALSE(r.valid);
  EXPECT_GT(r.boundary_faces_off_surface, 0);
}

TEST(MeshCheck, RejectsWrongDiagonals) {
  // Same box, but the input splits one face along the other diagonal.
  SurfaceMesh s = box_surface();
  // Face x = 0 is triangles 0 and 1 (quad 0 2 6 4, diagonal 0-6); use diagonal 2-4 instead.
  const Index alt[6] = {0, 4, 2, 2, 4, 6};
  std::copy(alt, alt + 6, s.tri.begin());
  const MeshCheckReport r = check_mesh(s, kuhn_box());
  EXPECT_FALSE(r.valid);
  EXPECT_GT(r.boundary_faces_off_surface, 0);
}

TEST(MeshCheck, AcceptsBoundarySteinerPointOnAFace) {
  // Split the Kuhn tets that own boundary face (0, 4, 6)? Simpler: cone the box from the centre of
  // face z = 0 and from the box centre. Build a pyramid decomposition: point 8 = (0.5, 0.5, 0)
  // on face z = 0 and point 9 = box centre; every input triangle split accordingly would change the
  // input, so instead cone every boundary triangle to the centre (valid, 12 tets) and then split
  // the two tets on face z = 0 by point 8 (a boundary Steiner point).
  SurfaceMesh s = box_surface();
  TetMesh m;
  m.xyz = box_points();
  m.xyz.insert(m.xyz.end(), {0.5, 0.5, 0.5, 0.25, 0.5, 0.0});
  const Index center = 8, steiner = 9;
  for (Index t = 0; t < s.num_triangles(); ++t) {
    const Index a = s.tri[3 * t], b = s.tri[3 * t + 1], c = s.tri[3 * t + 2];
    // Outward face (a, b, c) of tet (a, c, b, center)... orient positively.
    Index tet[4] = {a, c, b, center};
    const bool on_z0 = m.xyz[3 * a + 2] == 0 && m.xyz[3 * b + 2] == 0 && m.xyz[3 * c + 2] == 0;
    // Steiner point (0.25, 0.5, 0) lies inside exactly one z = 0 triangle: split that one.
    if (on_z0) {
      const Vec3 pa = m.point(a), pb = m.point(b), pc = m.point(c), ps = m.point(steiner);
      const bool inside = orient2d_projected(pa, pb, ps, 2) == orient2d_projected(pa, pb, pc, 2) &&
                          orient2d_projected(pb, pc, ps, 2) == orient2d_projected(pa, pb, pc, 2) &&
                          orient2d_projected(pc, pa, ps, 2) == orient2d_projected(pa, pb, pc, 2);
      if (inside) {
        const Index sub[3][3] = {{a, b, steiner}, {b, c, steiner}, {c, a, steiner}};
        for (const auto& f : sub) {
          Index tt[4] = {f[0], f[2], f[1], center};
          m.tet.insert(m.tet.end(), tt, tt + 4);
        }
        continue;
      }
    }
    m.tet.insert(m.tet.end(), tet, tet + 4);
  }
  const MeshCheckReport r = check_mesh(s, m);
  for (const auto& msg : r.messages) ADD_FAILURE() << msg;
  EXPECT_TRUE(r.valid);
  EXPECT_EQ(r.steiner_points, 2);
  EXPECT_EQ(r.boundary_steiner_points, 1);
}

TEST(MeshCheck, QuadraticMidNodesMustBeShared) {
  TetMesh lin = kuhn_box();
  TetMesh q;
  q.nodes_per_tet = 10;
  q.xyz = lin.xyz;
  std::map<std::pair<Index, Index>, Index> mids;
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (Index t = 0; t < lin.num_tets(); ++t) {
    const Index* c = &lin.tet[4 * t];
    q.tet.insert(q.tet.end(), c, c + 4);
    for (const auto& e : edges) {
      const auto key = std::minmax(c[e[0]], c[e[1]]);
      auto it = mids.find(key);
      if (it == mids.end()) {
        const Index id = q.num_points();
        for (int k = 0; k < 3; ++k) q.xyz.push_back((q.xyz[3 * key.first + k] + q.xyz[3 * key.second + k]) / 2);
        it = mids.emplace(key, id).first;
      }
      q.tet.push_back(it->second);
    }
  }
  EXPECT_TRUE(check_mesh(box_surface(), q).valid);
  // Give tet 0 its own copy of one mid-node.
  TetMesh bad = q;
  const Index id = bad.num_points();
  for (int k = 0; k < 3; ++k) bad.xyz.push_back(bad.xyz[3 * bad.tet[4] + k] + 1e-3);
  bad.tet[4] = id;
  const MeshCheckReport r = check_mesh(box_surface(), bad);
  EXPECT_FALSE(r.valid);
  EXPECT_GT(r.inconsistent_midnodes, 0);
}
