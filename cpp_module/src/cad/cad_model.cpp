// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: reading CAD files and numbering their topology (see cad_model.h).
#include "bsptet/cad/cad_model.h"

#include <algorithm>
#include <cctype>
#include <map>
#include <set>
#include <sstream>
#include <unordered_map>

#include <BRepBndLib.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <Bnd_Box.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <Interface_EntityIterator.hxx>
#include <Interface_Graph.hxx>
#include <STEPControl_Reader.hxx>
#include <StepBasic_Product.hxx>
#include <StepBasic_ProductDefinition.hxx>
#include <StepBasic_ProductDefinitionFormation.hxx>
#include <StepRepr_CharacterizedDefinition.hxx>
#include <StepRepr_PropertyDefinition.hxx>
#include <StepRepr_RepresentationItem.hxx>
#include <StepRepr_RepresentedDefinition.hxx>
#include <StepShape_ManifoldSolidBrep.hxx>
#include <StepShape_ShapeDefinitionRepresentation.hxx>
#include <Standard_Failure.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TopExp.hxx>
#include <TransferBRep.hxx>
#include <Transfer_TransientProcess.hxx>
#include <XSControl_TransferReader.hxx>
#include <XSControl_WorkSession.hxx>
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

// A CAD name as a set name (see cad_model.h), "" when it is not one.
std::string set_name(const std::string& cad_name) {
  std::string name;
  for (const unsigned char c : cad_name) {
    const bool keep = std::isalnum(c) || c == '-' || c == '_';
    if (keep || (!name.empty() && name.back() != '_')) name += keep ? static_cast<char>(c) : '_';
  }
  if (name.size() > 48) name.resize(48);  // set names: CalculiX and MED allow 80 characters
  while (!name.empty() && name.back() == '_') name.pop_back();
  std::string upper = name;
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return std::toupper(c); });
  const bool letter = std::any_of(name.begin(), name.end(), [](unsigned char c) { return std::isalpha(c); });
  return letter && upper != "NONE" ? name : "";
}

// The names a STEP file gives the entities its shapes were made from, by TShape (so every
// placement of an instanced part gets its part's names).
using ShapeNames = std::unordered_map<const TopoDS_TShape*, std::string>;

// The name of the product (part) whose shape representation holds `item`: the first
// SHAPE_DEFINITION_REPRESENTATION met going up from it through the entities that refer to it
// (at most 4 steps: the brep's representation, a representation relationship, ...); "" if none.
std::string product_name(const Interface_Graph& graph, const Handle(Standard_Transient)& item) {
  std::vector<Handle(Standard_Transient)> level{item};
  std::set<const Standard_Transient*> seen{item.get()};
  for (int depth = 0; depth < 4 && !level.empty(); ++depth) {
    std::vector<Handle(Standard_Transient)> up;
    for (const auto& entity : level) {
      Interface_EntityIterator it = graph.Sharings(entity);
      for (it.Start(); it.More(); it.Next()) {
        const Handle(Standard_Transient)& user = it.Value();
        if (!seen.insert(user.get()).second) continue;
        const auto sdr = Handle(StepShape_ShapeDefinitionRepresentation)::DownCast(user);
        if (sdr.IsNull()) {
          up.push_back(user);
          continue;
        }
        const Handle(StepRepr_PropertyDefinition) property = sdr->Definition().PropertyDefinition();
        if (property.IsNull()) continue;
        const Handle(StepBasic_ProductDefinition) definition = property->Definition().ProductDefinition();
        if (definition.IsNull() || definition->Formation().IsNull() || definition->Formation()->OfProduct().IsNull())
          continue;
        const Handle(TCollection_HAsciiString) name = definition->Formation()->OfProduct()->Name();
        return name.IsNull() ? "" : name->ToCString();
      }
    }
    level = std::move(up);
  }
  return "";
}

TopoDS_Shape read_step(const std::string& path, ShapeNames& names) {
  STEPControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) fail(path, "not a readable STEP file");
  reader.TransferRoots();
  const Handle(Transfer_TransientProcess) process = reader.WS()->TransferReader()->TransientProcess();
  for (int i = 1; !process.IsNull() && i <= process->NbMapped(); ++i) {
    const auto item = Handle(StepRepr_RepresentationItem)::DownCast(process->Mapped(i));
    if (item.IsNull()) continue;
    std::string name = item->Name().IsNull() ? "" : item->Name()->ToCString();
    // A solid without a name of its own (assemblies often give ids such as "#1345") takes its
    // part's product name.
    if (set_name(name).empty() && item->IsKind(STANDARD_TYPE(StepShape_ManifoldSolidBrep)))
      name = product_name(reader.WS()->Graph(), item);
    if (name.empty()) continue;
    const TopoDS_Shape made = TransferBRep::ShapeResult(process, item);
    if (!made.IsNull()) names.emplace(made.TShape().get(), name);
  }
  return reader.OneShape();
}

std::string upper_case(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::toupper(c); });
  return s;
}

// Fills model.solid_names and face_names (see cad_model.h) from `names` (may be empty).
void name_entities(CadModel& model, const ShapeNames& names) {
  struct Entity {
    std::vector<std::string>* out;
    std::string cad, fallback;
  };
  std::vector<Entity> entities;
  model.solid_names.resize(static_cast<std::size_t>(model.num_solids()));
  model.face_names.resize(static_cast<std::size_t>(model.num_faces()));
  const auto add = [&](const TopTools_IndexedMapOfShape& shapes, std::vector<std::string>& out, const char* prefix) {
    for (int k = 1; k <= shapes.Extent(); ++k) {
      const auto it = names.find(shapes(k).TShape().get());
      entities.push_back({&out, it == names.end() ? "" : set_name(it->second), prefix + std::to_string(k)});
    }
  };
  add(model.solids, model.solid_names, "Solid");
  add(model.faces, model.face_names, "Face");
  std::map<std::string, int> uses;  // upper-case name -> entities that would take it
  for (const Entity& e : entities) ++uses[upper_case(e.cad.empty() ? e.fallback : e.cad)];
  std::set<std::string> taken;
  std::size_t index[2] = {0, 0};
  for (const Entity& e : entities) {
    std::string name = e.cad.empty() ? e.fallback : e.cad;
    if (!e.cad.empty() && uses[upper_case(name)] > 1) name += "_" + e.fallback;
    if (!taken.insert(upper_case(name)).second) name = e.fallback;  // taken by a default name
    taken.insert(upper_case(name));
    const int which = e.out == &model.solid_names ? 0 : 1;
    (*e.out)[index[which]++] = name;
  }
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
  name_entities(model, ShapeNames());
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
  ShapeNames names;
  try {
    if (ext == "step" || ext == "stp") {
      shape = read_step(path, names);
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
  CadModel model = make_cad_model(shape, path, content);
  if (!names.empty()) name_entities(model, names);
  return model;
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
