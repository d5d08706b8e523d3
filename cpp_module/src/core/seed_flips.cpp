// SPDX-License-Identifier: LGPL-2.1-or-later
// The seed's flips (seed_flips.h).
#include "bsptet/core/seed_flips.h"

#include <algorithm>
#include <functional>
#include <tuple>
#include <utility>
#include <vector>

#include "bsptet/mesh/edge_map.h"
#include "bsptet/mesh/ring_triangulation.h"

namespace bsptet {

namespace {
constexpr auto& kFace = kTetOppositeFace;  // types.h
}  // namespace

void SeedFlips::protect_triangle(Index a, Index b, Index c) {
  std::array<Index, 3> k{{a, b, c}};
  std::sort(k.begin(), k.end());
  protected_faces_.push_back(key3(k));
  protected_edges_.push_back(edge_key(a, b));
  protected_edges_.push_back(edge_key(b, c));
  protected_edges_.push_back(edge_key(a, c));
  protection_sorted_ = false;
}

bool SeedFlips::has_edge(Index a, Index b) const {
  for (Index t : inc_[a])
    if (alive_[t] && contains(tets_[t], b)) return true;
  return false;
}

bool SeedFlips::recover_edge(Index a, Index b, int max_flips) {
  int removals = 0;  // edge removals so far (at most kMaxRemovalsPerEdge)
  for (int it = 0; it <= max_flips; ++it) {
    if (has_edge(a, b)) return true;
    if (it == max_flips) return false;
    bool flipped = false, degenerate = false;
    for (std::size_t k = 0; k < inc_[a].size() && !flipped && !degenerate; ++k) {
      const Index t = inc_[a][k];
      if (!alive_[t]) continue;
      const Tet& q = tets_[t];
      const int ia = index_of(q, a);
      // b against the three faces through a, each oriented with the tet on its positive side.
      int zeros = 0, zero_face = -1;
      bool inside = true;
      for (int j = 0; j < 4 && inside; ++j) {
        if (j == ia) continue;
        const int s = to_int(orient3d(pts_[q[kFace[j][0]]], pts_[q[kFace[j][1]]], pts_[q[kFace[j][2]]], pts_[b]));
        if (s < 0) inside = false;
        if (s == 0) {
          ++zeros;
          zero_face = j;
        }
      }
      if (!inside) continue;
      if (zeros == 0) {
        flipped = flip23(t, ia) || (removals < kMaxRemovalsPerEdge && remove_blocking_edge(t, ia) && ++removals);
        degenerate = !flipped;  // the segment leaves through that face: nothing else to try
      } else if (zeros == 1) {
        // Through the interior of the edge cd of the face opposite a that is not on face
        // zero_face: a, c, d and b are coplanar. One flip of a planar sequence (planar_flip).
        Index c = -1, d = -1;
        for (int j = 0; j < 4; ++j)
          if (j != ia && j != zero_face) (c < 0 ? c : d) = q[j];
        flipped = planar_flip(a, b, c, d) ||
                  (removals < kMaxRemovalsPerEdge && remove_edge_deep(c, d, kFlipLevels) && ++removals);
        degenerate = !flipped;
      }
    }
    if (!flipped) return false;
  }
  return false;
}

bool SeedFlips::recover_face(Index a, Index b, Index c) {
  if (has_face(a, b, c)) return true;
  for (const auto& [u, w, o] : {std::tuple{a, b, c}, std::tuple{b, c, a}, std::tuple{c, a, b}})
    for (Index t : ring_around(u, w)) {
      const auto [d, e] = other_two(t, u, w);
      if (d == o || e == o) continue;
      if (flip32(d, e, a, b, c)) return has_face(a, b, c);
    }
  return false;
}

std::vector<SeedFlips::Tet> SeedFlips::result(std::vector<std::array<Index, 4>>& nb) const {
  const std::size_t first = nb.size();
  std::vector<Index> renumber(tets_.size(), -1);
  Index m = 0;
  for (std::size_t t = 0; t < tets_.size(); ++t)
    if (alive_[t]) renumber[t] = m++;
  std::vector<Tet> out;
  std::vector<std::array<Index, 4>> out_nb;
  out.reserve(static_cast<std::size_t>(m));
  out_nb.reserve(static_cast<std::size_t>(m));
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    if (!alive_[t]) continue;
    const Tet& q = tets_[t];
    std::array<Index, 4> n;
    for (int i = 0; i < 4; ++i) {
      const Index old = t < first ? nb[t][i] : -2;
      if (old == -1) {
        n[i] = -1;  // the hull: never flipped
      } else if (old >= 0 && alive_[old]) {
        n[i] = renumber[old];
      } else {
        const Index o = tet_with(q[kFace[i][0]], q[kFace[i][1]], q[kFace[i][2]], static_cast<Index>(t));
        n[i] = o < 0 ? -1 : renumber[o];
      }
    }
    out.push_back(q);
    out_nb.push_back(n);
  }
  nb = std::move(out_nb);
  return out;
}

