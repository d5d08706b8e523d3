// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: cutting a solid in two along caps of its own vertices and new points (solid_cut.h).
#include "bsptet/pieces/solid_cut.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <cstdint>
#include <functional>
#include <iterator>
#include <memory>
#include <unordered_map>

#include "bsptet/numerics/exact_float.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {
namespace {

constexpr int kSmoothingRounds = 16;
constexpr double kSteepEdge = 4.0;
constexpr double kCapSpacing = 4.0;
constexpr double kCollarDepth = 0.5;
constexpr double kMaxCapGrid = 4e6;


// The caps' projection: along d = e_axis + tilt_u e_u + tilt_v e_v, the cut's axis or a direction
// a little off it (a plane that contains the axis, such as a CAD face or an earlier cap, projects
// to a line along the axis, and a loop zigzagging on it to a degenerate polygon; off the axis it
// projects one to one). orient(a, b, c) = sign(d . ((b - a) x (c - a))): POSITIVE when a, b, c
// turn counter-clockwise seen from the tip of d (with no tilt, orient2d_projected's sign),
// exact (a double filter, else ExactFloat). flat(p) = p - p[axis] d, rounded: 2D coordinates
// (the axis coordinate 0) for decisions of shape only (in-circle, the grid of cap points).
struct Projection {
  int axis, u, v;
  double d[3];

  Projection(int axis_, double tilt_u, double tilt_v) : axis(axis_), u((axis_ + 1) % 3), v((axis_ + 2) % 3) {
    d[axis] = 1, d[u] = tilt_u, d[v] = tilt_v;
  }

  Sign orient(const Vec3& a, const Vec3& b, const Vec3& c) const {
    const double r1[3] = {b.x - a.x, b.y - a.y, b.z - a.z}, r2[3] = {c.x - a.x, c.y - a.y, c.z - a.z};
    double det = 0, perm = 0;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      det += d[i] * (r1[j] * r2[k] - r1[k] * r2[j]);
      perm += std::fabs(d[i]) * (std::fabs(r1[j] * r2[k]) + std::fabs(r1[k] * r2[j]));
    }
    // The differences, products and sums each round by at most 2^-53 relatively: the error is
    // below 8 * 2^-53 * perm; 1e-14 * perm is about 11 times that.
    if (std::isfinite(perm) && perm > 1e-290 && std::fabs(det) > 1e-14 * perm)
      return det > 0 ? Sign::kPositive : Sign::kNegative;
    const ExactFloat e1[3] = {ExactFloat(b.x) - ExactFloat(a.x), ExactFloat(b.y) - ExactFloat(a.y),
                              ExactFloat(b.z) - ExactFloat(a.z)};
    const ExactFloat e2[3] = {ExactFloat(c.x) - ExactFloat(a.x), ExactFloat(c.y) - ExactFloat(a.y),
                              ExactFloat(c.z) - ExactFloat(a.z)};
    ExactFloat sum;
    for (int i = 0; i < 3; ++i) {
      if (d[i] == 0) continue;
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      sum += ExactFloat(d[i]) * (e1[j] * e2[k] - e1[k] * e2[j]);
    }
    return sum.sign() > 0 ? Sign::kPositive : sum.sign() < 0 ? Sign::kNegative : Sign::kZero;
  }

  Vec3 flat(const Vec3& p) const {
    double c[3];
    c[axis] = 0, c[u] = p[u] - d[u] * p[axis], c[v] = p[v] - d[v] * p[axis];
    return {c[0], c[1], c[2]};
  }
};

// The projections tried, in turn, on a loop that the one before could not clip.
constexpr double kTilts[][2] = {{0, 0}, {0.125, 0.0625}, {-0.0625, 0.125}, {0.25, -0.1875}};

