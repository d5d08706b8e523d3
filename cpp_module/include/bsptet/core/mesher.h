// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the single entry point of the tetrahedralizer.
//
//   TetMesh tetrahedralize(const SurfaceMesh& surface, const MeshOptions& options, MeshStats* stats)
//
// Pipeline (paper section -> file):
//   input check ................................ mesher.cpp (validate_surface)
//   planes of the input triangles .............. mesher.cpp (group_planes): coplanar triangles share one
//   2.1-2.2  BSP tree, convex cells ............ bsp_complex.cpp (conforming cell complex)
//   2.2.1    BSP points ........................ bsp_complex.cpp (TPI vertices of edge splits)
//   2.2      inside / outside .................. cell_classify.cpp (exact coverage + winding numbers)
//   2.3      per-cell tetrahedralization ....... cell_tetrahedralize.cpp, cell_delaunay.cpp (Bowyer-Watson)
//   2.4/2.5  glue, crossed-edge fixing ......... not needed: the complex is conforming (bsp_complex.h)
//   (new)    Steiner point removal ............. steiner_removal.cpp (collapse, move off the surface)
//   output   doubles, checked exactly .......... snap_round.cpp
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "bsptet/input/surface_check.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

struct MeshOptions {
  /// Keep BSP points on the input surface where they are exactly doubles. The default output has
  /// none (FEM loads find nodes on CAD faces): they are collapsed or moved inside.
  bool allow_boundary_steiner = false;
  /// Fill the inside cells by cones from an apex or a vertex (the filler before the per-cell
  /// Delaunay, cell_tetrahedralize.h CellFill::kCone) instead of the default per-cell Delaunay
  /// (paper Sec. 2.3). For comparison.
  bool cone_cells = false;
  /// Refine the faces on input planes along whole input edge lines (bsp_complex.h
  /// refine_covered_faces_along_lines) instead of one piece per input triangle.
  /// tetrahedralize() retries with it by itself when the Steiner removal gets stuck.
  bool covered_faces_along_lines = false;
  /// What the BSP starts from (bsp_complex.h BspSeed): kDelaunay, the Delaunay tetrahedralization
  /// of the input points (only the cells an input triangle crosses are split: far fewer BSP points
  /// on fine smooth surfaces); kBox, one box cell (the paper's auto-partition); kAuto (default),
  /// the Delaunay seed unless the input triangles cross more than kSeedConflictsPerTriangle of its
  /// tets per triangle on average (long thin triangles across many tets: there the box's
  /// partition is cheaper), then the box. Same kind of output either way (exact, checked).
  enum class Seed { kAuto, kDelaunay, kBox };
  Seed seed = Seed::kAuto;
  static constexpr double kSeedConflictsPerTriangle = 4.0;
  /// BspComplex::set_candidate_shift for the BSP's plane choice (0: the paper's sampling).
  std::size_t bsp_candidate_shift = 0;
  /// SteinerRemovalOptions::interior_work_per_point: how hard the core tries to remove one interior
  /// Steiner point (work: exact orientation tests and cavity growth; 0 = no limit).
  std::int64_t steiner_effort = 1000000;
  /// Check the cell complex's combinatorics after every split (slow; for tests and debugging).
  bool debug_checks = false;
  /// Called with (stage, fraction in [0, 1]); may be empty.
  std::function<void(const std::string&, double)> progress;
  /// Polled between steps; return true to stop (throws an Error with code kCancelled).
  std::function<bool()> cancelled;
};

