// SPDX-License-Identifier: LGPL-2.1-or-later
// The quality stage's target sizes (target_sizes.h).
#include "bsptet/refine/target_sizes.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

namespace bsptet {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

// Target size per point: `size`, lowered near tagged faces, graded along mesh edges (Dijkstra).
void TargetSizes::compute(bool raise_stuck) {
  const Index np = m_.num_points();
  target_.assign(static_cast<std::size_t>(np), o_.size);
  if (!o_.size_by_tag.empty())
    for (const auto& [face, parent] : m_.boundary_faces()) {
      auto it = o_.size_by_tag.find(m_.tag_of(parent));
      if (it == o_.size_by_tag.end()) continue;
      for (Index v : face) target_[static_cast<std::size_t>(v)] = std::min(target_[static_cast<std::size_t>(v)], it->second);
    }
  if (o_.size_from_surface) {
    const SurfaceMesh& in = m_.surface();
    for (const auto& [face, parent] : m_.boundary_faces()) {
      const Index* t = &in.tri[static_cast<std::size_t>(3 * parent)];
      double mean = 0;
      for (int k = 0; k < 3; ++k) {
        const std::size_t a = static_cast<std::size_t>(3 * t[k]), b = static_cast<std::size_t>(3 * t[(k + 1) % 3]);
        const double dx = in.xyz[a] - in.xyz[b], dy = in.xyz[a + 1] - in.xyz[b + 1], dz = in.xyz[a + 2] - in.xyz[b + 2];
        mean += std::sqrt(dx * dx + dy * dy + dz * dz) / 3;
      }
      for (Index v : face) target_[static_cast<std::size_t>(v)] = std::min(target_[static_cast<std::size_t>(v)], mean);
    }
  }
  if (floor_ == 0) compute_floor();
  if (o_.thickness_ratio > 0) apply_wall_thickness();
  // Grading: t(v) <= t(u) + grading * |uv|.
  std::vector<std::vector<Index>> nbr(static_cast<std::size_t>(np));
  for (const auto& e : m_.edges()) {
    nbr[static_cast<std::size_t>(e[0])].push_back(e[1]);
    nbr[static_cast<std::size_t>(e[1])].push_back(e[0]);
  }
  using Item = std::pair<double, Index>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
  for (Index v = 0; v < np; ++v)
    if (std::isfinite(target_[static_cast<std::size_t>(v)]) && !nbr[static_cast<std::size_t>(v)].empty())
      q.push({target_[static_cast<std::size_t>(v)], v});
  while (!q.empty()) {
    const auto [t, v] = q.top();
    q.pop();
    if (t > target_[static_cast<std::size_t>(v)]) continue;
    for (Index w : nbr[static_cast<std::size_t>(v)]) {
      const double c = t + o_.grading * std::sqrt(squared_distance(m_.point(v), m_.point(w)));
      if (c < target_[static_cast<std::size_t>(w)]) {
        target_[static_cast<std::size_t>(w)] = c;
        q.push({c, w});
      }
    }
  }
  // Where an edge could not be split (no exact point on the surface, or every candidate
  // inverted a tet) the target is raised to that edge's length / split_ratio on the edge,
  // decreasing by one unit per unit of distance from it: refinement then does not chase the edge
  // with ever closer points (degrading gracefully near facets without exact points).
  for (Index v = 0; v < np && raise_stuck; ++v) {
    const Vec3& p = m_.point(v);
    double& t = target_[static_cast<std::size_t>(v)];
    for (const Stuck& e : stuck_) {
      if (p.x < e.lo[0] - e.reach || p.x > e.hi[0] + e.reach || p.y < e.lo[1] - e.reach ||
          p.y > e.hi[1] + e.reach || p.z < e.lo[2] - e.reach || p.z > e.hi[2] + e.reach)
        continue;
      t = std::max(t, e.reach - segment_distance(p, e.a, e.b));
    }
  }
}

// The smallest length refinement works at (RefineOptions::min_size), from the asked targets
// (size, size_by_tag, size_from_surface), once.
void TargetSizes::compute_floor() {
  const Index np = m_.num_points();
  double smallest = kInf;
  for (Index v = 0; v < np; ++v)
    smallest = std::min(smallest, target_[static_cast<std::size_t>(v)]);
  if (o_.min_size > 0) {
    floor_ = o_.min_size;
  } else if (std::isfinite(smallest)) {
    floor_ = smallest / 8;
  } else {
    double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
    for (Index v = 0; v < np; ++v) {
      const Vec3& p = m_.point(v);
      for (int c = 0; c < 3; ++c) {
        lo[c] = std::min(lo[c], p[c]);
        hi[c] = std::max(hi[c], p[c]);
      }
    }
    floor_ = 1e-3 * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                              (hi[2] - lo[2]) * (hi[2] - lo[2]));
  }
}

