// SPDX-License-Identifier: LGPL-2.1-or-later
// The polish that keeps room for curved tet10 elements (curved_room.h) on a dented prism
// (tests/data/paper) meshed by the core and refined to size, with a projection hook that moves the
// mid-nodes of boundary edges towards the centre of its bounding box (a "true surface" inside the
// facets): straight elements are valid; the polish never makes more curved elements invalid,
// keeps the mesh valid by the exact checker over the same volume, exactly, never lowers the worst
// angle, and counts the invalid curved elements it leaves.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>

#include "bsptet/refine/curved_room.h"
#include "bsptet/refine/mesh_optimizer.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/size_refine.h"
#include "bsptet/refine/target_sizes.h"
#include "support/refine_fixture.h"

using namespace bsptet;

namespace {

// The dented prism refined to `fraction` of its diagonal without a hook (step 1), then `hook` for
// the curved elements.
struct CurvedBox {
  bsptet_test::FileInput in{"paper/dented_prism.off"};
  RefineOptions o, curved;
  RefineStats st;
  std::unique_ptr<RefineMesh> m;
  std::unique_ptr<TargetSizes> sizes;
  std::unique_ptr<MeshOptimizer> opt;
  std::unique_ptr<CurvedRoom> room;
  // `hook` gets the diagonal and the centre of the bounding box.
  CurvedBox(double fraction, const std::function<ProjectionHook(double, Vec3)>& hook) {
    o.size = fraction * in.diagonal();
    o.thickness_ratio = 0;
    curved = o;
    curved.order = 2;
    curved.projection = hook(in.diagonal(), in.centre());
    m = std::make_unique<RefineMesh>(in.surface, in.mesh);
    sizes = std::make_unique<TargetSizes>(*m, o);
    opt = std::make_unique<MeshOptimizer>(*m, o, st, *sizes);
    SizeRefiner refiner(*m, o, st, *sizes, *opt);
    sizes->compute();
    refiner.delaunay_refine();
    refiner.split_long_edges();
    room = std::make_unique<CurvedRoom>(*m, curved, st, *sizes, *opt);
  }
  int invalid() {
    room->prepare_check();
    int n = 0;
    for (Index t = 0; t < m->num_tet_slots(); ++t)
      if (m->tet_alive(t)) n += !room->element_ok(m->tet(t), corner_points(*m, m->tet(t)));
    return n;
  }
};

// Moves x by `fraction` of the diagonal towards the centre (a boundary edge's mid-node sinks into
// the solid).
std::function<ProjectionHook(double, Vec3)> sink(double fraction) {
  return [fraction](double diagonal, Vec3 centre) -> ProjectionHook {
    const double depth = fraction * diagonal;
    return [depth, centre](const Vec3& x, std::int32_t, std::int32_t) {
      const double dx = centre.x - x.x, dy = centre.y - x.y, dz = centre.z - x.z;
      const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
      return Vec3{x.x + depth * dx / len, x.y + depth * dy / len, x.z + depth * dz / len};
    };
  };
}

}  // namespace

TEST(CurvedRoom, StraightElementsAreValid) {
  CurvedBox box(0.15, [](double, Vec3) -> ProjectionHook {
    return [](const Vec3& x, std::int32_t, std::int32_t) { return x; };
  });
  EXPECT_EQ(box.invalid(), 0);
  box.room->polish(15.0);
  EXPECT_EQ(box.st.curving_conflicts_left, 0);
  EXPECT_TRUE(bsptet_test::valid(box.in.surface, *box.m));
}

TEST(CurvedRoom, WithoutAHookOrAtOrderOnePolishDoesNothing) {
  CurvedBox box(0.15, sink(0.03));
  CurvedRoom linear(*box.m, box.o, box.st, *box.sizes, *box.opt);
  const mpq_class volume = bsptet_test::exact_volume6(*box.m);
  const Index points = box.m->num_points();
  const std::int64_t tets = box.m->num_alive_tets();
  EXPECT_EQ(linear.polish(15.0), 0);
  EXPECT_EQ(box.m->num_points(), points);
  EXPECT_EQ(box.m->num_alive_tets(), tets);
  EXPECT_EQ(bsptet_test::exact_volume6(*box.m), volume);
}

TEST(CurvedRoom, PolishNeverMakesMoreInvalidElementsNorLowersTheWorst) {
  CurvedBox box(0.15, sink(0.03));
  const mpq_class volume = bsptet_test::exact_volume6(*box.m);
  const int before = box.invalid();
  ASSERT_GT(before, 0);
  const double worst = bsptet_test::worst_angle(*box.m);
  EXPECT_GT(box.room->polish(15.0), 0);
  const int after = box.invalid();
  EXPECT_LE(after, before);
  EXPECT_EQ(box.st.curving_conflicts_left, after);
  EXPECT_GE(bsptet_test::worst_angle(*box.m), worst);
  EXPECT_TRUE(bsptet_test::valid(box.in.surface, *box.m));
  EXPECT_EQ(bsptet_test::exact_volume6(*box.m), volume);
}
