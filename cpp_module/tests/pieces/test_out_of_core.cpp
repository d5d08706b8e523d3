// SPDX-License-Identifier: LGPL-2.1-or-later
// The out-of-core mode (out_of_core.h) and its cuts (solid_cut.h): the two pieces of a cut bound
// the input's solid between them exactly, and the pieces' meshes, streamed into one file, make a
// mesh of the input that the exact checker accepts.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/exact_float.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/mesh/mesh_io.h"
#include "bsptet/core/mesher.h"
#include "bsptet/pieces/out_of_core.h"
#include "bsptet/pieces/solid_cut.h"
#include "bsptet/input/surface_check.h"

using namespace bsptet;

namespace {

std::string data(const std::string& rel) { return std::string(FEMBSPTET_DATA_DIR) + "/" + rel; }

// A scratch file stem of this process (ctest runs the tests as parallel processes).
std::string scratch(const std::string& name) {
  return (testing::TempDir().empty() ? std::string("/tmp/") : testing::TempDir()) + "bsptet_ooc_" +
         std::to_string(getpid()) + "_" + name;
}

bool exists(const std::string& path) { return std::ifstream(path).good(); }

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A torus around the z axis (radii R = 1, r = 0.4; n by m quads, two triangles each), outward.
SurfaceMesh torus(int n, int m) {
  SurfaceMesh s;
  const double pi = std::acos(-1.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double th = 2 * pi * i / n, ph = 2 * pi * j / m;
      s.xyz.insert(s.xyz.end(), {(1 + 0.4 * std::cos(ph)) * std::cos(th), (1 + 0.4 * std::cos(ph)) * std::sin(th),
                                 0.4 * std::sin(ph)});
    }
  auto id = [&](int i, int j) { return static_cast<Index>(((i + n) % n) * m + (j + m) % m); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) s.tri.insert(s.tri.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
  SurfaceCheckOptions o;
  o.reorient = true;
  s.tri = check_surface(s, o).tri;
  return s;
}

// Six times the signed volume of the closed surface `tri` over `xyz`, exactly.
ExactFloat six_volume(const std::vector<double>& xyz, const std::vector<Index>& tri) {
  ExactFloat sum;
  for (std::size_t t = 0; t < tri.size(); t += 3) {
    ExactFloat p[3][3];
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) p[k][a] = ExactFloat(xyz[3 * static_cast<std::size_t>(tri[t + k]) + a]);
    sum += p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
           p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
  }
  return sum;
}

double median_corner_sum(const SurfaceMesh& s, int axis) {
  std::vector<double> sums;
  for (std::size_t t = 0; t < s.tri.size(); t += 3) sums.push_back(corner_sum(s.xyz, &s.tri[t], axis));
  std::nth_element(sums.begin(), sums.begin() + static_cast<std::ptrdiff_t>(sums.size() / 2), sums.end());
  return sums[sums.size() / 2];
}

// Checks a cut's two pieces: each passes the surface check as it is, together they hold every
// input triangle once and every cap triangle once each way (exact volumes add up), and the caps
// use only input vertices and the cut's own points.
void expect_sound_cut(const SurfaceMesh& s, const SolidCut& cut) {
  ASSERT_TRUE(cut.ok) << cut.reason;
  std::vector<double> xyz = s.xyz;
  xyz.insert(xyz.end(), cut.new_points.begin(), cut.new_points.end());
  for (const std::vector<Index>* piece : {&cut.below, &cut.above}) {
    SurfaceMesh p;
    p.xyz = xyz;
    p.tri = *piece;
    EXPECT_NO_THROW(check_surface(p));
  }
  EXPECT_EQ(cut.below.size() + cut.above.size(), s.tri.size() + 6 * static_cast<std::size_t>(cut.cap_triangles));
  EXPECT_TRUE(six_volume(xyz, cut.below) + six_volume(xyz, cut.above) == six_volume(s.xyz, s.tri));
  EXPECT_GT(six_volume(xyz, cut.below).sign(), 0);
  EXPECT_GT(six_volume(xyz, cut.above).sign(), 0);
  std::size_t caps = 0;
  for (Index src : cut.below_source) caps += src < 0;
  EXPECT_EQ(static_cast<std::int64_t>(caps), cut.cap_triangles);
}

// Pieces of at most `max` triangles, cut down to 100.
PieceOptions pieces_of_at_most(std::int64_t max) {
  PieceOptions po;
  po.max_piece_triangles = max;
  po.min_piece_triangles = 100;
  return po;
}

// Meshes `s` in pieces of at most `max` triangles into `stem`, reads the mesh back and checks it
// exactly against the input surface.
MeshCheckReport mesh_in_pieces(const SurfaceMesh& s, std::int64_t max, const std::string& stem, PieceStats* ps) {
  tetrahedralize_in_pieces(s, MeshOptions{}, pieces_of_at_most(max), stem, ps);
  return check_mesh(s, read_tetgen(stem));
}

}  // namespace