void SeedFlips::sort_protection() {
  if (protection_sorted_) return;
  std::sort(protected_faces_.begin(), protected_faces_.end());
  protected_faces_.erase(std::unique(protected_faces_.begin(), protected_faces_.end()), protected_faces_.end());
  std::sort(protected_edges_.begin(), protected_edges_.end());
  protected_edges_.erase(std::unique(protected_edges_.begin(), protected_edges_.end()), protected_edges_.end());
  protection_sorted_ = true;
}

bool SeedFlips::edge_protected(Index x, Index y) {
  sort_protection();
  return std::binary_search(protected_edges_.begin(), protected_edges_.end(), edge_key(x, y));
}

bool SeedFlips::face_protected(Index x, Index y, Index z) {
  sort_protection();
  return std::binary_search(protected_faces_.begin(), protected_faces_.end(), key3({x, y, z}));
}

Index SeedFlips::tet_with(Index x, Index y, Index z, Index not_t) const {
  for (Index t : inc_[x])
    if (t != not_t && alive_[t] && contains(tets_[t], y) && contains(tets_[t], z)) return t;
  return -1;
}

std::vector<Index> SeedFlips::ring_around(Index c, Index d) const {
  std::vector<Index> ring;
  for (Index t : inc_[c])
    if (alive_[t] && contains(tets_[t], d)) ring.push_back(t);
  return ring;
}

std::array<Index, 2> SeedFlips::other_two(Index t, Index c, Index d) const {
  std::array<Index, 2> o{{-1, -1}};
  for (Index v : tets_[t])
    if (v != c && v != d) (o[0] < 0 ? o[0] : o[1]) = v;
  return o;
}

void SeedFlips::replace(const std::vector<Index>& old_tets, const std::vector<Tet>& new_tets) {
  if (logging_) log_.push_back({old_tets, tets_.size()});
  for (Index t : old_tets)
    for (Index v : tets_[t]) ++changes_[v];
  for (Index t : old_tets) {
    alive_[t] = 0;
    for (Index v : tets_[t]) {
      auto& l = inc_[v];
      l.erase(std::find(l.begin(), l.end(), t));
    }
  }
  for (const Tet& q : new_tets) {
    const Index t = static_cast<Index>(tets_.size());
    tets_.push_back(q);
    alive_.push_back(1);
    for (Index v : q) inc_[v].push_back(t);
  }
  ++flips_;
}

void SeedFlips::undo_to(std::size_t mark) {
  while (log_.size() > mark) {
    const FlipLog& f = log_.back();
    while (tets_.size() > f.first_new) {
      const Index t = static_cast<Index>(tets_.size() - 1);
      for (Index v : tets_.back()) {
        auto& l = inc_[v];
        l.erase(std::find(l.begin(), l.end(), t));
        ++changes_[v];
      }
      tets_.pop_back();
      alive_.pop_back();
    }
    for (Index t : f.old_tets) {
      alive_[t] = 1;
      for (Index v : tets_[t]) inc_[v].push_back(t);
    }
    --flips_;
    log_.pop_back();
  }
}

