// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet FEM pipeline: a CAD model to a tetrahedral FEM mesh, one entry point.
//
//   FemMesh mesh_cad_model(const cad::CadModel& model, const FemOptions& options, FemStats* stats)
//
// Stages, in order:
//  0. cut: a model of one solid whose surface (stage 1) gives an estimate of kCutFromTets tets or
//     more is cut by one plane (cad/cad_split.h) into solids that share the cut faces, and the
//     stages below run on those pieces; the cut faces are meshed at the sizes the volume will
//     have there. After the merge the cut's triangles (interior) leave the face groups, the tags
//     go back to the model's faces and solid, and the cut's nodes are smoothed (they could not
//     move while the pieces were meshed apart). The choice depends on the model and the size
//     only: the mesh is the same for every number of workers. A cut OpenCASCADE makes badly
//     (an error, or a failure meshing the pieces) leaves the solid whole.
//  1. surface: every CAD edge, then every CAD face meshed once at the size field
//     (cad/cad_surface.h); each solid's closed surface from its faces;
//  2. core, per solid (FemOptions::workers solids at a time, each on its own thread with its own
//     projector; nothing is shared but the read-only model and surface): the exact tetrahedralization of that surface (mesher.h
//     check_and_tetrahedralize: the surface is checked, self-intersections included, beside the
//     core; no point is added on the surface);
//  3. refine, per solid: quality_refine.h at the size field's h, sizes extended from the surface
//     triangles (size_from_surface), new surface points and tet10 boundary mid-nodes put onto the
//     CAD faces and edges by the projection hook (cad/cad_projection.h);
//  4. merge: the solids' meshes in one node numbering. The CAD surface nodes are global (a face
//     shared by two solids of a CompSolid, or a compound made conformal by a general fuse, is
//     meshed once), so the solids' corner nodes coincide there.
//
// Faces shared by two solids: their surface is not refined (RefineOptions::fixed_tags: no point
// is added on such a face or on its border), so both solids keep the same triangles there and the
// merged mesh conforms. Their tet10 mid-nodes are projected by each solid; a mid-node the two
// solids placed differently (one solid had to put it back on its chord to keep its curved tets
// valid) is put on the chord for both, and any curved tet that this makes invalid gets all its
// mid-nodes on their chords, until every tet is certified valid (tet10.h certify_tet10).
// Solids that touch only along a CAD edge or at a CAD vertex share the CAD nodes there, but the
// refinement of one solid may add points on such an edge that the other does not have: the merged
// mesh is then not node-conforming along that edge (it is along shared faces).
// Solids of a compound that was not made conformal (no general fuse) are meshed one by one: where
// two of them touch along coincident but distinct CAD faces the mesh has two sets of nodes there
// (not connected), and where they overlap the tets overlap; nothing checks either.
//
// Output node order (of the pieces' model when the solid was cut): the CAD surface nodes
// (cad_surface.h order, unused ones dropped), then each
// solid's added corner nodes (solid order, then the refinement's order), then the mid-nodes of an
// order-2 mesh in the order their edges are first met (solid order, tet order, edge order m12 m23
// m31 m14 m24 m34). Deterministic: no step depends on timing or addresses.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bsptet/cad/cad_model.h"
#include "bsptet/cad/cad_projection.h"
#include "bsptet/cad/cad_surface.h"
#include "bsptet/mesh/types.h"

