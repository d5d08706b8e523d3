// SPDX-License-Identifier: LGPL-2.1-or-later
// The input surface check (surface_check.h) and its exact intersection tests: each defect is found,
// named (code, element index, words of the message), and the repairs of --reorient are right.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_io.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/input/self_intersection.h"
#include "bsptet/input/surface_check.h"
#include "bsptet/input/triangle_intersection.h"
#include "support/test_shapes.h"

using namespace bsptet;

namespace {

using bsptet_test::add_box;

SurfaceMesh box(bool inward = false) {
  SurfaceMesh m;
  add_box(m, 0, 1, inward);
  return m;
}

// Runs check_surface and returns the error (code, index, message); fails the test if none.
struct Caught {
  ErrorCode code = ErrorCode::kInternal;
  std::int64_t index = -2;
  std::string message;
};
Caught caught(const SurfaceMesh& m, const SurfaceCheckOptions& o = {}) {
  Caught c;
  try {
    check_surface(m, o);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    c = {e.code(), e.index(), e.what()};
  }
  return c;
}

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

IndexedTriangle tri(std::array<Index, 3> id, std::array<Vec3, 3> p) { return {id, p}; }

}  // namespace

TEST(SurfaceCheck, ValidBoxPasses) {
  const SurfaceMesh m = box();
  const SurfaceCheckResult r = check_surface(m);
  EXPECT_EQ(r.shells, 1);
  EXPECT_EQ(r.flipped_triangles, 0);
  EXPECT_EQ(r.tri, m.tri);
}

TEST(SurfaceCheck, NonFiniteAndIndices) {
  SurfaceMesh m = box();
  m.xyz[3 * 5 + 1] = std::nan("");
  Caught c = caught(m);
  EXPECT_EQ(c.code, ErrorCode::kNonFiniteCoordinate);
  EXPECT_EQ(c.index, 5);
  EXPECT_HAS(c.message, "vertex 5 has a non-finite coordinate");
  m = box();
  m.tri[3 * 7 + 2] = 8;
  c = caught(m);
  EXPECT_EQ(c.code, ErrorCode::kBadArgument);
  EXPECT_EQ(c.index, 7);
  EXPECT_HAS(c.message, "triangle 7 refers to vertex 8, which is out of range");
  m.tri[3 * 7 + 2] = -3;
  c = caught(m);
  EXPECT_HAS(c.message, "negative vertex index -3");
}

TEST(SurfaceCheck, DegenerateAndDuplicate) {
  SurfaceMesh m = box();
  m.xyz.insert(m.xyz.end(), {0.5, 0, 0});  // point 8, on the edge 0-1
  m.tri.insert(m.tri.end(), {0, 8, 1});
  Caught c = caught(m);
  EXPECT_EQ(c.code, ErrorCode::kDegenerateTriangle);
  EXPECT_EQ(c.index, 12);
  EXPECT_HAS(c.message, "collinear");
  m = box();
  m.xyz.insert(m.xyz.end(), {1, 1, 1});  // point 8 repeats point 7: one vertex
  m.tri.insert(m.tri.end(), {3, 6, 8});  // duplicates triangle 7 (3 6 7) through the merge
  c = caught(m);
  EXPECT_EQ(c.code, ErrorCode::kDuplicateTriangle);
  EXPECT_EQ(c.index, 12);
  EXPECT_HAS(c.message, "duplicates triangle 7");
}

TEST(SurfaceCheck, OpenAndNonManifoldEdges) {
  SurfaceMesh m = box();
  m.tri.resize(m.tri.size() - 3);
  Caught c = caught(m);
  EXPECT_EQ(c.code, ErrorCode::kOpenBoundary);
  EXPECT_HAS(c.message, "open");
  EXPECT_HAS(c.message, "3 open edges in all");
  // A tetrahedron hanging on the box's edge (0 1): four triangles share that edge.
  m = box();
  m.xyz.insert(m.xyz.end(), {0.5, -1, 0.5, 0.5, -1, -0.5});
  m.tri.insert(m.tri.end(), {0, 1, 8, 0, 8, 9, 0, 9, 1, 1, 9, 8});
  c = caught(m);
  EXPECT_EQ(c.code, ErrorCode::kNonManifold);
  EXPECT_HAS(c.message, "edge (0 1) is a non-manifold edge");
}

TEST(SurfaceCheck, NonManifoldVertex) {
  // Two boxes touching at one corner: (1, 1, 1).
  SurfaceMesh m = box();
  add_box(m, 1, 1);
  const Caught c = caught(m);
  EXPECT_EQ(c.code, ErrorCode::kNonManifold);
  EXPECT_EQ(c.index, 7);
  EXPECT_HAS(c.message, "vertex 7 (1, 1, 1) is a non-manifold vertex");
}

