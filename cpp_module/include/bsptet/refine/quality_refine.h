// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage: from the core's covering mesh to an FEM mesh of a given element size,
// with better-shaped tets and, on request, 10-node tets.
//
//   TetMesh refine_quality(const SurfaceMesh& surface, const TetMesh& mesh,
//                          const RefineOptions& options, RefineStats* stats)
//
// Input: a valid linear tet mesh of `surface` with double coordinates (the core's output: input
// points first, boundary = the input triangulation or a refinement of it). Output: a valid mesh of
// the same surface (exact mode) or of its projection (with a projection hook), see refine_mesh.h.
//
// Method (local operations, as in mmg or fTetWild; each one decided exactly by RefineMesh):
//  1. size, with a finite `size`: first Delaunay refinement (tets whose circumradius exceeds 0.9
//     times their target get a point at their circumcentre, Bowyer-Watson, refused closer than
//     0.8 times the target to the points of its cavity: the spacing rule that ends it); then
//     edges still longer than split_ratio * target are split at their midpoint, longest
//     (relative to the target) first, until none is left or max_passes; surface edges too (exact
//     points only, or through the projection hook). The target at a point is `size`, lowered near
//     input faces whose tag has a size in `size_by_tag`, graded (grows by at most `grading` per
//     unit length). Edges shorter than 2 * min_size are never split: this bounds the number of
//     points, so the stage terminates whatever the input's angles (near small input angles it
//     stops refining and the worst tets stay there);
//  2. optimization rounds: short edges collapsed (Steiner points only, within their support, never
//     making the worst tet around worse), ODT smoothing of every interior point (to the
//     volume-weighted mean of its tets' circumcentres when the mean angle around it rises), 2-3
//     and 3-2 flips, edge removals and smoothing of interior points that raise the smallest
//     dihedral angle locally (tets below 40 degrees), tets with a radius-edge ratio above the bound get
//     their shortest edge collapsed or their longest edge split, and tets below 15 degrees get a
//     new interior point where it raises the worst angle of its Bowyer-Watson cavity (candidates:
//     the apex of a regular tet over each of their faces, circumcentre, centroid; this lifts the
//     flat tets whose four corners lie on the surface, which no flip can mend). Without a size,
//     the longest-edge splits of slivers are skipped (they only grew the mesh there). With one,
//     they stop at the first round whose tets below 15 degrees are not fewer than the round
//     before's (except, for curved tet10 through a projection hook, while the mesh stays within
//     three times its size after step 1). A tet on which every flip (or every insertion
//     candidate) failed is not tried again until a tet around one of its corners changes
//     (RefineMesh change stamps). Rounds stop when nothing changes
//     or the worst dihedral reaches `min_dihedral_deg`. Input points never move, except those
//     flagged in `sliding_points` (with a hook): the ODT sweeps slide them along their face.
//  2b. separate_face_tags (optional): see the option;
//  2c. order 2 with a projection hook: the tets below 15 degrees polished by flips, moves,
//     collapses and insertions that raise the worst tet and make no more curved elements invalid
//     (curved_room.h);
//  3. order 2: mid-edge nodes (tet10.h), on the true surface through the hook.
// Deterministic: edges and tets are visited in sorted order; no randomness.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "bsptet/refine/refine_mesh.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