namespace bsptet::fem {

/// A model of one solid is cut (stage 0) from this many estimated tets: kTetsPerTriangle
/// (cad_split.h) per surface triangle plus the tets of edge h, h^3 / (6 sqrt 2) each, its volume
/// holds. Below it the cut, the second surface and the seam cost about what a second core saves
/// (the bracket at h = diagonal / 20, 5,000 tets: 0.41 s whole, 0.33 s cut).
constexpr double kCutFromTets = 20000;

/// The options a FreeCAD user sets (FreeCAD's mesher properties), with their units.
struct FemOptions {
  /// Largest element size h, model units (FreeCAD's CharacteristicLengthMax). 0: automatic, the
  /// bounding-box diagonal / 20; curvature lowers it further (points_per_circle).
  double size = 0;
  /// Smallest element size, model units (CharacteristicLengthMin). 0: size / 50.
  double min_size = 0;
  /// Size on given CAD faces (0-based index: FreeCAD's Face<k+1>), model units.
  std::map<int, double> size_by_face;
  /// Curved faces and edges get at most 2 pi R / points_per_circle (R the radius of curvature);
  /// 0 turns curvature sizing off.
  double points_per_circle = 12;
  /// How fast sizes grow away from smaller ones, per unit length, on the surface and in the volume
  /// (Netgen's "moderate" is 0.3).
  double grading = 0.3;
  /// 1: 4-node tets (CalculiX C3D4); 2: 10-node tets (C3D10) whose boundary mid-nodes lie on the
  /// CAD faces and edges.
  int order = 2;
  /// Optimization rounds of the quality stage at most (quality_refine.h). Over the 13 CAD parts
  /// at h = diagonal / 20 and / 40, 6 rounds gave the same median per-tet worst angle as 8 (48.62
  /// against 48.65 degrees, 49.51 against 49.50) for about 15% less time; 5 lost 0.1 degree at
  /// / 20.
  int optimize_rounds = 6;
  /// Rounds of local operations per CAD face at most (cad/face_mesher.h).
  int face_rounds = 20;
  /// Solids (or pieces of a cut solid, stage 0) meshed at the same time (stages 2 and 3, one
  /// thread each); 0: the machine's cores. The mesh is the same for every value.
  int workers = 0;
  /// Called with (stage, fraction of the whole run in [0, 1]); may be empty.
  std::function<void(const std::string&, double)> progress;
  /// Polled between steps; return true to stop (throws MeshingError with code kCancelled).
  std::function<bool()> cancelled;
};

struct FemStats {
  std::int64_t solids = 0, faces = 0;
  /// Solids meshed: the model's, or the pieces of a model of one solid cut by a plane
  /// (cad/cad_split.h), and the cut's nodes smoothed once the pieces are merged.
  std::int64_t pieces = 0, cut_nodes_smoothed = 0;
  double size = 0, min_size = 0;  ///< the size field's h and floor (automatic ones resolved)
  // Surface (stage 1).
  std::int64_t surface_nodes = 0, surface_triangles = 0;
  std::int64_t shared_faces = 0;  ///< CAD faces bounding two solids (kept as meshed, see above)
  // Core (stage 2), summed over the solids.
  std::int64_t core_points = 0, core_tets = 0, core_steiner_points = 0;
  // Refinement (stage 3), summed over the solids.
  std::int64_t surface_splits = 0;        ///< points added on the surface (projected onto the CAD)
  std::int64_t refinement_points = 0;     ///< interior points of the Delaunay refinement
  std::int64_t interior_splits = 0;       ///< interior points of edge splits (what refinement left long)
  std::int64_t collapses = 0;             ///< points removed by edge collapses
  std::int64_t splits_fixed_surface = 0;  ///< surface edges left on shared faces
  std::int64_t projection_refused = 0;    ///< hook answers the quality stage refused (see cad_projection.h)
  std::int64_t midnodes_projected = 0, midnodes_straightened = 0;  ///< order 2, per solid (tet10.h)
  std::int64_t curving_conflicts_left = 0;  ///< order 2: tets the refinement left invalid when curved
                                            ///< (interior mid-nodes straight), for the tet10 lift
  /// Order 2, the tet10 lift (tet10.h): tets made valid by moving mid-nodes, interior mid-nodes
  /// moved, boundary mid-nodes moved along their CAD face or edge, interior points inserted.
  std::int64_t midnodes_relaxed_tets = 0, midnodes_moved_interior = 0, midnodes_moved_surface = 0;
  std::int64_t lift_insertions = 0;
  /// The refinement's worst dihedral angle (degrees, least over the solids) when its optimization
  /// is done and at its end (RefineStats::worst_deg_*); the last equals min_dihedral_deg (the
  /// merge keeps the refined corners).
  double refine_worst_deg_optimized = 180, refine_worst_deg = 180;
  // Merge (stage 4).
  std::int64_t midnodes_reconciled = 0;  ///< shared mid-nodes two solids placed differently (put on the chord)
  std::int64_t midnodes_straightened_at_merge = 0;  ///< mid-nodes put on their chord after that
  // Result.
  std::int64_t nodes = 0, corner_nodes = 0, tets = 0, boundary_triangles = 0;
  double min_dihedral_deg = 0;             ///< smallest dihedral angle of the linear tets
  double median_tet_min_dihedral_deg = 0;  ///< median over tets of each tet's smallest dihedral
  double tets_below_10_deg = 0;            ///< share (0..1) of tets whose smallest dihedral is below 10 degrees
  cad::ProjectionStats projection;
  double seconds_surface = 0, seconds_core = 0, seconds_refine = 0, seconds_merge = 0, seconds_total = 0;
  /// The refinement's wall seconds per pass, summed over the solids (RefineStats::seconds_by_pass).
  std::map<std::string, double> refine_seconds_by_pass;
};

/// A tetrahedral FEM mesh of a CAD model.
struct FemMesh {
  /// Nodes (#N by 3) and tets (#K by 4 or 10, node order of types.h: n1..n4 m12 m23 m31 m14 m24 m34).
  TetMesh mesh;
  /// #K: the CAD solid (0-based, cad_model.h order) each tet fills.
  std::vector<std::int32_t> tet_solid;
  /// The triangles of every CAD face, each once (#F by nodes_per_triangle: n1 n2 n3, then for
  /// order 2 m12 m23 m31), oriented outward of the lowest-numbered solid the face bounds. Faces
  /// shared by two solids are inside the mesh; the others are its boundary.
  std::vector<Index> tri;
  int nodes_per_triangle = 3;
  /// #F: the CAD face (0-based: FreeCAD's Face<k+1>) of each triangle.
  std::vector<std::int32_t> tri_face;
  /// The model's names of its solids and faces, for the outputs' sets (cad_model.h).
  std::vector<std::string> solid_names, face_names;