TEST(SolidCut, MedianCutsOfASmoothSolidGivePiecesThatBoundItExactly) {
  const SurfaceMesh s = read_off(data("corpus/spot.off"));
  for (int axis = 0; axis < 3; ++axis) {
    SCOPED_TRACE(axis);
    const SolidCut cut = cut_solid(s.xyz, s.tri, axis, median_corner_sum(s, axis));
    expect_sound_cut(s, cut);
    EXPECT_GE(cut.loops, 1);
    EXPECT_GT(cut.cap_points, 0);  // the collar and the grid
  }
}

// Across the torus's axis the cross-section is a ring: its inner loop is a hole of the outer
// one's cap, bridged in.
TEST(SolidCut, ARingCrossSectionIsCappedWithItsHole) {
  const SurfaceMesh s = torus(96, 32);
  const SolidCut cut = cut_solid(s.xyz, s.tri, 2, median_corner_sum(s, 2));
  EXPECT_EQ(cut.loops, 2);
  expect_sound_cut(s, cut);
}

TEST(SolidCut, RefusesToCutWhenEveryTriangleIsOnOneSide) {
  const SurfaceMesh s = torus(24, 12);
  const SolidCut cut = cut_solid(s.xyz, s.tri, 0, -100.0);
  EXPECT_FALSE(cut.ok);
  EXPECT_NE(cut.reason.find("one side"), std::string::npos) << cut.reason;
}

TEST(SolidCut, EdgeNeighboursPairEveryEdgeOfAClosedSurface) {
  const SurfaceMesh s = torus(24, 12);
  const std::vector<Index> across = edge_neighbours(s.tri);
  for (std::size_t i = 0; i < across.size(); ++i) {
    ASSERT_GE(across[i], 0);
    const Index a = s.tri[i], b = s.tri[i / 3 * 3 + (i + 1) % 3];
    bool reversed = false;
    for (int k = 0; k < 3; ++k)
      reversed = reversed || (s.tri[3 * across[i] + k] == b && s.tri[3 * across[i] + (k + 1) % 3] == a);
    EXPECT_TRUE(reversed) << i;
  }
}

class PiecesOfModel : public ::testing::TestWithParam<const char*> {};

// The acceptance test of the mode: the pieces' meshes, streamed into one file, are one valid
// mesh of the input (the exact checker: conforming, positive tets, boundary = the input
// triangles, no Steiner point on the surface, the solid's exact volume).
TEST_P(PiecesOfModel, PiecesMergeIntoOneValidMeshOfTheInput) {
  const SurfaceMesh s = read_off(data(GetParam()));
  const std::string stem = scratch("model");
  PieceStats ps;
  const MeshCheckReport r = mesh_in_pieces(s, s.num_triangles() / 4, stem, &ps);
  EXPECT_TRUE(r.valid) << (r.messages.empty() ? "" : r.messages[0]);
  EXPECT_TRUE(r.volume_equal);
  EXPECT_EQ(r.boundary_steiner_points, 0);
  EXPECT_GE(ps.pieces, 4);
  EXPECT_TRUE(ps.uncut.empty()) << ps.uncut[0];
  EXPECT_TRUE(ps.pieces_checked);
  EXPECT_EQ(ps.tets, r.tets);
  std::remove((stem + ".node").c_str());
  std::remove((stem + ".ele").c_str());
}

