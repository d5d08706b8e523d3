// SPDX-License-Identifier: LGPL-2.1-or-later
// The FEM pipeline from CAD (fem/fem_mesh.h, fem/fem_faces.h) and the CAD projection hook
// (cad/cad_projection.h).
// Every mesh is held to invariants: checked exactly (positive tets, conforming faces, closed
// boundary, consistent mid-nodes), every 10-node tet certified valid, the boundary equal to the
// triangles of the faces no two solids share, every CAD face and solid present, per-solid volumes
// near the CAD's, and every node of a face triangle on its CAD face within 1e-6 of the diagonal
// plus the face's tolerance. Models: two STEP files of tests/data/cad and shapes built here with
// OpenCASCADE (a general fuse of a box and a ball: solids sharing curved faces; a box, ball, box
// compound whose solids touch at points).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <BRepAlgoAPI_BuilderAlgo.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Pnt.hxx>

#include "bsptet/cad/cad_model.h"
#include "bsptet/cad/cad_projection.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/fem/fem_faces.h"
#include "bsptet/fem/fem_mesh.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/core/mesher.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/tet10.h"

using namespace bsptet;

namespace {

std::string data(const std::string& rel) { return std::string(FEMBSPTET_DATA_DIR) + "/" + rel; }

double norm(const Vec3& a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

/// A box [0, 10]^3 and a ball of radius 4 centred on its face x = 10, cut against each other
/// (OpenCASCADE's general fuse): three solids (box without the ball, the half ball inside, the half
/// ball outside) that share a spherical cap and a disc.
cad::CadModel box_and_ball() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 10, 10, 10).Shape();
  const TopoDS_Shape ball = BRepPrimAPI_MakeSphere(gp_Pnt(10, 5, 5), 4).Shape();
  TopTools_ListOfShape args;
  args.Append(box);
  args.Append(ball);
  BRepAlgoAPI_BuilderAlgo fuse;
  fuse.SetArguments(args);
  fuse.Build();
  EXPECT_TRUE(fuse.IsDone());
  return cad::make_cad_model(fuse.Shape(), "box and ball (general fuse)");
}

/// Boxes [-15, -5] x [-5, 5]^2 and [5, 15] x [-5, 5]^2 and a ball of radius 5 at the origin, put
/// in one compound without any cut: each box touches the ball at one point.
cad::CadModel box_ball_box() {
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  builder.Add(compound, BRepPrimAPI_MakeBox(gp_Pnt(-15, -5, -5), 10, 10, 10).Shape());
  builder.Add(compound, BRepPrimAPI_MakeSphere(gp_Pnt(0, 0, 0), 5).Shape());
  builder.Add(compound, BRepPrimAPI_MakeBox(gp_Pnt(5, -5, -5), 10, 10, 10).Shape());
  return cad::make_cad_model(compound, "box, ball, box");
}

