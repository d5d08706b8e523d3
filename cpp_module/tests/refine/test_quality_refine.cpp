// SPDX-License-Identifier: LGPL-2.1-or-later
// The quality stage: RefineMesh's local operations on hand-made meshes (each checked exactly, each
// refused when invalid) and the driver on real data (tet10 validity: test_tet10_certify.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <string>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/mesh/mesh_io.h"
#include "bsptet/core/mesher.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/wall_thickness.h"

using namespace bsptet;

namespace {

std::string data(const std::string& rel) { return std::string(FEMBSPTET_DATA_DIR) + "/" + rel; }

// Two tets glued on face (0, 1, 2): apexes 3 (above) and 4 (below); a closed surface of 6 triangles.
void bipyramid(SurfaceMesh& s, TetMesh& m, double apex_x = 1.0, double height = 0.5) {
  s.xyz = {0, 0, 0, 4, 0, 0, 0, 4, 0, apex_x, apex_x, height, apex_x, apex_x, -height};
  s.tri = {0, 1, 3, 1, 2, 3, 2, 0, 3, 1, 0, 4, 2, 1, 4, 0, 2, 4};
  m.xyz = s.xyz;
  m.tet = {0, 1, 2, 3, 1, 0, 2, 4};
}

}  // namespace

TEST(RefineMesh, Flip23ThenFlip32RestoresAValidMesh) {
  SurfaceMesh s;
  TetMesh m;
  bipyramid(s, m);
  ASSERT_TRUE(check_mesh(s, m).valid);
  RefineMesh r(s, m);
  // The shared face is interior; segment 3-4 crosses it: the 2-3 flip is valid. It is applied only
  // if it raises the worst dihedral angle, which it does for this flat pair (19.5 -> 38.9 deg).
  EXPECT_TRUE(r.flip23(0, 3));
  EXPECT_EQ(r.num_alive_tets(), 3);
  EXPECT_TRUE(check_mesh(s, r.to_tet_mesh()).valid);
  // The reverse 3-2 flip would lower the worst angle again: refused.
  EXPECT_FALSE(r.flip32(3, 4));
  EXPECT_TRUE(check_mesh(s, r.to_tet_mesh()).valid);
}

TEST(RefineMesh, Flip23RefusedWhenTheNewEdgeLeavesTheSolid) {
  SurfaceMesh s;
  TetMesh m;
  bipyramid(s, m, 3.0);  // apexes above and below a point outside the shared triangle
  ASSERT_TRUE(check_mesh(s, m).valid);
  RefineMesh r(s, m);
  EXPECT_FALSE(r.flip23(0, 3));
  EXPECT_EQ(r.num_alive_tets(), 2);
}

TEST(RefineMesh, SplitOnAxisAlignedFacetIsExactAndCollapseUndoesIt) {
  SurfaceMesh s;
  TetMesh m;
  bipyramid(s, m);
  RefineMesh r(s, m);
  // Edge 0-1 lies on the input edge between triangles (0,1,3) and (1,0,4): the midpoint (2,0,0)
  // is exactly on it.
  Index n = -1;
  ASSERT_EQ(r.split_edge(0, 1, 0, &n), SplitOutcome::kSplit);
  EXPECT_EQ(r.support(n).kind, Support::kInputEdge);
  EXPECT_EQ(r.point(n).x, 2.0);
  TetMesh out = r.to_tet_mesh();
  MeshCheckReport rep = check_mesh(s, out);
  EXPECT_TRUE(rep.valid);
  EXPECT_EQ(rep.boundary_steiner_points, 1);
  // The new point may only go along its input edge: onto 0 or 1, not onto apex 3.
  EXPECT_FALSE(r.collapse_edge(n, 3, 0, INFINITY));
  EXPECT_TRUE(r.collapse_edge(n, 0, 0, INFINITY));
  out = r.to_tet_mesh();
  EXPECT_TRUE(check_mesh(s, out).valid);
  EXPECT_EQ(out.num_tets(), 2);
}

