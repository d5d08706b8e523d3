// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: the boundary of every solid of a CAD model, meshed at the size field.
//
//   CadSurface mesh_cad_surface(const CadModel& model, const CadSurfaceOptions& options,
//                               CadSurfaceStats* stats = nullptr)
//
// Order of work, as Gmsh and Netgen do it: every CAD edge once (edge_mesher.h: nodes on the curve,
// spaced by the size field), then every CAD face once with those edge nodes fixed
// (face_mesher.h), then each solid's closed surface from its faces. A face shared by two solids
// of a CompSolid is meshed once and used by both, reversed in one: the solids' meshes conform.
//
// Before any face is meshed, every face's boundary loops are made simple in its parameter
// plane: where two boundary segments cross or touch (chords of curved edges on a thin face),
// both edge segments are split at their parameter midpoint, on every face at once (the edges are
// shared), until none does.
//
// Nodes: the CAD vertices first (CAD vertex order, at BRep_Tool::Pnt), then the interior nodes of
// each edge (edge order, on its 3D curve; nodes added to make boundaries simple follow, in the
// order of those passes), then each face's interior nodes (face order, on its surface). Every node is evaluated on its CAD entity by OpenCASCADE; node_dim / node_entity say
// which. Triangles are tagged with their CAD face index (0-based, FreeCAD's Face<k+1>) and
// oriented outward of their solid (counter-clockwise seen from outside, as types.h says).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bsptet/cad/cad_model.h"
#include "bsptet/cad/size_field.h"
#include "bsptet/mesh/types.h"

namespace bsptet::cad {

struct CadSurfaceOptions {
  SizeOptions size;
  int face_rounds = 20;  ///< rounds of local operations per face at most (face_mesher.h)
  /// Per face (0-based), sizes set from outside it (FaceMeshOptions::size_sources).
  std::map<int, std::vector<std::pair<Vec3, double>>> size_sources;
  /// Called with (stage, fraction in [0, 1]); may be empty.
  std::function<void(const std::string&, double)> progress;
  /// Polled between faces; return true to stop (throws MeshingError with code kCancelled).
  std::function<bool()> cancelled;
};

struct CadSurfaceStats {
  std::int64_t nodes = 0, triangles = 0;
  std::int64_t folds = 0;         ///< face triangles whose normal opposes the surface's
  /// (CAD face index, folded triangles) of each face that kept folds, in face order: for messages
  std::vector<std::pair<int, int>> folded_faces;
  double min_quality = 1;         ///< smallest triangle shape quality (face_mesher.h)
  double size = 0, min_size = 0;  ///< the size field's h and floor (automatic ones resolved)
  double seconds = 0;
};

struct CadSurface {
  std::vector<double> xyz;               ///< #N by 3: every node
  std::vector<std::int8_t> node_dim;     ///< #N: 0 on a CAD vertex, 1 inside an edge, 2 inside a face
  std::vector<std::int32_t> node_entity; ///< #N: that vertex's, edge's or face's index (0-based)
  /// One closed surface per solid (CAD solid order): triangles in node ids of `xyz`, with tags.
  std::vector<std::vector<Index>> solid_tri;
  std::vector<std::vector<std::int32_t>> solid_tag;
  /// Every CAD face once (face order), counter-clockwise about the face's normal as the shape
  /// orients the face (a shell's faces agree where the shell is consistently oriented): triangles
  /// in node ids of `xyz`, and the face of each.
  std::vector<Index> face_tri;
  std::vector<std::int32_t> face_tag;

  /// Solid s's surface as a SurfaceMesh: only its own nodes, renumbered in increasing node id;
  /// `node_of` (if given) receives each new index's node id.
  SurfaceMesh solid_surface(int s, std::vector<Index>* node_of = nullptr) const;
};

/// Throws InputError naming the CAD face or edge when the model cannot be meshed as given (a
/// face whose boundary is not a closed loop in its parameter plane, an open solid), MeshingError
/// when a face's mesher fails on valid geometry.
CadSurface mesh_cad_surface(const CadModel& model, const CadSurfaceOptions& options, CadSurfaceStats* stats = nullptr);

}  // namespace bsptet::cad
