// SPDX-License-Identifier: LGPL-2.1-or-later
// The quality stage's target sizes (target_sizes.h) on a box meshed by the core: the targets are
// the asked size, lowered on a tagged face and graded away from it; the floor; a split gives its
// point the mean target and keeps the mesh valid over the same volume.
#include <gtest/gtest.h>

#include <cmath>

#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/target_sizes.h"
#include "support/refine_fixture.h"

using namespace bsptet;
using bsptet_test::BoxInput;

TEST(TargetSizes, UniformSizeAndItsFloor) {
  BoxInput in(2.0);
  RefineMesh m(in.surface, in.mesh);
  RefineOptions o;
  o.size = 0.5;
  o.thickness_ratio = 0;  // the box's walls are 2 thick: no effect, and no wall search here
  TargetSizes sizes(m, o);
  EXPECT_EQ(sizes.floor(), 0.0);  // before the first compute
  sizes.compute();
  EXPECT_EQ(sizes.floor(), 0.5 / 8);  // one eighth of the smallest target
  ASSERT_EQ(sizes.targets().size(), static_cast<std::size_t>(m.num_points()));
  for (Index v = 0; v < m.num_points(); ++v) EXPECT_EQ(sizes.target(v), 0.5);
  EXPECT_EQ(sizes.target(m.num_points() + 5), 0.5);  // a point not seen: `size`
  // The box's edges (length 2, diagonals 2 sqrt 2) are all longer than 2.0 * 0.5.
  for (const auto& e : m.edges()) EXPECT_TRUE(sizes.is_long(e[0], e[1]));
}

TEST(TargetSizes, TaggedFaceLowersTheTargetAndItIsGraded) {
  BoxInput in(1.0, true);
  RefineMesh m(in.surface, in.mesh);
  RefineOptions o;
  o.size = 0.5;
  o.size_by_tag = {{1, 0.05}};
  o.thickness_ratio = 0;
  TargetSizes sizes(m, o);
  sizes.compute();
  EXPECT_EQ(sizes.floor(), 0.05 / 8);
  for (Index v = 0; v < m.num_points(); ++v) {
    if (m.point(v).z == 0) EXPECT_EQ(sizes.target(v), 0.05);
    EXPECT_GE(sizes.target(v), 0.05);
    EXPECT_LE(sizes.target(v), 0.5);
  }
  // Grading: t(w) <= t(v) + grading * |vw| along every mesh edge.
  for (const auto& e : m.edges()) {
    const double l = sizes.length(e[0], e[1]);
    EXPECT_LE(sizes.target(e[1]), sizes.target(e[0]) + o.grading * l + 1e-15);
    EXPECT_LE(sizes.target(e[0]), sizes.target(e[1]) + o.grading * l + 1e-15);
  }
  // A point made in a tet: at most `size`, at most each corner's target plus the graded distance.
  const auto& q = m.tet(0);
  const Vec3 x{0.5, 0.5, 0.5};
  const double g = sizes.graded_target(x, q);
  EXPECT_LE(g, 0.5);
  for (Index k : q) EXPECT_LE(g, sizes.target(k) + o.grading * std::sqrt(squared_distance(x, m.point(k))));
}

TEST(TargetSizes, SplitGivesTheMeanTargetAndKeepsTheMeshValid) {
  BoxInput in(1.0);
  RefineMesh m(in.surface, in.mesh);
  RefineOptions o;
  o.size = 0.3;
  o.thickness_ratio = 0;
  TargetSizes sizes(m, o);
  sizes.compute();
  const mpq_class volume = bsptet_test::exact_volume6(m);
  // The longest edge first (an interior diagonal or a face diagonal of the box).
  std::array<Index, 2> longest{-1, -1};
  double best = 0;
  for (const auto& e : m.edges())
    if (sizes.length(e[0], e[1]) > best) best = sizes.length(e[0], e[1]), longest = e;
  RefineStats st;
  const Index before = m.num_points();
  ASSERT_TRUE(sizes.split(longest[0], longest[1], 0, st));
  EXPECT_EQ(st.splits, 1);
  EXPECT_EQ(m.num_points(), before + 1);
  EXPECT_EQ(sizes.target(before), 0.3);
  EXPECT_TRUE(bsptet_test::valid(in.surface, m));
  EXPECT_EQ(bsptet_test::exact_volume6(m), volume);
  EXPECT_EQ(volume, 6);
}
