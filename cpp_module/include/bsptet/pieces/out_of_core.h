// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: a solid meshed in pieces, for memory (the out-of-core mode) and for speed (the
// pieces meshed at the same time). The paper (Sec. 4.3) swaps completed cells to disk; this
// core's peak is in its Delaunay seed, before any cell is complete (docs/design/out-of-core.md),
// so instead the SOLID is cut into pieces, each piece is meshed whole by tetrahedralize
// (mesher.h) and spooled to disk, and the pieces are streamed into one TetGen .node/.ele pair.
// Peak memory: `workers` pieces' runs plus the input surface.
//
//   PieceOptions po;  po.max_piece_triangles = 200000;  po.workers = 2;
//   PieceStats ps;
//   tetrahedralize_in_pieces(surface, MeshOptions{}, po, "out/part", &ps);   // out/part.node, .ele
//
// The three steps are public for engines that run the pieces elsewhere (the Python side's
// cluster engine, FemBspTet/fem/pieces.py): cut_into_pieces, piece_surface + mesh_piece on each
// piece (anywhere), and the numbering below to merge them.
//
// Contract:
//  * `surface` is a closed oriented surface that check_surface (surface_check.h) accepts as it is
//    (outward, no self-intersection): the caller checks it first.
//  * Cuts (solid_cut.h): a piece with more than max_piece_triangles triangles is cut. The
//    candidates are the 3 axes by the quantiles 0.3, 0.35, ..., 0.7 of its triangles' corner
//    sums, tried shortest cut first (the length of the edges between the sides, those on an
//    earlier cap counted three times), until both halves pass check_surface exactly (caps that
//    cross the surface are first repaired, up to 8 times; folded cross-sections and caps that
//    still cross the surface are refused). The self-intersection part of that check looks only at
//    the pairs with a new cap triangle (the other triangles are the parent piece's, already
//    checked), among the triangles whose boxes meet the caps' box: exact, and local to the cut. A piece of at most min_piece_triangles is never cut. A piece that no tried cut splits is meshed whole, and
//    PieceStats::uncut says so (its run may then need more memory than the budget meant).
//  * The caps are made of input vertices and points of their own, and every piece is meshed with no Steiner point on its
//    boundary (MeshOptions::allow_boundary_steiner must be false), so two pieces meet in exactly
//    their caps' triangles: the union of the pieces' meshes is a conforming mesh of the solid
//    (its boundary the input triangles, the caps inside it as interior faces).
//  * check_pieces: each piece's mesh is checked exactly against its own surface (mesh_check.h)
//    before it is spooled; with the cut argument above that checks the whole mesh, in the
//    memory of one piece. A piece that fails throws MeshingError: nothing written.
//  * Output: stem.node (the used input points first, in input order, renumbered as
//    tetrahedralize does, then the caps' own points, which are inside the solid, then each
//    piece's Steiner points in piece order) and stem.ele (each
//    piece's tets in piece order), 1-based, as write_tetgen (mesh_io.h). Both are written to
//    temporary names beside them and renamed when complete; the spool files beside them are
//    removed whatever happens.
//  * Deterministic, and the same for every `workers`: the cuts do not depend on it, each piece's
//    mesh is tetrahedralize's on the piece alone, and the pieces are written in piece order.
//    With workers > 1 the pieces are meshed on that many threads at once (a piece finished out
//    of order waits in memory for the ones before it); a failing piece stops the others and the
//    run throws naming the first failing piece in piece order.
//  * Only the core's output: no quality refinement, first-order tets.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bsptet/core/mesher.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

