// The quality stage: RefineMesh's local operations on hand-made meshes (each checked exactly, each
// refused when invalid), the driver on real data, and the tet10 Jacobian.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "bsptet/errors.h"
#include "bsptet/mesh_check.h"
#include "bsptet/mesh_io.h"
#include "bsptet/mesher.h"
#include "bsptet/quality_refine.h"
#include "bsptet/refine_mesh.h"
#include "bsptet/tet10.h"

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

TEST(Tet10, StraightTetJacobianIsSixTimesItsVolume) {
  const double v[4][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}, {0, 0, 5}};  // volume 5
  double x[30];
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) x[3 * k + c] = v[k][c];
  const int e[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (int i = 0; i < 6; ++i)
    for (int c = 0; c < 3; ++c) x[3 * (4 + i) + c] = 0.5 * (v[e[i][0]][c] + v[e[i][1]][c]);
  EXPECT_DOUBLE_EQ(tet10_min_jacobian(x), 30.0);
  // Pulling mid-node m12 across the opposite face makes the element invalid.
  x[3 * 4 + 0] = -20;
  EXPECT_LT(tet10_min_jacobian(x), 0);
}
