// FemBspTet core: cutting a solid in two along caps made of its own vertices (solid_cut.h).
#include "bsptet/solid_cut.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>

#include "bsptet/predicates.h"

namespace bsptet {
namespace {

constexpr int kSmoothingRounds = 16;

struct DirectedEdge {
  Index u, v, t;
};

// A point of the cap polygon, projected along `axis`: its `axis` coordinate set to 0, so that
// orient2d_projected and the lifted 2D filter (predicates.h) see the projection only.
Vec3 projected(const std::vector<double>& xyz, Index i, int axis) {
  double c[3] = {xyz[3 * static_cast<std::size_t>(i)], xyz[3 * static_cast<std::size_t>(i) + 1],
                 xyz[3 * static_cast<std::size_t>(i) + 2]};
  c[axis] = 0;
  return {c[0], c[1], c[2]};
}

// Exact ear clipping of the polygon p[0..m-1] (projected points, expected counter-clockwise):
// appends counter-clockwise triangles of polygon positions to `out`. An ear is a strictly convex
// corner whose closed triangle holds no other corner that is not strictly convex (in a simple
// polygon the reflex corners are the only ones that can block an ear). False when a whole turn
// finds no ear or the last triangle is not strictly counter-clockwise (a clockwise polygon always
// ends so: the clipped triangles are positive and their areas add up to the polygon's).
bool clip_ears(const std::vector<Vec3>& p, int axis, std::vector<std::array<int, 3>>& out) {
  const int m = static_cast<int>(p.size());
  if (m < 3) return false;
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  std::vector<int> prev(m), next(m);
  for (int i = 0; i < m; ++i) prev[i] = (i + m - 1) % m, next[i] = (i + 1) % m;
  std::vector<char> convex(m), alive(m, 1);
  auto turn = [&](int i) { return orient2d_projected(p[prev[i]], p[i], p[next[i]], axis); };
  std::vector<int> reflex;
  for (int i = 0; i < m; ++i) {
    convex[i] = turn(i) == Sign::kPositive;
    if (!convex[i]) reflex.push_back(i);
  }
  auto in_closed = [&](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& x) {
    return orient2d_projected(a, b, x, axis) != Sign::kNegative && orient2d_projected(b, c, x, axis) != Sign::kNegative &&
           orient2d_projected(c, a, x, axis) != Sign::kNegative;
  };
  auto is_ear = [&](int i) {
    if (!convex[i]) return false;
    const Vec3 &a = p[prev[i]], &b = p[i], &c = p[next[i]];
    const double lo_u = std::min({a[u], b[u], c[u]}), hi_u = std::max({a[u], b[u], c[u]});
    const double lo_v = std::min({a[v], b[v], c[v]}), hi_v = std::max({a[v], b[v], c[v]});
    for (int r : reflex) {
      if (!alive[r] || convex[r] || r == prev[i] || r == next[i]) continue;
      const Vec3& x = p[r];
      if (x[u] < lo_u || x[u] > hi_u || x[v] < lo_v || x[v] > hi_v) continue;  // exact comparisons
      if (in_closed(a, b, c, x)) return false;
    }
    return true;
  };
  int remaining = m, i = 0, misses = 0, clips = 0;
  while (remaining > 3) {
    if (!is_ear(i)) {
      i = next[i];
      if (++misses > remaining) return false;
      continue;
    }
    const int a = prev[i], c = next[i];
    out.push_back({a, i, c});
    next[a] = c, prev[c] = a, alive[i] = 0, --remaining, misses = 0;
    for (int w : {a, c}) {
      const bool was = convex[w];
      convex[w] = turn(w) == Sign::kPositive;
      if (was && !convex[w]) reflex.push_back(w);
    }
    if (++clips % 64 == 0)  // drop the corners clipped or turned convex
      reflex.erase(std::remove_if(reflex.begin(), reflex.end(), [&](int r) { return !alive[r] || convex[r]; }),
                   reflex.end());
    i = a;
  }
  if (turn(i) != Sign::kPositive) return false;
  out.push_back({prev[i], i, next[i]});
  return true;
}

// Lawson flips of a triangulation of the polygon p (clip_ears' output) toward the Delaunay
// triangulation of the projection: an interior edge is flipped when the in-circle filter is
// certain that the opposite corner is strictly inside (an uncertain case is left as it is: the
// flips are for shape only) and both new triangles are strictly counter-clockwise (exact).
// Polygon edges are never flipped. Returns the number of flips.
std::int64_t flip_to_delaunay(const std::vector<Vec3>& p, int axis, std::vector<std::array<int, 3>>& tris) {
  auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
  };
  std::unordered_map<std::uint64_t, std::array<int, 2>> edges;
  edges.reserve(tris.size() * 3);
  for (int t = 0; t < static_cast<int>(tris.size()); ++t)
    for (int k = 0; k < 3; ++k) {
      auto [it, fresh] = edges.try_emplace(key(tris[t][k], tris[t][(k + 1) % 3]), std::array<int, 2>{t, -1});
      if (!fresh) it->second[1] = t;
    }
  std::vector<std::uint64_t> queue;
  for (const auto& [k, ts] : edges)
    if (ts[1] >= 0) queue.push_back(k);
  std::sort(queue.begin(), queue.end());  // deterministic, whatever the hash order
  // The corner of triangle t after the directed edge a -> b, or -1 when t does not hold a -> b.
  auto third_after = [&](int t, int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (tris[t][k] == a && tris[t][(k + 1) % 3] == b) return tris[t][(k + 2) % 3];
    return -1;
  };
  auto replace = [&](std::uint64_t k, int from, int to) {
    auto& ts = edges.at(k);
    (ts[0] == from ? ts[0] : ts[1]) = to;
  };
  std::int64_t flips = 0;
  const std::int64_t max_flips = 64 * static_cast<std::int64_t>(p.size()) + 1024;
  while (!queue.empty() && flips < max_flips) {
    const std::uint64_t k = queue.back();
    queue.pop_back();
    auto it = edges.find(k);
    if (it == edges.end() || it->second[1] < 0) continue;
    int t1 = it->second[0], t2 = it->second[1];
    int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xffffffffu);
    int c = third_after(t1, a, b);
    if (c < 0) std::swap(t1, t2), c = third_after(t1, a, b);
    const int d = third_after(t2, b, a);
    if (c < 0 || d < 0) continue;
    Sign in_circle;
    if (!lifted_det2_filter(p[a], p[b], p[c], p[d], axis, in_circle) || in_circle != Sign::kPositive) continue;
    if (orient2d_projected(p[a], p[d], p[c], axis) != Sign::kPositive ||
        orient2d_projected(p[d], p[b], p[c], axis) != Sign::kPositive)
      continue;
    tris[t1] = {a, d, c};
    tris[t2] = {d, b, c};
    edges.erase(it);
    edges.emplace(key(c, d), std::array<int, 2>{t1, t2});
    replace(key(a, d), t2, t1);
    replace(key(b, c), t1, t2);
    ++flips;
    for (std::uint64_t e : {key(a, d), key(d, b), key(b, c), key(c, a)})
      if (edges.at(e)[1] >= 0) queue.push_back(e);
  }
  return flips;
}

}  // namespace