struct RefineOptions {
  /// Target edge length h, model units (as FreeCAD's CharacteristicLengthMax). Infinity: no size
  /// bound (only optimization and the per-tag sizes).
  double size = std::numeric_limits<double>::infinity();
  /// Smallest length refinement works at: edges shorter than 2 * min_size are never split. 0:
  /// one eighth of the smallest target size (or 1e-3 of the bounding-box diagonal without sizes).
  double min_size = 0;
  /// Target size near the input triangles of a face tag (a CAD face), model units.
  std::map<std::int32_t, double> size_by_tag;
  /// Also lower the target at the corners of every input triangle to that triangle's mean edge
  /// length (as Gmsh's Mesh.MeshSizeExtendFromBoundary): the volume grades from a surface that
  /// is already meshed to size (a remeshed CAD surface) instead of meeting small surface
  /// triangles with tets of `size`, which are flat there.
  bool size_from_surface = false;
  /// Thin walls: the target at a surface point is at most thickness_ratio times the solid's local
  /// thickness there (the distance across the solid to the nearest opposing input triangle,
  /// wall_thickness.h), never below the floor (min_size). Tets of the asked size across a wall
  /// much thinner than it are flat whatever the optimization does (a hollow sphere whose wall is
  /// 1/17 of h: worst angle 2 degrees; at 4 times the thickness, 7.5). 0: off.
  double thickness_ratio = 4;
  /// How fast the target grows away from smaller sizes: at most `grading` per unit length.
  double grading = 0.5;
  /// An edge is split when longer than split_ratio * target (1.0 would make `size` a strict
  /// maximum). Midpoint bisection leaves points much closer than the longest edge: with 1.4 the
  /// median edge came out at 0.56 h and 4 to 9 times Gmsh's tets at its CharacteristicLengthMax
  /// = h; with 2.0 (and the collapses below) the median edge is about 0.8 h, Gmsh's 1.0 h (its
  /// edges reach 2 h), and the counts 1.2 to 3 times Gmsh's (docs/design/quality-stage.md).
  double split_ratio = 2.0;
  /// Edges shorter than collapse_ratio * target are collapsed where a Steiner point can go (never
  /// making an edge longer than split_ratio * target, and see collapse_min_dihedral_deg).
  double collapse_ratio = 0.8;
  /// A collapse is applied when its new tets' smallest dihedral angle is at least
  /// min(max(collapse_min_dihedral_deg, the mesh's worst), the worst tet's around the point
  /// before); degrees. So collapses never lower the mesh's worst angle, and may lower a local
  /// worst down to this bound. 180: a collapse never makes the worst tet around worse (many
  /// short edges then stay).
  double collapse_min_dihedral_deg = 10;
  /// Tets whose circumradius / shortest edge exceeds this are refined (0: no bound). TetGen's -q
  /// default is 2.0; 1.414 is stricter.
  double radius_edge_bound = 0;
  /// The optimization stops when the smallest dihedral angle reaches this (degrees; 0: it runs
  /// until no operation helps or optimize_rounds).
  double min_dihedral_deg = 0;
  /// Make the mesh readable by FEM pre-processors that find the element faces on a CAD face by
  /// node membership alone (FreeCAD's getccxVolumesByFace and its CalculiX writer: a tet counts
  /// as having a face on face tag T when exactly three of its corners lie on T). After this step
  /// no tet has four corners on one tag's boundary triangles, and a tet with three corners on tag
  /// T has them as one of its boundary faces of tag T. Done by splitting, per offending tet, an
  /// edge between two such corners that is not an edge of a boundary face of tag T (an interior
  /// edge, or an edge of another tag's face: the new point lies off T). Only with face tags.
  bool separate_face_tags = false;
  /// Face tags whose input triangles are kept as they are: no point is put on a boundary edge of
  /// a triangle with one of these tags (RefineMesh::set_fixed_tags). A face two solids share,
  /// each solid refined by its own call, stays conforming so. Tet10 mid-nodes on those faces are
  /// still placed by the hook.
  std::vector<std::int32_t> fixed_tags;
  /// 1: linear tets; 2: 10-node tets (tet10.h).
  int order = 1;
  int max_passes = 40;       ///< size passes at most
  int optimize_rounds = 8;   ///< optimization rounds at most
  /// Moves every new surface point onto the true surface; empty: see surface_points.
  ProjectionHook projection;
  /// With a projection hook: the input points (flags indexed like the surface's points) that
  /// the smoothing may slide along their true surface face, the hook putting them back on it
  /// (RefineMesh::set_sliding_points). The FEM path flags the CAD nodes inside a face that no
  /// other solid shares; a point on a CAD edge or vertex never moves. Empty: none moves.
  std::vector<char> sliding_points;
  /// Without a hook: kExact (default) puts points on the surface only where a double lies exactly
  /// on the facet (the output tiles the input exactly; elsewhere surface edges stay long);
  /// kRounded takes rounded midpoints (refines every facet; boundary within rounding of the input).
  SurfacePoints surface_points = SurfacePoints::kExact;
  /// Called with (stage, fraction in [0, 1]); may be empty.
  std::function<void(const std::string&, double)> progress;
  /// Polled between steps; return true to stop (throws MeshingError with code kCancelled).
  std::function<bool()> cancelled;
};