TEST(RefineMesh, NoExactPointOnAGenericEdgeInExactMode) {
  SurfaceMesh s;
  TetMesh m;
  bipyramid(s, m);
  // Move apex 3 to a non-dyadic position: no candidate near the midpoint of edge 1-3 is on it.
  s.xyz[9] = 0.1;
  s.xyz[10] = 0.3;
  s.xyz[11] = 1.7;
  m.xyz = s.xyz;
  ASSERT_TRUE(check_mesh(s, m).valid);
  RefineMesh exact(s, m);
  EXPECT_EQ(exact.split_edge(1, 3), SplitOutcome::kNoExactPoint);
  EXPECT_TRUE(check_mesh(s, exact.to_tet_mesh()).valid);  // unchanged
  RefineMesh rounded(s, m, {}, SurfacePoints::kRounded);
  EXPECT_EQ(rounded.split_edge(1, 3), SplitOutcome::kSplit);
  // The rounded point is off the input edge: the exact checker against the input says so.
  EXPECT_FALSE(check_mesh(s, rounded.to_tet_mesh()).valid);
}

namespace {

// The n tets around the interior edge u = n, v = n + 1 (u above the ring's plane z = 0, v below):
// ring points 0..n-1 at the given (x, y), counter-clockwise seen from above; the closed surface is
// the two cones over the ring.
void edge_shell(SurfaceMesh& s, TetMesh& m, const std::vector<std::array<double, 2>>& ring, const Vec3& u,
                const Vec3& v) {
  const Index n = static_cast<Index>(ring.size());
  s.xyz.clear();
  s.tri.clear();
  for (const auto& w : ring) s.xyz.insert(s.xyz.end(), {w[0], w[1], 0});
  s.xyz.insert(s.xyz.end(), {u.x, u.y, u.z, v.x, v.y, v.z});
  m.tet.clear();
  for (Index i = 0; i < n; ++i) {
    const Index j = (i + 1) % n;
    s.tri.insert(s.tri.end(), {i, j, n, j, i, n + 1});
    m.tet.insert(m.tet.end(), {i, j, n + 1, n});
  }
  m.xyz = s.xyz;
}

// n ring points counter-clockwise around the z axis, at radius `even` for even k, `odd` for odd k.
std::vector<std::array<double, 2>> ring_points(int n, double even, double odd) {
  std::vector<std::array<double, 2>> out;
  for (int k = 0; k < n; ++k) {
    const double r = k % 2 ? odd : even;
    out.push_back({r * std::cos(2 * k * M_PI / n), r * std::sin(2 * k * M_PI / n)});
  }
  return out;
}

double worst_angle(RefineMesh& r) {
  double w = 180;
  for (Index t = 0; t < r.num_tet_slots(); ++t)
    if (r.tet_alive(t)) w = std::min(w, r.tet_quality(t));
  return w;
}

}  // namespace

TEST(RefineMesh, EdgeRemovalReplacesTheShellByTheBestValidTriangulationOfItsRing) {
  // A hexagon around a long edge through a point near one ring corner: the wedges next to that
  // corner are slivers.
  SurfaceMesh s;
  TetMesh m;
  edge_shell(s, m, ring_points(6, 1.0, 1.0), {0.8, 0.05, 0.9}, {0.8, 0.05, -0.9});
  ASSERT_TRUE(check_mesh(s, m).valid);
  RefineMesh r(s, m);
  const double before = worst_angle(r);
  // Refused by the acceptance hook: nothing changes, the hook saw 6 old and 8 new tets.
  std::size_t removed_seen = 0, created_seen = 0;
  EXPECT_FALSE(r.remove_edge(6, 7, 7, [&](const auto& removed, const auto& created) {
    removed_seen = removed.size();
    created_seen = created.size();
    return false;
  }));
  EXPECT_EQ(removed_seen, 6u);
  EXPECT_EQ(created_seen, 8u);
  EXPECT_EQ(r.num_alive_tets(), 6);
  // A ring larger than allowed: not tried.
  EXPECT_FALSE(r.remove_edge(6, 7, 5));
  // A boundary edge: never.
  EXPECT_FALSE(r.remove_edge(0, 6));
  ASSERT_TRUE(r.remove_edge(6, 7));
  EXPECT_EQ(r.num_alive_tets(), 8);
  EXPECT_TRUE(r.tets_around_edge(6, 7).empty());
  EXPECT_GT(worst_angle(r), before + 10);  // 13.5 -> 29.6 degrees
  const TetMesh out = r.to_tet_mesh();
  EXPECT_TRUE(check_mesh(s, out).valid);
}