bool SeedFlips::remove_edge_deep(Index c, Index d, int level) {
  if (remove_edge(c, d, -1, -1)) return true;
  if (level <= 0 || edge_protected(c, d)) return false;
  const std::vector<Index> ring = ring_apexes(c, d);
  if (ring.size() < 3 || static_cast<int>(ring.size()) > kMaxRing) return false;
  // It depends only on the tets at c, d and the ring's vertices: a failure is remembered with
  // their change counters (which only grow), and not tried again while their sum is unchanged.
  auto signature = [&] {
    std::uint64_t sum = changes_[c] + changes_[d];
    for (Index p : ring) sum += changes_[p];
    return sum;
  };
  const std::uint64_t key = edge_key(c, d);
  if (const auto it = failed_deep_.find(key);
      it != failed_deep_.end() && it->second == std::pair{level, signature()})
    return false;
  const bool was_logging = logging_;
  logging_ = true;
  bool done = false;
  for (std::size_t i = 0; i < ring.size() && !done; ++i)
    for (Index x : {c, d}) {
      const std::size_t mark = log_.size();
      if (remove_edge_deep(x, ring[i], level - 1) && remove_edge(c, d, -1, -1)) {
        done = true;
        break;
      }
      undo_to(mark);
    }
  logging_ = was_logging;
  if (!logging_) log_.clear();
  if (!done) failed_deep_[key] = {level, signature()};  // after the undos (they count as changes)
  return done;
}

bool SeedFlips::across(Index t, int ia, Index& t2, Index& f) {
  const Tet& q = tets_[t];
  const Index c = q[kFace[ia][0]], d = q[kFace[ia][1]], e = q[kFace[ia][2]];
  if (face_protected(c, d, e)) return false;
  t2 = tet_with(c, d, e, t);
  if (t2 < 0) return false;
  f = -1;
  for (Index v : tets_[t2])
    if (v != c && v != d && v != e) f = v;
  return true;
}

bool SeedFlips::flip23(Index t, int ia) {
  const Tet q = tets_[t];
  const Index c = q[kFace[ia][0]], d = q[kFace[ia][1]], e = q[kFace[ia][2]];
  Index t2, f;
  if (!across(t, ia, t2, f)) return false;
  // Each new tet keeps one face of t through a (its other vertex replaced by f).
  std::vector<Tet> made;
  for (Index x : {c, d, e}) {
    const Tet n = substituted(q, x, f);
    if (!positive(n)) return false;
    made.push_back(n);
  }
  replace({t, t2}, made);
  return true;
}

bool SeedFlips::remove_blocking_edge(Index t, int ia) {
  const Tet q = tets_[t];
  const Index c = q[kFace[ia][0]], d = q[kFace[ia][1]], e = q[kFace[ia][2]];
  Index t2, f;
  if (!across(t, ia, t2, f)) return false;
  for (const auto& [x, y, z] : {std::tuple{c, d, e}, std::tuple{d, e, c}, std::tuple{e, c, d}}) {
    if (positive(substituted(q, x, f))) continue;
    if (remove_edge_deep(y, z, kFlipLevels)) return true;
  }
  return false;
}

bool SeedFlips::flip32(Index d, Index e, Index a, Index b, Index c) {
  if (edge_protected(d, e)) return false;
  const std::vector<Index> ring = ring_around(d, e);
  if (ring.size() != 3) return false;
  for (Index t : ring) {
    const auto [u, w] = other_two(t, d, e);
    const bool in_abc = (u == a || u == b || u == c) && (w == a || w == b || w == c);
    if (!in_abc || face_protected(d, e, u) || face_protected(d, e, w)) return false;
  }
  // The tet of the ring through a and b keeps its faces (a, b, d) and (a, b, e): its vertex e
  // (resp. d) replaced by c.
  Index tab = -1;
  for (Index t : ring)
    if (contains(tets_[t], a) && contains(tets_[t], b)) tab = t;
  if (tab < 0) return false;
  const Tet n1 = substituted(tets_[tab], e, c), n2 = substituted(tets_[tab], d, c);
  if (!positive(n1) || !positive(n2)) return false;
  replace(ring, {n1, n2});
  return true;
}

