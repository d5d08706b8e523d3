// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the out-of-core mode. The paper (Sec. 4.3) swaps completed cells to disk; this
// core's peak is in its Delaunay seed, before any cell is complete (docs/design/out-of-core.md),
// so instead the SOLID is cut into pieces small enough for the memory, each piece is meshed
// whole by tetrahedralize (mesher.h) and spooled to disk, and the pieces are streamed into one
// TetGen .node/.ele pair. Peak memory: the largest piece's run plus the input surface.
//
//   PieceOptions po;  po.max_piece_triangles = 200000;
//   PieceStats ps;
//   tetrahedralize_in_pieces(surface, MeshOptions{}, po, "out/part", &ps);   // out/part.node, .ele
//
// Contract:
//  * `surface` is a closed oriented surface that check_surface (surface_check.h) accepts as it is
//    (outward, no self-intersection): the caller checks it first.
//  * Cuts (solid_cut.h): a piece with more than max_piece_triangles triangles is cut. The
//    candidates are the 3 axes by the quantiles 0.3, 0.35, ..., 0.7 of its triangles' corner
//    sums, tried shortest cut first (the length of the edges between the sides, those on an
//    earlier cap counted three times), until both halves pass check_surface exactly (caps that
//    cross the surface are first repaired, up to 8 times; folded cross-sections and caps that
//    still cross the surface are refused). A piece of at most min_piece_triangles is never cut. A piece that no tried cut splits is meshed whole, and
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
//    removed whatever happens. Deterministic.
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

/// See the contract above.
void tetrahedralize_in_pieces(const SurfaceMesh& surface, const MeshOptions& options, const PieceOptions& piece_options,
                              const std::string& stem, PieceStats* stats = nullptr);

}  // namespace bsptet