TEST(RefineMesh, EdgeRemovalOnANonConvexRingUsesOnlyDiagonalsInsideIt) {
  // A star-shaped, non-convex ring (radii alternating 1 and 0.35): the diagonals between its outer
  // corners pass outside it (at 0.5 from the axis), so every triangulation with one of them has a
  // negative tet; the best valid one (the inner triangle and three ears) raises the worst angle.
  SurfaceMesh s;
  TetMesh m;
  edge_shell(s, m, ring_points(6, 1.0, 0.35), {0.0, 0.0, 2.0}, {0.0, 0.0, -2.0});
  ASSERT_TRUE(check_mesh(s, m).valid);
  RefineMesh r(s, m);
  const double before = worst_angle(r);
  ASSERT_TRUE(r.remove_edge(6, 7));
  EXPECT_TRUE(check_mesh(s, r.to_tet_mesh()).valid);
  EXPECT_EQ(r.num_alive_tets(), 8);
  EXPECT_GT(worst_angle(r), before + 10);  // 22.3 -> 44.7 degrees
  for (Index t = 0; t < r.num_tet_slots(); ++t) {
    if (!r.tet_alive(t)) continue;
    int outer = 0;
    for (Index w : r.tet(t)) outer += w < 6 && w % 2 == 0;
    EXPECT_LE(outer, 1) << "a tet on a diagonal between two outer corners";
  }
}

TEST(RefineMesh, InsertPointFillsItsCavityExactlyAndRespectsItsAcceptance) {
  SurfaceMesh s;
  TetMesh m;
  bipyramid(s, m);
  RefineMesh r(s, m);
  const Vec3 inside{1.2, 1.2, 0.1}, outside{5, 5, 0};
  // Outside the solid: the walk meets the boundary, nothing changes.
  EXPECT_EQ(r.insert_point(0, outside, 0), InsertOutcome::kOutside);
  EXPECT_EQ(r.num_alive_tets(), 2);
  // Refused by the acceptance hook: nothing changes; it saw the cone (new point as -1).
  std::size_t seen = 0;
  auto refuse = [&](const std::vector<std::array<Index, 4>>& cone, const Vec3& p) {
    seen = cone.size();
    for (const auto& t : cone) EXPECT_EQ(t[3], -1);
    EXPECT_EQ(p.z, inside.z);
    return false;
  };
  EXPECT_EQ(r.insert_point(0, inside, 0, nullptr, 512, false, refuse), InsertOutcome::kNoImprovement);
  EXPECT_EQ(seen, 6u);  // both tets in the cavity: the cone over the 6 surface triangles
  EXPECT_EQ(r.num_alive_tets(), 2);
  // Accepted: 6 positive tets, the mesh valid against the input, the point interior.
  Index n = -1;
  ASSERT_EQ(r.insert_point(0, inside, 0, &n), InsertOutcome::kInserted);
  EXPECT_EQ(r.num_alive_tets(), 6);
  EXPECT_EQ(r.support(n).kind, Support::kInterior);
  const MeshCheckReport rep = check_mesh(s, r.to_tet_mesh());
  EXPECT_TRUE(rep.valid);
  EXPECT_EQ(rep.boundary_steiner_points, 0);
  // The walk starts from a live tet (tet 0 is gone); too close to an existing vertex: refused.
  EXPECT_EQ(r.insert_point(0, {1.2, 1.2, 0.11}, 0.5), InsertOutcome::kWalkFailed);
  Index live = 0;
  while (!r.tet_alive(live)) ++live;
  EXPECT_EQ(r.insert_point(live, {1.2, 1.2, 0.11}, 0.5), InsertOutcome::kTooClose);
  EXPECT_EQ(r.num_alive_tets(), 6);
}