struct PieceOptions {
  /// A piece with more triangles (its caps included) is cut; 0: no cut (one piece).
  std::int64_t max_piece_triangles = 0;
  /// A piece with at most this many triangles is never cut (cutting small pieces saves no memory
  /// worth having, and their coarse caps are more often refused).
  std::int64_t min_piece_triangles = 1000;
  /// Check each piece's mesh exactly before spooling it (see the contract).
  bool check_pieces = true;
  /// Pieces meshed at the same time, each on a thread of its own (1: one after the other).
  int workers = 1;
  /// Called with one line per cut and per piece meshed (may be empty).
  std::function<void(const std::string&)> log;
};

struct PieceStats {
  std::int64_t pieces = 0, cuts = 0, cuts_refused = 0, cap_triangles = 0, cap_points = 0;
  std::int64_t largest_piece_triangles = 0;
  std::int64_t points = 0, tets = 0, steiner_points = 0;
  bool pieces_checked = false;  ///< every piece's mesh was checked exactly (and was valid)
  double seconds_cutting = 0, seconds_meshing = 0, seconds_writing = 0;
  std::vector<std::string> refused;  ///< why refused cuts were refused, one line each
  std::vector<std::string> uncut;    ///< pieces over max_piece_triangles meshed whole, and why
};

/// Estimated peak bytes of one tetrahedralize run on `triangles` triangles (the program's own
/// measurements: about 1 KiB per triangle at 10^6 on smooth and CAD surfaces, taken as 2 KiB,
/// plus 32 MiB; inputs whose triangles cross many seed tets take more).
std::int64_t estimated_core_peak_bytes(std::int64_t triangles);
/// The largest piece (triangles) whose estimated peak fits in `budget_bytes`; at least 1000.
std::int64_t piece_triangles_for_budget(std::int64_t budget_bytes);

/// The piece size for `workers` pieces meshed at once on `triangles` triangles: a quarter more
/// than an even share, so that a cut at the 0.3 to 0.7 quantiles (the contract) splits the solid
/// into about `workers` pieces, not twice as many (no cap is free: each cut and its checks take
/// about as long as meshing a tenth of its piece). 0 (no cut) for one worker.
std::int64_t piece_triangles_for_workers(std::int64_t triangles, int workers);

/// Step 1: the solid cut into pieces.
struct SolidPieces {
  std::vector<double> xyz;                 ///< the input points, then the caps' own points
  Index input_points = 0;                  ///< how many of xyz are the input's
  std::vector<std::vector<Index>> pieces;  ///< each piece's closed outward surface, over xyz
};
/// Cuts `surface` (checked as in the contract) until every piece is small enough. Fills the
/// cutting figures of `stats` (pieces, cuts, refused, uncut, caps, seconds_cutting).
SolidPieces cut_into_pieces(const SurfaceMesh& surface, const MeshOptions& options, const PieceOptions& piece_options,
                            PieceStats* stats = nullptr);

/// Step 2: a piece as a surface of its own: the points of xyz its triangles use, in ascending
/// order (their ids in xyz returned in `globals`), and its triangles over them.
SurfaceMesh piece_surface(const std::vector<double>& xyz, const std::vector<Index>& triangles, std::vector<Index>& globals);
/// Meshes one piece's surface by tetrahedralize: the piece's points first, as given, then its
/// Steiner points. With `check`, the mesh is checked exactly against the piece's surface; a
/// failing check throws MeshingError naming `name`.
TetMesh mesh_piece(const SurfaceMesh& piece, const MeshOptions& options, bool check, const std::string& name,
                   MeshStats* stats = nullptr);

/// Step 3, the numbering of the merged mesh: for each point of `solid.xyz`, its output id (the
/// used input points in input order, then every cap point), or -1 for an unused input point.
/// The k-th Steiner point of piece p gets (number of used points) + (Steiner points of the
/// pieces before p) + k.
std::vector<Index> merged_point_ids(const SolidPieces& solid);

/// All three steps; see the contract above.
void tetrahedralize_in_pieces(const SurfaceMesh& surface, const MeshOptions& options, const PieceOptions& piece_options,
                              const std::string& stem, PieceStats* stats = nullptr);

}  // namespace bsptet
