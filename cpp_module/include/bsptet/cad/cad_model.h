// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: a CAD shape read through OpenCASCADE, with its topology numbered.
//
//   CadModel read_cad_file(const std::string& path)       // .step .stp .brep .brp .iges .igs
//   CadModel read_brep_string(const std::string& brep)    // FreeCAD's Shape.exportBrepToString()
//
// Numbering, stated once for the CAD layer: solids, faces, edges and vertices are numbered by
// OpenCASCADE's TopExp::MapShapes over the whole shape, the order FreeCAD's Shape.Faces (Face1,
// Face2, ...) uses. Indices here are 0-based: face k is FreeCAD's "Face<k+1>" and the surface
// tag of its triangles. A face shared by two solids of a CompSolid has one index.
//
// Names, for the outputs' sets: solid k is "Solid<k+1>" and face k "Face<k+1>" (FreeCAD's
// names), unless a STEP file names the entity (MANIFOLD_SOLID_BREP, ADVANCED_FACE, ...: the
// name of the representation item the shape was made from; a solid whose item has no such name
// takes the name of the product, the part, it belongs to). A STEP name is kept when it holds a
// letter and is not "NONE"; characters other than letters, digits, '-' and '_' become '_', and
// it is cut at 48 characters (CalculiX and MED allow 80 in a set name); a name
// that several entities share, or that equals another name up to case (solvers such as CalculiX
// ignore case), gets the default name appended ("nut_Solid3"). Every name is unique up to case.
//
// This layer is the only one that links OpenCASCADE; nothing below it (mesh, core, refine) does.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Shape.hxx>

namespace bsptet::cad {

struct CadModel {
  TopoDS_Shape shape;
  TopTools_IndexedMapOfShape solids, faces, edges, vertices;  ///< 1-based maps (OCC's own)
  std::string source;  ///< the file name, or "BREP string": named in messages
  /// 0-based, see "Names" above; always num_solids() and num_faces() long.
  std::vector<std::string> solid_names, face_names;

  int num_solids() const { return solids.Extent(); }
  int num_faces() const { return faces.Extent(); }
  int num_edges() const { return edges.Extent(); }
  int num_vertices() const { return vertices.Extent(); }
  /// 0-based indices of a sub-shape (orientation ignored), -1 when it is not in the model.
  int face_index(const TopoDS_Shape& f) const { return faces.FindIndex(f) - 1; }
  int edge_index(const TopoDS_Shape& e) const { return edges.FindIndex(e) - 1; }
  int vertex_index(const TopoDS_Shape& v) const { return vertices.FindIndex(v) - 1; }
  /// Axis-aligned bounding box diagonal of the shape (model units).
  double diagonal() const;
  /// 0-based indices of the vertices at the two ends of edge `e` (0-based; equal for a closed
  /// edge).
  std::array<int, 2> edge_ends(int e) const;
};

/// What a model must hold: solids (a volume mesh; every face bounds a solid), or faces (a surface
/// mesh of every face: a Face, a Shell, or the faces of solids).
enum class CadContent { kSolids, kFaces };

/// Reads a STEP, BREP or IGES file (chosen by extension, case-insensitive). Throws InputError
/// naming the file when it cannot be read, is empty, or does not hold what `content` asks (the
/// message says what it holds instead: shells, faces, ...).
CadModel read_cad_file(const std::string& path, CadContent content = CadContent::kSolids);

/// Reads a shape in OpenCASCADE's BREP text format (what FreeCAD's Shape.exportBrepToString()
/// gives). Same errors as read_cad_file.
CadModel read_brep_string(const std::string& brep, const std::string& source = "BREP string",
                          CadContent content = CadContent::kSolids);

/// Numbers an existing shape's topology (no copy of the geometry). Same errors.
CadModel make_cad_model(const TopoDS_Shape& shape, const std::string& source,
                        CadContent content = CadContent::kSolids);

}  // namespace bsptet::cad