INSTANTIATE_TEST_SUITE_P(Models, PiecesOfModel,
                         ::testing::Values("corpus/spot.off", "corpus/fertility.off", "corpus/knot2.off",
                                           "corpus/fandisk.off", "corpus/triceratops.off", "cad/bottle_freecad.off"));

TEST(OutOfCore, TorusPiecesMergeIntoOneValidMesh) {
  const SurfaceMesh s = torus(128, 48);
  const std::string stem = scratch("torus");
  PieceStats ps;
  const MeshCheckReport r = mesh_in_pieces(s, 2000, stem, &ps);
  EXPECT_TRUE(r.valid) << (r.messages.empty() ? "" : r.messages[0]);
  EXPECT_TRUE(r.volume_equal);
  EXPECT_GE(ps.pieces, 6);
  EXPECT_LE(ps.largest_piece_triangles, 2000);
  EXPECT_GT(ps.cap_points, 0);
  std::remove((stem + ".node").c_str());
  std::remove((stem + ".ele").c_str());
}

TEST(OutOfCore, SameInputSameFilesAndNoScratchLeft) {
  const SurfaceMesh s = read_off(data("corpus/spot.off"));
  const PieceOptions po = pieces_of_at_most(1500);
  const std::string a = scratch("det_a"), b = scratch("det_b");
  tetrahedralize_in_pieces(s, MeshOptions{}, po, a);
  tetrahedralize_in_pieces(s, MeshOptions{}, po, b);
  EXPECT_EQ(slurp(a + ".node"), slurp(b + ".node"));
  EXPECT_EQ(slurp(a + ".ele"), slurp(b + ".ele"));
  for (const char* ext : {".steiner.spool", ".tets.spool", ".node.part", ".ele.part"}) EXPECT_FALSE(exists(a + ext)) << ext;
  for (const std::string& stem : {a, b}) {
    std::remove((stem + ".node").c_str());
    std::remove((stem + ".ele").c_str());
  }
}

// Pieces meshed on threads at once give the files of one thread, byte for byte (the contract's
// determinism), for every number of workers.
TEST(OutOfCore, WorkersMeshThePiecesAtOnceIntoTheSameFiles) {
  const SurfaceMesh s = read_off(data("corpus/fertility.off"));
  PieceOptions po = pieces_of_at_most(s.num_triangles() / 5);
  const std::string one = scratch("workers_1");
  PieceStats ps1;
  tetrahedralize_in_pieces(s, MeshOptions{}, po, one, &ps1);
  ASSERT_GE(ps1.pieces, 5);
  for (int workers : {2, 3, 16}) {
    SCOPED_TRACE(workers);
    po.workers = workers;
    const std::string many = scratch("workers_n");
    PieceStats ps;
    tetrahedralize_in_pieces(s, MeshOptions{}, po, many, &ps);
    EXPECT_EQ(ps.pieces, ps1.pieces);
    EXPECT_TRUE(ps.pieces_checked);
    EXPECT_EQ(slurp(one + ".node"), slurp(many + ".node"));
    EXPECT_EQ(slurp(one + ".ele"), slurp(many + ".ele"));
    std::remove((many + ".node").c_str());
    std::remove((many + ".ele").c_str());
  }
  const MeshCheckReport r = check_mesh(s, read_tetgen(one));
  EXPECT_TRUE(r.valid) << (r.messages.empty() ? "" : r.messages[0]);
  std::remove((one + ".node").c_str());
  std::remove((one + ".ele").c_str());
}