  Index num_triangles() const { return static_cast<Index>(tri_face.size()); }
};

/// How far the nodes of a FemMesh's face triangles lie from their CAD faces.
struct CadDistance {
  double max_corner = 0;   ///< largest distance of a triangle corner to a face it is on, model units
  double max_midnode = 0;  ///< the same for order-2 mid-nodes (0 for order 1)
  std::int64_t pairs = 0;  ///< (node, face) pairs measured: a node on triangles of k faces counts k times
  std::int64_t worst_node = -1;
  int worst_face = -1;
};

/// Measures, for every node of every face triangle (corners and mid-nodes) and every CAD face whose
/// triangles use it, the distance to the bounded face: the smaller of cad::distance_to_face
/// (BRepExtrema_DistShapeShape, as FreeCAD's getNodesByFace measures; to the face's edges too)
/// and the distance to CadProjector::to_face's nearest point of the trimmed surface. Both are
/// distances to points of the face, so both bound the true distance from above; BRepExtrema can
/// stop at a local minimum on B-spline faces (bottle.brep's thread flanks: 0.026 mm for a point
/// the surface projection puts on the face). Slow (one extrema search per pair): for tests and
/// reports.
CadDistance measure_cad_distance(const cad::CadModel& model, const FemMesh& mesh);

/// Meshes every solid of `model` (see the file comment). Throws InputError naming the option for
/// bad options and naming the CAD face, edge or solid for a model that cannot be meshed as given;
/// MeshingError when a stage fails on valid input (code kCancelled when cancelled).
FemMesh mesh_cad_model(const cad::CadModel& model, const FemOptions& options, FemStats* stats = nullptr);

/// Throws InputError naming the option when `options` holds a value out of range.
void check_fem_options(const FemOptions& options);

/// The options schema, stated once: calls f(name, member pointer) for every value option of
/// FemOptions (not the callbacks). The bindings bind FemOptions from it (FemBspTet's Python
/// options, the CLI flags and the FreeCAD properties are checked against it by tests).
template <class F>
void for_each_fem_option(F&& f) {
  f("size", &FemOptions::size);
  f("min_size", &FemOptions::min_size);
  f("size_by_face", &FemOptions::size_by_face);
  f("points_per_circle", &FemOptions::points_per_circle);
  f("grading", &FemOptions::grading);
  f("order", &FemOptions::order);
  f("optimize_rounds", &FemOptions::optimize_rounds);
  f("face_rounds", &FemOptions::face_rounds);
  f("workers", &FemOptions::workers);
}

/// The statistics schema, stated once: calls f(name, member pointer) for every figure of FemStats
/// but the projection counts (cad::ProjectionStats, named "projection_<field>" by the bindings).
/// The names are the keys of the statistics JSON.
template <class F>
void for_each_fem_stat(F&& f) {
  f("solids", &FemStats::solids);
  f("faces", &FemStats::faces);
  f("pieces", &FemStats::pieces);
  f("cut_nodes_smoothed", &FemStats::cut_nodes_smoothed);
  f("size", &FemStats::size);
  f("min_size", &FemStats::min_size);
  f("surface_nodes", &FemStats::surface_nodes);
  f("surface_triangles", &FemStats::surface_triangles);
  f("shared_faces", &FemStats::shared_faces);
  f("core_points", &FemStats::core_points);
  f("core_tets", &FemStats::core_tets);
  f("core_steiner_points", &FemStats::core_steiner_points);
  f("surface_splits", &FemStats::surface_splits);
  f("refinement_points", &FemStats::refinement_points);
  f("interior_splits", &FemStats::interior_splits);
  f("collapses", &FemStats::collapses);
  f("splits_fixed_surface", &FemStats::splits_fixed_surface);
  f("projection_refused", &FemStats::projection_refused);
  f("midnodes_projected", &FemStats::midnodes_projected);
  f("midnodes_straightened", &FemStats::midnodes_straightened);
  f("curving_conflicts_left", &FemStats::curving_conflicts_left);
  f("midnodes_relaxed_tets", &FemStats::midnodes_relaxed_tets);
  f("midnodes_moved_interior", &FemStats::midnodes_moved_interior);
  f("midnodes_moved_surface", &FemStats::midnodes_moved_surface);
  f("lift_insertions", &FemStats::lift_insertions);
  f("refine_worst_deg_optimized", &FemStats::refine_worst_deg_optimized);
  f("refine_worst_deg", &FemStats::refine_worst_deg);
  f("midnodes_reconciled", &FemStats::midnodes_reconciled);
  f("midnodes_straightened_at_merge", &FemStats::midnodes_straightened_at_merge);
  f("nodes", &FemStats::nodes);
  f("corner_nodes", &FemStats::corner_nodes);
  f("tets", &FemStats::tets);
  f("boundary_triangles", &FemStats::boundary_triangles);
  f("min_dihedral_deg", &FemStats::min_dihedral_deg);
  f("median_tet_min_dihedral_deg", &FemStats::median_tet_min_dihedral_deg);
  f("tets_below_10_deg", &FemStats::tets_below_10_deg);
  f("seconds_surface", &FemStats::seconds_surface);
  f("seconds_core", &FemStats::seconds_core);
  f("seconds_refine", &FemStats::seconds_refine);
  f("seconds_merge", &FemStats::seconds_merge);
  f("seconds_total", &FemStats::seconds_total);
  f("refine_seconds_by_pass", &FemStats::refine_seconds_by_pass);
}

/// The CAD layer's surface options for `options` (size field, face rounds, cancel; no progress).
cad::CadSurfaceOptions cad_surface_options(const FemOptions& options);

}  // namespace bsptet::fem