std::array<Index, 3> sorted3(Index a, Index b, Index c) {
  std::array<Index, 3> k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

/// The invariants every FEM mesh of `model` must meet (file comment).
void expect_valid_fem_mesh(const cad::CadModel& model, const fem::FemMesh& fm, const fem::FemStats& st, int order) {
  const TetMesh& m = fm.mesh;
  const int npt = order == 2 ? 10 : 4;
  ASSERT_EQ(m.nodes_per_tet, npt);
  ASSERT_EQ(fm.nodes_per_triangle, order == 2 ? 6 : 3);
  ASSERT_GT(m.num_tets(), 0);
  ASSERT_EQ(fm.tet_solid.size(), static_cast<std::size_t>(m.num_tets()));
  ASSERT_EQ(fm.tri.size(), fm.tri_face.size() * static_cast<std::size_t>(fm.nodes_per_triangle));
  EXPECT_EQ(st.tets, m.num_tets());
  EXPECT_EQ(st.nodes, m.num_points());

  // Exactly: positive tets, conforming faces, closed boundary, one mid-node per edge.
  const SurfaceMesh boundary = boundary_surface(m);
  const MeshCheckReport rep = check_mesh(boundary, m);
  EXPECT_TRUE(rep.valid) << (rep.messages.empty() ? std::string("?") : rep.messages.front());
  EXPECT_EQ(rep.inverted_tets + rep.flat_tets, 0);
  EXPECT_EQ(rep.duplicate_points, 0);
  EXPECT_EQ(rep.inconsistent_midnodes, 0);

  // Curved tets: every one certified valid.
  if (order == 2) {
    std::int64_t not_certified = 0;
    for (Index k = 0; k < m.num_tets(); ++k) {
      double x[30];
      for (int i = 0; i < 10; ++i) {
        const Vec3 p = m.point(m.tet[static_cast<std::size_t>(10 * k + i)]);
        x[3 * i] = p.x, x[3 * i + 1] = p.y, x[3 * i + 2] = p.z;
      }
      if (certify_tet10(x) != Tet10Validity::kCertified) ++not_certified;
    }
    EXPECT_EQ(not_certified, 0);
  }

  // Every CAD face has triangles; the mesh's boundary is exactly the triangles of the faces that
  // bound one solid, and the triangles of shared faces are interior faces.
  std::vector<int> solids_of_face(static_cast<std::size_t>(model.num_faces()), 0);
  for (int s = 1; s <= model.num_solids(); ++s) {
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(model.solids(s), TopAbs_FACE, faces);
    for (int f = 1; f <= faces.Extent(); ++f) ++solids_of_face[static_cast<std::size_t>(model.face_index(faces(f)))];
  }
  std::set<std::array<Index, 3>> outer, mesh_boundary;
  std::vector<char> face_seen(static_cast<std::size_t>(model.num_faces()), 0);
  const int npf = fm.nodes_per_triangle;
  for (Index t = 0; t < fm.num_triangles(); ++t) {
    const Index* c = &fm.tri[static_cast<std::size_t>(npf * t)];
    const int f = fm.tri_face[static_cast<std::size_t>(t)];
    ASSERT_GE(f, 0);
    ASSERT_LT(f, model.num_faces());
    face_seen[static_cast<std::size_t>(f)] = 1;
    if (solids_of_face[static_cast<std::size_t>(f)] == 1) outer.insert(sorted3(c[0], c[1], c[2]));
  }
  for (int f = 0; f < model.num_faces(); ++f) EXPECT_TRUE(face_seen[static_cast<std::size_t>(f)]) << "Face" << f + 1;
  for (Index t = 0; t < boundary.num_triangles(); ++t) {
    const Index* c = &boundary.tri[static_cast<std::size_t>(3 * t)];
    mesh_boundary.insert(sorted3(c[0], c[1], c[2]));
  }
  EXPECT_EQ(outer, mesh_boundary);
  EXPECT_EQ(outer.size(), static_cast<std::size_t>(boundary.num_triangles()));

  // Every solid has tets, and their volume is near the solid's (chords cut a little off curved
  // faces at order 1: a circle of 12 segments loses 4.5 % of its area).
  std::vector<double> volume(static_cast<std::size_t>(model.num_solids()), 0.0);
  for (Index k = 0; k < m.num_tets(); ++k) {
    const Index* q = &m.tet[static_cast<std::size_t>(npt * k)];
    const Vec3 a = m.point(q[0]), b = m.point(q[1]), c = m.point(q[2]), d = m.point(q[3]);
    const double u[3] = {b.x - a.x, b.y - a.y, b.z - a.z}, v[3] = {c.x - a.x, c.y - a.y, c.z - a.z},
                 w[3] = {d.x - a.x, d.y - a.y, d.z - a.z};
    const double det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                       u[2] * (v[0] * w[1] - v[1] * w[0]);
    const int s = fm.tet_solid[static_cast<std::size_t>(k)];
    ASSERT_GE(s, 0);
    ASSERT_LT(s, model.num_solids());
    volume[static_cast<std::size_t>(s)] += det / 6;
  }
  for (int s = 0; s < model.num_solids(); ++s) {
    GProp_GProps props;
    BRepGProp::VolumeProperties(model.solids(s + 1), props);
    const double cad_volume = std::abs(props.Mass());
    EXPECT_NEAR(volume[static_cast<std::size_t>(s)], cad_volume, 0.06 * cad_volume) << "Solid" << s + 1;
  }

  // Every node of a face triangle (corners and, at order 2, mid-nodes) on its CAD face.
  double tolerance = 0;
  for (int f = 0; f < model.num_faces(); ++f) tolerance = std::max(tolerance, cad::face_tolerance(model, f));
  tolerance += 1e-6 * model.diagonal();
  const fem::CadDistance d = fem::measure_cad_distance(model, fm);
  EXPECT_GT(d.pairs, 0);
  EXPECT_LE(d.max_corner, tolerance) << "node " << d.worst_node << " Face" << d.worst_face + 1;
  EXPECT_LE(d.max_midnode, tolerance) << "node " << d.worst_node << " Face" << d.worst_face + 1;
}

}  // namespace

