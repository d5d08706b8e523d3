// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: polygon triangulation in the parameter plane (see uv_polygon.h).
#include "bsptet/cad/uv_polygon.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "bsptet/numerics/predicates.h"

namespace bsptet::cad {
namespace {

/// Whether the direction from sequence position k towards point h leaves into the polygon's interior
/// (the interior is left of the counter-clockwise boundary).
bool enters_interior(const std::vector<Uv>& uv, const std::vector<int>& seq, std::size_t k, int h) {
  const std::size_t n = seq.size();
  const Uv& a = uv[static_cast<std::size_t>(seq[(k + n - 1) % n])];
  const Uv& p = uv[static_cast<std::size_t>(seq[k])];
  const Uv& b = uv[static_cast<std::size_t>(seq[(k + 1) % n])];
  const Uv& q = uv[static_cast<std::size_t>(h)];
  const int oa = uv_orient(a, p, q), ob = uv_orient(p, b, q);
  if (uv_orient(a, p, b) > 0) return oa > 0 && ob > 0;
  return oa > 0 || ob > 0;
}

/// Joins `hole` into `outer` through a bridge from the hole's rightmost point.
void bridge_hole(const std::vector<Uv>& uv, std::vector<int>& outer, const std::vector<int>& hole,
                 const std::vector<std::vector<int>>& others) {
  std::size_t hk = 0;
  for (std::size_t i = 1; i < hole.size(); ++i) {
    const Uv& p = uv[static_cast<std::size_t>(hole[i])];
    const Uv& best = uv[static_cast<std::size_t>(hole[hk])];
    if (p[0] > best[0] || (p[0] == best[0] && p[1] > best[1])) hk = i;
  }
  const int h = hole[hk];
  const Uv& hp = uv[static_cast<std::size_t>(h)];
  std::vector<std::size_t> order(outer.size());
  std::iota(order.begin(), order.end(), 0);
  auto d2 = [&](std::size_t k) {
    const Uv& p = uv[static_cast<std::size_t>(outer[k])];
    return (p[0] - hp[0]) * (p[0] - hp[0]) + (p[1] - hp[1]) * (p[1] - hp[1]);
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return d2(a) < d2(b); });
  auto blocked_by = [&](const std::vector<int>& loop, int p) {
    const std::size_t n = loop.size();
    for (std::size_t i = 0; i < n; ++i) {
      const int e0 = loop[i], e1 = loop[(i + 1) % n];
      if (e0 == p || e1 == p || e0 == h || e1 == h) continue;
      if (uv_segments_meet(uv[static_cast<std::size_t>(e0)], uv[static_cast<std::size_t>(e1)], hp,
                        uv[static_cast<std::size_t>(p)]))
        return true;
    }
    return false;
  };
  for (std::size_t k : order) {
    const int p = outer[k];
    if (!enters_interior(uv, outer, k, h)) continue;
    if (blocked_by(outer, p) || blocked_by(hole, p)) continue;
    bool free = true;
    for (const auto& other : others) free = free && !blocked_by(other, p);
    if (!free) continue;
    std::vector<int> merged(outer.begin(), outer.begin() + static_cast<std::ptrdiff_t>(k) + 1);
    for (std::size_t i = 0; i <= hole.size(); ++i) merged.push_back(hole[(hk + i) % hole.size()]);
    merged.insert(merged.end(), outer.begin() + static_cast<std::ptrdiff_t>(k), outer.end());
    outer.swap(merged);
    return;
  }
  throw std::runtime_error("a hole of the face's parameter domain has no visible bridge to its outer boundary");
}

}  // namespace

bool uv_segments_meet(const Uv& a, const Uv& b, const Uv& c, const Uv& d) {
  const int o1 = uv_orient(a, b, c), o2 = uv_orient(a, b, d), o3 = uv_orient(c, d, a), o4 = uv_orient(c, d, b);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  auto on = [](const Uv& p, const Uv& q, const Uv& r) {  // r on segment pq, given collinear
    return std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) && std::min(p[1], q[1]) <= r[1] &&
           r[1] <= std::max(p[1], q[1]);
  };
  if (o1 == 0 && on(a, b, c)) return true;
  if (o2 == 0 && on(a, b, d)) return true;
  if (o3 == 0 && on(c, d, a)) return true;
  if (o4 == 0 && on(c, d, b)) return true;
  return false;
}

int uv_orient(const Uv& a, const Uv& b, const Uv& c) {
  return to_int(orient2d_projected(Vec3{a[0], a[1], 0}, Vec3{b[0], b[1], 0}, Vec3{c[0], c[1], 0}, 2));
}

std::vector<std::array<int, 3>> triangulate_polygon(const std::vector<Uv>& uv, const std::vector<std::vector<int>>& loops) {
  if (loops.empty() || loops[0].size() < 3) throw std::runtime_error("the face's boundary has fewer than 3 nodes");
  std::vector<int> seq = loops[0];
  // Holes by decreasing rightmost u, as usual for bridging.
  std::vector<std::size_t> holes;
  for (std::size_t i = 1; i < loops.size(); ++i) holes.push_back(i);
  auto max_u = [&](std::size_t i) {
    double m = -1e300;
    for (int p : loops[i]) m = std::max(m, uv[static_cast<std::size_t>(p)][0]);
    return m;
  };
  std::stable_sort(holes.begin(), holes.end(), [&](std::size_t a, std::size_t b) { return max_u(a) > max_u(b); });
  for (std::size_t idx = 0; idx < holes.size(); ++idx) {
    std::vector<std::vector<int>> others;
    for (std::size_t j = idx + 1; j < holes.size(); ++j) others.push_back(loops[holes[j]]);
    bridge_hole(uv, seq, loops[holes[idx]], others);
  }

  // Ear clipping on a doubly linked list of sequence positions.
  const std::size_t n = seq.size();
  std::vector<std::size_t> prev(n), next(n);
  for (std::size_t i = 0; i < n; ++i) {
    prev[i] = (i + n - 1) % n;
    next[i] = (i + 1) % n;
  }
  auto P = [&](std::size_t k) -> const Uv& { return uv[static_cast<std::size_t>(seq[k])]; };
  auto is_ear = [&](std::size_t k) {
    const std::size_t a = prev[k], b = next[k];
    if (uv_orient(P(a), P(k), P(b)) <= 0) return false;
    for (std::size_t j = next[b]; j != a; j = next[j]) {
      const int q = seq[j];
      if (q == seq[a] || q == seq[k] || q == seq[b]) continue;
      const Uv& x = P(j);
      if (uv_orient(P(a), P(k), x) >= 0 && uv_orient(P(k), P(b), x) >= 0 && uv_orient(P(b), P(a), x) >= 0) return false;
    }
    return true;
  };
  std::vector<std::array<int, 3>> tris;
  tris.reserve(n);
  std::size_t remaining = n, k = 0, since_last = 0;
  while (remaining > 3) {
    if (is_ear(k)) {
      tris.push_back({seq[prev[k]], seq[k], seq[next[k]]});
      next[prev[k]] = next[k];
      prev[next[k]] = prev[k];
      --remaining;
      k = prev[k];
      since_last = 0;
      continue;
    }
    k = next[k];
    if (++since_last > remaining) throw std::runtime_error("the face's boundary in its parameter plane is not a simple polygon");
  }
  if (uv_orient(P(prev[k]), P(k), P(next[k])) <= 0)
    throw std::runtime_error("the face's boundary in its parameter plane is not a simple polygon (last triangle flat)");
  tris.push_back({seq[prev[k]], seq[k], seq[next[k]]});
  return tris;
}

}  // namespace bsptet::cad