// A cap: tet (a, b, c, d) under two nearly coplanar boundary faces (a, c, b) and (a, b, d), its
// circumsphere (centre at z = +30) beyond the surface, and two tets below it down to e. A point
// below the cap is not in the cap's circumsphere: the plain Bowyer-Watson cavity leaves the cap;
// with must_contain the cap goes into the cavity (grown through the faces the point does not
// see) and the cone from the point replaces it.
TEST(RefineMesh, InsertPointWithMustContainReplacesACapWhoseCircumsphereIsOutside) {
  const double eps = 0.05;
  SurfaceMesh s;
  s.xyz = {0, 0, 0, 4, 0, 0, 2, -1, -eps, 2, 1, -eps, 2, 0, -3};
  s.tri = {0, 2, 1, 0, 1, 3, 0, 4, 2, 2, 4, 1, 1, 4, 3, 3, 4, 0};
  TetMesh m;
  m.xyz = s.xyz;
  m.tet = {0, 1, 2, 3, 0, 3, 2, 4, 1, 2, 3, 4};
  ASSERT_TRUE(check_mesh(s, m).valid);
  const Vec3 below{2.1, 0, -1};
  {
    RefineMesh plain(s, m);
    const double cap = plain.tet_quality(0);
    EXPECT_LT(cap, 5.0);  // 3.2 degrees
    Index n = -1;
    if (plain.insert_point(2, below, 0, &n) == InsertOutcome::kInserted) EXPECT_TRUE(plain.tet_alive(0));
  }
  RefineMesh r(s, m);
  const double before = worst_angle(r);
  Index n = -1;
  ASSERT_EQ(r.insert_point(2, below, 0, &n, 512, true, {}, 0), InsertOutcome::kInserted);
  EXPECT_FALSE(r.tet_alive(0));
  EXPECT_EQ(r.num_alive_tets(), 6);  // the cone over the six surface triangles
  const MeshCheckReport rep = check_mesh(s, r.to_tet_mesh());
  EXPECT_TRUE(rep.valid);
  EXPECT_EQ(rep.boundary_steiner_points, 0);
  EXPECT_GT(worst_angle(r), before + 5);
  // A dead tet cannot be asked for.
  Index live = 0;
  while (!r.tet_alive(live)) ++live;
  EXPECT_EQ(r.insert_point(live, below, 0, nullptr, 512, false, {}, 0), InsertOutcome::kWalkFailed);
}

TEST(RefineMesh, RelocateIfMovesOnlyInteriorPointsToValidPlacesItsHookAccepts) {
  SurfaceMesh s;
  TetMesh m;
  bipyramid(s, m);
  RefineMesh r(s, m);
  Index n = -1;
  ASSERT_EQ(r.insert_point(0, {1.2, 1.2, 0.1}, 0, &n), InsertOutcome::kInserted);
  auto yes = [](const std::vector<std::array<Vec3, 4>>&) { return true; };
  auto no = [](const std::vector<std::array<Vec3, 4>>&) { return false; };
  EXPECT_FALSE(r.relocate_point_if(0, {0.1, 0.1, 0}, yes));      // an input point never moves
  EXPECT_FALSE(r.relocate_point_if(n, {1.3, 1.3, 0.0}, no));      // refused by the hook
  EXPECT_FALSE(r.relocate_point_if(n, {3.0, 3.0, 0.0}, yes));     // outside the solid: not positive
  EXPECT_EQ(r.point(n).x, 1.2);
  EXPECT_TRUE(r.relocate_point_if(n, {1.3, 1.3, 0.0}, yes));
  EXPECT_EQ(r.point(n).x, 1.3);
  EXPECT_TRUE(check_mesh(s, r.to_tet_mesh()).valid);
}

TEST(QualityRefine, BoxWithHoleToSizeIsValidAndBetterShaped) {
  const SurfaceMesh s = read_off(data("paper/box_with_hole.off"));
  const TetMesh core = tetrahedralize(s);
  RefineOptions o;
  o.size = 0.5;
  RefineStats st;
  const TetMesh m = refine_quality(s, core, o, &st);
  const MeshCheckReport r = check_mesh(s, m);
  EXPECT_TRUE(r.valid);
  EXPECT_GT(m.num_tets(), 5 * core.num_tets());
  EXPECT_GE(r.quality.min_dihedral_deg, check_mesh(s, core).quality.min_dihedral_deg);
  EXPECT_GT(st.surface_splits, 0);
  EXPECT_EQ(st.splits_no_exact_point, 0);
}