// ---- What keeps shared faces conforming: RefineOptions::fixed_tags. ----

TEST(RefineFixedTags, FixedFacesKeepTheirTrianglesOthersAreRefined) {
  // The unit cube, two triangles per side, side k tagged k (outward, counter-clockwise).
  SurfaceMesh cube;
  cube.xyz = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
  cube.tri = {0, 2, 1, 0, 3, 2,  4, 5, 6, 4, 6, 7,  0, 1, 5, 0, 5, 4,
              1, 2, 6, 1, 6, 5,  2, 3, 7, 2, 7, 6,  3, 0, 4, 3, 4, 7};
  cube.tag = {0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5};
  const TetMesh core = tetrahedralize(cube);
  RefineOptions o;
  o.size = 0.25;
  o.surface_points = SurfacePoints::kRounded;  // midpoints of these edges are exact: checkable below
  o.fixed_tags = {0, 3};
  RefineStats st;
  SurfaceMesh boundary;
  const TetMesh out = refine_quality(cube, core, o, &st, &boundary);
  EXPECT_TRUE(check_mesh(cube, out).valid);
  EXPECT_GT(st.surface_splits, 0);
  EXPECT_GT(st.splits_fixed_surface, 0);
  // Sides 0 and 3 are their two input triangles still (input points keep their indices); every
  // other side has more.
  std::map<std::int32_t, std::set<std::array<Index, 3>>> by_tag;
  for (Index t = 0; t < boundary.num_triangles(); ++t) {
    const Index* c = &boundary.tri[static_cast<std::size_t>(3 * t)];
    by_tag[boundary.tag[static_cast<std::size_t>(t)]].insert(sorted3(c[0], c[1], c[2]));
  }
  for (std::int32_t tag : {0, 3}) {
    std::set<std::array<Index, 3>> input;
    for (Index t = 0; t < cube.num_triangles(); ++t)
      if (cube.tag[static_cast<std::size_t>(t)] == tag)
        input.insert(sorted3(cube.tri[3 * t], cube.tri[3 * t + 1], cube.tri[3 * t + 2]));
    EXPECT_EQ(by_tag[tag], input) << "side " << tag;
  }
  for (std::int32_t tag : {1, 2, 4, 5}) EXPECT_GT(by_tag[tag].size(), 2u) << "side " << tag;
}

// ---- The projection hook. ----

