// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage: the optimization passes of the linear tets (step 2 of quality_refine.h):
// collapses of short edges and of Steiner corners of flat tets, ODT smoothing, flips and edge
// removals, moves of interior points, new interior points for the worst tets, splits of slivers'
// longest edges and the radius-edge pass, and optimize(), the rounds that run them.
//
// Contract:
//  * Takes a valid RefineMesh, RefineOptions already checked, the stats it adds its counts to, and
//    the TargetSizes whose targets it reads (and sets for the points it makes); all must outlive it.
//  * Every operation goes through RefineMesh's exact local operations, so after any call the mesh
//    is valid (mesh_check.h) and, without a projection hook, covers the same region (exactly the
//    same volume): input points and boundary points never move. Points are added by insert_for
//    (insert_pass), sliver_pass (interior points) and radius_edge_pass (its splits may put a
//    point on a surface edge, through RefineMesh::split_edge and the projection hook when there
//    is one); the collapses remove Steiner points only, within their support.
//  * Angles are smallest dihedral angles of a tet in degrees (RefineMesh::tet_quality). What each
//    pass promises about them is stated at the pass (mesh_optimizer.cpp); in short: flip_pass,
//    smooth_pass (and smooth_point), collapse_pass and flat_collapse_pass never lower the mesh's
//    worst angle; odt_smooth_pass keeps every moved point's tets at or above min(their worst
//    before, 15 degrees); radius_edge_pass's splits, and sliver_pass's for curved tet10, may
//    lower it.
//  * Passes return the number of changes they made; a pass that returns 0 changed nothing.
//  * Deterministic: tets are visited worst first (ties by index), points and edges in index order.
#pragma once

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bsptet/mesh/types.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/target_sizes.h"