// flip_boundary_edge on every boundary edge inside one input triangle of a refined mesh (exact
// mode: box_with_hole's axis-aligned facets are split exactly), each accepted whatever its angles:
// after every flip the mesh is still an exact refinement of the input (the check is against the
// INPUT surface), and edges between two input triangles are never flipped.
TEST(RefineMesh, BoundaryEdgeFlipsKeepTheMeshAnExactRefinementOfTheInput) {
  const SurfaceMesh s = read_off(data("paper/box_with_hole.off"));
  RefineOptions o;
  o.size = 0.5;
  o.optimize_rounds = 0;
  const TetMesh refined = refine_quality(s, tetrahedralize(s), o);
  RefineMesh r(s, refined);
  const auto any = [](const std::vector<std::array<Index, 4>>&, const std::vector<std::array<Index, 4>>&) {
    return true;
  };
  int in_face = 0, flipped = 0, on_input_edge = 0;
  for (const auto& e : r.edges()) {
    if (!r.edge_exists(e[0], e[1])) continue;  // an earlier flip removed it
    const EdgeKind k = r.edge_kind(e[0], e[1]);
    if (k == EdgeKind::kOnInputEdge) {
      ++on_input_edge;
      EXPECT_FALSE(r.flip_boundary_edge(e[0], e[1], 7, any));
    }
    if (k != EdgeKind::kInFace) continue;
    ++in_face;
    if (!r.flip_boundary_edge(e[0], e[1], 7, any)) continue;
    ++flipped;
    EXPECT_FALSE(r.edge_exists(e[0], e[1]));
    if (flipped % 25 == 1) ASSERT_TRUE(check_mesh(s, r.to_tet_mesh()).valid) << "after flip " << flipped;
  }
  const MeshCheckReport rep = check_mesh(s, r.to_tet_mesh());
  EXPECT_TRUE(rep.valid);
  EXPECT_GT(in_face, 50);
  EXPECT_GT(on_input_edge, 0);
  EXPECT_GT(flipped, 10);
}

TEST(QualityRefine, BadOptionsAreInputErrors) {
  const SurfaceMesh s = read_off(data("paper/dented_box.off"));
  const TetMesh core = tetrahedralize(s);
  RefineOptions o;
  o.size = -1;
  EXPECT_THROW(refine_quality(s, core, o), InputError);
  o.size = 1;
  o.order = 3;
  EXPECT_THROW(refine_quality(s, core, o), InputError);
}

// A 12-gon prism (a faceted cylinder of radius 10, height 30): side triangles tag 0, top tag 1,
// bottom tag 2. Its core mesh has no interior point: every tet has its corners on the rims, so
// three or four of them on the side's triangles.
SurfaceMesh tagged_prism() {
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
  return s;
}

// The prism's output mesh: its boundary as a surface (outward faces of exactly one tet) and the
// number of tets that FreeCAD's node-membership face search would misread: four corners on one
// tag's boundary faces, or three that are not a boundary face of that tag. Tags are told by
// place (caps at z = 0 and z = 30).
int misread_tets(const TetMesh& m, SurfaceMesh* boundary) {
  *boundary = boundary_surface(m);
  std::map<std::array<Index, 3>, int> tag_of_face;
  std::vector<std::set<int>> point_tags(static_cast<std::size_t>(m.num_points()));
  for (Index b = 0; b < boundary->num_triangles(); ++b) {
    const std::array<Index, 3> f{boundary->tri[3 * b], boundary->tri[3 * b + 1], boundary->tri[3 * b + 2]};
    std::array<Index, 3> key = f;
    std::sort(key.begin(), key.end());
    const double z0 = m.point(f[0]).z, z1 = m.point(f[1]).z, z2 = m.point(f[2]).z;
    const int tag = (z0 == 0 && z1 == 0 && z2 == 0) ? 2 : (z0 == 30 && z1 == 30 && z2 == 30) ? 1 : 0;
    tag_of_face[key] = tag;
    for (Index v : f) point_tags[static_cast<std::size_t>(v)].insert(tag);
  }
  int misread = 0;
  for (Index t = 0; t < m.num_tets(); ++t) {
    const Index* q = &m.tet[static_cast<std::size_t>(4 * t)];
    for (int tag = 0; tag < 3; ++tag) {
      std::vector<Index> on;
      for (int k = 0; k < 4; ++k)
        if (point_tags[static_cast<std::size_t>(q[k])].count(tag)) on.push_back(q[k]);
      std::array<Index, 3> f{on.size() > 0 ? on[0] : -1, on.size() > 1 ? on[1] : -1, on.size() > 2 ? on[2] : -1};
      std::sort(f.begin(), f.end());
      const auto it = tag_of_face.find(f);
      if (on.size() == 4 || (on.size() == 3 && (it == tag_of_face.end() || it->second != tag))) {
        ++misread;
        break;
      }
    }
  }
  return misread;
}