TEST(CadProjection, CylinderFacesEdgesAndTrim) {
  // Cylinder of radius 5, height 10 on the z axis: a side face and two discs.
  const cad::CadModel model =
      cad::make_cad_model(BRepPrimAPI_MakeCylinder(5, 10).Shape(), "cylinder r 5 h 10");
  ASSERT_EQ(model.num_faces(), 3);
  int side = -1, top = -1;
  for (int f = 0; f < 3; ++f) {
    GProp_GProps props;
    BRepGProp::SurfaceProperties(model.faces(f + 1), props);
    if (std::abs(props.Mass() - 2 * M_PI * 5 * 10) < 1e-6) side = f;
    if (std::abs(props.CentreOfMass().Z() - 10) < 1e-9 && std::abs(props.Mass() - M_PI * 25) < 1e-6) top = f;
  }
  ASSERT_GE(side, 0);
  ASSERT_GE(top, 0);
  std::shared_ptr<cad::CadProjector> projector;
  const ProjectionHook hook = cad::make_projection_hook(model, &projector);

  // Onto the side: radius 5 at the same height and angle.
  const Vec3 p = hook({4.9, 0.3, 3.0}, side, -1);
  EXPECT_NEAR(std::hypot(p.x, p.y), 5.0, 1e-9);
  EXPECT_NEAR(p.z, 3.0, 1e-9);
  EXPECT_NEAR(std::atan2(p.y, p.x), std::atan2(0.3, 4.9), 1e-9);
  EXPECT_NEAR(cad::distance_to_face(model, side, p), 0.0, 1e-7);
  // Same tag twice: the same as one face.
  const Vec3 p2 = hook({4.9, 0.3, 3.0}, side, side);
  EXPECT_EQ(p.x, p2.x);
  EXPECT_EQ(p.y, p2.y);
  EXPECT_EQ(p.z, p2.z);

  // Onto the common edge of the side and the top: the circle of radius 5 at z = 10, whichever
  // order the tags come in.
  const Vec3 e = hook({3.0, 3.5, 9.9}, side, top);
  EXPECT_NEAR(std::hypot(e.x, e.y), 5.0, 1e-9);
  EXPECT_NEAR(e.z, 10.0, 1e-9);
  const Vec3 e2 = hook({3.0, 3.5, 9.9}, top, side);
  EXPECT_NEAR(norm({e.x - e2.x, e.y - e2.y, e.z - e2.z}), 0.0, 1e-12);
  EXPECT_NEAR(cad::distance_to_face(model, side, e), 0.0, 1e-7);
  EXPECT_NEAR(cad::distance_to_face(model, top, e), 0.0, 1e-7);
  ASSERT_EQ(projector->common_edges(side, top).size(), 1u);

  // A point of the top's plane outside its disc: the hook refuses it (NaN); to_face gives the
  // nearest point of the bounded face, on its rim.
  const Vec3 out = hook({6.0, 0.0, 10.0}, top, -1);
  EXPECT_TRUE(std::isnan(out.x) && std::isnan(out.y) && std::isnan(out.z));
  bool inside = true;
  const Vec3 rim = projector->to_face({6.0, 0.0, 10.0}, top, &inside);
  EXPECT_FALSE(inside);
  EXPECT_NEAR(rim.x, 5.0, 1e-7);
  EXPECT_NEAR(rim.z, 10.0, 1e-7);
  EXPECT_GE(projector->stats().outside_trim, 1);
  // Inside the disc: onto the plane.
  const Vec3 in = hook({1.0, 2.0, 10.25}, top, -1);
  EXPECT_DOUBLE_EQ(in.z, 10.0);
  EXPECT_NEAR(in.x, 1.0, 1e-12);

  EXPECT_THROW(hook({0, 0, 0}, 3, -1), InputError);
  EXPECT_THROW(hook({0, 0, 0}, side, 7), InputError);
  EXPECT_THROW(hook({0, 0, 0}, -1, -1), InputError);
}

// ---- The pipeline. ----

TEST(CadPipeline, BadOptionsAreInputErrors) {
  const cad::CadModel model = cad::read_cad_file(data("cad/red_cube_blue_cylinder.step"));
  fem::FemOptions o;
  o.order = 3;
  EXPECT_THROW(fem::mesh_cad_model(model, o), InputError);
  o.order = 1;
  o.size = -1;
  EXPECT_THROW(fem::mesh_cad_model(model, o), InputError);
  o.size = 0;
  o.size_by_face[0] = 0;
  EXPECT_THROW(fem::mesh_cad_model(model, o), InputError);
  o.size_by_face.clear();
  o.workers = -1;
  EXPECT_THROW(fem::mesh_cad_model(model, o), InputError);
}

class CadPipelineOrder : public ::testing::TestWithParam<int> {};

TEST_P(CadPipelineOrder, RedCubeBlueCylinder) {
  const cad::CadModel model = cad::read_cad_file(data("cad/red_cube_blue_cylinder.step"));
  fem::FemOptions o;
  o.order = GetParam();
  fem::FemStats st;
  const fem::FemMesh fm = fem::mesh_cad_model(model, o, &st);
  expect_valid_fem_mesh(model, fm, st, o.order);
  EXPECT_EQ(st.solids, 2);
  EXPECT_EQ(st.shared_faces, 0);
  for (int s = 0; s < 2; ++s) EXPECT_NE(std::count(fm.tet_solid.begin(), fm.tet_solid.end(), s), 0);
}

TEST_P(CadPipelineOrder, Bracket) {
  const cad::CadModel model = cad::read_cad_file(data("cad/bracket.step"));
  fem::FemOptions o;
  o.order = GetParam();
  fem::FemStats st;
  const fem::FemMesh fm = fem::mesh_cad_model(model, o, &st);
  expect_valid_fem_mesh(model, fm, st, o.order);
  EXPECT_EQ(st.solids, 1);
}

