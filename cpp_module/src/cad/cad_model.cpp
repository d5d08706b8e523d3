// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: reading CAD files and numbering their topology (see cad_model.h).
#include "bsptet/cad/cad_model.h"

#include <algorithm>
#include <cctype>
#include <sstream>

#include <BRepBndLib.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <Bnd_Box.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Vertex.hxx>

#include "bsptet/numerics/errors.h"

namespace bsptet::cad {
namespace {

const char* kStage = "cad_read";

std::string lower_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw InputError(ErrorCode::kBadArgument, kStage, -1, source + ": " + what);
}

TopoDS_Shape read_step(const std::string& path) {
  STEPControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) fail(path, "not a readable STEP file");
  reader.TransferRoots();
  return reader.OneShape();
}

TopoDS_Shape read_iges(const std::string& path) {
  IGESControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) fail(path, "not a readable IGES file");
  reader.TransferRoots();
  return reader.OneShape();
}

TopoDS_Shape read_brep_file(const std::string& path) {
  TopoDS_Shape shape;
  BRep_Builder builder;
  if (!BRepTools::Read(shape, path.c_str(), builder)) fail(path, "not a readable BREP file");
  return shape;
}

}  // namespace

double CadModel::diagonal() const {
  Bnd_Box box;
  BRepBndLib::Add(shape, box, /*useTriangulation=*/false);
  if (box.IsVoid()) return 0;
  double x0, y0, z0, x1, y1, z1;
  box.Get(x0, y0, z0, x1, y1, z1);
  const double dx = x1 - x0, dy = y1 - y0, dz = z1 - z0;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

std::array<int, 2> CadModel::edge_ends(int e) const {
  TopoDS_Vertex v0, v1;
  TopExp::Vertices(TopoDS::Edge(edges(e + 1).Oriented(TopAbs_FORWARD)), v0, v1);
  return {vertex_index(v0), vertex_index(v1)};
}

CadModel make_cad_model(const TopoDS_Shape& shape, const std::string& source, CadContent content) {
  if (shape.IsNull()) fail(source, "holds no shape");
  CadModel model;
  model.shape = shape;
  model.source = source;
  TopExp::MapShapes(shape, TopAbs_SOLID, model.solids);
  TopExp::MapShapes(shape, TopAbs_FACE, model.faces);
  TopExp::MapShapes(shape, TopAbs_EDGE, model.edges);
  TopExp::MapShapes(shape, TopAbs_VERTEX, model.vertices);
  if (content == CadContent::kFaces) {
    if (model.faces.Extent() == 0) fail(source, "holds no face: a surface mesh needs a Face or a Shell");
    return model;
  }
  if (model.solids.Extent() == 0) {
    TopTools_IndexedMapOfShape shells;
    TopExp::MapShapes(shape, TopAbs_SHELL, shells);
    std::ostringstream what;
    what << "holds no solid (" << shells.Extent() << " shell(s), " << model.faces.Extent()
         << " face(s)); a volume mesh needs a closed solid: make one in FreeCAD (Part > Convert to solid, "
            "or Part > Shape builder > Solid from shell) and export it again";
    fail(source, what.str());
  }
  // Faces outside every solid would have no volume to bound.
  TopTools_IndexedMapOfShape in_solids;
  for (int s = 1; s <= model.solids.Extent(); ++s) TopExp::MapShapes(model.solids(s), TopAbs_FACE, in_solids);
  for (int f = 1; f <= model.faces.Extent(); ++f) {
    if (!in_solids.Contains(model.faces(f))) {
      std::ostringstream what;
      what << "Face" << f << " belongs to no solid; mesh the solids alone (remove free faces and shells)";
      fail(source, what.str());
    }
  }
  return model;
}

CadModel read_cad_file(const std::string& path, CadContent content) {
  const std::string ext = lower_extension(path);
  TopoDS_Shape shape;
  try {
    if (ext == "step" || ext == "stp") {
      shape = read_step(path);
    } else if (ext == "iges" || ext == "igs") {
      shape = read_iges(path);
    } else if (ext == "brep" || ext == "brp") {
      shape = read_brep_file(path);
    } else {
      fail(path, "unknown CAD extension '." + ext + "' (expected .step, .stp, .brep, .brp, .iges or .igs)");
    }
  } catch (const Standard_Failure& e) {
    fail(path, std::string("OpenCASCADE could not read it: ") + (e.GetMessageString() ? e.GetMessageString() : "?"));
  }
  return make_cad_model(shape, path, content);
}

CadModel read_brep_string(const std::string& brep, const std::string& source, CadContent content) {
  TopoDS_Shape shape;
  BRep_Builder builder;
  std::istringstream in(brep);
  try {
    BRepTools::Read(shape, in, builder);
  } catch (const Standard_Failure& e) {
    fail(source, std::string("not a BREP shape: ") + (e.GetMessageString() ? e.GetMessageString() : "?"));
  }
  return make_cad_model(shape, source, content);
}

}  // namespace bsptet::cad