// With a projection hook (the FreeCAD case: points go onto the true cylinder and planes) every
// offending tet is mended; the mesh stays valid.
TEST(QualityRefine, SeparateFaceTagsLeavesOnlyTrueBoundaryFacesOnEachTag) {
  const SurfaceMesh s = tagged_prism();
  const TetMesh core = tetrahedralize(s, MeshOptions{});
  ASSERT_TRUE(check_mesh(s, core).valid);
  SurfaceMesh b;
  ASSERT_GT(misread_tets(core, &b), 0);
  RefineOptions o;
  o.max_passes = 0;
  o.optimize_rounds = 0;
  o.separate_face_tags = true;
  o.projection = [](const Vec3& p, std::int32_t tag, std::int32_t other) {
    if (tag != 0 && other != 0) return p;  // on a cap: the rounded midpoint is on its plane
    const double r = std::hypot(p.x, p.y);
    return Vec3{10 * p.x / r, 10 * p.y / r, p.z};
  };
  RefineStats st;
  const TetMesh m = refine_quality(s, core, o, &st);
  EXPECT_GT(st.tag_splits, 0);
  EXPECT_EQ(st.tag_conflicts_left, 0);
  EXPECT_EQ(misread_tets(m, &b), 0);
  EXPECT_TRUE(check_mesh(b, m).valid);
}

// Exact mode cannot split the caps' input edges (no double lies exactly on most of them): what is
// left is counted honestly, and the mesh is still an exact mesh of the input.
TEST(QualityRefine, SeparateFaceTagsReportsWhatExactModeCannotMend) {
  const SurfaceMesh s = tagged_prism();
  const TetMesh core = tetrahedralize(s, MeshOptions{});
  RefineOptions o;
  o.max_passes = 0;
  o.optimize_rounds = 0;
  o.separate_face_tags = true;
  RefineStats st;
  const TetMesh m = refine_quality(s, core, o, &st);
  SurfaceMesh b;
  const int left = misread_tets(m, &b);
  EXPECT_TRUE(check_mesh(s, m).valid);
  EXPECT_GT(st.tag_splits, 0);
  EXPECT_EQ(st.tag_conflicts_left, left);
  EXPECT_LT(left, misread_tets(core, &b));
}

namespace {

// The axis-aligned box [x0, x1] x [y0, y1] x [z0, z1] as 12 outward triangles, appended to s.
void add_box(SurfaceMesh& s, double x0, double y0, double z0, double x1, double y1, double z1) {
  const Index b = s.num_points();
  for (int k = 0; k < 8; ++k) {
    s.xyz.push_back(k & 1 ? x1 : x0);
    s.xyz.push_back(k & 2 ? y1 : y0);
    s.xyz.push_back(k & 4 ? z1 : z0);
  }
  // Outward quads (corner bits: 1 = x, 2 = y, 4 = z), counter-clockwise seen from outside.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (int t : {q[0], q[1], q[2], q[0], q[2], q[3]}) s.tri.push_back(b + t);
}

std::vector<Index> triangles_on(const SurfaceMesh& s, int axis, double value) {
  std::vector<Index> out;
  for (Index t = 0; t < s.num_triangles(); ++t) {
    bool all = true;
    for (int k = 0; k < 3; ++k) all = all && s.point(s.tri[3 * t + k])[axis] == value;
    if (all) out.push_back(t);
  }
  return out;
}

}  // namespace

// The thickness of a plate on both faces and across its length; an opposing wall across air (a
// second box above the plate) does not count; nothing beyond the reach.
TEST(WallThickness, PlateFacesSeeTheirOppositeFaceNotTheGapAbove) {
  SurfaceMesh s;
  add_box(s, 0, 0, 0, 10, 10, 1);
  add_box(s, 0, 0, 1.5, 10, 10, 2.5);
  ASSERT_EQ(s.num_triangles(), 24);
  for (Index t = 0; t < s.num_triangles(); ++t) {  // every triangle outward: its normal leaves its box
    const Index box = t / 12;
    const Vec3 c{5, 5, box == 0 ? 0.5 : 2.0};
    EXPECT_EQ(orient3d(s.point(s.tri[3 * t]), s.point(s.tri[3 * t + 1]), s.point(s.tri[3 * t + 2]), c),
              Sign::kNegative);
  }
  const WallThickness walls(s);
  const std::vector<Index> top = triangles_on(s, 2, 1.0), bottom = triangles_on(s, 2, 0.0),
                           right = triangles_on(s, 0, 10.0);
  EXPECT_DOUBLE_EQ(walls.at({5, 5, 1}, {0, 0, 1}, top, 20), 1.0);  // not 0.5 (the gap above)
  EXPECT_DOUBLE_EQ(walls.at({3, 7, 0}, {0, 0, -1}, bottom, 20), 1.0);
  EXPECT_DOUBLE_EQ(walls.at({2, 2, 2.5}, {0, 0, 1}, triangles_on(s, 2, 2.5), 20), 1.0);
  // On x = 10 the plate's own face at x = 0 opposes (the second box's x = 0 face too, farther).
  EXPECT_DOUBLE_EQ(walls.at({10, 5, 0.5}, {1, 0, 0}, right, 20), 10.0);
  EXPECT_TRUE(std::isinf(walls.at({10, 5, 0.5}, {1, 0, 0}, right, 5)));
  // Its own triangles are skipped: without them, a corner point's own faces at distance 0 do
  // not count either (distance 0), so the answer is the same.
  EXPECT_DOUBLE_EQ(walls.at({10, 0, 1}, {0, 0, 1}, {}, 20), 1.0);
}