struct RefineStats {
  std::int64_t points = 0, tets = 0, nodes = 0;
  std::int64_t splits = 0;               ///< edges split (all)
  std::int64_t surface_splits = 0;       ///< of which on the surface
  std::int64_t splits_no_exact_point = 0;  ///< surface edges left long: no double exactly on them
  std::int64_t splits_rejected = 0;      ///< splits refused (a new tet not positive)
  std::int64_t projection_rejected = 0;  ///< hook results refused (non-finite)
  std::int64_t splits_fixed_surface = 0;  ///< surface edges left: their face tag is fixed
  std::int64_t collapses = 0, flips23 = 0, flips32 = 0, relocations = 0;
  /// Of `collapses`: Steiner corners of near-flat tets collapsed whatever their edge lengths.
  std::int64_t flat_collapses = 0;
  std::int64_t edge_removals = 0;        ///< n-to-2(n-2) flips, 4 <= n <= 7 (RefineMesh::remove_edge)
  std::int64_t insertions = 0;           ///< interior points inserted where they raise the worst angle
  std::int64_t refinement_points = 0;    ///< interior points of the Delaunay refinement (size)
  std::int64_t size_passes = 0, optimize_rounds = 0;
  /// Edges of the result longer than split_ratio * the asked target (size, size_by_tag, graded;
  /// not raised around edges that could not be split).
  std::int64_t long_edges_left = 0;
  std::int64_t tag_splits = 0;           ///< separate_face_tags: edges split
  std::int64_t tag_conflicts_left = 0;   ///< separate_face_tags: tets still offending (see there)
  std::int64_t midnodes_projected = 0, midnodes_straightened = 0;  ///< order 2 (tet10.h)
  std::int64_t curving_lifts = 0;  ///< order 2 with a hook: changes made by CurvedRoom::lift (curved_room.h)
  std::int64_t curving_conflicts_left = 0;  ///< tets whose curved element (interior mid-nodes
                                            ///< straight) was still invalid; the tet10 lift mends them
  /// Order 2 with a hook, the tet10 lift (tet10.h make_second_order): tets made valid by moving
  /// mid-nodes, interior mid-nodes moved off their chords, boundary mid-nodes moved along their
  /// CAD face or edge, interior points inserted for tets the moves could not mend.
  std::int64_t midnodes_relaxed_tets = 0, midnodes_moved_interior = 0, midnodes_moved_surface = 0;
  std::int64_t lift_insertions = 0;
  /// Smallest min dihedral angle of the linear tets (degrees) when the optimization (and
  /// separate_face_tags) is done, and at the end (the output's corner tets: after the polish of
  /// curved_room.h and the points the tet10 lift inserts). 180 for a mesh without tets.
  double worst_deg_optimized = 180, worst_deg = 180;
  double seconds = 0;
  /// Wall seconds per pass: targets, size, collapse, flip, smooth, radius_edge, insert, sliver,
  /// separate_face_tags, curving, tet10 (order 2: make_second_order) (the passes that ran).
  std::map<std::string, double> seconds_by_pass;
};

