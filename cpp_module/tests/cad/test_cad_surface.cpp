// SPDX-License-Identifier: LGPL-2.1-or-later
// The CAD surface mesher (cad/cad_surface.h) on real parts and on shapes built here: each solid's
// surface is closed and oriented outward, every CAD face is meshed, no triangle is folded, the
// triangles are shaped and sized as asked, and every node lies on the CAD entity it names.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <BRepBuilderAPI_Transform.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRepPrimAPI_MakeWedge.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <GeomAPI_ProjectPointOnCurve.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Shell.hxx>
#include <gp_Ax1.hxx>
#include <gp_Trsf.hxx>

#include "bsptet/cad/cad_model.h"
#include "bsptet/cad/cad_surface.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/input/self_intersection.h"

using namespace bsptet;

namespace {

std::string data(const std::string& rel) { return std::string(FEMBSPTET_DATA_DIR) + "/" + rel; }

Vec3 node(const cad::CadSurface& s, Index n) {
  return {s.xyz[3 * static_cast<std::size_t>(n)], s.xyz[3 * static_cast<std::size_t>(n) + 1],
          s.xyz[3 * static_cast<std::size_t>(n) + 2]};
}
Vec3 sub(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 cross(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// The invariants every meshed model must meet; returns the surface for further checks.
cad::CadSurface mesh_and_check(const cad::CadModel& model, double size = 0, double min_size = 0) {
  cad::CadSurfaceOptions options;
  options.size.size = size;
  options.size.min_size = min_size;
  cad::CadSurfaceStats stats;
  const cad::CadSurface s = cad::mesh_cad_surface(model, options, &stats);
  EXPECT_EQ(static_cast<int>(s.solid_tri.size()), model.num_solids());
  EXPECT_EQ(stats.folds, 0) << model.source;
  EXPECT_GT(stats.min_quality, 0.15) << model.source;
  const double h = stats.size;
  const double diagonal = model.diagonal();

  std::set<int> faces_meshed;
  for (std::size_t solid = 0; solid < s.solid_tri.size(); ++solid) {
    const auto& tri = s.solid_tri[solid];
    EXPECT_EQ(tri.size(), 3 * s.solid_tag[solid].size());
    // Closed and consistently oriented: every directed edge once, its reverse once.
    std::map<std::array<Index, 2>, int> directed;
    double volume6 = 0, area = 0;
    for (std::size_t k = 0; k < tri.size(); k += 3) {
      for (int i = 0; i < 3; ++i) ++directed[{tri[k + i], tri[k + (i + 1) % 3]}];
      const Vec3 a = node(s, tri[k]), b = node(s, tri[k + 1]), c = node(s, tri[k + 2]);
      volume6 += dot(a, cross(b, c));
      const Vec3 n = cross(sub(b, a), sub(c, a));
      area += 0.5 * std::sqrt(dot(n, n));
      EXPECT_NE(tri[k], tri[k + 1]);
      EXPECT_NE(tri[k + 1], tri[k + 2]);
      EXPECT_NE(tri[k + 2], tri[k]);
    }
    for (const auto& [e, count] : directed) {
      EXPECT_EQ(count, 1) << model.source << " solid " << solid << ": edge " << e[0] << "-" << e[1] << " used twice one way";
      const auto back = directed.find({e[1], e[0]});
      EXPECT_TRUE(back != directed.end()) << model.source << " solid " << solid << ": open edge " << e[0] << "-" << e[1];
    }
    // Outward: the enclosed volume is the CAD solid's, positive, within the chords' sag (12
    // segments per circle cut 4.5% off a disc's area; a torus loses it in two directions).
    GProp_GProps props;
    BRepGProp::VolumeProperties(model.solids(static_cast<int>(solid) + 1), props);
    EXPECT_NEAR(volume6 / 6, std::abs(props.Mass()), 0.1 * std::abs(props.Mass())) << model.source;
    // Sized as asked: about as many triangles as equilateral ones of side h would need, never
    // orders of magnitude more (curvature and small features may ask for more).
    const double at_h = area / (std::sqrt(3.0) / 4 * h * h);
    EXPECT_GT(static_cast<double>(s.solid_tag[solid].size()), 0.5 * at_h) << model.source;
    for (std::int32_t t : s.solid_tag[solid]) faces_meshed.insert(t);
  }
  EXPECT_EQ(static_cast<int>(faces_meshed.size()), model.num_faces()) << model.source;

  // Every node on its CAD entity: vertices at their point, edge nodes on the curve, face nodes on
  // the surface (the mesher evaluates them there; 1e-9 of the diagonal is rounding).
  for (Index n = 0; n < static_cast<Index>(s.node_dim.size()); ++n) {
    const Vec3 p = node(s, n);
    const gp_Pnt q(p.x, p.y, p.z);
    const int entity = s.node_entity[static_cast<std::size_t>(n)];
    double distance = 0;
    if (s.node_dim[static_cast<std::size_t>(n)] == 0) {
      distance = BRep_Tool::Pnt(TopoDS::Vertex(model.vertices(entity + 1))).Distance(q);
    } else if (s.node_dim[static_cast<std::size_t>(n)] == 1) {
      double t0, t1;
      const Handle(Geom_Curve) curve = BRep_Tool::Curve(TopoDS::Edge(model.edges(entity + 1)), t0, t1);
      GeomAPI_ProjectPointOnCurve projection(q, curve, t0, t1);
      EXPECT_GT(projection.NbPoints(), 0);
      if (projection.NbPoints() == 0) continue;
      distance = projection.LowerDistance();
    } else {
      const Handle(Geom_Surface) surface = BRep_Tool::Surface(TopoDS::Face(model.faces(entity + 1)));
      GeomAPI_ProjectPointOnSurf projection(q, surface);
      EXPECT_GT(projection.NbPoints(), 0);
      if (projection.NbPoints() == 0) continue;
      distance = projection.LowerDistance();
    }
    EXPECT_LT(distance, 1e-9 * diagonal) << model.source << ": node " << n << " dim "
                                         << int(s.node_dim[static_cast<std::size_t>(n)]) << " entity " << entity;
  }
  return s;
}

cad::CadModel rotated(const TopoDS_Shape& shape, const std::string& name) {
  gp_Trsf turn;
  turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(1, 2, 3)), 0.7);
  return cad::make_cad_model(BRepBuilderAPI_Transform(shape, turn, true).Shape(), name);
}

// The shortest surface edge at a CAD vertex node, leaving out edges between two CAD vertices (a
// CAD edge meshed as one segment).
double shortest_edge_leaving_vertices(const cad::CadSurface& s) {
  double shortest = std::numeric_limits<double>::infinity();
  for (const auto& tri : s.solid_tri)
    for (std::size_t k = 0; k < tri.size(); k += 3)
      for (int i = 0; i < 3; ++i) {
        const Index a = tri[k + i], b = tri[k + (i + 1) % 3];
        const bool at_a = s.node_dim[static_cast<std::size_t>(a)] == 0, at_b = s.node_dim[static_cast<std::size_t>(b)] == 0;
        if (at_a == at_b) continue;
        const Vec3 d = sub(node(s, a), node(s, b));
        shortest = std::min(shortest, std::sqrt(dot(d, d)));
      }
  return shortest;
}

}  // namespace

