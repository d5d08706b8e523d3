// SPDX-License-Identifier: LGPL-2.1-or-later
// The quality stage's refinement to size (size_refine.h).
#include "bsptet/refine/size_refine.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <vector>

#include "bsptet/mesh/tet_shape.h"

namespace bsptet {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Delaunay refinement (SizeRefiner::delaunay_refine): tets with a circumradius above this times
// the target get a point; none lands closer than kRefineSpacing times the target to the points
// of its cavity. A regular tet of edge h has circumradius 0.61 h.
constexpr double kRefineCircumradius = 0.9;
constexpr double kRefineSpacing = 0.8;

}  // namespace

// A bound on the points the size phase may create: four times what regular tets of the smallest
// target would need to fill the volume, plus the input's. It only stops a runaway.
void SizeRefiner::set_budget() {
  double volume = 0, smallest = kInf;
  for (Index t = 0; t < m_.num_tet_slots(); ++t) {
    if (!m_.tet_alive(t)) continue;
    const auto& q = m_.tet(t);
    const Vec3 a = m_.point(q[0]), b = m_.point(q[1]), c = m_.point(q[2]), d = m_.point(q[3]);
    const double bx = b.x - a.x, by = b.y - a.y, bz = b.z - a.z, cx = c.x - a.x, cy = c.y - a.y, cz = c.z - a.z,
                 dx = d.x - a.x, dy = d.y - a.y, dz = d.z - a.z;
    volume += (bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx)) / 6;
  }
  for (double t : size_.targets()) smallest = std::min(smallest, t);
  smallest = std::max(smallest, size_.floor());
  const double regular = smallest * smallest * smallest / (6 * std::sqrt(2.0));
  const double estimate = std::isfinite(regular) && regular > 0 ? 4 * volume / regular : 0;
  budget_ = m_.num_points() + static_cast<Index>(std::min(estimate + 1000.0, 5e8));
}

// Tets whose circumradius exceeds kRefineCircumradius * their target (the mean of their
// corners') get a point at their circumcentre, inserted Bowyer-Watson (RefineMesh::insert_point:
// the cavity is shaped by the circumspheres, made star-shaped exactly), largest relative radius
// first, in rounds until none is left. The spacing rule: the insertion is refused when a vertex
// of its cavity is closer than kRefineSpacing * the target there, so every new point keeps that
// distance from the points it connects to and the refinement ends. A circumcentre outside the
// solid (or on its boundary) is skipped: the surface is already at size (the CAD surface
// mesher), and the edge-split phase after this one splits what is still long. Points spread
// this way are far more regular than midpoints of split edges, so the optimization that
// follows has less to mend. Only with a finite size.
void SizeRefiner::delaunay_refine() {
  if (!std::isfinite(o_.size)) return;
  set_budget();
  FailureMemory refused_at;  // failure memory as the flip pass's
  for (int round = 0; round < o_.max_passes; ++round) {
    poll_refine(o_, "refining to size", std::min(0.4, 0.04 * round));
    std::vector<std::tuple<double, Index>> todo;
    for (Index t = 0; t < m_.num_tet_slots(); ++t) {
      if (!m_.tet_alive(t) || refused_at.failed_before(m_, t)) continue;
      const auto& q = m_.tet(t);
      Vec3 c;
      double r2 = 0;
      if (!tet_circumsphere(m_.point(q[0]), m_.point(q[1]), m_.point(q[2]), m_.point(q[3]), &c, &r2)) continue;
      const double tg = 0.25 * (size_.target(q[0]) + size_.target(q[1]) + size_.target(q[2]) + size_.target(q[3]));
      const double ratio = std::sqrt(r2) / tg;
      if (ratio > kRefineCircumradius) todo.emplace_back(-ratio, t);
    }
    if (todo.empty()) break;
    std::sort(todo.begin(), todo.end());
    std::int64_t done = 0;
    for (const auto& [key, t] : todo) {
      if (m_.num_points() >= budget_) return;
      if (!m_.tet_alive(t)) continue;
      const auto q = m_.tet(t);
      Vec3 c;
      double r2 = 0;
      if (!tet_circumsphere(m_.point(q[0]), m_.point(q[1]), m_.point(q[2]), m_.point(q[3]), &c, &r2)) continue;
      const double tg = 0.25 * (size_.target(q[0]) + size_.target(q[1]) + size_.target(q[2]) + size_.target(q[3]));
      Index p = -1;
      if (m_.insert_point(t, c, kRefineSpacing * tg, &p, 256) == InsertOutcome::kInserted) {
        ++st_.refinement_points;
        size_.set_target(p, size_.graded_target(c, q));
        ++done;
      } else {
        refused_at.record(m_, t);
      }
    }
    if (done == 0) break;
  }
}

void SizeRefiner::split_long_edges(double min_quality) {
  set_budget();
  for (int pass = 0; pass < o_.max_passes; ++pass) {
    poll_refine(o_, "refining to size", std::min(0.5, 0.05 * pass));
    if (pass > 0) size_.compute();
    std::vector<std::tuple<double, Index, Index>> todo;
    for (const auto& e : m_.edges())
      if (size_.is_long(e[0], e[1])) todo.emplace_back(-size_.length(e[0], e[1]) / size_.edge_target(e[0], e[1]), e[0], e[1]);
    if (todo.empty()) break;
    std::sort(todo.begin(), todo.end());
    std::int64_t done = 0;
    for (const auto& [key, u, v] : todo) {
      if (m_.num_points() >= budget_) break;
      done += size_.split(u, v, min_quality, st_) ? 1 : 0;
    }
    ++st_.size_passes;
    opt_.flip_pass(30.0);
    if (done == 0) break;
  }
}

}  // namespace bsptet