TEST_P(CadPipelineOrder, SolidsSharingCurvedFacesConform) {
  const cad::CadModel model = box_and_ball();
  ASSERT_EQ(model.num_solids(), 3);
  fem::FemOptions o;
  o.order = GetParam();
  fem::FemStats st;
  const fem::FemMesh fm = fem::mesh_cad_model(model, o, &st);
  EXPECT_EQ(st.shared_faces, 2);  // the cap inside the box and the disc on its face
  expect_valid_fem_mesh(model, fm, st, o.order);
  for (int s = 0; s < 3; ++s) EXPECT_NE(std::count(fm.tet_solid.begin(), fm.tet_solid.end(), s), 0);
}

TEST_P(CadPipelineOrder, SolidsTouchingAtPoints) {
  const cad::CadModel model = box_ball_box();
  ASSERT_EQ(model.num_solids(), 3);
  fem::FemOptions o;
  o.order = GetParam();
  fem::FemStats st;
  const fem::FemMesh fm = fem::mesh_cad_model(model, o, &st);
  EXPECT_EQ(st.shared_faces, 0);
  expect_valid_fem_mesh(model, fm, st, o.order);
}

// FemOptions::workers solids at a time, each on its own thread: the same mesh, array for array,
// for 1, 2 and 3 workers (three solids that share a curved cap and a disc).
TEST_P(CadPipelineOrder, SolidsMeshedAtTheSameTimeGiveTheSameMesh) {
  const cad::CadModel model = box_and_ball();
  std::vector<fem::FemMesh> meshes;
  for (int workers : {1, 2, 3}) {
    fem::FemOptions o;
    o.order = GetParam();
    o.workers = workers;
    fem::FemStats st;
    meshes.push_back(fem::mesh_cad_model(model, o, &st));
    if (workers == 2) expect_valid_fem_mesh(model, meshes.back(), st, o.order);
  }
  for (std::size_t i = 1; i < meshes.size(); ++i) {
    EXPECT_EQ(meshes[i].mesh.xyz, meshes[0].mesh.xyz);
    EXPECT_EQ(meshes[i].mesh.tet, meshes[0].mesh.tet);
    EXPECT_EQ(meshes[i].tet_solid, meshes[0].tet_solid);
    EXPECT_EQ(meshes[i].tri, meshes[0].tri);
    EXPECT_EQ(meshes[i].tri_face, meshes[0].tri_face);
  }
}

// A model of one solid big enough is cut by a plane (cad/cad_split.h) and its pieces meshed at
// the same time: the mesh is one solid's (every tet Solid1, every face triangle on one of the
// model's faces, the boundary exactly those triangles: nothing left of the cut), valid and on the
// CAD as any, the cut's nodes smoothed once merged, and the same for 1 and 2 workers.
TEST_P(CadPipelineOrder, OneBigSolidIsCutAndItsPiecesMergeIntoOneMesh) {
  const cad::CadModel model = cad::read_cad_file(data("cad/bracket.step"));
  std::vector<fem::FemMesh> meshes;
  for (int workers : {1, 2}) {
    fem::FemOptions o;
    o.order = GetParam();
    o.size = model.diagonal() / 40;
    o.workers = workers;
    fem::FemStats st;
    meshes.push_back(fem::mesh_cad_model(model, o, &st));
    EXPECT_EQ(st.solids, 1);
    EXPECT_GE(st.pieces, 2);
    EXPECT_GT(st.cut_nodes_smoothed, 0);
    EXPECT_EQ(st.faces, model.num_faces());
    EXPECT_EQ(st.shared_faces, 0);
    expect_valid_fem_mesh(model, meshes.back(), st, o.order);
    EXPECT_EQ(std::count(meshes.back().tet_solid.begin(), meshes.back().tet_solid.end(), 0),
              static_cast<std::ptrdiff_t>(meshes.back().tet_solid.size()));
    EXPECT_EQ(meshes.back().face_names, model.face_names);
    EXPECT_EQ(meshes.back().solid_names, model.solid_names);
  }
  EXPECT_EQ(meshes[1].mesh.xyz, meshes[0].mesh.xyz);
  EXPECT_EQ(meshes[1].mesh.tet, meshes[0].mesh.tet);
  EXPECT_EQ(meshes[1].tri, meshes[0].tri);
  EXPECT_EQ(meshes[1].tri_face, meshes[0].tri_face);
}

INSTANTIATE_TEST_SUITE_P(Orders, CadPipelineOrder, ::testing::Values(1, 2),
                         [](const ::testing::TestParamInfo<int>& info) { return "order" + std::to_string(info.param); });

