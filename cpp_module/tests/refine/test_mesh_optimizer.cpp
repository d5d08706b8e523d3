// SPDX-License-Identifier: LGPL-2.1-or-later
// The quality stage's optimization passes (mesh_optimizer.h) on a dented prism (tests/data/paper)
// meshed by the core and refined to size: after every pass the mesh is valid by the exact checker
// (mesh_check.h), covers the same volume, exactly, and its worst dihedral angle is not lower where
// the pass promises that; the face frames and the failure memory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "bsptet/refine/mesh_optimizer.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/size_refine.h"
#include "bsptet/refine/target_sizes.h"
#include "support/refine_fixture.h"

using namespace bsptet;

namespace {

// A surface of tests/data meshed by the core and refined to `fraction` of its bounding box's
// diagonal (Delaunay refinement and edge splits, as quality_refine's step 1). The dented prism at
// 0.15: 94 points, 269 tets, the worst at 0.55 degrees, 205 tets below 40.
struct Refined {
  bsptet_test::FileInput in;
  RefineOptions o;
  RefineStats st;
  std::unique_ptr<RefineMesh> m;
  std::unique_ptr<TargetSizes> sizes;
  std::unique_ptr<MeshOptimizer> opt;
  explicit Refined(double fraction, const char* file = "paper/dented_prism.off") : in(file) {
    o.size = fraction * in.diagonal();
    o.thickness_ratio = 0;
    m = std::make_unique<RefineMesh>(in.surface, in.mesh);
    sizes = std::make_unique<TargetSizes>(*m, o);
    opt = std::make_unique<MeshOptimizer>(*m, o, st, *sizes);
    SizeRefiner refiner(*m, o, st, *sizes, *opt);
    sizes->compute();
    refiner.delaunay_refine();
    refiner.split_long_edges();
  }
  bool valid() const { return bsptet_test::valid(in.surface, *m); }
  mpq_class volume6() const { return bsptet_test::exact_volume6(*m); }
  double worst() const { return bsptet_test::worst_angle(*m); }
};

}  // namespace

TEST(FaceFrame, NormalTowardsTheFourthCornerAndRegularApex) {
  const Vec3 A{0, 0, 0}, B{1, 0, 0}, C{0.5, std::sqrt(3.0) / 2, 0};
  FaceFrame f;
  ASSERT_TRUE(face_frame(A, B, C, {0.2, 0.2, -3}, &f));
  EXPECT_DOUBLE_EQ(f.normal.z, -1.0);
  EXPECT_DOUBLE_EQ(f.mean_edge, 1.0);
  const Vec3 apex = f.apex(1.0);  // a regular tet's apex: every edge to it is 1 long
  for (const Vec3& P : {A, B, C}) EXPECT_NEAR(std::sqrt(squared_distance(apex, P)), 1.0, 1e-12);
  EXPECT_FALSE(face_frame(A, B, {2, 0, 0}, {0, 0, 1}, &f));  // collinear corners
}

TEST(MeshOptimizer, WorstQualityAndTetsBelowAgree) {
  Refined box(0.15);
  const double worst = box.m->worst_tet_quality();
  EXPECT_EQ(worst, box.worst());
  const std::vector<Index> below = box.opt->tets_below(30.0);
  EXPECT_EQ(below.size(), box.opt->count_below(30.0));
  for (std::size_t i = 0; i < below.size(); ++i) {
    EXPECT_LT(box.m->tet_quality(below[i]), 30.0);
    if (i > 0) EXPECT_LE(box.m->tet_quality(below[i - 1]), box.m->tet_quality(below[i]));
  }
  if (!below.empty()) EXPECT_EQ(box.m->tet_quality(below.front()), worst);
}

TEST(MeshOptimizer, FlipCollapseAndSmoothPassesKeepTheMeshAndItsWorstAngle) {
  Refined box(0.15);
  ASSERT_TRUE(box.valid());
  const mpq_class volume = box.volume6();
  struct Pass {
    const char* name;
    std::function<std::int64_t()> run;
  };
  MeshOptimizer& opt = *box.opt;
  const Pass passes[] = {
      {"flip_pass", [&] { return opt.flip_pass(40.0); }},
      {"collapse_pass", [&] { return opt.collapse_pass(); }},
      {"flat_collapse_pass", [&] { return opt.flat_collapse_pass(1.0); }},
      {"smooth_pass", [&] { return opt.smooth_pass(40.0); }},
  };
  std::int64_t changes = 0;
  for (const Pass& p : passes) {
    const double before = box.worst();
    changes += p.run();
    EXPECT_TRUE(box.valid()) << p.name;
    EXPECT_EQ(box.volume6(), volume) << p.name;
    EXPECT_GE(box.worst(), before) << p.name;
  }
  EXPECT_GT(changes, 0);
}