struct MeshStats {
  std::int64_t input_points = 0, input_triangles = 0, input_planes = 0;
  std::int64_t points = 0, tets = 0, steiner_points = 0, boundary_steiner_points = 0;
  std::int64_t bsp_nodes = 0, convex_cells = 0, inside_cells = 0, bsp_points = 0;
  std::int64_t delaunay_seeded = 0;  ///< 1 when the mesh was made from the Delaunay seed
  std::int64_t seed_tets = 0;  ///< cells of the Delaunay seed (also when kAuto then took the box)
  std::int64_t seed_untouched_tets = 0;  ///< of those, kept out of the cell complex (bsp_complex.h UntouchedSeedTets)
  std::int64_t seed_conflicts = 0;  ///< (seed tet, input triangle crossing it) pairs (BspStats; kAuto stops counting past its bound)
  std::int64_t seed_faces_relabelled = 0;  ///< seed faces given their input plane by the walk (BspStats)
  std::int64_t seed_missing_edges = 0, seed_recovered_edges = 0, seed_flips = 0;  ///< BspStats
  std::int64_t seed_missing_faces = 0, seed_recovered_faces = 0;                ///< BspStats
  std::int64_t seed_fell_back = 0;  ///< the seeded attempt failed and the box meshed (tetrahedralize's retries)
  std::int64_t steiner_before_removal = 0, boundary_steiner_before_removal = 0, collapsed = 0, relocated = 0, pushed = 0;
  std::int64_t apex_cells = 0, pulled_cells = 0;
  std::int64_t delaunay_cells = 0, delaunay_recovered_cells = 0, delaunay_fallback_cells = 0;  ///< CellTets
  std::int64_t exact_fallbacks = 0;
  /// 1 when the first run's Steiner removal got stuck and the mesh comes from the retry with
  /// MeshOptions::covered_faces_along_lines (the failed attempts' seconds are in
  /// seconds_by_stage["first_run"]).
  std::int64_t retried_along_lines = 0;
  /// How many attempts failed before the mesh was made (tetrahedralize's retries: 0, along lines,
  /// then candidate shifts 1 and 2), and the BSP candidate shift of the attempt that made it.
  std::int64_t retries = 0, bsp_candidate_shift = 0;
  /// Seconds per stage: input_check, planes, bsp (the seed included), classify, cell_tets,
  /// steiner_removal, snap_round; and, inside bsp, the Delaunay seed's steps (seed_delaunay,
  /// seed_flips, seed_faces, seed_walk, seed_lines: BspStats::seed_seconds).
  std::map<std::string, double> seconds_by_stage;
  /// The Steiner removal's phases (SteinerRemovalStats::seconds_by_phase, removed_by_phase).
  std::map<std::string, double> steiner_seconds_by_phase;
  std::map<std::string, std::int64_t> steiner_removed_by_phase;
  double seconds_total = 0;
};

/// The options schema, stated once: calls f(name, member pointer) for every value option of
/// MeshOptions (not the callbacks). The bindings bind MeshOptions from it.
template <class F>
void for_each_mesh_option(F&& f) {
  f("allow_boundary_steiner", &MeshOptions::allow_boundary_steiner);
  f("cone_cells", &MeshOptions::cone_cells);
  f("covered_faces_along_lines", &MeshOptions::covered_faces_along_lines);
  f("seed", &MeshOptions::seed);
  f("bsp_candidate_shift", &MeshOptions::bsp_candidate_shift);
  f("steiner_effort", &MeshOptions::steiner_effort);
  f("debug_checks", &MeshOptions::debug_checks);
}