// A wedge whose top edges (0.005 long) are shorter than the automatic floor h / 50 (about
// 0.017 at h = diagonal / 20): the edges leaving their ends start at about their length and grade
// up, instead of meeting them at the floor's size (needles). With the floor given as min_size,
// nothing goes below it.
TEST(CadSurface, ShortEdgesGradeTheSizesDownToThem) {
  const cad::CadModel model = rotated(BRepPrimAPI_MakeWedge(10, 10, 10, 0.005).Shape(), "wedge");
  const double floor = model.diagonal() / 20 / 50;
  ASSERT_LT(0.005, floor);
  const cad::CadSurface automatic = mesh_and_check(model);
  const cad::CadSurface floored = mesh_and_check(model, 0, floor);
  EXPECT_LT(shortest_edge_leaving_vertices(automatic), 0.5 * floor);
  EXPECT_GT(shortest_edge_leaving_vertices(floored), 0.5 * floor);
}

TEST(CadSurface, BracketHolesAndFilletAreUniform) {
  const cad::CadModel model = cad::read_cad_file(data("cad/bracket.step"));
  const cad::CadSurface s = mesh_and_check(model);
  // At h = diagonal / 20 the bracket needs a couple of thousand triangles, not tens of thousands.
  EXPECT_LT(s.solid_tag[0].size(), 6000u);
}