// The bracket and the red cube with the blue cylinder have no CAD angle under 10 degrees (their
// faces meet and their face corners turn at right angles): at the default size (diagonal / 20)
// their tet10 meshes have no tet under 10 degrees. The refinement's stage figures
// (RefineStats::worst_deg_*) agree with the mesh: its end is the mesh's worst (the merge and the
// second order keep the refined corners), and the last polish (curved_room.h) only ever raises
// the worst tet it changes.
TEST(CadPipeline, NoTetUnderTenDegreesWhereTheCadHasNoSharpAngle) {
  for (const char* part : {"cad/bracket.step", "cad/red_cube_blue_cylinder.step"}) {
    const cad::CadModel model = cad::read_cad_file(data(part));
    fem::FemOptions o;
    o.order = 2;
    fem::FemStats st;
    const fem::FemMesh fm = fem::mesh_cad_model(model, o, &st);
    ASSERT_GT(fm.mesh.num_tets(), 0) << part;
    EXPECT_GE(st.min_dihedral_deg, 10.0) << part;
    EXPECT_EQ(st.tets_below_10_deg, 0.0) << part;
    EXPECT_EQ(st.refine_worst_deg, st.min_dihedral_deg) << part;
    EXPECT_GE(st.refine_worst_deg, st.refine_worst_deg_optimized) << part;
    EXPECT_LT(st.refine_worst_deg_optimized, 180.0) << part;
  }
}

// Smoothing slides the CAD nodes inside a face along it (the mesh's first nodes are the CAD
// surface's, mesh_cad_model's numbering); nodes on CAD edges and vertices, and every node of a
// face two solids share, stay where the surface mesher put them. Where the moved nodes lie is
// checked by expect_valid_fem_mesh (on their CAD face within its tolerance).
TEST(CadPipeline, NodesInsideFacesSlideOthersStay) {
  struct Case {
    cad::CadModel model;
    bool has_shared;
  };
  std::vector<Case> cases;
  cases.push_back({cad::read_cad_file(data("cad/bracket.step")), false});
  cases.push_back({box_and_ball(), true});
  for (const Case& c : cases) {
    fem::FemOptions o;
    o.order = 2;
    fem::FemStats st;
    const fem::FemMesh fm = fem::mesh_cad_model(c.model, o, &st);
    expect_valid_fem_mesh(c.model, fm, st, o.order);
    const cad::CadSurface surface = cad::mesh_cad_surface(c.model, fem::cad_surface_options(o));
    std::vector<int> solids_of_face(static_cast<std::size_t>(c.model.num_faces()), 0);
    for (const auto& tags : surface.solid_tag) {
      std::set<std::int32_t> faces(tags.begin(), tags.end());
      for (std::int32_t f : faces) ++solids_of_face[static_cast<std::size_t>(f)];
    }
    std::int64_t inside = 0, slid = 0, shared_inside = 0;
    for (std::size_t i = 0; i < surface.node_dim.size(); ++i) {
      const Vec3 cad{surface.xyz[3 * i], surface.xyz[3 * i + 1], surface.xyz[3 * i + 2]};
      const Vec3 now = fm.mesh.point(static_cast<Index>(i));
      const bool moved = cad.x != now.x || cad.y != now.y || cad.z != now.z;
      const bool shared = surface.node_dim[i] == 2 && solids_of_face[static_cast<std::size_t>(surface.node_entity[i])] > 1;
      if (surface.node_dim[i] != 2 || shared) {
        EXPECT_FALSE(moved) << c.model.source << ": node " << i << " (dimension " << int(surface.node_dim[i])
                            << (shared ? ", on a shared face" : "") << ") moved";
        shared_inside += shared;
      } else {
        ++inside;
        slid += moved;
      }
    }
    // Most nodes inside faces move a little: the surface mesher's layout is not the volume's best.
    EXPECT_GT(slid, inside / 4) << c.model.source << ": " << slid << " of " << inside;
    EXPECT_EQ(shared_inside > 0, c.has_shared) << c.model.source;
  }
}

TEST(CadPipeline, CancelledRunThrows) {
  const cad::CadModel model = cad::read_cad_file(data("cad/red_cube_blue_cylinder.step"));
  fem::FemOptions o;
  int polls = 0;
  o.cancelled = [&] { return ++polls > 3; };
  try {
    fem::mesh_cad_model(model, o);
    FAIL() << "not cancelled";
  } catch (const MeshingError& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled);
  }
}