TEST(MeshOptimizer, OdtSmoothingKeepsTetsAboveFifteenDegreesOrTheWorst) {
  Refined box(0.15);
  const mpq_class volume = box.volume6();
  const double before = box.worst();
  const std::int64_t moves = box.opt->odt_smooth_pass(1);
  EXPECT_GT(moves, 0);
  EXPECT_EQ(box.st.relocations, moves);
  EXPECT_TRUE(box.valid());
  EXPECT_EQ(box.volume6(), volume);
  EXPECT_GE(box.worst(), std::min(before, 15.0));
  // Further sweeps visit only the neighbours of moved points, and still keep the bound.
  const std::int64_t more = box.opt->odt_smooth_pass(3);
  EXPECT_EQ(box.st.relocations, moves + more);
  EXPECT_TRUE(box.valid());
  EXPECT_EQ(box.volume6(), volume);
  EXPECT_GE(box.worst(), std::min(before, 15.0));
}

TEST(MeshOptimizer, OptimizeRaisesTheWorstAngle) {
  Refined box(0.15);
  const mpq_class volume = box.volume6();
  const double before = box.worst();
  box.opt->optimize(4, box.m->num_alive_tets());
  EXPECT_GE(box.st.optimize_rounds, 1);
  EXPECT_TRUE(box.valid());
  EXPECT_EQ(box.volume6(), volume);
  EXPECT_GE(box.worst(), std::min(before, 15.0));
  EXPECT_GT(box.worst(), before);
}

TEST(MeshOptimizer, InsertionsAndSliverSplitsKeepTheMeshValid) {
  Refined box(0.15);
  const mpq_class volume = box.volume6();
  const Index points = box.m->num_points();
  const double before = box.worst();
  box.opt->insert_pass(70.0);
  EXPECT_TRUE(box.valid());
  EXPECT_EQ(box.volume6(), volume);
  EXPECT_EQ(box.m->num_points() - points, box.st.insertions);
  box.opt->sliver_pass(70.0);  // not curved tet10: no split below the mesh's worst
  EXPECT_TRUE(box.valid());
  EXPECT_EQ(box.volume6(), volume);
  EXPECT_GE(box.worst(), std::min(before, 15.0));
}

TEST(FailureMemory, ForgetsATetWhenATetAroundItsCornersChanges) {
  Refined box(0.25);
  FailureMemory memory;
  Index t = 0;
  while (!box.m->tet_alive(t)) ++t;
  EXPECT_FALSE(memory.failed_before(*box.m, t));
  const Index slots = box.m->num_tet_slots();
  for (Index s = 0; s < slots; ++s)
    if (box.m->tet_alive(s)) memory.record(*box.m, s);
  for (Index s = 0; s < slots; ++s)
    if (box.m->tet_alive(s)) EXPECT_TRUE(memory.failed_before(*box.m, s));
  EXPECT_FALSE(memory.failed_before(*box.m, slots + 3));  // never recorded
  // A split of one of t's edges changes the tets at its ends: every tet left at them is tried again.
  const auto q = box.m->tet(t);
  RefineStats st;
  Index u = -1;
  for (int i = 0; i < 4 && u < 0; ++i)
    for (int j = i + 1; j < 4 && u < 0; ++j)
      if (box.sizes->split(q[i], q[j], 0, st)) u = q[i];
  ASSERT_GE(u, 0);
  int retried = 0;
  for (Index s = 0; s < slots; ++s) {
    if (!box.m->tet_alive(s)) continue;
    const auto& c = box.m->tet(s);
    if (c[0] == u || c[1] == u || c[2] == u || c[3] == u) {
      EXPECT_FALSE(memory.failed_before(*box.m, s));
      ++retried;
    }
  }
  EXPECT_GT(retried, 0);
}

// The balls (RefineMesh::tets_around_point) and the edge list (RefineMesh::edges) against the
// live tets counted by brute force, after passes that flip, collapse and move: each ball holds
// exactly the live tets at its point in increasing id order (a tet leaves them when it dies),
// and edges() is every edge of a live tet once, sorted.
TEST(MeshOptimizer, BallsAndEdgesFollowTheLiveTetsThroughThePasses) {
  Refined box(0.15);
  box.opt->flip_pass(40.0);
  box.opt->collapse_pass();
  box.opt->flat_collapse_pass(1.0);
  box.opt->odt_smooth_pass(2);
  RefineMesh& m = *box.m;
  std::vector<std::vector<Index>> balls(static_cast<std::size_t>(m.num_points()));
  std::vector<std::array<Index, 2>> edges;
  for (Index t = 0; t < m.num_tet_slots(); ++t) {
    if (!m.tet_alive(t)) continue;
    const auto& q = m.tet(t);
    for (int i = 0; i < 4; ++i) {
      balls[static_cast<std::size_t>(q[i])].push_back(t);
      for (int j = i + 1; j < 4; ++j) edges.push_back({std::min(q[i], q[j]), std::max(q[i], q[j])});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  EXPECT_EQ(m.edges(), edges);
  for (Index v = 0; v < m.num_points(); ++v) EXPECT_EQ(m.tets_around_point(v), balls[static_cast<std::size_t>(v)]) << v;
  EXPECT_GT(box.st.collapses + box.st.flips23 + box.st.flips32 + box.st.edge_removals, 0);
}