// Exact ear clipping of the polygon p[0..m-1] (3D points, expected counter-clockwise in the
// projection pr; ids: their vertex ids, equal at the two ends of a bridge to a hole, whose copies
// never block an ear; no ear whose new diagonal is a surface edge):
// appends counter-clockwise triangles of polygon positions to `out`. An ear is a strictly convex
// corner whose closed triangle holds no other corner that is not strictly convex (in a simple
// polygon the reflex corners are the only ones that can block an ear). False when a whole turn
// finds no ear or the last triangle is not strictly counter-clockwise (a clockwise polygon always
// ends so: the clipped triangles are positive and their areas add up to the polygon's).
bool clip_ears(const std::vector<Vec3>& p, const std::vector<Index>& ids, const Projection& pr,
               const std::function<bool(Index, Index)>& surface_edge, std::vector<std::array<int, 3>>& out) {
  const int m = static_cast<int>(p.size());
  if (m < 3) return false;
  const int u = pr.u, v = pr.v;
  std::vector<Vec3> f(m);  // flat coordinates: only to skip corners far from an ear (with a margin)
  double extent = 0;
  for (int i = 0; i < m; ++i) f[i] = pr.flat(p[i]), extent = std::max({extent, std::fabs(f[i][u]), std::fabs(f[i][v])});
  const double margin = 1e-9 * extent;
  std::vector<int> prev(m), next(m);
  for (int i = 0; i < m; ++i) prev[i] = (i + m - 1) % m, next[i] = (i + 1) % m;
  std::vector<char> convex(m), alive(m, 1);
  auto turn = [&](int i) { return pr.orient(p[prev[i]], p[i], p[next[i]]); };
  std::vector<int> reflex;
  for (int i = 0; i < m; ++i) {
    convex[i] = turn(i) == Sign::kPositive;
    if (!convex[i]) reflex.push_back(i);
  }
  auto in_closed = [&](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& x) {
    return pr.orient(a, b, x) != Sign::kNegative && pr.orient(b, c, x) != Sign::kNegative &&
           pr.orient(c, a, x) != Sign::kNegative;
  };
  auto is_ear = [&](int i) {
    if (!convex[i] || surface_edge(ids[prev[i]], ids[next[i]])) return false;
    const Vec3 &a = p[prev[i]], &b = p[i], &c = p[next[i]];
    const Vec3 &fa = f[prev[i]], &fb = f[i], &fc = f[next[i]];
    const double lo_u = std::min({fa[u], fb[u], fc[u]}) - margin, hi_u = std::max({fa[u], fb[u], fc[u]}) + margin;
    const double lo_v = std::min({fa[v], fb[v], fc[v]}) - margin, hi_v = std::max({fa[v], fb[v], fc[v]}) + margin;
    for (int r : reflex) {
      if (!alive[r] || convex[r] || ids[r] == ids[prev[i]] || ids[r] == ids[i] || ids[r] == ids[next[i]]) continue;
      const Vec3& x = f[r];
      if (x[u] < lo_u || x[u] > hi_u || x[v] < lo_v || x[v] > hi_v) continue;
      if (in_closed(a, b, c, p[r])) return false;
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

// A triangulation of a cap polygon in the projection pr (3D points: the polygon's corners first,
// then the points added inside), counter-clockwise triangles with their neighbours: nbr[t][k] is
// the triangle across the edge opposite corner k, -1 across a polygon edge (never flipped). Every
// orientation is decided exactly (Projection::orient); the in-circle test, on the flat
// coordinates, only decides shape.
class CapTriangulation {
 public:
  // `surface_edge(a, b)`: a and b (positions) are joined by a surface edge, which no flip may make.
  CapTriangulation(std::vector<Vec3> p, const Projection& pr, const std::vector<std::array<int, 3>>& tris,
                   std::function<bool(int, int)> surface_edge)
      : p_(std::move(p)), pr_(pr), tri_(tris), nbr_(tris.size(), {-1, -1, -1}), surface_edge_(std::move(surface_edge)) {
    for (const Vec3& x : p_) flat_.push_back(pr_.flat(x));
    std::unordered_map<std::uint64_t, std::pair<int, int>> edge;  // directed edge -> (triangle, corner)
    auto key = [](int a, int b) { return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b); };
    for (int t = 0; t < static_cast<int>(tri_.size()); ++t)
      for (int k = 0; k < 3; ++k) edge[key(tri_[t][(k + 1) % 3], tri_[t][(k + 2) % 3])] = {t, k};
    for (int t = 0; t < static_cast<int>(tri_.size()); ++t)
      for (int k = 0; k < 3; ++k) {
        auto it = edge.find(key(tri_[t][(k + 2) % 3], tri_[t][(k + 1) % 3]));
        if (it != edge.end()) nbr_[t][k] = it->second.first;
      }
  }

  // Lawson flips over every interior edge until the triangulation is Delaunay in the projection
  // (as far as the in-circle filter is certain; bounded). Returns the number of flips.
  std::int64_t make_delaunay() {
    for (int t = 0; t < static_cast<int>(tri_.size()); ++t)
      for (int k = 0; k < 3; ++k) stack_.push_back({t, k});
    return legalize();
  }

  // Inserts the projected point q (found by walking from the last triangle made) when it lies
  // strictly inside a triangle, and restores the Delaunay property around it. False (nothing
  // changed) when the walk leaves the polygon, runs too long, or q is on an edge.
  bool insert(const Vec3& q) {
    int t = hint_, k = 0;
    for (std::size_t steps = 0;; ++steps) {
      if (steps > tri_.size() + 16) return false;
      int out = -1;
      for (int i = 0; i < 3 && out < 0; ++i) {
        const int e = (i + static_cast<int>(steps)) % 3;  // vary the first edge tried: no cycling
        if (orient(tri_[t][(e + 1) % 3], tri_[t][(e + 2) % 3], q) == Sign::kNegative) out = e;
      }
      if (out < 0) break;
      if (nbr_[t][out] < 0) return false;
      t = nbr_[t][out];
    }
    for (k = 0; k < 3; ++k)
      if (orient(tri_[t][(k + 1) % 3], tri_[t][(k + 2) % 3], q) != Sign::kPositive) return false;
    const int n = static_cast<int>(p_.size());
    p_.push_back(q);
    flat_.push_back(pr_.flat(q));
    const auto [a, b, c] = tri_[t];
    const auto [nbc, nca, nab] = nbr_[t];
    const int t1 = static_cast<int>(tri_.size()), t2 = t1 + 1;
    tri_[t] = {n, a, b}, nbr_[t] = {nab, t1, t2};
    tri_.push_back({n, b, c}), nbr_.push_back({nbc, t2, t});
    tri_.push_back({n, c, a}), nbr_.push_back({nca, t, t1});
    repoint(nbc, t, t1);
    repoint(nca, t, t2);
    for (int x : {t, t1, t2}) stack_.push_back({x, 0});
    legalize();
    hint_ = t;
    return true;
  }

  const std::vector<Vec3>& points() const { return p_; }
  const std::vector<Vec3>& flat_points() const { return flat_; }
  const std::vector<std::array<int, 3>>& triangles() const { return tri_; }

 private:
  Sign orient(int a, int b, const Vec3& q) const { return pr_.orient(p_[a], p_[b], q); }

  void repoint(int x, int from, int to) {
    if (x < 0) return;
    for (int& y : nbr_[x])
      if (y == from) y = to;
  }

  // Flips the edges on the stack (triangle, corner: the edge opposite that corner) that are not
  // Delaunay; the two edges a flip exposes are stacked in turn.
  std::int64_t legalize() {
    std::int64_t flips = 0;
    const std::int64_t max_flips = 64 * static_cast<std::int64_t>(p_.size()) + 1024;
    while (!stack_.empty() && flips_ < max_flips) {
      auto [t, k] = stack_.back();
      stack_.pop_back();
      const int u = nbr_[t][k];
      if (u < 0) continue;
      // t = (a, b, c) with a = corner k; u holds c -> b and its third corner d.
      const int a = tri_[t][k], b = tri_[t][(k + 1) % 3], c = tri_[t][(k + 2) % 3];
      int j = 0;
      while (j < 3 && nbr_[u][j] != t) ++j;
      if (j == 3) continue;
      const int d = tri_[u][j];
      Sign in_circle;
      if (!lifted_det2_filter(flat_[a], flat_[b], flat_[c], flat_[d], pr_.axis, in_circle) ||
          in_circle != Sign::kPositive)
        continue;
      if (orient(a, b, p_[d]) != Sign::kPositive || orient(a, d, p_[c]) != Sign::kPositive || surface_edge_(a, d))
        continue;
      const int n_ca = nbr_[t][(k + 1) % 3], n_ab = nbr_[t][(k + 2) % 3];
      // In u = (d, c, b) from corner j: the edge opposite c is b-d, opposite b is d-c.
      const int n_bd = tri_[u][(j + 1) % 3] == c ? nbr_[u][(j + 1) % 3] : nbr_[u][(j + 2) % 3];
      const int n_dc = tri_[u][(j + 1) % 3] == c ? nbr_[u][(j + 2) % 3] : nbr_[u][(j + 1) % 3];
      tri_[t] = {a, b, d}, nbr_[t] = {n_bd, u, n_ab};
      tri_[u] = {a, d, c}, nbr_[u] = {n_dc, n_ca, t};
      repoint(n_bd, u, t);
      repoint(n_ca, t, u);
      ++flips, ++flips_;
      stack_.push_back({t, 0});
      stack_.push_back({u, 0});
    }
    stack_.clear();
    return flips;
  }

  std::vector<Vec3> p_, flat_;
  Projection pr_;
  std::vector<std::array<int, 3>> tri_, nbr_;
  std::vector<std::pair<int, int>> stack_;
  std::function<bool(int, int)> surface_edge_;
  int hint_ = 0;
  std::int64_t flips_ = 0;
};

// Whether the closed segments pq and rs meet (exact, in the projection).
bool segments_meet(const Projection& pr, const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const Sign a = pr.orient(p, q, r), b = pr.orient(p, q, s), c = pr.orient(r, s, p), d = pr.orient(r, s, q);
  if (a == Sign::kZero && b == Sign::kZero) {  // collinear: overlapping boxes in the flat coordinates
    const Vec3 fp = pr.flat(p), fq = pr.flat(q), fr = pr.flat(r), fs = pr.flat(s);
    for (int k : {pr.u, pr.v})
      if (std::max(fp[k], fq[k]) < std::min(fr[k], fs[k]) || std::max(fr[k], fs[k]) < std::min(fp[k], fq[k])) return false;
    return true;
  }
  return to_int(a) * to_int(b) <= 0 && to_int(c) * to_int(d) <= 0;
}

// Whether the direction from corner o (between a before it and b after it, the region on the
// left) towards x points strictly into the region.
bool into_region(const Projection& pr, const Vec3& a, const Vec3& o, const Vec3& b, const Vec3& x) {
  const bool left_of_ao = pr.orient(a, o, x) == Sign::kPositive, left_of_ob = pr.orient(o, b, x) == Sign::kPositive;
  return pr.orient(a, o, b) == Sign::kPositive ? left_of_ao && left_of_ob : left_of_ao || left_of_ob;
}

// Joins the hole `hole` (positions into p, clockwise: the region on its left) to the polygon
// `poly` (counter-clockwise) by a bridge, two copies of an edge from the hole's corner of largest
// flat u to the nearest corner of poly it sees (exactly: the bridge meets no edge of poly, of the
// hole or of `others`, the holes still to join, and leaves both corners into the region; not a
// surface edge). False when no corner of poly is seen.
bool bridge_hole(const std::vector<Vec3>& p, const std::vector<Index>& ids, const Projection& pr,
                 const std::function<bool(Index, Index)>& surface_edge, std::vector<int>& poly,
                 const std::vector<int>& hole, const std::vector<std::vector<int>>& others) {
  std::size_t hi = 0;
  for (std::size_t i = 1; i < hole.size(); ++i)
    if (pr.flat(p[hole[i]])[pr.u] > pr.flat(p[hole[hi]])[pr.u]) hi = i;
  const int h = hole[hi];
  const Vec3 fh = pr.flat(p[h]);
  std::vector<std::pair<double, std::size_t>> by_distance;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec3 f = pr.flat(p[poly[i]]);
    by_distance.push_back({std::hypot(f[pr.u] - fh[pr.u], f[pr.v] - fh[pr.v]), i});
  }
  std::sort(by_distance.begin(), by_distance.end());
  auto crosses = [&](const std::vector<int>& ring, int o) {
    for (std::size_t k = 0; k < ring.size(); ++k) {
      const int r = ring[k], s = ring[(k + 1) % ring.size()];
      if (ids[r] == ids[h] || ids[s] == ids[h] || ids[r] == ids[o] || ids[s] == ids[o]) continue;
      if (segments_meet(pr, p[h], p[o], p[r], p[s])) return true;
    }
    return false;
  };
  const std::size_t tries = std::min<std::size_t>(by_distance.size(), 64);
  for (std::size_t t = 0; t < tries; ++t) {
    const std::size_t oi = by_distance[t].second;
    const int o = poly[oi];
    if (ids[o] == ids[h] || surface_edge(ids[o], ids[h])) continue;
    if (!into_region(pr, p[poly[(oi + poly.size() - 1) % poly.size()]], p[o], p[poly[(oi + 1) % poly.size()]], p[h]) ||
        !into_region(pr, p[hole[(hi + hole.size() - 1) % hole.size()]], p[h], p[hole[(hi + 1) % hole.size()]], p[o]))
      continue;
    if (crosses(poly, o) || crosses(hole, o)) continue;
    bool blocked = false;
    for (const auto& other : others) blocked = blocked || crosses(other, o);
    if (blocked) continue;
    // poly: ..., o, h, (the hole from h round to h), o, ...
    std::vector<int> spliced(poly.begin(), poly.begin() + static_cast<std::ptrdiff_t>(oi) + 1);
    for (std::size_t k = 0; k <= hole.size(); ++k) spliced.push_back(hole[(hi + k) % hole.size()]);
    spliced.insert(spliced.end(), poly.begin() + static_cast<std::ptrdiff_t>(oi), poly.end());
    poly = std::move(spliced);
    return true;
  }
  return false;
}

// Points inside the cap. First a collar: for each polygon edge a -> b, a point half the edge's
// length inside it in the flat coordinates, at the mean of a and b along the axis (so that the
// cap near the loop is made of triangles on loop edges, not of chords between loop vertices,
// which run along the surface and may cross it where the surface is curved). Then a triangular
// lattice of spacing kCapSpacing times the median flat edge length, without the cells along the loop, at
// `level` along the axis. Each point is inserted where it falls strictly inside the
// triangulation (else skipped). Returns how many were added (the triangulation's last points).
std::int64_t add_cap_points(CapTriangulation& cap, std::size_t m, const Projection& pr, double level) {
  const int u = pr.u, v = pr.v;
  const std::vector<Vec3> p(cap.flat_points().begin(), cap.flat_points().begin() + static_cast<std::ptrdiff_t>(m));
  const std::vector<Vec3> p3(cap.points().begin(), cap.points().begin() + static_cast<std::ptrdiff_t>(m));
  std::int64_t added = 0;
  double lo_u = p[0][u], hi_u = lo_u, lo_v = p[0][v], hi_v = lo_v;
  std::vector<double> lengths(m);
  for (std::size_t i = 0; i < m; ++i) {
    const Vec3 &a = p[i], &b = p[(i + 1) % m];
    lo_u = std::min(lo_u, a[u]), hi_u = std::max(hi_u, a[u]);
    lo_v = std::min(lo_v, a[v]), hi_v = std::max(hi_v, a[v]);
    lengths[i] = std::hypot(b[u] - a[u], b[v] - a[v]);
    const double w = (p3[i][pr.axis] + p3[(i + 1) % m][pr.axis]) / 2;
    double c[3];
    c[pr.axis] = w;
    c[u] = (a[u] + b[u]) / 2 - kCollarDepth * (b[v] - a[v]) + pr.d[u] * w;
    c[v] = (a[v] + b[v]) / 2 + kCollarDepth * (b[u] - a[u]) + pr.d[v] * w;
    added += cap.insert({c[0], c[1], c[2]});
  }
  std::nth_element(lengths.begin(), lengths.begin() + static_cast<std::ptrdiff_t>(m / 2), lengths.end());
  double h = kCapSpacing * lengths[m / 2];
  if (!(h > 0) || !std::isfinite(h)) return added;
  while ((hi_u - lo_u) / h * ((hi_v - lo_v) / h) > kMaxCapGrid) h *= 2;
  // A triangular lattice (rows hv apart, every other row shifted by h / 2): its Delaunay
  // triangulation is unique (no four points on a circle), unlike a square grid's.
  const double hv = h * 0.8660254037844386;
  const long nu = static_cast<long>((hi_u - lo_u) / h) + 1, nv = static_cast<long>((hi_v - lo_v) / hv) + 1;
  if (nu < 3 || nv < 3) return added;
  std::vector<char> near_loop(static_cast<std::size_t>(nu * nv));  // cell (i, j) at near_loop[j * nu + i]
  auto mark = [&](double x, double y) {
    const long i = static_cast<long>((x - lo_u) / h), j = static_cast<long>((y - lo_v) / hv);
    for (long b = std::max(0L, j - 1); b <= std::min(nv - 1, j + 1); ++b)
      for (long a = std::max(0L, i - 1); a <= std::min(nu - 1, i + 1); ++a) near_loop[b * nu + a] = 1;
  };
  for (std::size_t i = 0; i < m; ++i) {
    const Vec3 &a = p[i], &b = p[(i + 1) % m];
    const long steps = static_cast<long>(2 * std::hypot(b[u] - a[u], b[v] - a[v]) / hv) + 1;
    for (long s = 0; s <= steps; ++s) {
      const double f = static_cast<double>(s) / static_cast<double>(steps);
      mark(a[u] + f * (b[u] - a[u]), a[v] + f * (b[v] - a[v]));
    }
  }
  for (long j = 0; j < nv; ++j)
    for (long ii = 0; ii < nu; ++ii) {
      const long i = j % 2 ? nu - 1 - ii : ii;  // serpentine: each point next to the last
      if (near_loop[j * nu + i]) continue;
      double c[3];
      c[pr.axis] = level;
      c[u] = lo_u + (static_cast<double>(i) + (j % 2 ? 0.75 : 0.25)) * h + pr.d[u] * level;
      c[v] = lo_v + (static_cast<double>(j) + 0.5) * hv + pr.d[v] * level;
      added += cap.insert({c[0], c[1], c[2]});
    }
  return added;
}


}  // namespace