/// The options schema, stated once: calls f(name, member pointer) for every value option of
/// RefineOptions (not the hook and the callbacks). The bindings bind RefineOptions from it; the
/// Python options (FemBspTet.kernel.core.REFINE_OPTIONS) are checked against it by a test.
template <class F>
void for_each_refine_option(F&& f) {
  f("size", &RefineOptions::size);
  f("min_size", &RefineOptions::min_size);
  f("size_by_tag", &RefineOptions::size_by_tag);
  f("size_from_surface", &RefineOptions::size_from_surface);
  f("thickness_ratio", &RefineOptions::thickness_ratio);
  f("grading", &RefineOptions::grading);
  f("split_ratio", &RefineOptions::split_ratio);
  f("collapse_ratio", &RefineOptions::collapse_ratio);
  f("collapse_min_dihedral_deg", &RefineOptions::collapse_min_dihedral_deg);
  f("radius_edge_bound", &RefineOptions::radius_edge_bound);
  f("min_dihedral_deg", &RefineOptions::min_dihedral_deg);
  f("separate_face_tags", &RefineOptions::separate_face_tags);
  f("fixed_tags", &RefineOptions::fixed_tags);
  f("order", &RefineOptions::order);
  f("max_passes", &RefineOptions::max_passes);
  f("optimize_rounds", &RefineOptions::optimize_rounds);
  f("surface_points", &RefineOptions::surface_points);
}

/// The statistics schema, stated once: calls f(key, member pointer) for every figure of
/// RefineStats; the keys are those of the statistics JSON.
template <class F>
void for_each_refine_stat(F&& f) {
  f("points", &RefineStats::points);
  f("tets", &RefineStats::tets);
  f("nodes", &RefineStats::nodes);
  f("splits", &RefineStats::splits);
  f("surface_splits", &RefineStats::surface_splits);
  f("splits_no_exact_point", &RefineStats::splits_no_exact_point);
  f("splits_rejected", &RefineStats::splits_rejected);
  f("projection_rejected", &RefineStats::projection_rejected);
  f("splits_fixed_surface", &RefineStats::splits_fixed_surface);
  f("collapses", &RefineStats::collapses);
  f("flat_collapses", &RefineStats::flat_collapses);
  f("flips23", &RefineStats::flips23);
  f("flips32", &RefineStats::flips32);
  f("edge_removals", &RefineStats::edge_removals);
  f("relocations", &RefineStats::relocations);
  f("insertions", &RefineStats::insertions);
  f("refinement_points", &RefineStats::refinement_points);
  f("size_passes", &RefineStats::size_passes);
  f("optimize_rounds", &RefineStats::optimize_rounds);
  f("long_edges_left", &RefineStats::long_edges_left);
  f("tag_splits", &RefineStats::tag_splits);
  f("tag_conflicts_left", &RefineStats::tag_conflicts_left);
  f("midnodes_projected", &RefineStats::midnodes_projected);
  f("midnodes_straightened", &RefineStats::midnodes_straightened);
  f("curving_lifts", &RefineStats::curving_lifts);
  f("curving_conflicts_left", &RefineStats::curving_conflicts_left);
  f("midnodes_relaxed_tets", &RefineStats::midnodes_relaxed_tets);
  f("midnodes_moved_interior", &RefineStats::midnodes_moved_interior);
  f("midnodes_moved_surface", &RefineStats::midnodes_moved_surface);
  f("lift_insertions", &RefineStats::lift_insertions);
  f("worst_deg_optimized", &RefineStats::worst_deg_optimized);
  f("worst_deg", &RefineStats::worst_deg);
  f("seconds", &RefineStats::seconds);
  f("seconds_by_pass", &RefineStats::seconds_by_pass);
}

/// Refines and optimizes `mesh`, a valid linear tet mesh of `surface`. Throws InputError for bad
/// options (naming the option), MeshingError otherwise (code kCancelled when cancelled).
/// `boundary` (optional) receives the result's boundary faces (faces of one tet), oriented outward,
/// as corner indices of the result, each with the tag of the input triangle it lies on (-1 when
/// the surface has no tags), in the order of their sorted corners; its `xyz` is left empty.
TetMesh refine_quality(const SurfaceMesh& surface, const TetMesh& mesh, const RefineOptions& options,
                       RefineStats* stats = nullptr, SurfaceMesh* boundary = nullptr);

}  // namespace bsptet