TEST(SurfaceCheck, InconsistentOrientationAndReorient) {
  SurfaceMesh m = box();
  std::swap(m.tri[3 * 4 + 1], m.tri[3 * 4 + 2]);
  const Caught c = caught(m);
  EXPECT_EQ(c.code, ErrorCode::kInconsistentOrientation);
  EXPECT_HAS(c.message, "--reorient");
  SurfaceCheckOptions o;
  o.reorient = true;
  const SurfaceCheckResult r = check_surface(m, o);
  EXPECT_EQ(r.flipped_triangles, 1);
  EXPECT_EQ(r.tri, box().tri);
}

TEST(SurfaceCheck, InwardShellAndReorient) {
  const Caught c = caught(box(true));
  EXPECT_EQ(c.code, ErrorCode::kInwardFacing);
  EXPECT_HAS(c.message, "faces inward");
  SurfaceCheckOptions o;
  o.reorient = true;
  const SurfaceCheckResult r = check_surface(box(true), o);
  EXPECT_EQ(r.flipped_triangles, 12);
  EXPECT_EQ(r.tri, box().tri);
}

TEST(SurfaceCheck, CavitiesMustFaceInward) {
  SurfaceMesh m;
  add_box(m, 0, 4);
  add_box(m, 1, 1, /*inward=*/true);  // a cavity: valid
  EXPECT_EQ(check_surface(m).shells, 2);
  SurfaceMesh bad;
  add_box(bad, 0, 4);
  add_box(bad, 1, 1);  // a solid inside a solid
  const Caught c = caught(bad);
  EXPECT_EQ(c.code, ErrorCode::kInwardFacing);
  EXPECT_EQ(c.index, 12);
  EXPECT_HAS(c.message, "lies inside the shell of triangle 0");
  SurfaceCheckOptions o;
  o.reorient = true;
  EXPECT_EQ(check_surface(bad, o).tri, m.tri);
  // Side by side, both outward: valid.
  SurfaceMesh two;
  add_box(two, 0, 1);
  add_box(two, 2, 1);
  EXPECT_EQ(check_surface(two).shells, 2);
}

TEST(SurfaceCheck, SelfIntersectionNamesThePairs) {
  SurfaceMesh m;
  add_box(m, 0, 2);
  add_box(m, 1, 2);  // overlapping boxes
  try {
    check_surface(m);
    FAIL() << "no error";
  } catch (const SelfIntersectionError& e) {
    EXPECT_EQ(e.code(), ErrorCode::kSelfIntersection);
    EXPECT_TRUE(e.complete());
    ASSERT_FALSE(e.pairs().empty());
    for (const auto& p : e.pairs()) {
      EXPECT_LT(p[0], 12);  // each pair: one triangle of each box
      EXPECT_GE(p[1], 12);
    }
    EXPECT_HAS(std::string(e.what()), "intersects itself");
  }
  SurfaceCheckOptions o;
  o.max_reported_pairs = 2;
  try {
    check_surface(m, o);
    FAIL() << "no error";
  } catch (const SelfIntersectionError& e) {
    EXPECT_EQ(e.pairs().size(), 2u);
    EXPECT_FALSE(e.complete());
    EXPECT_HAS(std::string(e.what()), "at least 2 pairs");
  }
}

TEST(SurfaceCheck, CorpusModels) {
  const std::string dir = FEMBSPTET_DATA_DIR;
  for (const char* good : {"/corpus/cube.off", "/corpus/tinytorus.off", "/corpus/cray_left.off", "/corpus/knot2.off",
                           "/paper/schoenhardt.off", "/corpus/joint.off"})
    EXPECT_NO_THROW(check_surface(read_off(dir + good))) << good;
  const Caught fold = caught(read_off(dir + "/corpus/cube_with_fold.off"));
  EXPECT_EQ(fold.code, ErrorCode::kSelfIntersection);
  const Caught spike = caught(read_off(dir + "/corpus/td_spike-1-10.off"));
  EXPECT_EQ(spike.code, ErrorCode::kInconsistentOrientation);
  SurfaceCheckOptions o;
  o.reorient = true;
  const SurfaceMesh s = read_off(dir + "/corpus/td_spike-1-10.off");
  const SurfaceCheckResult r = check_surface(s, o);
  EXPECT_GT(r.flipped_triangles, 0);
  SurfaceMesh fixed = s;
  fixed.tri = r.tri;
  EXPECT_NO_THROW(check_surface(fixed));
  EXPECT_EQ(caught(read_off(dir + "/corpus/engine_bracket.off")).code, ErrorCode::kInwardFacing);
  EXPECT_EQ(caught(read_off(dir + "/corpus/box.off")).code, ErrorCode::kSelfIntersection);
  EXPECT_EQ(caught(read_off(dir + "/corpus/openscad-nonmanifold-crash.off")).code, ErrorCode::kDegenerateTriangle);
}