// RefineOptions::thickness_ratio: the target at a boundary point is at most thickness_ratio times
// the wall's thickness there (wall_thickness.h), measured against the input triangles with the
// point's normal the mean of its boundary faces' parents' normals; never below floor_. Walls
// are looked for only up to min(target, twice the longest edge of the point's input triangles)
// / thickness_ratio away: a wall thicker than the input's own triangles around the point is
// crossed by tets no longer than those triangles, not flat ones (and the search stays local on
// a fine tessellation meshed at a coarse size). Points without a finite target are left.
void TargetSizes::apply_wall_thickness() {
  if (!walls_) walls_ = std::make_unique<WallThickness>(m_.surface());
  const SurfaceMesh& in = m_.surface();
  const Index np = m_.num_points();
  std::vector<std::vector<Index>> own(static_cast<std::size_t>(np));
  for (const auto& [face, parent] : m_.boundary_faces())
    for (Index v : face) {
      auto& list = own[static_cast<std::size_t>(v)];
      if (std::find(list.begin(), list.end(), parent) == list.end()) list.push_back(parent);
    }
  for (Index v = 0; v < np; ++v) {
    const auto& list = own[static_cast<std::size_t>(v)];
    double& t = target_[static_cast<std::size_t>(v)];
    if (list.empty() || !std::isfinite(t)) continue;
    Vec3 n;
    double longest = 0;
    for (Index tri : list) {
      const Vec3& m = walls_->normal(tri);
      n = {n.x + m.x, n.y + m.y, n.z + m.z};
      for (int k = 0; k < 3; ++k)
        longest = std::max(longest, squared_distance(in.point(in.tri[3 * tri + k]), in.point(in.tri[3 * tri + (k + 1) % 3])));
    }
    const double len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    if (!(len > 0)) continue;
    n = {n.x / len, n.y / len, n.z / len};
    const double reach = std::min(t, 2 * std::sqrt(longest)) / o_.thickness_ratio;
    const double thickness = walls_->at(m_.point(v), n, list, reach);
    if (std::isfinite(thickness)) t = std::min(t, std::max(o_.thickness_ratio * thickness, floor_));
  }
}

double TargetSizes::segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
  const double wx = p.x - a.x, wy = p.y - a.y, wz = p.z - a.z;
  const double uu = ux * ux + uy * uy + uz * uz;
  double t = uu > 0 ? (ux * wx + uy * wy + uz * wz) / uu : 0;
  t = std::max(0.0, std::min(1.0, t));
  const double dx = wx - t * ux, dy = wy - t * uy, dz = wz - t * uz;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

void TargetSizes::raise_lower(Index u, Index v) {
  Stuck e;
  e.a = m_.point(u);
  e.b = m_.point(v);
  e.reach = length(u, v) / o_.split_ratio * 1.0001;
  for (int c = 0; c < 3; ++c) {
    e.lo[c] = std::min(e.a[c], e.b[c]);
    e.hi[c] = std::max(e.a[c], e.b[c]);
  }
  stuck_.push_back(e);
  for (Index w : {u, v}) set_target(w, std::max(target(w), e.reach));
}

bool TargetSizes::split(Index u, Index v, double min_quality, RefineStats& st) {
  Index n = -1;
  const SplitOutcome r = m_.split_edge(u, v, min_quality, &n);
  if (r != SplitOutcome::kSplit && r != SplitOutcome::kNoEdge) raise_lower(u, v);
  switch (r) {
    case SplitOutcome::kSplit:
      ++st.splits;
      if (m_.support(n).kind != Support::kInterior) ++st.surface_splits;
      set_target(n, 0.5 * (target(u) + target(v)));
      return true;
    case SplitOutcome::kNoExactPoint:
      ++st.splits_no_exact_point;
      return false;
    case SplitOutcome::kInverted:
      ++st.splits_rejected;
      return false;
    case SplitOutcome::kBadProjection:
      ++st.projection_rejected;
      return false;
    case SplitOutcome::kFixedSurface:
      ++st.splits_fixed_surface;
      return false;
    case SplitOutcome::kNoEdge:
      return false;
  }
  return false;
}

}  // namespace bsptet