// The public steps (cut_into_pieces, piece_surface, mesh_piece, merged_point_ids), as an engine
// that meshes the pieces elsewhere runs them, give tetrahedralize_in_pieces's mesh.
TEST(OutOfCore, TheStepsRunByHandGiveTheSameMesh) {
  const SurfaceMesh s = read_off(data("corpus/spot.off"));
  const PieceOptions po = pieces_of_at_most(1500);
  const std::string stem = scratch("steps");
  tetrahedralize_in_pieces(s, MeshOptions{}, po, stem);
  const TetMesh whole = read_tetgen(stem);
  const SolidPieces solid = cut_into_pieces(s, MeshOptions{}, po);
  ASSERT_GE(solid.pieces.size(), 2u);
  EXPECT_EQ(solid.input_points, s.num_points());
  const std::vector<Index> ids = merged_point_ids(solid);
  Index used = 0;
  for (Index id : ids) used = std::max(used, id + 1);
  TetMesh merged;
  merged.xyz.resize(3 * static_cast<std::size_t>(used));
  for (std::size_t g = 0; g < ids.size(); ++g)
    if (ids[g] >= 0) std::copy(&solid.xyz[3 * g], &solid.xyz[3 * g + 3], &merged.xyz[3 * static_cast<std::size_t>(ids[g])]);
  for (std::size_t p = 0; p < solid.pieces.size(); ++p) {
    std::vector<Index> globals;
    const SurfaceMesh local = piece_surface(solid.xyz, solid.pieces[p], globals);
    const TetMesh m = mesh_piece(local, MeshOptions{}, true, "piece");
    const Index nloc = local.num_points(), first_steiner = merged.num_points();
    merged.xyz.insert(merged.xyz.end(), m.xyz.begin() + 3 * nloc, m.xyz.end());
    for (Index v : m.tet) merged.tet.push_back(v < nloc ? ids[globals[v]] : first_steiner + v - nloc);
  }
  EXPECT_EQ(merged.xyz, whole.xyz);
  EXPECT_EQ(merged.tet, whole.tet);
  std::remove((stem + ".node").c_str());
  std::remove((stem + ".ele").c_str());
}

// A run that stops (cancelled after its first piece, or refused) leaves the previous files as
// they were and no scratch file.
TEST(OutOfCore, AStoppedRunLeavesThePreviousMeshAlone) {
  const SurfaceMesh s = read_off(data("corpus/spot.off"));
  const std::string stem = scratch("stopped");
  std::ofstream(stem + ".node") << "previous node\n";
  std::ofstream(stem + ".ele") << "previous ele\n";
  const PieceOptions po = pieces_of_at_most(1500);
  MeshOptions o;
  int pieces_started = 0;
  o.progress = [&](const std::string& stage, double) {
    if (stage.rfind("piece ", 0) == 0 && stage.find("checking the input") != std::string::npos) ++pieces_started;
  };
  o.cancelled = [&] { return pieces_started >= 2; };
  try {
    tetrahedralize_in_pieces(s, o, po, stem);
    FAIL() << "not cancelled";
  } catch (const MeshingError& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled);
  }
  MeshOptions bad;
  bad.allow_boundary_steiner = true;
  EXPECT_THROW(tetrahedralize_in_pieces(s, bad, po, stem), InputError);
  EXPECT_EQ(slurp(stem + ".node"), "previous node\n");
  EXPECT_EQ(slurp(stem + ".ele"), "previous ele\n");
  for (const char* ext : {".steiner.spool", ".tets.spool", ".node.part", ".ele.part"}) EXPECT_FALSE(exists(stem + ext)) << ext;
  std::remove((stem + ".node").c_str());
  std::remove((stem + ".ele").c_str());
}

TEST(OutOfCore, PieceSizeFollowsTheBudget) {
  EXPECT_EQ(piece_triangles_for_budget(1), 1000);
  EXPECT_GT(piece_triangles_for_budget(1LL << 30), 400000);
  EXPECT_LE(estimated_core_peak_bytes(piece_triangles_for_budget(1LL << 30)), 1LL << 30);
}
