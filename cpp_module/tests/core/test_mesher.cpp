// SPDX-License-Identifier: LGPL-2.1-or-later
// The tetrahedralizer on the paper's polyhedra and on small generated solids: every output is
// checked by the exact checker.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/mesh/mesh_io.h"
#include "bsptet/core/mesher.h"
#include "support/test_shapes.h"

using namespace bsptet;

namespace {

std::string data(const std::string& rel) { return std::string(FEMBSPTET_DATA_DIR) + "/" + rel; }

}  // namespace

struct PaperCase {
  const char* name;
  int paper_steiner, paper_tets;    // Joshi & Ourselin, Table 1
  int tetgen_steiner, tetgen_tets;  // tetgen 1.5 -pY on the same surface
};

class PaperPolyhedron : public ::testing::TestWithParam<PaperCase> {};

// The default output must be fully valid (exact checker), with no Steiner point on the surface.
// Steiner counts are printed beside the paper's and TetGen's, and must not exceed TetGen's
// box_with_hole reaches TetGen's 0 through RETETRAHEDRALIZE, steiner_removal.h).
TEST_P(PaperPolyhedron, DefaultMeshIsValidWithNoSurfaceSteinerPoint) {
  const PaperCase c = GetParam();
  const SurfaceMesh s = read_off(data(std::string("paper/") + c.name + ".off"));
  MeshOptions o;
  o.debug_checks = true;
  MeshStats st;
  const TetMesh m = tetrahedralize(s, o, &st);
  std::printf("%-14s ours %2lld Steiner / %3lld tets | paper %d/%d | tetgen -pY %d/%d\n", c.name,
              (long long)st.steiner_points, (long long)st.tets, c.paper_steiner, c.paper_tets, c.tetgen_steiner,
              c.tetgen_tets);
  const MeshCheckReport r = check_mesh(s, m);
  EXPECT_TRUE(r.valid);
  for (const auto& msg : r.messages) ADD_FAILURE() << msg;
  EXPECT_EQ(r.boundary_steiner_points, 0);
  EXPECT_EQ(st.boundary_steiner_points, 0);
  EXPECT_LE(st.steiner_points, c.tetgen_steiner);
  EXPECT_EQ(r.steiner_points, st.steiner_points);
  EXPECT_EQ(r.tets, st.tets);
  // The Steiner removal's phases account for every point it removed (rounding removes none).
  EXPECT_EQ(st.steiner_seconds_by_phase.size(), 8u);
  std::int64_t removed = 0;
  for (const auto& [phase, n] : st.steiner_removed_by_phase) {
    EXPECT_GE(n, 0) << phase;
    EXPECT_GE(st.steiner_seconds_by_phase.at(phase), 0.0) << phase;
    removed += n;
  }
  EXPECT_EQ(removed, st.steiner_before_removal - st.steiner_points);
  // Deterministic: the same input gives the same mesh.
  const TetMesh again = tetrahedralize(s, o);
  EXPECT_EQ(again.xyz, m.xyz);
  EXPECT_EQ(again.tet, m.tet);
}

TEST_P(PaperPolyhedron, BoundarySteinerPointsAllowedStillValid) {
  const PaperCase c = GetParam();
  const SurfaceMesh s = read_off(data(std::string("paper/") + c.name + ".off"));
  MeshOptions o;
  o.allow_boundary_steiner = true;
  MeshStats st;
  const TetMesh m = tetrahedralize(s, o, &st);
  const MeshCheckReport r = check_mesh(s, m);
  EXPECT_TRUE(r.valid);
  for (const auto& msg : r.messages) ADD_FAILURE() << msg;
  EXPECT_EQ(r.boundary_steiner_points, st.boundary_steiner_points);
}