/// The statistics schema, stated once: calls f(key, member pointer) for every figure of
/// MeshStats; the keys are those of the statistics JSON (the bindings add the keys computed from
/// several fields: interior_steiner_points, bsp_seed).
template <class F>
void for_each_mesh_stat(F&& f) {
  f("input_points", &MeshStats::input_points);
  f("input_triangles", &MeshStats::input_triangles);
  f("input_planes", &MeshStats::input_planes);
  f("points", &MeshStats::points);
  f("tets", &MeshStats::tets);
  f("steiner_points", &MeshStats::steiner_points);
  f("boundary_steiner_points", &MeshStats::boundary_steiner_points);
  f("bsp_nodes", &MeshStats::bsp_nodes);
  f("convex_cells", &MeshStats::convex_cells);
  f("inside_cells", &MeshStats::inside_cells);
  f("bsp_points", &MeshStats::bsp_points);
  f("seed_tets", &MeshStats::seed_tets);
  f("seed_untouched_tets", &MeshStats::seed_untouched_tets);
  f("seed_conflicts", &MeshStats::seed_conflicts);
  f("seed_fell_back", &MeshStats::seed_fell_back);
  f("seed_faces_relabelled", &MeshStats::seed_faces_relabelled);
  f("seed_missing_edges", &MeshStats::seed_missing_edges);
  f("seed_recovered_edges", &MeshStats::seed_recovered_edges);
  f("seed_flips", &MeshStats::seed_flips);
  f("seed_missing_faces", &MeshStats::seed_missing_faces);
  f("seed_recovered_faces", &MeshStats::seed_recovered_faces);
  f("steiner_points_before_removal", &MeshStats::steiner_before_removal);
  f("surface_steiner_points_before_removal", &MeshStats::boundary_steiner_before_removal);
  f("collapsed", &MeshStats::collapsed);
  f("relocated", &MeshStats::relocated);
  f("exact_fallbacks", &MeshStats::exact_fallbacks);
  f("retried_along_lines", &MeshStats::retried_along_lines);
  f("retries", &MeshStats::retries);
  f("bsp_candidate_shift", &MeshStats::bsp_candidate_shift);
  f("delaunay_cells", &MeshStats::delaunay_cells);
  f("delaunay_recovered_cells", &MeshStats::delaunay_recovered_cells);
  f("delaunay_fallback_cells", &MeshStats::delaunay_fallback_cells);
  f("apex_cells", &MeshStats::apex_cells);
  f("pulled_cells", &MeshStats::pulled_cells);
  f("seconds_by_stage", &MeshStats::seconds_by_stage);
  f("steiner_seconds_by_phase", &MeshStats::steiner_seconds_by_phase);
  f("steiner_removed_by_phase", &MeshStats::steiner_removed_by_phase);
  f("seconds_core", &MeshStats::seconds_total);
}

/// Checks the input surface: finite coordinates, indices in range, no degenerate or duplicate
/// triangles, every edge shared by exactly two triangles in opposite directions. Throws InputError
/// naming the first offending triangle or vertex.
void validate_surface(const SurfaceMesh& surface);

/// Tetrahedralizes the solid bounded by `surface`. Throws InputError for bad input, MeshingError
/// (code kCancelled when cancelled) otherwise. Output: every input point first (same indices,
/// unused ones dropped and the rest renumbered), then the Steiner points.
TetMesh tetrahedralize(const SurfaceMesh& surface, const MeshOptions& options = {}, MeshStats* stats = nullptr);

/// check_surface(surface, check), then tetrahedralize the checked surface (flipped triangles
/// reversed): the same mesh, and the same first error, as the two calls one after the other. The
/// check's costly step, the self-intersection search (surface_check.h step 9), runs on a second
/// thread while the core meshes; when it finds a pair the core is cancelled and its
/// SelfIntersectionError is thrown, whatever the core did meanwhile (the core fills any closed
/// oriented surface without crashing or looping, even one that crosses itself; its mesh is then
/// dropped). Errors of the steps after 9 are only reported once step 9 has passed, as in
/// check_surface (the core does not repeat its own, weaker input check). `checked` (optional)
/// receives the check's result.
TetMesh check_and_tetrahedralize(const SurfaceMesh& surface, const SurfaceCheckOptions& check,
                                 const MeshOptions& options = {}, MeshStats* stats = nullptr,
                                 SurfaceCheckResult* checked = nullptr);

/// The paper's picture of the BSP (its Figs. 2-6): the leaf cells of the auto-partition of a box
/// around `surface` by the planes of its triangles, each a convex polyhedron, inside the solid
/// (winding 1) or outside (0). For display only: the vertices are rounded to doubles.
struct BspCellsView {
  std::vector<Vec3> points;  ///< every vertex of the complex, rounded
  /// Per leaf cell, its faces, each a vertex cycle (counter-clockwise seen from outside the cell).
  std::vector<std::vector<std::vector<Index>>> cells;
  std::vector<int> inside;  ///< per cell: 1 inside the solid, 0 outside
};

/// Builds the view (validate_surface's errors for a bad surface). The box partition is the
/// paper's; the mesher itself usually starts from a Delaunay seed instead (bsp_seed.h).
BspCellsView bsp_cells_view(const SurfaceMesh& surface);

}  // namespace bsptet