// Every region of the nearest-point computation (3 corners, 3 edges, the inside), against the
// answer worked out by hand.
TEST(WallThickness, NearestPointOnATriangleInEveryRegion) {
  const Vec3 a{0, 0, 0}, b{4, 0, 0}, c{0, 4, 0};
  const struct {
    Vec3 p, q;
  } cases[] = {{{-1, -1, 2}, {0, 0, 0}}, {{6, -1, 1}, {4, 0, 0}},  {{-1, 7, 0}, {0, 4, 0}},
               {{2, -3, 1}, {2, 0, 0}},  {{-2, 1, 5}, {0, 1, 0}},  {{3, 3, -1}, {2, 2, 0}},
               {{1, 1, 3}, {1, 1, 0}}};
  for (const auto& k : cases) {
    Vec3 q;
    const double d2 = point_triangle_squared_distance(k.p, a, b, c, &q);
    EXPECT_NEAR(q.x, k.q.x, 1e-12);
    EXPECT_NEAR(q.y, k.q.y, 1e-12);
    EXPECT_NEAR(q.z, k.q.z, 1e-12);
    const double e2 = (k.p.x - k.q.x) * (k.p.x - k.q.x) + (k.p.y - k.q.y) * (k.p.y - k.q.y) + (k.p.z - k.q.z) * (k.p.z - k.q.z);
    EXPECT_NEAR(d2, e2, 1e-12);
  }
}

