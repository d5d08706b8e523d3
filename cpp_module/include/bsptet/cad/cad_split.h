// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: one solid cut in two by a plane, so that the halves mesh at the same time.
//
//   CutPlane choose_cut_plane(const CadModel& model, const CadSurface& surface, double size)
//   CadSplit split_by_plane(const CadModel& model, const CutPlane& plane)
//
// The FEM pipeline meshes solids at the same time, one per thread; a model of one big solid
// would use one core. It is cut by one plane into solids that share the cut faces (a CompSolid,
// as a general fuse makes it; two, or more where the plane crosses the solid more than once),
// meshed like any solids that share a face: the cut faces' surface mesh is fixed, both sides keep
// it, the merged mesh conforms across it. The cut faces are meshed at the sizes the volume will
// have there (cut_size_sources). The caller maps the pieces' tags back (CadSplit::face_origin,
// solid_origin) and frees the cut's nodes once the pieces are merged (fem_mesh.h).
//
// The plane (choose_cut_plane) is normal to a coordinate axis, so that the cut face's nodes are
// exactly coplanar (the core's exact predicates see one plane, not many nearly equal ones). It
// is chosen on the model's surface mesh at the size field (cad_surface.h), among 128 positions
// per axis, from those that leave 45 to 55% of the work on each side. The work of a side is
// estimated as kTetsPerTriangle tets per surface triangle (by centroid) plus the tets of edge
// `size` its volume holds (the volume below a plane is exact for the triangles: divergence
// theorem with the field (x_axis - c) e_axis, which vanishes on the cut). The plane must stay
// clear of what makes a bad seam:
//   - every CAD vertex at least half its local size (the mean length of the surface mesh's edges
//     at it) from the plane (a vertex near it makes short edges);
//   - every surface triangle the plane crosses at least kMinCutAngleDeg from parallel to it
//     (a face nearly tangent to the plane makes a thin wedge between the face and the cut, and
//     a section curve that OpenCASCADE places poorly);
//   - every triangle edge along a CAD edge that the plane crosses at least kMinCutAngleDeg from
//     parallel to it.
// Among the positions that pass, the one with the fewest CAD faces crossed wins, then the one
// with the smallest cut (the cut's area is exact for the triangles too: -(the a-component of the
// vector area below)), areas within 1% counting as equal, then the best balance, then the lowest
// axis and position; no position passing: no cut. The choice
// depends on the model and the size only (never on the number of threads), so the mesh is the
// same for every number of workers.
//
// split_by_plane cuts with OpenCASCADE's BRepAlgoAPI_Splitter (a general fuse of the solid and a
// planar face larger than the model) and numbers the result as any model (cad_model.h). It
// returns no cut (CadSplit::cut false) when OpenCASCADE reports an error or the result is not
// solids (two or more: a plane may cross a solid more than once) that share the cut faces, with
// every original face accounted for.
#pragma once

#include <vector>

#include "bsptet/cad/cad_model.h"
#include "bsptet/cad/cad_surface.h"

namespace bsptet::cad {

/// Smallest angle, degrees, between the cut plane and a face or CAD edge it crosses.
constexpr double kMinCutAngleDeg = 35.0;
/// Tets per surface triangle in the estimate of a side's work (graded meshes of parts with small
/// features hold about 4 over the CAD corpus); the volume adds the tets of edge `size` it holds.
constexpr double kTetsPerTriangle = 4;

struct CutPlane {
  bool found = false;
  int axis = -1;          ///< 0, 1, 2: the plane x_axis = position
  double position = 0;    ///< model units
  double below = 0;       ///< share of the work on the side x_axis < position
  int faces_crossed = 0;  ///< CAD faces the plane crosses
  double clearance = 0;   ///< smallest distance of a CAD vertex to the plane over its local size
  double area = 0;        ///< the cut's area (model units squared)
};

struct CadSplit {
  bool cut = false;
  CadModel model;                ///< the cut model (solids sharing the cut faces) when cut
  std::vector<int> face_origin;  ///< per face of `model`: the original face (0-based), -1 on the cut
  std::vector<int> solid_origin; ///< per solid of `model`: the original solid (0-based)
};

/// The volume enclosed by solid `solid`'s closed surface in `surface` (its triangles outward).
double enclosed_volume(const CadSurface& surface, int solid);

/// The plane, from the surface mesh of `model` (one solid) at the size field's `size` (see the
/// file comment). Not found for a model of more than one solid.
CutPlane choose_cut_plane(const CadModel& model, const CadSurface& surface, double size);

/// The sizes the volume will have on the cut (as quality_refine.h's size_from_surface makes them:
/// at a surface node the smallest mean edge length of its triangles, growing by `grading` per
/// unit length, at most `size`): the surface nodes from which that growth stays under `size` at
/// the plane, with their sizes, for the cut faces' meshing (FaceMeshOptions::size_sources).
std::vector<std::pair<Vec3, double>> cut_size_sources(const CadSurface& surface, const CutPlane& plane, double size,
                                                      double grading);

/// `model` (one solid) cut by `plane` (found). Not cut when OpenCASCADE fails (see above).
CadSplit split_by_plane(const CadModel& model, const CutPlane& plane);

}  // namespace bsptet::cad