SolidCut cut_solid(const std::vector<double>& xyz, const std::vector<Index>& tri, int axis, double threshold,
                   const std::vector<std::pair<Index, char>>& forced) {
  SolidCut cut;
  const std::size_t n = tri.size() / 3;
  std::vector<char> below(n);
  std::size_t n_below = 0;
  for (std::size_t t = 0; t < n; ++t) n_below += below[t] = corner_sum(xyz, &tri[3 * t], axis) < threshold;
  std::vector<DirectedEdge> edges(3 * n);
  for (std::size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k)
      edges[3 * t + k] = {tri[3 * t + k], tri[3 * t + (k + 1) % 3], static_cast<Index>(t)};
  auto by_ends = [](const DirectedEdge& e, const DirectedEdge& f) { return e.u != f.u ? e.u < f.u : e.v < f.v; };
  std::sort(edges.begin(), edges.end(), by_ends);
  auto triangle_of = [&](Index u, Index v) -> Index {
    auto it = std::lower_bound(edges.begin(), edges.end(), DirectedEdge{u, v, 0}, by_ends);
    return it != edges.end() && it->u == u && it->v == v ? it->t : -1;
  };
  // Smoothing (see the header): spikes and pinches of the boundary between the sides would give
  // a cap triangle equal to a surface triangle, or loops through one vertex.
  std::vector<Index> across(3 * n);  // the triangle across each corner's edge
  for (std::size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      across[3 * t + k] = triangle_of(tri[3 * t + (k + 1) % 3], tri[3 * t + k]);
      if (across[3 * t + k] < 0) {
        cut.reason = "edge " + std::to_string(tri[3 * t + k]) + "-" + std::to_string(tri[3 * t + (k + 1) % 3]) +
                     " has one triangle (the surface is not closed)";
        return cut;
      }
    }
  std::vector<std::pair<Index, Index>> corners(3 * n);  // (vertex, triangle), sorted: each vertex's fan
  for (std::size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) corners[3 * t + k] = {tri[3 * t + k], static_cast<Index>(t)};
  std::sort(corners.begin(), corners.end());
  for (const auto& [vertex, side] : forced)
    for (auto it = std::lower_bound(corners.begin(), corners.end(), std::pair<Index, Index>{vertex, -1});
         it != corners.end() && it->first == vertex; ++it)
      below[it->second] = side;
  for (int round = 0; round < kSmoothingRounds; ++round) {
    bool changed = false;
    for (std::size_t t = 0; t < n; ++t) {
      int other = 0;
      for (int k = 0; k < 3; ++k) other += below[across[3 * t + k]] != below[t];
      if (other >= 2) below[t] = !below[t], changed = true;
    }
    for (std::size_t i = 0, j; i < corners.size(); i = j) {
      int sides = 0, lower = 0, count = 0;  // boundary edges at the vertex (each fan edge counted once)
      for (j = i; j < corners.size() && corners[j].first == corners[i].first; ++j) {
        const Index t = corners[j].second;
        ++count, lower += below[t];
        for (int k = 0; k < 3; ++k)
          if (tri[3 * t + k] == corners[i].first) sides += below[across[3 * t + k]] != below[t];
      }
      if (sides <= 2) continue;  // no loop, or one loop through the vertex once
      const char side = 2 * lower >= count;
      for (std::size_t k = i; k < j; ++k) below[corners[k].second] = side;
      changed = true;
    }
    if (!changed) break;
  }
  corners = {};
  across = {};
  n_below = static_cast<std::size_t>(std::count(below.begin(), below.end(), 1));
  if (n_below == 0 || n_below == n) {
    cut.reason = "every triangle is on one side of the cut";
    return cut;
  }
  // The below piece's boundary edges (u -> v as in their below triangle), sorted by u.
  std::vector<std::pair<Index, Index>> loop_edges;
  for (std::size_t t = 0; t < n; ++t) {
    if (!below[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const Index a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3];
      const Index s = triangle_of(b, a);
      if (s < 0) {
        cut.reason = "edge " + std::to_string(a) + "-" + std::to_string(b) + " has one triangle (the surface is not closed)";
        return cut;
      }
      if (!below[s]) loop_edges.emplace_back(a, b);
    }
  }
  edges.clear();
  edges.shrink_to_fit();
  std::sort(loop_edges.begin(), loop_edges.end());
  for (std::size_t i = 1; i < loop_edges.size(); ++i)
    if (loop_edges[i].first == loop_edges[i - 1].first) {
      cut.reason = "the cut's loops meet at vertex " + std::to_string(loop_edges[i].first);
      return cut;
    }
  auto edge_from = [&](Index u) -> std::ptrdiff_t {
    auto it = std::lower_bound(loop_edges.begin(), loop_edges.end(), std::pair<Index, Index>{u, -1});
    return it != loop_edges.end() && it->first == u ? it - loop_edges.begin() : -1;
  };
  std::vector<char> traced(loop_edges.size());
  cut.below.reserve(3 * n_below + 3 * loop_edges.size());
  cut.above.reserve(3 * (n - n_below) + 3 * loop_edges.size());
  for (std::size_t t = 0; t < n; ++t) {
    (below[t] ? cut.below : cut.above).insert((below[t] ? cut.below : cut.above).end(), &tri[3 * t], &tri[3 * t + 3]);
    (below[t] ? cut.below_source : cut.above_source).push_back(static_cast<Index>(t));
  }
  for (std::size_t start = 0; start < loop_edges.size(); ++start) {
    if (traced[start]) continue;
    std::vector<Index> loop;
    for (std::ptrdiff_t e = static_cast<std::ptrdiff_t>(start); !traced[e];) {
      traced[e] = 1;
      loop.push_back(loop_edges[e].first);
      e = edge_from(loop_edges[e].second);
      if (e < 0) {
        cut.reason = "the cut's edges do not close into loops";
        return cut;
      }
    }
    ++cut.loops;
    // The cap's boundary runs against the loop: its polygon is the loop reversed.
    std::reverse(loop.begin(), loop.end());
    std::vector<Vec3> p(loop.size());
    for (std::size_t i = 0; i < loop.size(); ++i) p[i] = projected(xyz, loop[i], axis);
    std::vector<std::array<int, 3>> cap;
    if (!clip_ears(p, axis, cap)) {
      cut.reason = "a loop of " + std::to_string(loop.size()) + " vertices through vertex " + std::to_string(loop[0]) +
                   " does not project to a simple counter-clockwise polygon (a hole or a fold of the cross-section)";
      return cut;
    }
    cut.cap_flips += flip_to_delaunay(p, axis, cap);
    for (const auto& c : cap) {
      cut.below.insert(cut.below.end(), {loop[c[0]], loop[c[1]], loop[c[2]]});
      cut.above.insert(cut.above.end(), {loop[c[0]], loop[c[2]], loop[c[1]]});
    }
    cut.cap_triangles += static_cast<std::int64_t>(cap.size());
  }
  cut.below_source.resize(cut.below.size() / 3, -1);
  cut.above_source.resize(cut.above.size() / 3, -1);
  cut.ok = true;
  return cut;
}

}  // namespace bsptet