INSTANTIATE_TEST_SUITE_P(Paper, PaperPolyhedron,
                         ::testing::Values(PaperCase{"dented_box", 0, 9, 0, 6},
                                           PaperCase{"schoenhardt", 6, 18, 1, 8},
                                           PaperCase{"box_with_hole", 1, 29, 0, 24},
                                           PaperCase{"dented_prism", 7, 70, 1, 41}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(Mesher, RejectsOpenSurface) {
  SurfaceMesh s = read_off(data("paper/dented_box.off"));
  s.tri.resize(s.tri.size() - 3);
  try {
    tetrahedralize(s);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.code(), ErrorCode::kOpenBoundary);
    EXPECT_NE(std::string(e.what()).find("open"), std::string::npos) << e.what();
  }
}

TEST(Mesher, RejectsInwardSurface) {
  SurfaceMesh s = read_off(data("paper/schoenhardt.off"));
  for (Index t = 0; t < s.num_triangles(); ++t) std::swap(s.tri[3 * t + 1], s.tri[3 * t + 2]);
  MeshOptions o;
  o.allow_boundary_steiner = true;
  try {
    tetrahedralize(s, o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInwardFacing) << e.what();
  }
}

namespace {

// A star-shaped prism: a star polygon with `spikes` spikes (alternate radii 1 and 0.45), every side
// subdivided into `k` segments, extruded to height 0.3; each cap is a fan of thin triangles from a
// point near the centre, each wall quad two triangles, outward. The walls' planes cut the caps
// along chords that cross many fan edges: the case where splitting a covered face along whole edge
// lines makes an arrangement.
SurfaceMesh star_prism(int spikes, int k) {
  std::vector<std::array<double, 2>> ring;
  const double pi = std::acos(-1.0);
  for (int i = 0; i < 2 * spikes; ++i) {
    auto corner = [&](int j) {
      const double r = j % 2 == 0 ? 1.0 : 0.45, a = pi * j / spikes;
      return std::array<double, 2>{r * std::cos(a), 0.8 * r * std::sin(a)};
    };
    const auto p = corner(i), q = corner((i + 1) % (2 * spikes));
    for (int s = 0; s < k; ++s) {
      const double t = static_cast<double>(s) / k;
      ring.push_back({p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t});
    }
  }
  SurfaceMesh s;
  const Index n = static_cast<Index>(ring.size());
  for (double z : {0.0, 0.3})
    for (const auto& p : ring)
      for (double c : {p[0], p[1], z}) s.xyz.push_back(c);
  for (double z : {0.0, 0.3})
    for (double c : {0.013, 0.007, z}) s.xyz.push_back(c);
  const Index cb = 2 * n, ct = 2 * n + 1;
  for (Index i = 0; i < n; ++i) {
    const Index j = (i + 1) % n;
    for (Index x : {cb, j, i, ct, n + i, n + j, i, j, n + j, i, n + j, n + i}) s.tri.push_back(x);
  }
  return s;
}

}  // namespace

// Faces on input planes covered by many triangles are cut into one piece per triangle (conforming,
// checked after every split), not along whole edge lines: fewer BSP points (12 spikes x 8: 2359
// against 3284 along whole lines, 3.1 per input triangle; 4 allowed), and the mesh is valid with no
// surface Steiner point. (16 x 16, not run here: 8808 against 13448, 17 s against 308 s.)
TEST(Mesher, ManyTrianglesOnOnePlaneStayLinear) {
  // Both starts of the BSP: the box (the paper's partition; its covered faces refined per input
  // triangle) and the Delaunay seed (the fanned caps' long triangles cross many seed tets).
  for (const auto seed : {MeshOptions::Seed::kBox, MeshOptions::Seed::kDelaunay})
    for (const auto& [spikes, k] : {std::pair{5, 3}, std::pair{12, 8}}) {
      const bool box = seed == MeshOptions::Seed::kBox;
      const SurfaceMesh s = star_prism(spikes, k);
      MeshOptions o;
      o.seed = seed;
      o.debug_checks = spikes <= 5;
      MeshStats st;
      const TetMesh m = tetrahedralize(s, o, &st);
      std::printf("%s: star prism %d spikes, %d segments per side: %lld triangles, %lld BSP points, %lld Steiner "
                  "points, %lld tets\n",
                  box ? "box" : "Delaunay seed", spikes, k, (long long)st.input_triangles, (long long)st.bsp_points,
                  (long long)st.steiner_points, (long long)st.tets);
      const MeshCheckReport r = check_mesh(s, m);
      EXPECT_TRUE(r.valid);
      for (const auto& msg : r.messages) ADD_FAILURE() << msg;
      EXPECT_EQ(r.boundary_steiner_points, 0);
      EXPECT_EQ(st.delaunay_seeded, box ? 0 : 1);
      EXPECT_LE(st.bsp_points, (box ? 4 : 5) * st.input_triangles);
      EXPECT_EQ(st.retried_along_lines, 0);
      EXPECT_EQ(st.seed_fell_back, 0);
      if (!box) continue;
      // The earlier refinement along whole edge lines (the fallback when the Steiner removal gets
      // stuck) is valid too, with more BSP points on the fanned caps.
      o.covered_faces_along_lines = true;
      MeshStats lines;
      const TetMesh ml = tetrahedralize(s, o, &lines);
      std::printf("  along whole lines: %lld BSP points, %lld Steiner points, %lld tets\n", (long long)lines.bsp_points,
                  (long long)lines.steiner_points, (long long)lines.tets);
      const MeshCheckReport rl = check_mesh(s, ml);
      EXPECT_TRUE(rl.valid);
      EXPECT_EQ(rl.boundary_steiner_points, 0);
      EXPECT_GT(lines.bsp_points, st.bsp_points);
    }
}

// The effort bound of the optional Steiner removal phases (MeshOptions::steiner_effort): with
// almost no effort the interior Steiner points that need the expensive phases stay, the mesh is
// still fully valid with none on the surface, and it is the same mesh every time; without a bound
// there are at most as many.
TEST(Mesher, SteinerEffortBoundKeepsTheMeshValid) {
  const SurfaceMesh s = read_off(data("corpus/joint.off"));
  MeshOptions little;
  little.steiner_effort = 1;
  MeshStats st_little, st_again, st_full;
  const TetMesh m = tetrahedralize(s, little, &st_little);
  const TetMesh again = tetrahedralize(s, little, &st_again);
  MeshOptions full;
  full.steiner_effort = 0;
  const TetMesh mf = tetrahedralize(s, full, &st_full);
  std::printf("joint: effort 1: %lld Steiner points, %lld tets; unbounded: %lld, %lld\n",
              (long long)st_little.steiner_points, (long long)st_little.tets, (long long)st_full.steiner_points,
              (long long)st_full.tets);
  for (const TetMesh* mesh : {&m, &mf}) {
    const MeshCheckReport r = check_mesh(s, *mesh);
    EXPECT_TRUE(r.valid);
    for (const auto& msg : r.messages) ADD_FAILURE() << msg;
    EXPECT_EQ(r.boundary_steiner_points, 0);
  }
  EXPECT_EQ(m.xyz, again.xyz);
  EXPECT_EQ(m.tet, again.tet);
  EXPECT_GE(st_little.steiner_points, st_full.steiner_points);
  EXPECT_GT(st_little.steiner_points, st_full.steiner_points) << "joint needs the optional phases";
}

namespace {

// The first error of check_surface then tetrahedralize, one after the other ("" and kInternal
// when both pass).
std::pair<ErrorCode, std::string> sequential_error(const SurfaceMesh& s, const SurfaceCheckOptions& check) {
  try {
    SurfaceMesh c = s;
    c.tri = check_surface(s, check).tri;
    tetrahedralize(c);
  } catch (const Error& e) {
    return {e.code(), e.what()};
  }
  return {ErrorCode::kInternal, ""};
}

}  // namespace

// check_and_tetrahedralize runs the self-intersection search beside the core: same mesh as the
// check then the core, one after the other.
TEST(CheckAndTetrahedralize, SameMeshAsTheCheckThenTheCore) {
  for (const char* name : {"paper/dented_prism.off", "paper/schoenhardt.off", "corpus/pinion.off", "corpus/eight.off",
                           "corpus/td_spike-1-10.off", "corpus/fandisk.off" /* 12,946 triangles: searched on a thread */}) {
    const SurfaceMesh s = read_off(data(name));
    SurfaceCheckOptions check;
    check.reorient = true;  // td_spike needs it
    SurfaceMesh c = s;
    const SurfaceCheckResult r0 = check_surface(s, check);
    c.tri = r0.tri;
    const TetMesh sequential = tetrahedralize(c);
    SurfaceCheckResult r1;
    MeshStats st;
    const TetMesh together = check_and_tetrahedralize(s, check, {}, &st, &r1);
    EXPECT_EQ(together.xyz, sequential.xyz) << name;
    EXPECT_EQ(together.tet, sequential.tet) << name;
    EXPECT_EQ(r1.tri, r0.tri) << name;
    EXPECT_EQ(r1.flipped_triangles, r0.flipped_triangles) << name;
    EXPECT_EQ(st.tets, together.num_tets()) << name;
    EXPECT_TRUE(check_mesh(c, together).valid) << name;
  }
}

// Surfaces that cross themselves: the core meshes them meanwhile (and must neither crash nor loop:
// the sanitizer build runs this), and the reported error is the check's, as in sequence, also when
// a later step (shells facing inward) would fail too.
TEST(CheckAndTetrahedralize, SelfIntersectionWinsWhateverTheCoreDoes) {
  std::vector<std::pair<std::string, SurfaceMesh>> cases;
  cases.push_back({"corpus/box.off", read_off(data("corpus/box.off"))});
  cases.push_back({"corpus/cube_with_fold.off", read_off(data("corpus/cube_with_fold.off"))});
  SurfaceMesh overlapping;
  bsptet_test::add_box(overlapping, 0, 2);
  bsptet_test::add_box(overlapping, 1, 2);
  cases.push_back({"two overlapping cubes", overlapping});
  SurfaceMesh inward_too;
  bsptet_test::add_box(inward_too, 0, 2, /*inward=*/true);
  bsptet_test::add_box(inward_too, 1, 2, /*inward=*/true);
  cases.push_back({"two overlapping inward cubes", inward_too});
  for (const auto& [name, s] : cases) {
    const auto [code, message] = sequential_error(s, {});
    ASSERT_EQ(code, ErrorCode::kSelfIntersection) << name << ": " << message;
    try {
      check_and_tetrahedralize(s, {});
      ADD_FAILURE() << name << ": no error";
    } catch (const SelfIntersectionError& e) {
      EXPECT_EQ(std::string(e.what()), message) << name;
      EXPECT_FALSE(e.pairs().empty()) << name;
    }
    // The core alone (it validates the surface but does not look for crossings): a mesh or a typed
    // error, never a crash.
    SurfaceMesh c = s;
    try {
      tetrahedralize(c);
    } catch (const Error& e) {
      EXPECT_NE(e.code(), ErrorCode::kCancelled) << name << ": " << e.what();
    }
  }
  // Without crossings, a later step's error is reported as it is.
  SurfaceMesh inward;
  bsptet_test::add_box(inward, 0, 2, /*inward=*/true);
  try {
    check_and_tetrahedralize(inward, {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInwardFacing) << e.what();
  }
}

// The caller's cancellation still stops the core (the search's flag is added to it, not put in its
// place).
TEST(CheckAndTetrahedralize, CallerCancellationStillStops) {
  const SurfaceMesh s = read_off(data("corpus/pinion.off"));
  MeshOptions o;
  o.cancelled = [] { return true; };
  try {
    check_and_tetrahedralize(s, {}, o);
    ADD_FAILURE() << "no error";
  } catch (const MeshingError& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled);
  }
}