// The tree's pruned search gives what a scan of every triangle gives, on a random soup of
// triangles of very different sizes, for reaches from tiny to unbounded.
TEST(WallThickness, TreeSearchAgreesWithAScanOfEveryTriangle) {
  SurfaceMesh s;
  std::uint64_t state = 12345;
  auto rnd = [&]() {  // deterministic, in [0, 1)
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  for (int t = 0; t < 600; ++t) {
    const double scale = t % 10 == 0 ? 5.0 : 0.3;
    const Vec3 o{10 * rnd(), 10 * rnd(), 10 * rnd()};
    for (int k = 0; k < 3; ++k) {
      s.xyz.push_back(o.x + scale * (rnd() - 0.5));
      s.xyz.push_back(o.y + scale * (rnd() - 0.5));
      s.xyz.push_back(o.z + scale * (rnd() - 0.5));
      s.tri.push_back(3 * t + k);
    }
  }
  const WallThickness walls(s);
  int found = 0;
  for (int q = 0; q < 300; ++q) {
    const Vec3 p{10 * rnd(), 10 * rnd(), 10 * rnd()};
    Vec3 n{rnd() - 0.5, rnd() - 0.5, rnd() - 0.5};
    const double len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    n = {n.x / len, n.y / len, n.z / len};
    for (double reach : {0.2, 1.0, 3.0, std::numeric_limits<double>::infinity()}) {
      double best = std::numeric_limits<double>::infinity();
      for (Index t = 0; t < s.num_triangles(); ++t) {
        const Vec3& m = walls.normal(t);
        if (!(m.x * n.x + m.y * n.y + m.z * n.z < -0.5)) continue;
        Vec3 c;
        const double d = std::sqrt(point_triangle_squared_distance(p, s.point(3 * t), s.point(3 * t + 1), s.point(3 * t + 2), &c));
        const Vec3 pq{c.x - p.x, c.y - p.y, c.z - p.z};
        if (d > 0 && d < reach && pq.x * n.x + pq.y * n.y + pq.z * n.z < 0 && pq.x * m.x + pq.y * m.y + pq.z * m.z > 0)
          best = std::min(best, d);
      }
      const double got = walls.at(p, n, {}, reach);
      if (std::isinf(best)) {
        EXPECT_TRUE(std::isinf(got)) << "query " << q << " reach " << reach;
      } else {
        ++found;
        EXPECT_NEAR(got, best, 1e-12) << "query " << q << " reach " << reach;
      }
    }
  }
  EXPECT_GT(found, 300);
}

// A plate 40 x 40 x 2 refined to size 16 (8 times its thickness), rounded surface points: without
// thickness sizing its tets span the wall flat (4.0 degrees); with thickness_ratio 2 the worst
// angle is 7.3 (size 4 everywhere gives 9.6), and the mesh stays valid against its own boundary.
TEST(QualityRefine, ThinWallSizingLiftsTheWorstAngleAcrossAPlate) {
  SurfaceMesh s;
  add_box(s, 0, 0, 0, 40, 40, 2);
  const TetMesh core = tetrahedralize(s);
  RefineOptions o;
  o.size = 16;
  o.surface_points = SurfacePoints::kRounded;
  o.thickness_ratio = 0;
  const TetMesh flat = refine_quality(s, core, o);
  o.thickness_ratio = 2;
  const TetMesh lifted = refine_quality(s, core, o);
  const MeshCheckReport rf = check_mesh(boundary_surface(flat), flat),
                        rl = check_mesh(boundary_surface(lifted), lifted);
  ASSERT_TRUE(rf.valid);
  ASSERT_TRUE(rl.valid);
  EXPECT_GT(rl.quality.min_dihedral_deg, rf.quality.min_dihedral_deg + 2.5);  // 4.0 -> 7.3
  EXPECT_GT(rl.quality.min_dihedral_deg, 7);
  EXPECT_GT(lifted.num_tets(), flat.num_tets());
  std::printf("plate 40x40x2 at size 16: worst angle %.2f (%d tets) without, %.2f (%d tets) with ratio 2\n",
              rf.quality.min_dihedral_deg, flat.num_tets(), rl.quality.min_dihedral_deg, lifted.num_tets());
}

// Three interior points in a row a few ulps above the base of a tetrahedron (what the core's
// Steiner point relocation can leave): every tet with all three is flat wherever its fourth
// corner is, and moving one point at a time keeps some tet flat. The quality stage's flat
// collapse removes such corners whatever their edge lengths: the worst angle rises from below
// 0.001 degree to above 20 (30.9; without the pass the other passes reach 13.5), at least one
// flat collapse is counted, and the mesh stays valid.
TEST(QualityRefine, FlatTetsBetweenCollinearSteinerPointsAreCollapsedAway) {
  SurfaceMesh s;
  s.xyz = {0, 0, 0, 8, 0, 0, 0, 8, 0, 2, 2, 6};
  s.tri = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
  TetMesh m;
  m.xyz = s.xyz;
  m.tet = {0, 1, 2, 3};
  ASSERT_TRUE(check_mesh(s, m).valid);
  RefineMesh r(s, m);
  for (const double x : {1.5, 2.5, 3.5}) {
    Index live = 0;
    while (!r.tet_alive(live)) ++live;
    ASSERT_EQ(r.insert_point(live, {x, 1.0, 1e-8 + 1e-12 * x * x}, 0), InsertOutcome::kInserted);
  }
  const TetMesh flat = r.to_tet_mesh();
  const MeshCheckReport before = check_mesh(s, flat);
  ASSERT_TRUE(before.valid);
  ASSERT_LT(before.quality.min_dihedral_deg, 1e-3);
  RefineOptions o;  // no size: optimization only
  RefineStats st;
  const TetMesh out = refine_quality(s, flat, o, &st);
  const MeshCheckReport after = check_mesh(s, out);
  EXPECT_TRUE(after.valid);
  EXPECT_GE(st.flat_collapses, 1);
  EXPECT_GT(after.quality.min_dihedral_deg, 20.0);
  std::printf("worst angle %.3g -> %.3g, flat collapses %lld, tets %d\n", before.quality.min_dihedral_deg,
              after.quality.min_dihedral_deg, static_cast<long long>(st.flat_collapses), out.num_tets());
}
