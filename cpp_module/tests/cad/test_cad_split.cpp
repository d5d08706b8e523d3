// SPDX-License-Identifier: LGPL-2.1-or-later
// One solid cut in two by a plane (cad/cad_split.h): the enclosed volume of a surface mesh, the
// plane's choice (balanced, normal to an axis, clear of vertices and of faces nearly parallel to
// it) and the cut model's numbering back to the original's faces.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeWedge.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <gp_Ax2.hxx>

#include "bsptet/cad/cad_model.h"
#include "bsptet/cad/cad_split.h"
#include "bsptet/cad/cad_surface.h"

using namespace bsptet;

namespace {

cad::CadSurface surface_of(const cad::CadModel& model, double size) {
  cad::CadSurfaceOptions o;
  o.size.size = size;
  return cad::mesh_cad_surface(model, o);
}

}  // namespace

// A 30 x 10 x 10 box: its volume from the surface mesh is exact up to rounding; the plane is
// normal to its long axis (the first axis of those that balance the work as well), in the
// middle, crossing its four side faces at right angles; the cut gives two boxes sharing a square,
// each side face split in two, the end faces whole.
TEST(CadSplit, BoxIsCutAcrossItsLongAxisInTheMiddle) {
  const cad::CadModel model = cad::make_cad_model(BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 30, 10, 10).Shape(), "box");
  const cad::CadSurface surface = surface_of(model, 2.0);
  EXPECT_NEAR(cad::enclosed_volume(surface, 0), 3000.0, 1e-9);
  const cad::CutPlane plane = cad::choose_cut_plane(model, surface, 2.0);
  ASSERT_TRUE(plane.found);
  EXPECT_EQ(plane.axis, 0);
  EXPECT_NEAR(plane.position, 15.0, 0.2);
  EXPECT_NEAR(plane.below, 0.5, 0.02);
  EXPECT_EQ(plane.faces_crossed, 4);
  EXPECT_GE(plane.clearance, 0.5);

  const cad::CadSplit split = cad::split_by_plane(model, plane);
  ASSERT_TRUE(split.cut);
  EXPECT_EQ(split.model.num_solids(), 2);
  ASSERT_EQ(split.face_origin.size(), static_cast<std::size_t>(split.model.num_faces()));
  EXPECT_EQ(split.model.num_faces(), 11);  // 4 side faces in two, 2 ends, the cut
  std::map<int, int> images;
  for (int origin : split.face_origin) ++images[origin];
  EXPECT_EQ(images[-1], 1);
  for (int f = 0; f < model.num_faces(); ++f) EXPECT_GE(images[f], 1) << "Face" << f + 1;
  EXPECT_EQ(split.solid_origin, std::vector<int>(2, 0));
  // The cut face is the plane x = position, exactly, and bounds both solids.
  TopTools_IndexedDataMapOfShapeListOfShape solids_of_face;
  TopExp::MapShapesAndAncestors(split.model.shape, TopAbs_FACE, TopAbs_SOLID, solids_of_face);
  for (int g = 0; g < split.model.num_faces(); ++g) {
    if (split.face_origin[static_cast<std::size_t>(g)] >= 0) continue;
    const TopTools_ListOfShape& solids = solids_of_face.FindFromKey(split.model.faces(g + 1));
    std::set<const void*> distinct;
    for (TopTools_ListIteratorOfListOfShape it(solids); it.More(); it.Next()) distinct.insert(it.Value().TShape().get());
    EXPECT_EQ(distinct.size(), 2u);
  }
  const cad::CadSurface cut_surface = surface_of(split.model, 2.0);
  for (std::size_t i = 0; i < cut_surface.node_dim.size(); ++i)
    if (cut_surface.node_dim[i] == 2 && split.face_origin[static_cast<std::size_t>(cut_surface.node_entity[i])] < 0)
      EXPECT_EQ(cut_surface.xyz[3 * i], plane.position) << "node " << i;
  // The cut's size sources: nodes with their sizes, none larger than the size.
  for (const auto& [p, s] : cad::cut_size_sources(surface, plane, 2.0, 0.3)) EXPECT_LE(s, 2.0);
}

// A plane is never put where a face is nearly parallel to it, and fewer faces crossed win: a
// wedge whose sloped face makes 10 degrees with the x axis is cut normal to z (3 faces crossed,
// all at right angles), not normal to x (4 faces) nor to y (the slope at 10 degrees). A block
// with a hole through it is cut with every face accounted for in the cut model.
TEST(CadSplit, NoPlaneWhereAFaceIsNearlyParallelToIt) {
  // Wedge: x in [0, 40], y in [0, 40 tan 10 deg] at x = 0 down to 0 at x = 40 (ltx = 0), z in [0, 10].
  const double height = 40 * std::tan(10 * 3.14159265358979323846 / 180);
  const cad::CadModel model = cad::make_cad_model(BRepPrimAPI_MakeWedge(40, height, 10, 0).Shape(), "wedge");
  const cad::CadSurface surface = surface_of(model, 2.0);
  const cad::CutPlane plane = cad::choose_cut_plane(model, surface, 2.0);
  ASSERT_TRUE(plane.found);
  EXPECT_EQ(plane.axis, 2);
  EXPECT_EQ(plane.faces_crossed, 3);

  const TopoDS_Shape block = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 10, 10, 10).Shape();
  const TopoDS_Shape hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(5, 5, -1), gp_Dir(0, 0, 1)), 2, 12).Shape();
  const cad::CadModel holed = cad::make_cad_model(BRepAlgoAPI_Cut(block, hole).Shape(), "block with a hole");
  const cad::CutPlane through = cad::choose_cut_plane(holed, surface_of(holed, 1.0), 1.0);
  ASSERT_TRUE(through.found);
  const cad::CadSplit split = cad::split_by_plane(holed, through);
  ASSERT_TRUE(split.cut);
  std::map<int, int> images;
  for (int origin : split.face_origin) ++images[origin];
  for (int f = 0; f < holed.num_faces(); ++f) EXPECT_GE(images[f], 1) << "Face" << f + 1;
  EXPECT_GE(images[-1], 1);
}