bool SeedFlips::planar_flip(Index a, Index b, Index c, Index d) {
  int axis = 0;
  while (axis < 3 && orient2d_projected(pts_[a], pts_[c], pts_[d], axis) == Sign::kZero) ++axis;
  if (axis == 3) return false;
  auto o2 = [&](Index x, Index y, Index z) { return to_int(orient2d_projected(pts_[x], pts_[y], pts_[z], axis)); };
  struct Crossed {
    Index c, d, x, y;  // edge (c, d) crossed by ab; x before it, y beyond it (plane triangles)
  };
  std::vector<Crossed> crossed;
  Index x = a;
  for (int step = 0;; ++step) {
    if (step > kMaxCrossed) return false;
    Index y = -1;
    for (Index v : ring_apexes(c, d))
      if (v != x && o2(c, d, v) != 0 && o2(c, d, v) == -o2(c, d, x) &&
          orient3d(pts_[a], pts_[c], pts_[d], pts_[v]) == Sign::kZero)
        y = v;
    if (y < 0) return false;
    crossed.push_back({c, d, x, y});
    if (y == b) break;
    const int sy = o2(a, b, y);
    if (sy == 0) return false;  // a vertex on the segment ab
    // The next crossed edge: (c, y) or (d, y), the one whose end is on the other side of ab.
    if (o2(a, b, c) == -sy) d = y;
    else c = y;
    x = crossed.back().c == c ? crossed.back().d : crossed.back().c;
  }
  for (const Crossed& e : crossed) {
    const bool clears = e.x == a || e.y == b || o2(a, b, e.x) * o2(a, b, e.y) >= 0;
    if (clears && remove_edge(e.c, e.d, e.x, e.y)) return true;
  }
  return false;
}

std::vector<Index> SeedFlips::ring_apexes(Index c, Index d) const {
  std::vector<Index> out;
  for (Index t : ring_around(c, d))
    for (Index v : other_two(t, c, d))
      if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  return out;
}

bool SeedFlips::remove_edge(Index c, Index d, Index a, Index e) {
  if (edge_protected(c, d)) return false;
  const std::vector<Index> ring = ring_around(c, d);
  const int n = static_cast<int>(ring.size());
  if (n < 3 || n > kMaxRing) return false;
  // next[u] = w for each ring tet (c, d, u, w) positive in that order.
  std::vector<std::pair<Index, Index>> next;
  for (Index t : ring) {
    const auto [u, w] = other_two(t, c, d);
    if (face_protected(c, d, u) || face_protected(c, d, w)) return false;
    next.push_back(even_order(tets_[t], c, d, u, w) ? std::pair{u, w} : std::pair{w, u});
  }
  if (a < 0) a = next[0].first;  // any triangulation: the ring from any of its vertices
  std::vector<Index> p{a};
  for (int i = 1; i <= n; ++i) {
    const auto it = std::find_if(next.begin(), next.end(), [&](const auto& uw) { return uw.first == p.back(); });
    if (it == next.end()) return false;  // not a ring through a
    if (i == n) {
      if (it->second != a) return false;
      break;
    }
    p.push_back(it->second);
  }
  // e < 0: any triangulation (the whole polygon, p_0 .. p_{n-1}, is the sub-polygon (0, n - 1)).
  const int k = e < 0 ? n - 1 : static_cast<int>(std::find(p.begin(), p.end(), e) - p.begin());
  if (e >= 0 && (k <= 1 || k >= n - 1)) return false;  // e must be a ring vertex not next to a
  // Triangle (p_i, p_k, p_j) in ring order: tets (c, p_i, p_k, p_j) and (d, p_k, p_i, p_j); the
  // first allowed triangulation (mesh/ring_triangulation.h) of p_0 .. p_k and of p_k .. p_n
  // (p_n = p_0).
  auto at = [&](int i) { return p[i % n]; };
  auto ring_polygon = make_ring_triangulation(
      n + 1, 0.0, 1.0,
      [&](int i, int m, int j, double) {
        return positive({c, at(i), at(m), at(j)}) && positive({d, at(m), at(i), at(j)}) ? 1.0 : -1.0;
      },
      [](int, int) { return true; });
  if (ring_polygon.best(0, k) <= 0 || (e >= 0 && ring_polygon.best(k, n) <= 0)) return false;
  std::vector<Tet> made;
  const auto emit = [&](int i, int m, int j) {
    made.push_back({c, at(i), at(m), at(j)});
    made.push_back({d, at(m), at(i), at(j)});
  };
  ring_polygon.for_each_triangle(0, k, emit);
  if (e >= 0) ring_polygon.for_each_triangle(k, n, emit);
  replace(ring, made);
  return true;
}

}  // namespace bsptet
