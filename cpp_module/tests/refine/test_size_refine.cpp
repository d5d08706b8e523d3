// SPDX-License-Identifier: LGPL-2.1-or-later
// The quality stage's refinement to size (size_refine.h) on a box meshed by the core: Delaunay
// refinement adds interior points only, the edge splits leave no edge long; after each the mesh is
// valid by the exact checker over the same volume, exactly.
#include <gtest/gtest.h>

#include "bsptet/refine/mesh_optimizer.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/size_refine.h"
#include "bsptet/refine/target_sizes.h"
#include "support/refine_fixture.h"

using namespace bsptet;
using bsptet_test::BoxInput;

namespace {

RefineOptions box_options(double size) {
  RefineOptions o;
  o.size = size;
  o.thickness_ratio = 0;
  return o;
}

}  // namespace

TEST(SizeRefiner, DelaunayRefinementAddsInteriorPointsOnly) {
  BoxInput in(1.0);
  RefineMesh m(in.surface, in.mesh);
  const RefineOptions o = box_options(0.3);
  RefineStats st;
  TargetSizes sizes(m, o);
  MeshOptimizer opt(m, o, st, sizes);
  SizeRefiner refiner(m, o, st, sizes, opt);
  sizes.compute();
  const mpq_class volume = bsptet_test::exact_volume6(m);
  const Index before = m.num_points();
  refiner.delaunay_refine();
  EXPECT_GT(st.refinement_points, 0);
  EXPECT_EQ(m.num_points(), before + st.refinement_points);
  for (Index v = before; v < m.num_points(); ++v) EXPECT_EQ(m.support(v).kind, Support::kInterior);
  EXPECT_TRUE(bsptet_test::valid(in.surface, m));
  EXPECT_EQ(bsptet_test::exact_volume6(m), volume);
  EXPECT_EQ(st.splits, 0);
}

TEST(SizeRefiner, WithoutSizeNothingHappens) {
  BoxInput in(1.0);
  RefineMesh m(in.surface, in.mesh);
  RefineOptions o;  // size infinite
  RefineStats st;
  TargetSizes sizes(m, o);
  MeshOptimizer opt(m, o, st, sizes);
  SizeRefiner refiner(m, o, st, sizes, opt);
  sizes.compute();
  const Index before = m.num_points();
  refiner.delaunay_refine();
  EXPECT_EQ(m.num_points(), before);
  EXPECT_EQ(st.refinement_points, 0);
}

TEST(SizeRefiner, EdgeSplitsLeaveNoLongEdge) {
  BoxInput in(1.0);
  RefineMesh m(in.surface, in.mesh);
  const RefineOptions o = box_options(0.2);
  RefineStats st;
  TargetSizes sizes(m, o);
  MeshOptimizer opt(m, o, st, sizes);
  SizeRefiner refiner(m, o, st, sizes, opt);
  sizes.compute();
  const mpq_class volume = bsptet_test::exact_volume6(m);
  refiner.split_long_edges();
  EXPECT_GT(st.splits, 0);
  EXPECT_GT(st.surface_splits, 0);  // the box's faces: midpoints of axis-aligned edges are exact
  EXPECT_GE(st.size_passes, 1);
  EXPECT_TRUE(bsptet_test::valid(in.surface, m));
  EXPECT_EQ(bsptet_test::exact_volume6(m), volume);
  sizes.compute(false);
  for (const auto& e : m.edges()) EXPECT_FALSE(sizes.is_long(e[0], e[1])) << e[0] << " " << e[1];
}
