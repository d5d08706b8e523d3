// The tetrahedralizer on the paper's polyhedra and on small generated solids: every output is
// checked by the exact checker.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "bsptet/errors.h"
#include "bsptet/mesh_check.h"
#include "bsptet/mesh_io.h"
#include "bsptet/mesher.h"

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
// Steiner counts are printed beside the paper's and TetGen's, and must not exceed TetGen's (issue 3;
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