// The OCCT tutorial bottle at tet10 (default size, h = diagonal / 20): its thread's narrow
// B-spline flanks and the fillets along them give curved tets that are not valid with their
// mid-nodes just projected (an interior apex below a curved face's sag, needle faces whose curved
// long edge tilts past the short one, tets with two faces on tangent-continuous CAD faces). Every
// one is mended by the tet10 lift (tet10.h): no mid-node is left on its chord, every boundary
// mid-node lies on its CAD face within that face's tolerance, and every tet is certified valid.
TEST(CadPipeline, BottleTet10MidNodesOnTheirFaces) {
  const cad::CadModel model = cad::read_cad_file(data("cad/bottle.brep"));
  fem::FemOptions o;
  o.order = 2;
  fem::FemStats st;
  const fem::FemMesh fm = fem::mesh_cad_model(model, o, &st);
  const TetMesh& m = fm.mesh;
  EXPECT_EQ(st.midnodes_straightened, 0);
  EXPECT_EQ(st.midnodes_straightened_at_merge, 0);
  EXPECT_GT(st.midnodes_relaxed_tets, 0);  // the case this test is about

  const MeshCheckReport rep = check_mesh(boundary_surface(m), m);
  EXPECT_TRUE(rep.valid) << (rep.messages.empty() ? std::string("?") : rep.messages.front());
  EXPECT_EQ(rep.inverted_tets + rep.flat_tets, 0);
  EXPECT_EQ(rep.inconsistent_midnodes, 0);
  std::int64_t not_certified = 0;
  for (Index k = 0; k < m.num_tets(); ++k) {
    double x[30];
    for (int i = 0; i < 10; ++i) {
      const Vec3 p = m.point(m.tet[static_cast<std::size_t>(10 * k + i)]);
      x[3 * i] = p.x, x[3 * i + 1] = p.y, x[3 * i + 2] = p.z;
    }
    if (certify_tet10(x) != Tet10Validity::kCertified) ++not_certified;
  }
  EXPECT_EQ(not_certified, 0);

  // Every mid-node of a face triangle against its face. Two measures, each the distance to a
  // point of the face, so each at least the true distance: the nearest point of the trimmed
  // surface (cad_projection.h to_face), and, when that is over the face's tolerance,
  // BRepExtrema_DistShapeShape (what FreeCAD's getNodesByFace and distToShape use; it also
  // measures to the face's edges, whose 3D curves may lie off the surface by their tolerance).
  // The smaller one counts: BRepExtrema may stop at a local minimum on the thread's B-spline
  // flanks (0.026 mm for a point the surface projection puts at 0).
  std::set<std::pair<Index, int>> pairs;
  for (Index t = 0; t < fm.num_triangles(); ++t)
    for (int e = 3; e < 6; ++e) pairs.insert({fm.tri[static_cast<std::size_t>(6 * t + e)], fm.tri_face[static_cast<std::size_t>(t)]});
  ASSERT_FALSE(pairs.empty());
  cad::CadProjector projector(model);
  std::int64_t off_face = 0;
  double worst = 0;
  for (const auto& [node, face] : pairs) {
    const Vec3 p = m.point(node);
    const Vec3 q = projector.to_face(p, face);
    double d = norm({p.x - q.x, p.y - q.y, p.z - q.z});
    const double tolerance = cad::face_tolerance(model, face);
    if (d > tolerance) d = std::min(d, cad::distance_to_face(model, face, p));
    worst = std::max(worst, d);
    if (d > tolerance) ++off_face;
  }
  EXPECT_EQ(off_face, 0) << "largest distance " << worst;
}

// ---- 2D: the CAD faces as triangles (fem/fem_faces.h). ----

