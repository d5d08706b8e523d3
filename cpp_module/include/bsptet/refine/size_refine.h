// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage: refinement to size (step 1 of quality_refine.h): interior points by
// Delaunay refinement, then splits of the edges still long.
//
// Contract:
//  * Takes a valid RefineMesh, RefineOptions already checked, the stats it adds its counts to,
//    the TargetSizes (computed: TargetSizes::compute) whose targets it reads and sets for the points
//    it makes, and the MeshOptimizer whose flip_pass runs after each pass of split_long_edges; all
//    must outlive it.
//  * Both phases only add points (and flips): after either, the mesh is valid (mesh_check.h),
//    covers the same region (same volume) and tiles the same boundary surface; input points never
//    move. delaunay_refine adds interior points only; split_long_edges also splits surface edges
//    (exact points only, or through the projection hook, RefineMesh::split_edge).
//  * Termination: no inserted point is closer than 0.8 times the target to the points of its
//    cavity, no edge shorter than 2 * TargetSizes::floor() is split, at most max_passes rounds or
//    passes each, and both stop at a budget of four times the points regular tets of the smallest
//    target would need (plus the input's).
//  * Deterministic: tets and edges are visited in sorted order (largest relative size first).
#pragma once

#include "bsptet/mesh/types.h"
#include "bsptet/refine/mesh_optimizer.h"
#include "bsptet/refine/quality_refine.h"
#include "bsptet/refine/refine_mesh.h"
#include "bsptet/refine/target_sizes.h"

namespace bsptet {

class SizeRefiner {
 public:
  SizeRefiner(RefineMesh& m, const RefineOptions& o, RefineStats& st, TargetSizes& size, MeshOptimizer& opt)
      : m_(m), o_(o), st_(st), size_(size), opt_(opt) {}

  /// Tets whose circumradius exceeds 0.9 times their target (the mean of their corners') get a
  /// point at their circumcentre (Bowyer-Watson), largest relative radius first, in rounds until
  /// none is left or none goes in; counts RefineStats::refinement_points. Only with a finite size.
  void delaunay_refine();
  /// Splits the edges longer than split_ratio * their target (TargetSizes::is_long) at their
  /// midpoint, longest relative to the target first, in passes (targets recomputed before each
  /// but the first, flip_pass(30) after each) until none is split or max_passes; counts
  /// RefineStats::size_passes. `min_quality`: as RefineMesh::split_edge's (0: any valid split).
  void split_long_edges(double min_quality = 0);

 private:
  void set_budget();

  RefineMesh& m_;
  const RefineOptions& o_;
  RefineStats& st_;
  TargetSizes& size_;
  MeshOptimizer& opt_;
  Index budget_ = 0;
};

}  // namespace bsptet