SolidTopology::SolidTopology(const std::vector<Index>& tri) {
  // Counting sorts by vertex, linear in the surface (a comparison sort of every directed edge and
  // corner would be most of a large cut's time): each vertex's directed edges and corners in
  // triangle order, its edges then ordered by their other end (a handful each).
  const std::size_t n = tri.size() / 3;
  Index top = -1;
  for (Index v : tri) top = std::max(top, v);
  edge_start.assign(static_cast<std::size_t>(top) + 2, 0);
  for (Index v : tri) ++edge_start[static_cast<std::size_t>(v) + 1];
  for (std::size_t v = 1; v < edge_start.size(); ++v) edge_start[v] += edge_start[v - 1];
  edges.resize(tri.size());
  corners.resize(tri.size());
  // Filled through the starts (each ends at the next vertex's start), then shifted back: the
  // only array as long as the vertex ids (a piece's ids are the whole solid's).
  for (std::size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const Index u = tri[3 * t + k];
      const std::size_t at = static_cast<std::size_t>(edge_start[static_cast<std::size_t>(u)]++);
      edges[at] = {u, tri[3 * t + (k + 1) % 3], static_cast<Index>(t)};
      corners[at] = {u, static_cast<Index>(t)};
    }
  for (std::size_t v = edge_start.size() - 1; v > 0; --v) edge_start[v] = edge_start[v - 1];
  edge_start[0] = 0;
  for (std::size_t v = 0; v + 1 < edge_start.size(); ++v)
    std::sort(edges.begin() + edge_start[v], edges.begin() + edge_start[v + 1],
              [](const std::array<Index, 3>& e, const std::array<Index, 3>& f) {
                return e[1] != f[1] ? e[1] < f[1] : e[2] < f[2];
              });
  across.resize(tri.size());
  for (std::size_t i = 0; i < tri.size(); ++i) across[i] = triangle_of(tri[i / 3 * 3 + (i + 1) % 3], tri[i]);
}