TEST(TriangleIntersection, SharedCornerAndEdgeCases) {
  const Vec3 o{0, 0, 0}, x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1}, xy{1, 1, 0}, mx{-1, 0, 0}, my{0, -1, 0};
  // Sharing an edge, not coplanar: only the edge.
  EXPECT_FALSE(triangles_intersect(tri({0, 1, 2}, {o, x, y}), tri({1, 0, 3}, {x, o, z})));
  // Sharing an edge, coplanar, opposite sides: only the edge; same side: a fold.
  EXPECT_FALSE(triangles_intersect(tri({0, 1, 2}, {o, x, y}), tri({1, 0, 3}, {x, o, my})));
  EXPECT_TRUE(triangles_intersect(tri({0, 1, 2}, {o, x, y}), tri({1, 0, 3}, {x, o, xy})));
  // Sharing a corner: apart, then overlapping in the plane, then an edge lying along the other.
  EXPECT_FALSE(triangles_intersect(tri({0, 1, 2}, {o, x, y}), tri({0, 3, 4}, {o, mx, my})));
  EXPECT_TRUE(triangles_intersect(tri({0, 1, 2}, {o, x, y}), tri({0, 3, 4}, {o, xy, Vec3{2, -1, 0}})));
  EXPECT_TRUE(triangles_intersect(tri({0, 1, 2}, {o, x, y}), tri({0, 3, 4}, {o, Vec3{2, 0, 0}, z})));
  // Sharing a corner, the opposite edge piercing the other triangle.
  EXPECT_TRUE(triangles_intersect(tri({0, 1, 2}, {o, x, y}),
                                  tri({0, 3, 4}, {o, Vec3{0.2, 0.2, -1}, Vec3{0.2, 0.2, 1}})));
  // No shared vertex: a corner exactly on the other triangle counts; one ulp above it does not.
  EXPECT_TRUE(triangles_intersect(tri({0, 1, 2}, {o, x, y}), tri({3, 4, 5}, {Vec3{0.25, 0.25, 0}, Vec3{0, 0, 2}, Vec3{1, 1, 2}})));
  EXPECT_FALSE(triangles_intersect(tri({0, 1, 2}, {o, x, y}),
                                   tri({3, 4, 5}, {Vec3{0.25, 0.25, 4.9406564584124654e-324}, Vec3{0, 0, 2}, Vec3{1, 1, 2}})));
  // Classification used by ray casting.
  EXPECT_EQ(classify_segment_triangle(Vec3{0.2, 0.2, -1}, Vec3{0.2, 0.2, 1}, o, x, y), SegmentTriangleContact::kCrossing);
  EXPECT_EQ(classify_segment_triangle(Vec3{0.5, 0, -1}, Vec3{0.5, 0, 1}, o, x, y), SegmentTriangleContact::kDegenerate);
  EXPECT_EQ(classify_segment_triangle(Vec3{2, 2, -1}, Vec3{2, 2, 1}, o, x, y), SegmentTriangleContact::kNone);
}

TEST(MeshIoFuzzRegressions, LyingCountsDoNotExhaustMemory) {
  // A header claiming 2^31 - 1 vertices must fail on the missing data, not on reserving 48 GiB.
  EXPECT_THROW(parse_off("OFF\n2147483647 2147483647 0\n0 0 0\n", "big.off"), InputError);
  EXPECT_THROW(parse_tetgen("3 3 9223372036854775807 0\n", "0 4 0\n", "a.node", "a.ele"), InputError);
  EXPECT_THROW(parse_tetgen("1 3 0 0\n1 0 0 0\n", "1 4 0\n1 -9223372036854775808 1 1 1\n", "a.node", "a.ele"),
               InputError);
}

// The exactness certificates in predicates.cpp (taken when the filter cannot decide) must agree
// with the exact evaluation: grid points (many exact zeros), scaled far up and down, and points
// one ulp off the grid (where the certificate must refuse and fall back).
TEST(PredicateCertificates, AgreeWithExactOnGridsAndNearThem) {
  std::uint64_t state = 12345;
  auto next = [&]() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<int>((state >> 33) % 7) - 3;
  };
  const double scales[] = {1.0, 0.5, 0x1p-30, 0x1p40, 0x1p-390, 0x1p-420, 1e300};
  int zeros = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double s = scales[trial % 7];
    Vec3 p[4];
    for (auto& q : p) q = {next() * s, next() * s, next() * s};
    if (trial % 5 == 0) p[3] = Vec3{std::nextafter(p[3].x, 1e308), p[3].y, p[3].z};
    if (trial % 11 == 0) p[2] = Vec3{p[0].x + 1e6 * s, p[0].y, p[0].z};
    const Sign fast = orient3d(p[0], p[1], p[2], p[3]), exact = orient3d_exact(p[0], p[1], p[2], p[3]);
    ASSERT_EQ(fast, exact) << trial;
    zeros += exact == Sign::kZero;
    for (int axis = 0; axis < 3; ++axis)
      ASSERT_EQ(orient2d_projected(p[0], p[1], p[3], axis), orient2d_projected_exact(p[0], p[1], p[3], axis)) << trial;
  }
  EXPECT_GT(zeros, 1000);  // the test does exercise exact zeros
}