TEST(CadSurface, ThreadStripWindingAroundItsAxisMeshesWithoutCrossings) {
  // The OCCT tutorial bottle: its thread's flanks are B-spline strips 0.4 mm wide that wind twice
  // around the neck (Face4 while u runs over [0, pi], Face2 over [0, 4 pi]), so nodes close in
  // (u, v) are up to a whole turn apart on the surface. Ear cutting fans one boundary node out to
  // hundreds across the strip: needles a turn long, folded through the neck in places and thin
  // but facing the surface's way elsewhere. Whether the later rounds happened to untangle what
  // was left depended on the size (4.697 meshed, FreeCAD's diagonal / 20 = 4.697073557013984 did
  // not), so the surface must come out free of crossing triangles at several sizes, that one
  // included (0: the automatic size).
  const cad::CadModel model = cad::read_cad_file(data("cad/bottle.brep"));
  for (const double size : {0.0, 4.697073557013984, 4.697, 3.0, 4.5, 5.0, 6.0, model.diagonal() / 12}) {
    SCOPED_TRACE("size " + std::to_string(size));
    cad::CadSurfaceOptions options;
    options.size.size = size;
    cad::CadSurfaceStats stats;
    const cad::CadSurface s = cad::mesh_cad_surface(model, options, &stats);
    ASSERT_EQ(s.solid_tri.size(), 1u);
    bool complete = true;
    const auto pairs = find_self_intersections(s.solid_surface(0), 10, &complete);
    EXPECT_TRUE(pairs.empty()) << pairs.size() << " crossing pairs, the first triangles " << pairs[0][0] << " and "
                               << pairs[0][1] << ", of Face" << s.solid_tag[0][static_cast<std::size_t>(pairs[0][0])] + 1
                               << " and Face" << s.solid_tag[0][static_cast<std::size_t>(pairs[0][1])] + 1;
    // Face4's end creases (its normal turns by more than 90 degrees within 1% of its u range):
    // the few triangles there that oppose one corner's normal are the only folds.
    for (const auto& [face, folds] : stats.folded_faces) EXPECT_EQ(face, 3) << "Face" << face + 1 << ": " << folds;
    EXPECT_LT(stats.folds, stats.triangles / 1000);
  }
}

TEST(CadSurface, TwoSolidsWithSeams) {
  mesh_and_check(cad::read_cad_file(data("cad/red_cube_blue_cylinder.step")));
}

TEST(CadSurface, ConeApexTorusAndRotatedCylinder) {
  // A cylinder and a torus (seams, a periodic face in both directions) turned off the axes.
  mesh_and_check(rotated(BRepPrimAPI_MakeCylinder(3, 10).Shape(), "rotated cylinder"));
  mesh_and_check(rotated(BRepPrimAPI_MakeTorus(10, 3).Shape(), "rotated torus"));
  // A truncated cone has no apex; its side is a periodic face with a seam.
  mesh_and_check(rotated(BRepPrimAPI_MakeCone(5, 2, 8).Shape(), "truncated cone"));
}

TEST(CadSurface, SmallerSizeGivesMoreTriangles) {
  // A box has no curvature: its triangle count follows h alone, about as 1 / h^2.
  const cad::CadModel model = rotated(BRepPrimAPI_MakeBox(10, 20, 5).Shape(), "box");
  const cad::CadSurface coarse = mesh_and_check(model, 0.2 * model.diagonal());
  const cad::CadSurface fine = mesh_and_check(model, 0.05 * model.diagonal());
  EXPECT_GT(fine.solid_tag[0].size(), 8 * coarse.solid_tag[0].size());
}

TEST(CadSurface, OpenShellIsRefusedNamingWhatTheFileHolds) {
  // Five faces of a box: a shell, no solid.
  BRep_Builder builder;
  TopoDS_Shell shell;
  builder.MakeShell(shell);
  int count = 0;
  for (TopExp_Explorer faces(BRepPrimAPI_MakeBox(10, 10, 10).Shape(), TopAbs_FACE); faces.More() && count < 5;
       faces.Next(), ++count)
    builder.Add(shell, faces.Current());
  try {
    cad::make_cad_model(shell, "open box");
    FAIL() << "an open shell was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no solid"), std::string::npos) << e.what();
  }
}

TEST(CadSurface, NegativeSizeIsRefused) {
  const cad::CadModel model = cad::make_cad_model(BRepPrimAPI_MakeBox(10, 10, 10).Shape(), "box");
  cad::CadSurfaceOptions options;
  options.size.size = -1;
  EXPECT_THROW(cad::mesh_cad_surface(model, options), InputError);
}