/// A cylinder's side face alone (no solid): a surface mesh whose every node, tria6 mid-nodes
/// included, lies on the cylinder (radius 5) within the CAD's precision, whose triangles cover
/// the face's area, all turned the way the face is, and no curved triangle needed straightening.
TEST(CadFaces, CylinderSideFaceTria6OnTheSurface) {
  const TopoDS_Shape cylinder = BRepPrimAPI_MakeCylinder(5, 10).Shape();
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(cylinder, TopAbs_FACE, faces);
  const TopoDS_Shape side = faces(1);  // the lateral face
  EXPECT_THROW(cad::make_cad_model(side, "side"), InputError);  // no solid: no volume mesh
  const cad::CadModel model = cad::make_cad_model(side, "side", cad::CadContent::kFaces);
  for (int order : {1, 2}) {
    fem::FemOptions o;
    o.size = 2;
    o.order = order;
    fem::FemStats st;
    const fem::FemMesh m = fem::mesh_cad_faces(model, o, &st);
    ASSERT_EQ(m.nodes_per_triangle, order == 1 ? 3 : 6);
    EXPECT_EQ(m.mesh.num_tets(), 0);
    ASSERT_GT(m.num_triangles(), 50);
    EXPECT_EQ(st.midnodes_straightened, 0);
    auto P = [&](Index v) { return Vec3{m.mesh.xyz[3 * v], m.mesh.xyz[3 * v + 1], m.mesh.xyz[3 * v + 2]}; };
    double area = 0;
    for (Index t = 0; t < m.num_triangles(); ++t) {
      const Index* n = &m.tri[static_cast<std::size_t>(m.nodes_per_triangle * t)];
      EXPECT_EQ(m.tri_face[static_cast<std::size_t>(t)], 0);
      for (int k = 0; k < m.nodes_per_triangle; ++k) {
        const Vec3 p = P(n[k]);
        EXPECT_NEAR(std::hypot(p.x, p.y), 5.0, 1e-9) << "node " << n[k];
        EXPECT_GE(p.z, -1e-12);
        EXPECT_LE(p.z, 10 + 1e-12);
      }
      const Vec3 a = P(n[0]), b = P(n[1]), c = P(n[2]);
      const Vec3 u{b.x - a.x, b.y - a.y, b.z - a.z}, v{c.x - a.x, c.y - a.y, c.z - a.z};
      const Vec3 normal{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
      area += 0.5 * norm(normal);
      // the cylinder's face normal points away from the axis: every triangle agrees
      const Vec3 centre{(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3, 0};
      EXPECT_GT(normal.x * centre.x + normal.y * centre.y, 0) << "triangle " << t;
    }
    // chords inside the circle: the area is a little below 2 pi r h, never above
    EXPECT_LT(area, 2 * M_PI * 5 * 10);
    EXPECT_GT(area, 0.97 * 2 * M_PI * 5 * 10);
  }
}

/// An open box (five faces of a cube, a Shell with a free border): the mesh is conforming along
/// the CAD edges the faces share (every triangle edge is used twice, except along the free
/// border, used once), and the free border's mid-nodes lie on the square z = 10.
TEST(CadFaces, OpenBoxConformsAndKeepsItsFreeBorder) {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 10, 10, 10).Shape();
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(box, TopAbs_FACE, faces);
  BRep_Builder builder;
  TopoDS_Compound five;
  builder.MakeCompound(five);
  int top = -1;
  for (int f = 1; f <= faces.Extent(); ++f) {
    GProp_GProps props;
    BRepGProp::SurfaceProperties(faces(f), props);
    if (props.CentreOfMass().Z() > 9.9) {
      top = f;
      continue;
    }
    builder.Add(five, faces(f));
  }
  ASSERT_GT(top, 0);
  const cad::CadModel model = cad::make_cad_model(five, "open box", cad::CadContent::kFaces);
  fem::FemOptions o;
  o.size = 2.5;
  o.order = 2;
  const fem::FemMesh m = fem::mesh_cad_faces(model, o);
  std::map<std::array<Index, 2>, std::vector<Index>> uses;  // corner pair -> mid-nodes met
  for (Index t = 0; t < m.num_triangles(); ++t) {
    const Index* n = &m.tri[static_cast<std::size_t>(6 * t)];
    for (int k = 0; k < 3; ++k)
      uses[{std::min(n[k], n[(k + 1) % 3]), std::max(n[k], n[(k + 1) % 3])}].push_back(n[3 + k]);
  }
  int border = 0;
  for (const auto& [edge, mids] : uses) {
    ASSERT_LE(mids.size(), 2u);
    if (mids.size() == 2) {
      EXPECT_EQ(mids[0], mids[1]);  // one mid-node per edge
      continue;
    }
    ++border;
    const double z0 = m.mesh.xyz[3 * edge[0] + 2], z1 = m.mesh.xyz[3 * edge[1] + 2];
    EXPECT_EQ(z0, 10);
    EXPECT_EQ(z1, 10);
    EXPECT_NEAR(m.mesh.xyz[3 * mids[0] + 2], 10, 1e-12);
  }
  EXPECT_GE(border, 16);  // the square of side 10 at size 2.5: at least 4 segments a side
}