Index SolidTopology::triangle_of(Index u, Index v) const {
  if (u < 0 || static_cast<std::size_t>(u) + 1 >= edge_start.size()) return -1;
  for (Index i = edge_start[static_cast<std::size_t>(u)]; i < edge_start[static_cast<std::size_t>(u) + 1]; ++i)
    if (edges[static_cast<std::size_t>(i)][1] == v) return edges[static_cast<std::size_t>(i)][2];
  return -1;
}

std::vector<Index> edge_neighbours(const std::vector<Index>& tri) { return SolidTopology(tri).across; }

SolidCut cut_solid(const std::vector<double>& xyz, const std::vector<Index>& tri, int axis, double threshold,
                   const std::vector<std::pair<Index, char>>& forced, const SolidTopology* topology) {
  std::unique_ptr<SolidTopology> own;
  if (!topology) own = std::make_unique<SolidTopology>(tri), topology = own.get();
  const SolidTopology& topo = *topology;
  SolidCut cut;
  const std::size_t n = tri.size() / 3;
  const double level = threshold / 3;  // where the cap's own points go along `axis`
  std::vector<char> below(n);
  std::size_t n_below = 0;
  for (std::size_t t = 0; t < n; ++t) n_below += below[t] = corner_sum(xyz, &tri[3 * t], axis) < threshold;
  auto triangle_of = [&](Index u, Index v) { return topo.triangle_of(u, v); };
  // Smoothing (see the header): spikes and pinches of the boundary between the sides would give
  // a cap triangle equal to a surface triangle, or loops through one vertex.
  const std::vector<Index>& across = topo.across;
  for (std::size_t i = 0; i < across.size(); ++i)
    if (across[i] < 0) {
      cut.reason = "edge " + std::to_string(tri[i]) + "-" + std::to_string(tri[i / 3 * 3 + (i + 1) % 3]) +
                   " has one triangle (the surface is not closed)";
      return cut;
    }
  const std::vector<std::pair<Index, Index>>& corners = topo.corners;  // each vertex's fan
  for (const auto& [vertex, side] : forced)
    for (auto it = std::lower_bound(corners.begin(), corners.end(), std::pair<Index, Index>{vertex, -1});
         it != corners.end() && it->first == vertex; ++it)
      below[it->second] = side;
  const int au = (axis + 1) % 3, av = (axis + 2) % 3;
  auto coord = [&](Index v, int a) { return xyz[3 * static_cast<std::size_t>(v) + a]; };
  for (int round = 0; round < kSmoothingRounds; ++round) {
    bool changed = false;
    for (std::size_t t = 0; t < n; ++t) {
      int other = 0;
      for (int k = 0; k < 3; ++k) other += below[across[3 * t + k]] != below[t];
      if (other >= 2) below[t] = !below[t], changed = true;
    }
    // A boundary edge much steeper along the axis than across it (along a crease, an earlier
    // cap's rim or a long strip parallel to the axis) folds the loop's projection: its two
    // triangles join the side where the edge's middle lies.
    for (std::size_t t = 0; t < n; ++t) {
      if (!below[t]) continue;
      for (int k = 0; k < 3; ++k) {
        const Index s = across[3 * t + k];
        if (below[s]) continue;
        const Index a = tri[3 * t + k], b = tri[3 * t + (k + 1) % 3];
        const double rise = std::fabs(coord(a, axis) - coord(b, axis));
        const double run = std::fabs(coord(a, au) - coord(b, au)) + std::fabs(coord(a, av) - coord(b, av));
        if (!(rise > kSteepEdge * run)) continue;
        if (coord(a, axis) + coord(b, axis) < 2 * level)
          below[s] = 1;
        else
          below[t] = 0;
        changed = true;
        break;
      }
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
  // The loops, reversed (a cap's boundary runs against its loop), as positions into pts / gid.
  std::vector<Vec3> pts;
  std::vector<Index> gid;
  std::vector<std::vector<int>> loops;
  for (std::size_t start = 0; start < loop_edges.size(); ++start) {
    if (traced[start]) continue;
    std::vector<int> loop;
    for (std::ptrdiff_t e = static_cast<std::ptrdiff_t>(start); !traced[e];) {
      traced[e] = 1;
      const Index v = loop_edges[e].first;
      const std::size_t g = 3 * static_cast<std::size_t>(v);
      loop.push_back(static_cast<int>(pts.size()));
      pts.push_back({xyz[g], xyz[g + 1], xyz[g + 2]});
      gid.push_back(v);
      e = edge_from(loop_edges[e].second);
      if (e < 0) {
        cut.reason = "the cut's edges do not close into loops";
        return cut;
      }
    }
    std::reverse(loop.begin(), loop.end());
    loops.push_back(std::move(loop));
  }
  cut.loops = static_cast<std::int64_t>(loops.size());
  auto surface_edge = [&](Index a, Index b) { return a < static_cast<Index>(xyz.size() / 3) && b < static_cast<Index>(xyz.size() / 3) && triangle_of(a, b) >= 0; };
  // Per projection tried: the outer polygons (counter-clockwise; holes bridged in) and their ear
  // clippings. A loop turning clockwise is a hole of the smallest outer loop around it.
  std::vector<std::vector<int>> polys;
  std::vector<std::vector<std::array<int, 3>>> clippings;
  int tilt = 0;
  std::string why;
  for (; tilt < static_cast<int>(std::size(kTilts)); ++tilt) {
    const Projection pr(axis, kTilts[tilt][0], kTilts[tilt][1]);
    polys.clear(), clippings.clear(), why.clear();
    std::vector<double> area(loops.size());
    std::vector<std::vector<Vec3>> flat(loops.size());
    for (std::size_t l = 0; l < loops.size(); ++l) {
      for (int i : loops[l]) flat[l].push_back(pr.flat(pts[i]));
      for (std::size_t i = 0; i < flat[l].size(); ++i) {
        const Vec3 &f = flat[l][i], &g = flat[l][(i + 1) % flat[l].size()];
        area[l] += f[pr.u] * g[pr.v] - g[pr.u] * f[pr.v];
      }
    }
    auto inside = [&](const Vec3& x, std::size_t l) {  // crossing parity in the flat coordinates
      bool in = false;
      const auto& f = flat[l];
      for (std::size_t i = 0, j = f.size() - 1; i < f.size(); j = i++)
        if ((f[i][pr.v] > x[pr.v]) != (f[j][pr.v] > x[pr.v]) &&
            x[pr.u] < (f[j][pr.u] - f[i][pr.u]) * (x[pr.v] - f[i][pr.v]) / (f[j][pr.v] - f[i][pr.v]) + f[i][pr.u])
          in = !in;
      return in;
    };
    std::vector<std::vector<std::size_t>> holes_of(loops.size());
    for (std::size_t l = 0; l < loops.size() && why.empty(); ++l) {
      if (area[l] > 0) continue;
      std::size_t best = loops.size();
      for (std::size_t o = 0; o < loops.size(); ++o)
        if (area[o] > 0 && inside(flat[l][0], o) && (best == loops.size() || area[o] < area[best])) best = o;
      if (best == loops.size())
        why = "a loop of " + std::to_string(loops[l].size()) + " vertices through vertex " + std::to_string(gid[loops[l][0]]) +
              " turns clockwise outside every other loop (a fold of the cross-section)";
      else
        holes_of[best].push_back(l);
    }
    for (std::size_t l = 0; l < loops.size() && why.empty(); ++l) {
      if (!(area[l] > 0)) continue;
      std::vector<int> poly = loops[l];
      auto& hs = holes_of[l];
      auto max_u = [&](std::size_t h) {
        double m = flat[h][0][pr.u];
        for (const Vec3& f : flat[h]) m = std::max(m, f[pr.u]);
        return m;
      };
      std::sort(hs.begin(), hs.end(), [&](std::size_t a, std::size_t b) { return max_u(a) > max_u(b); });
      for (std::size_t k = 0; k < hs.size() && why.empty(); ++k) {
        std::vector<std::vector<int>> others;
        for (std::size_t r = k + 1; r < hs.size(); ++r) others.push_back(loops[hs[r]]);
        if (!bridge_hole(pts, gid, pr, surface_edge, poly, loops[hs[k]], others))
          why = "no bridge from the hole through vertex " + std::to_string(gid[loops[hs[k]][0]]) +
                " to the loop around it";
      }
      if (!why.empty()) break;
      std::vector<Vec3> p;
      std::vector<Index> ids;
      for (int i : poly) p.push_back(pts[i]), ids.push_back(gid[i]);
      std::vector<std::array<int, 3>> clipped;
      if (!clip_ears(p, ids, pr, surface_edge, clipped)) {
        why = "the cap of a loop of " + std::to_string(loops[l].size()) + " vertices through vertex " +
              std::to_string(gid[loops[l][0]]) + (hs.empty() ? "" : " and " + std::to_string(hs.size()) + " holes") +
              " cannot be triangulated in the projection (the loop folds over itself)";
        break;
      }
      polys.push_back(std::move(poly));
      clippings.push_back(std::move(clipped));
    }
    if (why.empty()) break;
  }
  if (!why.empty()) {
    cut.reason = why;
    return cut;
  }
  const Projection pr(axis, kTilts[tilt][0], kTilts[tilt][1]);
  for (std::size_t c = 0; c < polys.size(); ++c) {
    const std::vector<int>& poly = polys[c];
    std::vector<Vec3> p;
    std::vector<Index> ids;
    for (int i : poly) p.push_back(pts[i]), ids.push_back(gid[i]);
    const int m = static_cast<int>(poly.size());
    CapTriangulation cap(std::move(p), pr, clippings[c],
                         [&](int a, int b) { return a < m && b < m && surface_edge(ids[a], ids[b]); });
    cut.cap_flips += cap.make_delaunay();
    const std::int64_t added = add_cap_points(cap, poly.size(), pr, level);
    // The cap's vertex ids: the polygon's, then the new points' (after the input's and the earlier
    // caps' new points).
    const Index first_new = static_cast<Index>(xyz.size() / 3 + cut.new_points.size() / 3);
    for (std::size_t i = poly.size(); i < cap.points().size(); ++i) {
      const Vec3& q = cap.points()[i];
      cut.new_points.insert(cut.new_points.end(), {q.x, q.y, q.z});
    }
    cut.cap_points += added;
    auto id = [&](int i) { return i < m ? ids[i] : first_new + (i - m); };
    for (const auto& t : cap.triangles()) {
      cut.below.insert(cut.below.end(), {id(t[0]), id(t[1]), id(t[2])});
      cut.above.insert(cut.above.end(), {id(t[0]), id(t[2]), id(t[1])});
    }
    cut.cap_triangles += static_cast<std::int64_t>(cap.triangles().size());
  }
  cut.below_source.resize(cut.below.size() / 3, -1);
  cut.above_source.resize(cut.above.size() / 3, -1);
  cut.ok = true;
  return cut;
}

}  // namespace bsptet