namespace bsptet {

/// Accepts a point move from the corner positions of the moved point's tets (in the order of
/// RefineMesh::tets_around_point), as RefineMesh::relocate_point_if.
using MoveAccept = std::function<bool(const std::vector<std::array<Vec3, 4>>&)>;

/// Face (A, B, C) of a tet whose fourth corner is D, for placing points over it.
struct FaceFrame {
  Vec3 centroid;
  Vec3 normal;  ///< unit, towards D
  double mean_edge = 0;
  /// The point at `fraction` of a regular tet's height (sqrt(2/3) * mean edge) over the face.
  Vec3 apex(double fraction) const {
    const double h = fraction * std::sqrt(2.0 / 3.0) * mean_edge;
    return {centroid.x + normal.x * h, centroid.y + normal.y * h, centroid.z + normal.z * h};
  }
};

/// The frame of face (A, B, C) towards D; false for a degenerate face (f untouched).
bool face_frame(const Vec3& A, const Vec3& B, const Vec3& C, const Vec3& D, FaceFrame* f);

/// The positions of the corners q of a tet of m.
inline std::array<Vec3, 4> corner_points(const RefineMesh& m, const std::array<Index, 4>& q) {
  return {m.point(q[0]), m.point(q[1]), m.point(q[2]), m.point(q[3])};
}

/// Throws MeshingError(kCancelled) when o.cancelled says so, else reports (stage, fraction) to
/// o.progress (when set).
void poll_refine(const RefineOptions& o, const std::string& stage, double fraction);

/// Runs f, adding its wall time to st.seconds_by_pass[pass]; returns f's result.
template <class F>
std::int64_t timed_pass(RefineStats& st, const char* pass, F&& f) {
  const auto start = std::chrono::steady_clock::now();
  const std::int64_t result = f();
  st.seconds_by_pass[pass] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

/// Failure memory of the flip and insertion passes: a tet on which every operation failed is not
/// tried again until a tet around one of its corners changes (RefineMesh::tet_stamp). Exact for
/// the 3-2 and 2-3 flips and edge removals up to their checks that a new edge does not exist yet;
/// for insertions the cavity can reach further, so a retry that would now succeed can be skipped
/// (adis16480 at h = diagonal / 20: 2.3 million attempts for 3,600 insertions before this).
class FailureMemory {
 public:
  /// True when t failed and no tet around its corners changed since.
  bool failed_before(const RefineMesh& m, Index t) const {
    const auto i = static_cast<std::size_t>(t);
    return i < at_.size() && at_[i] != 0 && m.tet_stamp(t) <= at_[i];
  }
  /// Remembers that t failed now (RefineMesh::clock).
  void record(const RefineMesh& m, Index t) {
    const auto i = static_cast<std::size_t>(t);
    if (at_.size() <= i) at_.resize(std::max<std::size_t>(i + 1, 2 * at_.size()), 0);
    at_[i] = std::max<std::uint64_t>(m.clock(), 1);
  }

 private:
  std::vector<std::uint64_t> at_;
};

/// The same for moves of a point: a point whose move failed is not tried again until a tet around
/// it changes (RefineMesh::point_stamp), exact when the move depends on those tets alone.
class PointFailureMemory {
 public:
  /// True when v's last try failed and no tet around v changed since; otherwise notes a try of v
  /// starting now (a move touches v's tets, which stamps v anew, so only a failure keeps it).
  bool skip(const RefineMesh& m, Index v) {
    const auto i = static_cast<std::size_t>(v);
    if (tried_at_.size() <= i) tried_at_.resize(std::max<std::size_t>(i + 1, 2 * tried_at_.size()), 0);
    if (tried_at_[i] != 0 && m.point_stamp(v) <= tried_at_[i]) return true;
    tried_at_[i] = std::max<std::uint64_t>(m.clock(), 1);
    return false;
  }

 private:
  std::vector<std::uint64_t> tried_at_;
};

class MeshOptimizer {
 public:
  /// Edge removals (RefineMesh::remove_edge) look at shells of at most this many tets.
  static constexpr int kMaxEdgeRing = 7;

  MeshOptimizer(RefineMesh& m, const RefineOptions& o, RefineStats& st, TargetSizes& size)
      : m_(m), o_(o), st_(st), size_(size) {}

  /// Up to `rounds` optimization rounds (quality_refine.h, step 2): collapse_pass,
  /// flat_collapse_pass, odt_smooth_pass, flip_pass, smooth_pass, radius_edge_pass, flip_pass,
  /// insert_pass, and (with a finite size, not in the last round) sliver_pass while the tets below
  /// 15 degrees get fewer. Stops when a round changes nothing or the worst angle reaches
  /// min_dihedral_deg. `tets_after_size`: the live tets after the first size phase (curved tet10
  /// keeps the sliver pass while the mesh stays within three times that).
  void optimize(int rounds, Index tets_after_size);

  // ---- The passes (each returns its changes) ----
  /// 3-2 flips of the edges, 2-3 flips of the faces, edge removals of the tets below `below`
  /// degrees, worst first, the first that raises the worst tet involved; up to 4 sweeps.
  std::int64_t flip_pass(double below);
  /// Collapses edges shorter than collapse_ratio * target (one end a Steiner point).
  std::int64_t collapse_pass();
  /// Collapses Steiner corners of the tets below `below` degrees whatever their edge lengths.
  std::int64_t flat_collapse_pass(double below);
  /// ODT smoothing: a sweep over every interior point and every sliding surface point
  /// (RefineMesh::slides), then up to sweeps - 1 more over the neighbours of the points the
  /// previous sweep moved.
  std::int64_t odt_smooth_pass(int sweeps);
  /// Moves the interior corners of the tets below `below` degrees (smooth_point).
  std::int64_t smooth_pass(double below);
  /// A new interior point for each tet below `below` degrees where one raises the worst angle.
  std::int64_t insert_pass(double below);
  /// Splits the longest interior edge of the tets below `below` degrees (only with a size).
  std::int64_t sliver_pass(double below);
  /// Tets above radius_edge_bound: shortest edge collapsed, else longest edge split.
  std::int64_t radius_edge_pass();

  // ---- Single operations ----
  /// odt_smooth_pass's move of interior point v (the ODT point, else its neighbours' centroid)
  /// or of sliding surface point v (its boundary neighbours' centroid, else the ODT point, each
  /// put back on its face); a point whose move failed is not tried again until a tet around it
  /// changes (RefineMesh::point_stamp); when it moves, sets moved_near[w] for every corner w of
  /// its tets. True when v moved.
  bool odt_move(Index v, std::vector<char>* moved_near);
  /// Moves interior point v to the first position that raises the worst tet around it; true when
  /// it moved. Not tried again after a failure until a tet around v changes.
  bool smooth_point(Index v);
  /// Steepest ascent of the worst angle around interior point v (steps from 0.1 * mean_edge);
  /// with `keep`, every step must also pass it. True when v moved.
  bool ascend_point(Index v, double mean_edge, const MoveAccept* keep = nullptr);
  /// One interior point that improves tet t (see insert_pass); false when no candidate does.
  bool insert_for(Index t);

  // ---- Queries ----
  /// The live tets below q degrees, worst first (ties by index).
  std::vector<Index> tets_below(double q) const;
  std::size_t count_below(double q) const;
  /// Curved tet10 through a projection hook (FreeCAD's tet10). Its insertion and sliver passes
  /// keep an earlier form (no forced tet, one height, the h / 8 clearance floor, sliver splits not
  /// held to the worst angle; insert_point's walk is the one of the other meshes): the curving
  /// stage after them needs the room those left over curved faces. With the other form 9 of the
  /// 13 CAD corpus files meshed at tet10 instead of 10 (featuretype.STEP and bottle.brep stopped
  /// with inverted curved elements, SampleCrankshaft4A meshed).
  bool curved_tet10() const { return o_.order == 2 && static_cast<bool>(o_.projection); }

 private:
  RefineMesh& m_;
  const RefineOptions& o_;
  RefineStats& st_;
  TargetSizes& size_;
  FailureMemory flip_failed_, insert_failed_;
  PointFailureMemory odt_failed_, smooth_failed_;
};

}  // namespace bsptet
