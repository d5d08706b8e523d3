// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage: the last polish of the worst tets, keeping room for curved 10-node
// tets (step 2c of quality_refine.h), with a projection hook and order 2, before the mid-nodes
// are placed (tet10.h).
//
// A curved element here is the tet10 of a linear tet whose boundary edges' mid-nodes lie on the
// true surface (the hook at the edge's midpoint, with the tags of the edge's boundary faces) and
// whose other mid-nodes are straight; it is valid when certify_tet10 certifies its Jacobian
// determinant positive (a tet with no curved edge is valid as its corner tet is positive).
// Elements left invalid here are mended later by moving mid-nodes (tet10.h, make_second_order).
// Only when that leaves mid-nodes straightened (off the true surface) does the stage go back to
// the linear mesh as it was before the tet10 lift and make room first (lift: interior points
// lifted off the curved faces, reconnections, insertions, down to 1 degree), then polish and lift
// the tet10 again, keeping whichever tet10 mesh straightened fewer mid-nodes
// (quality_refine.cpp). Making room always, before the mid-node moves, made worse meshes on CAD
// parts (t20_data: worst 3.7 degrees against 12.1) and no fewer straightened mid-nodes there; a
// coarse thin tube (6 segments around) needs it to keep every mid-node on its surface.
//
// Contract:
//  * Takes a valid RefineMesh whose boundary is final (no later step splits a surface edge),
//    RefineOptions already checked, the stats it adds its counts to, the TargetSizes and the
//    MeshOptimizer of the stage; all must outlive it.
//  * lift() and polish(below) do nothing without a hook or with order 1. lift() lifts interior
//    points, changes connectivity or inserts interior points so that fewer curved elements are
//    invalid, accepting new tets down to min(10 degrees, the worst they replace), then, for what
//    that leaves, down to min(1 degree, the worst they replace). polish(below) raises the
//    tets below `below` degrees, never lowering the worst tet a change replaces and never making
//    more curved elements invalid than it removes, so it never lowers the mesh's worst angle.
//    Both set RefineStats::curving_conflicts_left to the invalid curved elements they leave.
//  * After either the linear mesh is valid (mesh_check.h), covers the same region and has the same
//    boundary: input points, boundary points and the surface never move.
//  * element_ok needs prepare_check() (lift and polish call it) after the last change of the boundary;
//    hook results are cached per boundary edge (boundary points never move).
//  * Deterministic: tets worst first or in index order, candidates in a fixed order.
#pragma once

#include <array>
#include <cstdint>
#include <map>

#include "bsptet/mesh/edge_map.h"
#include "bsptet/mesh/types.h"
#include "bsptet/refine/mesh_optimizer.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/target_sizes.h"

namespace bsptet {

class CurvedRoom {
 public:
  CurvedRoom(RefineMesh& m, const RefineOptions& o, RefineStats& st, TargetSizes& size, MeshOptimizer& opt)
      : m_(m), o_(o), st_(st), size_(size), opt_(opt) {}

  /// Makes the invalid curved elements valid where it can (see the contract); sets
  /// RefineStats::curving_conflicts_left.
  void lift();
  /// Flips, moves, collapses and insertions around the tets below `below` degrees (see the
  /// contract); returns the changes made.
  std::int64_t polish(double below);

  /// The tags of each boundary edge's faces, for the hook; call once the surface is final.
  void prepare_check();
  /// True when the curved element of corners q at positions P is valid (see above).
  bool element_ok(const std::array<Index, 4>& q, const std::array<Vec3, 4>& P);

 private:
  void lift_rounds();
  bool insert_keeping_curved(Index t);
  bool move_keeping_curved(Index v);
  template <class CurvedOk, class Corners>
  bool reconnect_for_curving(Index t, const CurvedOk& curved_ok, const Corners& corners);

  RefineMesh& m_;
  const RefineOptions& o_;
  RefineStats& st_;
  TargetSizes& size_;
  MeshOptimizer& opt_;
  EdgeMap<std::array<std::int32_t, 2>> edge_tags_;  // prepare_check (edge_key)
  EdgeMap<Vec3> projected_;  // hook results at boundary edge midpoints (edge_key)
  double floor_deg_ = 1.0;  // lift: no new tet below min(this, the worst it replaces)
};

}  // namespace bsptet
