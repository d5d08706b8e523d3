// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/cell_delaunay.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <set>
#include <utility>

#include "bsptet/core/cell_tetrahedralize.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/splitmix.h"

namespace bsptet {

std::vector<std::array<Index, 3>> delaunay_face(ImplicitGeometry& geo, const BspFace& face) {
  std::vector<std::array<Index, 3>> tris = triangulate_face(geo, face);
  if (tris.size() < 2) return tris;
  Sign ns = Sign::kZero;
  const int axis = geo.projection_axis(face.plane, &ns);
  // Lawson flips: an edge (a, b) between (a, b, c) and (b, a, d) is flipped to (c, d) when d is
  // strictly inside the perturbed circumcircle of (a, b, c) and the quadrilateral is strictly
  // convex. Each flip strictly lowers the (perturbed) lifted surface, so this ends; when no edge
  // flips, every edge is locally regular and the triangulation is the perturbed regular one (all
  // points are vertices of their lifted hull). The cap only guards against a bug; the result is a
  // valid triangulation either way, and it is computed once per face.
  // Neighbours: nb[t][k] is the triangle across edge (tris[t][k], tris[t][k + 1]), or -1 on the
  // face's boundary. Built once from the sorted directed edges, then kept up to date by each flip.
  const std::size_t m = tris.size();
  std::vector<std::array<std::ptrdiff_t, 3>> nb(m, {-1, -1, -1});
  {
    std::vector<std::pair<std::pair<Index, Index>, std::pair<std::size_t, int>>> edge;
    edge.reserve(3 * m);
    for (std::size_t t = 0; t < m; ++t)
      for (int k = 0; k < 3; ++k) edge.push_back({{tris[t][k], tris[t][(k + 1) % 3]}, {t, k}});
    std::sort(edge.begin(), edge.end());
    for (const auto& e : edge) {
      const auto it = std::lower_bound(
          edge.begin(), edge.end(),
          std::make_pair(std::make_pair(e.first.second, e.first.first), std::make_pair(std::size_t(0), 0)));
      if (it != edge.end() && it->first == std::make_pair(e.first.second, e.first.first))
        nb[e.second.first][e.second.second] = static_cast<std::ptrdiff_t>(it->second.first);
    }
  }
  // Position in triangle t of the directed edge (a, b).
  auto position = [&](std::size_t t, Index a, Index b) {
    for (int k = 0; k < 3; ++k)
      if (tris[t][k] == a && tris[t][(k + 1) % 3] == b) return k;
    throw MeshingError(ErrorCode::kInternal, "delaunay_face", face.plane, "neighbour lost its shared edge");
  };
  // Lawson's stack: every edge once at the start, then the four outer edges of each flip. The
  // order is fixed (deterministic); the result does not depend on it (it is the unique perturbed
  // regular triangulation). The flip count guards only against a bug.
  std::vector<std::pair<std::size_t, int>> stack;
  stack.reserve(3 * m);
  for (std::size_t t = m; t-- > 0;)
    for (int k = 3; k-- > 0;) stack.push_back({t, k});
  const std::size_t cap = 8 * m * m + 64;
  std::size_t flips = 0;
  while (!stack.empty() && flips < cap) {
    const auto [t, k] = stack.back();
    stack.pop_back();
    const std::ptrdiff_t us = nb[t][k];
    if (us < 0) continue;
    const std::size_t u = static_cast<std::size_t>(us);
    const Index a = tris[t][k], b = tris[t][(k + 1) % 3], c = tris[t][(k + 2) % 3];
    const int j = position(u, b, a);
    const Index d = tris[u][(j + 2) % 3];
    if (geo.lifted_det2(a, b, c, d, axis) != ns) continue;
    if (geo.orient2d(a, d, c, axis) != ns || geo.orient2d(d, b, c, axis) != ns) continue;
    const std::ptrdiff_t x_bc = nb[t][(k + 1) % 3], x_ca = nb[t][(k + 2) % 3];
    const std::ptrdiff_t y_ad = nb[u][(j + 1) % 3], y_db = nb[u][(j + 2) % 3];
    tris[t] = {a, d, c};
    tris[u] = {d, b, c};
    nb[t] = {y_ad, static_cast<std::ptrdiff_t>(u), x_ca};
    nb[u] = {y_db, x_bc, static_cast<std::ptrdiff_t>(t)};
    if (x_bc >= 0) nb[x_bc][position(x_bc, c, b)] = static_cast<std::ptrdiff_t>(u);
    if (y_ad >= 0) nb[y_ad][position(y_ad, d, a)] = static_cast<std::ptrdiff_t>(t);
    stack.push_back({t, 0});
    stack.push_back({t, 2});
    stack.push_back({u, 0});
    stack.push_back({u, 1});
    ++flips;
  }
  return tris;
}

namespace {

constexpr int kInf = -1;
constexpr auto& kFace = kTetOppositeFace;  // types.h

struct Tet {
  std::array<int, 4> v;   ///< local point ids; a ghost has kInf at position 3 (and only there)
  std::array<int, 4> nb;  ///< tet across the face opposite v[i]
};

// Bowyer-Watson over local point ids 0..n-1 (global ids in pts). Real tets are positive; a ghost
// (a, b, c, INF) carries hull face (a, b, c) with the outside on its positive side.
class BowyerWatson {
 public:
  BowyerWatson(ImplicitGeometry& geo, std::vector<Index> pts, const std::vector<Index>& planes)
      : geo_(geo), p_(std::move(pts)) {
    for (std::size_t k = 0; k < planes.size() && planes_.size() < 64; ++k)
      if (std::find(planes_.begin(), planes_.end(), planes[k]) == planes_.end()) planes_.push_back(planes[k]);
    axis_.assign(planes_.size(), -1);
    ns_.assign(planes_.size(), Sign::kZero);
    mask_.assign(p_.size(), 0);
    for (std::size_t i = 0; i < p_.size(); ++i)
      for (std::size_t k = 0; k < planes_.size(); ++k)
        if (geo_.known_on_plane(p_[i], planes_[k])) mask_[i] |= std::uint64_t(1) << k;
  }

  /// Inserts the points in an order drawn from `seed` (the result does not depend on it).
  bool run(std::uint64_t seed) {
    const int n = static_cast<int>(p_.size());
    if (n < 4) return false;
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    std::uint64_t s = seed;
    for (int i = n - 1; i > 0; --i) std::swap(order[i], order[static_cast<int>(splitmix64(s) % (i + 1))]);
    rng_ = splitmix64(s);
    // First tet: the first point, the next, the first not collinear, the first not coplanar.
    const int a = order[0], b = order[1];
    int c = -1, d = -1;
    for (int i = 2; i < n && c < 0; ++i) {
      Sign s;
      if (triangle_axis(a, b, order[i], &s) >= 0) c = order[i];
    }
    if (c < 0) return false;
    Sign o = Sign::kZero;
    for (int i = 2; i < n && d < 0; ++i) {
      if (order[i] == c) continue;
      o = orient_face(a, b, c, order[i]);
      if (o != Sign::kZero) d = order[i];
    }
    if (d < 0) return false;
    std::array<int, 4> first = o == Sign::kPositive ? std::array<int, 4>{a, b, c, d} : std::array<int, 4>{b, a, c, d};
    std::vector<int> ids;
    ids.push_back(alloc({first, {-1, -1, -1, -1}}));
    for (int i = 0; i < 4; ++i) {
      const int* f = kFace[i];
      // Reversed face: the cell's inside on its negative side.
      ids.push_back(alloc({{first[f[0]], first[f[2]], first[f[1]], kInf}, {-1, -1, -1, -1}}));
    }
    std::vector<std::pair<int, int>> faces;
    for (int t : ids)
      for (int k = 0; k < 4; ++k) faces.push_back({t, k});
    if (!link(faces)) return false;
    hint_ = ids[0];
    for (int i = 0; i < n; ++i) {
      const int e = order[i];
      if (e == a || e == b || e == c || e == d) continue;
      if (!insert(e)) return false;
    }
    return true;
  }

  bool collect(CellDelaunay& out) {
    out.tets.clear();
    out.hull.clear();
    // Oriented boundary of the chain of output tets, computed from the tets alone.
    struct F {
      std::array<Index, 3> key;  // sorted
      std::array<Index, 3> tri;  // outward, rotated so the smallest id comes first
      bool parity;
    };
    std::vector<F> fs;
    for (std::size_t t = 0; t < tets_.size(); ++t) {
      if (dead_[t] || tets_[t].v[3] == kInf) continue;
      const auto& v = tets_[t].v;
      const std::array<Index, 4> g{{p_[v[0]], p_[v[1]], p_[v[2]], p_[v[3]]}};
      if (geo_.orient3d(g[0], g[1], g[2], g[3]) != Sign::kPositive) return false;
      out.tets.push_back(g);
      for (int i = 0; i < 4; ++i) {
        std::array<Index, 3> tri{{g[kFace[i][0]], g[kFace[i][2]], g[kFace[i][1]]}};
        std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
        std::array<Index, 3> key = tri;
        std::sort(key.begin(), key.end());
        fs.push_back({key, tri, tri[1] < tri[2]});
      }
    }
    std::sort(fs.begin(), fs.end(), [](const F& x, const F& y) { return x.key < y.key; });
    for (std::size_t i = 0; i < fs.size();) {
      std::size_t j = i;
      while (j < fs.size() && fs[j].key == fs[i].key) ++j;
      if (j - i == 1) {
        out.hull.push_back(fs[i].tri);
      } else if (j - i != 2 || fs[i].parity == fs[i + 1].parity) {
        return false;
      }
      i = j;
    }
    return true;
  }

 private:
  int alloc(const Tet& t) {
    if (!free_.empty()) {
      const int id = free_.back();
      free_.pop_back();
      tets_[id] = t;
      dead_[id] = 0;
      return id;
    }
    tets_.push_back(t);
    dead_.push_back(0);
    in_conflict_.push_back(0);
    tested_.push_back(0);
    return static_cast<int>(tets_.size() - 1);
  }

  // Pairs the given faces (tet, opposite vertex) by their vertex sets; each set must occur twice.
  bool link(const std::vector<std::pair<int, int>>& faces) {
    std::vector<std::pair<std::array<int, 3>, std::pair<int, int>>> keys;
    keys.reserve(faces.size());
    for (const auto& [t, k] : faces) {
      std::array<int, 3> key;
      int m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != k) key[m++] = tets_[t].v[j];
      std::sort(key.begin(), key.end());
      keys.push_back({key, {t, k}});
    }
    std::sort(keys.begin(), keys.end());
    if (keys.size() % 2) return false;
    for (std::size_t i = 0; i < keys.size(); i += 2) {
      if (keys[i].first != keys[i + 1].first || (i + 2 < keys.size() && keys[i + 2].first == keys[i].first))
        return false;
      const auto [t, k] = keys[i].second;
      const auto [u, m] = keys[i + 1].second;
      tets_[t].nb[k] = u;
      tets_[u].nb[m] = t;
    }
    return true;
  }

  // Plane k's projection axis and normal sign (cached).
  int plane_axis(int k) {
    if (axis_[k] < 0) axis_[k] = geo_.projection_axis(planes_[k], &ns_[k]);
    return axis_[k];
  }
  // Axes ordered by the magnitude of the rounded normal of (a, b, c): the first one is
  // non-degenerate unless the triangle is nearly parallel to two axes (then the others are tried).
  std::array<int, 3> axes(int a, int b, int c) {
    const Vec3 pa = geo_.rounded(p_[a]), pb = geo_.rounded(p_[b]), pc = geo_.rounded(p_[c]);
    const double ux = pb.x - pa.x, uy = pb.y - pa.y, uz = pb.z - pa.z, vx = pc.x - pa.x, vy = pc.y - pa.y,
                 vz = pc.z - pa.z;
    const double n[3] = {std::fabs(uy * vz - uz * vy), std::fabs(uz * vx - ux * vz), std::fabs(ux * vy - uy * vx)};
    std::array<int, 3> o{{0, 1, 2}};
    std::stable_sort(o.begin(), o.end(), [&](int i, int j) { return n[i] > n[j]; });
    return o;
  }
  // A projection axis along which (a, b, c) is non-degenerate, and its orientation there; -1 if
  // the three are collinear.
  int triangle_axis(int a, int b, int c, Sign* s) {
    const std::uint64_t m = mask_[a] & mask_[b] & mask_[c];
    if (m & (m - 1)) return -1;  // on two distinct planes through a: on their line
    if (m) {
      const int axis = plane_axis(__builtin_ctzll(m));
      *s = geo_.orient2d(p_[a], p_[b], p_[c], axis);
      if (*s != Sign::kZero) return axis;
      return -1;  // projection one-to-one on the plane: collinear
    }
    for (int axis : axes(a, b, c)) {
      *s = geo_.orient2d(p_[a], p_[b], p_[c], axis);
      if (*s != Sign::kZero) return axis;
    }
    return -1;
  }
  // orient3d(a, b, c, e) for a non-degenerate triangle (a, b, c); through the side of a cell plane
  // when the triangle is known to lie on one (no arithmetic when e is known on it too).
  Sign orient_face(int a, int b, int c, int e) {
    const std::uint64_t m = mask_[a] & mask_[b] & mask_[c];
    if (m) {
      const int k = __builtin_ctzll(m);
      if (mask_[e] >> k & 1) return Sign::kZero;
      const int axis = plane_axis(k);
      const Sign s = geo_.orient2d(p_[a], p_[b], p_[c], axis);
      const Sign side = geo_.side(planes_[k], p_[e]);
      if (s != Sign::kZero) return static_cast<Sign>(to_int(side) * to_int(s) * to_int(ns_[k]));
    }
    return geo_.orient3d(p_[a], p_[b], p_[c], p_[e]);
  }

  bool conflict(int t, int e) {
    const auto& v = tets_[t].v;
    if (v[3] != kInf) return geo_.lifted_det3(p_[v[0]], p_[v[1]], p_[v[2]], p_[v[3]], p_[e]) == Sign::kNegative;
    const Sign o = orient_face(v[0], v[1], v[2], e);
    if (o != Sign::kZero) return o == Sign::kPositive;
    // e on the hull face's plane: in conflict iff inside its perturbed circumcircle.
    Sign s = Sign::kZero;
    const int axis = triangle_axis(v[0], v[1], v[2], &s);
    if (axis < 0) return false;  // not reached: ghost faces are non-degenerate
    return geo_.lifted_det2(p_[v[0]], p_[v[1]], p_[v[2]], p_[e], axis) == s;
  }

  // Visibility walk from hint_ (random face order from a local generator); -1 if it does not end.
  int locate(int e) {
    int t = hint_;
    if (dead_[t] || tets_[t].v[3] == kInf) {
      for (t = 0; t < static_cast<int>(tets_.size()); ++t)
        if (!dead_[t] && tets_[t].v[3] != kInf) break;
    }
    const std::size_t cap = 4 * tets_.size() + 64;
    for (std::size_t step = 0; step < cap; ++step) {
      if (tets_[t].v[3] == kInf) return t;  // crossed a hull face strictly: e is beyond it
      const auto& v = tets_[t].v;
      const int r = static_cast<int>(splitmix64(rng_) & 3);
      int next = -1;
      for (int k = 0; k < 4 && next < 0; ++k) {
        const int i = (r + k) & 3;
        const int* f = kFace[i];
        if (orient_face(v[f[0]], v[f[1]], v[f[2]], e) == Sign::kNegative) next = tets_[t].nb[i];
      }
      if (next < 0) return t;  // e in the closed tet (not a vertex): strictly inside its sphere
      t = next;
    }
    return -1;
  }

  bool insert(int e) {
    ++stamp_;
    int t0 = locate(e);
    if (t0 < 0 || !conflict(t0, e)) {
      t0 = -1;
      for (int t = 0; t < static_cast<int>(tets_.size()) && t0 < 0; ++t)
        if (!dead_[t] && conflict(t, e)) t0 = t;
      if (t0 < 0) return false;
    }
    std::vector<int> cavity{t0};
    in_conflict_[t0] = stamp_;
    std::vector<std::pair<int, int>> boundary;
    for (std::size_t q = 0; q < cavity.size(); ++q) {
      const int t = cavity[q];
      for (int i = 0; i < 4; ++i) {
        const int n = tets_[t].nb[i];
        if (in_conflict_[n] == stamp_) continue;
        if (tested_[n] != stamp_) {
          if (conflict(n, e)) {
            in_conflict_[n] = stamp_;
            cavity.push_back(n);
            continue;
          }
          tested_[n] = stamp_;
        }
        boundary.push_back({t, i});
      }
    }
    std::vector<std::pair<int, int>> inner;
    int last_real = -1;
    for (const auto& [t, i] : boundary) {
      Tet nt{tets_[t].v, {-1, -1, -1, -1}};
      nt.v[i] = e;
      const int o = tets_[t].nb[i];
      nt.nb[i] = o;
      const int id = alloc(nt);
      for (int j = 0; j < 4; ++j)
        if (tets_[o].nb[j] == t) tets_[o].nb[j] = id;
      for (int k = 0; k < 4; ++k)
        if (k != i) inner.push_back({id, k});
      if (nt.v[3] != kInf) last_real = id;
    }
    if (!link(inner)) return false;
    for (int t : cavity) {
      dead_[t] = 1;
      free_.push_back(t);
    }
    if (last_real >= 0) hint_ = last_real;
    return true;
  }

  ImplicitGeometry& geo_;
  std::vector<Index> p_;
  std::vector<Index> planes_;     ///< the cell's face planes (at most 64)
  std::vector<int> axis_;         ///< cache of projection_axis per plane
  std::vector<Sign> ns_;
  std::vector<std::uint64_t> mask_;  ///< per point: the planes it is known to lie on
  std::vector<Tet> tets_;
  std::vector<char> dead_;
  std::vector<int> free_;
  std::vector<std::uint32_t> in_conflict_, tested_;
  std::uint32_t stamp_ = 0;
  int hint_ = 0;
  std::uint64_t rng_ = 0;
};

}  // namespace

bool delaunay_cell(ImplicitGeometry& geo, std::vector<Index> points, const std::vector<Index>& planes,
                   std::uint64_t seed, CellDelaunay& out) {
  BowyerWatson bw(geo, std::move(points), planes);
  if (!bw.run(seed)) return false;
  return bw.collect(out);
}

namespace {

using Tri = std::array<Index, 3>;

Tri canonical_tri(Tri t) {
  std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  return t;
}
Tri reversed(const Tri& t) { return canonical_tri({t[0], t[2], t[1]}); }

// Outward faces of tet t, canonical.
std::array<Tri, 4> outward_faces(const std::array<Index, 4>& t) {
  std::array<Tri, 4> f;
  for (int i = 0; i < 4; ++i) f[i] = canonical_tri({t[kFace[i][0]], t[kFace[i][2]], t[kFace[i][1]]});
  return f;
}

// The boundary of the chain of a set of tets (outward, canonical, sorted): per triangle, the
// number of outward copies minus the number of reversed ones; a net multiplicity m != 0 gives |m|
// copies of the triangle in its net orientation (so a comparison with a set of triangles fails
// unless every |m| is 1).
std::vector<Tri> chain_boundary(const std::vector<std::array<Index, 4>>& tets, const std::vector<std::size_t>& ids) {
  std::vector<std::pair<Tri, int>> all;  // (sorted key, +1 / -1 by orientation parity)
  for (std::size_t i : ids)
    for (const Tri& f : outward_faces(tets[i])) {
      Tri key = f;
      std::sort(key.begin(), key.end());
      all.push_back({key, f[1] < f[2] ? 1 : -1});  // f is rotated to start with its smallest id
    }
  std::sort(all.begin(), all.end());
  std::vector<Tri> out;
  for (std::size_t i = 0; i < all.size();) {
    std::size_t j = i;
    int net = 0;
    for (; j < all.size() && all[j].first == all[i].first; ++j) net += all[j].second;
    const Tri& k = all[i].first;  // k[0] < k[1] < k[2]: parity +1 is (k0, k1, k2)
    const Tri t = net > 0 ? Tri{k[0], k[1], k[2]} : Tri{k[0], k[2], k[1]};
    for (int m = 0; m < (net > 0 ? net : -net); ++m) out.push_back(t);
    i = j;
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

namespace {

std::vector<Tri> all_boundary(const std::vector<std::array<Index, 4>>& tets) {
  std::vector<std::size_t> ids(tets.size());
  for (std::size_t i = 0; i < tets.size(); ++i) ids[i] = i;
  return chain_boundary(tets, ids);
}

// The tets of one cell while its boundary is repaired: dead tets stay in place (ids are stable),
// `owner` maps each outward face of a live tet to it, `hull` is the boundary of the live tets.
struct CellMesh {
  std::vector<std::array<Index, 4>> tets;
  std::vector<char> alive;
  std::map<Tri, std::size_t> owner;
  std::set<Tri> hull;

  void add_tet(const std::array<Index, 4>& t) {
    tets.push_back(t);
    alive.push_back(1);
    for (const Tri& f : outward_faces(t)) owner[f] = tets.size() - 1;
  }
  void kill(std::size_t i) {
    alive[i] = 0;
    for (const Tri& f : outward_faces(tets[i])) owner.erase(f);
  }
  // The live tet beyond face f of the cavity (the owner of f reversed); -1 on the cell boundary.
  std::int64_t beyond(const Tri& f) const {
    const auto it = owner.find(reversed(f));
    return it == owner.end() ? -1 : static_cast<std::int64_t>(it->second);
  }
};

// Replaces the cell-boundary triangles `remove` (outward, canonical, sorted; all faces of live
// tets) by `add` (same region, same boundary edges). The cavity C starts as the tets with a face in
// `remove` (plus, when `edge` is given, every tet around that edge); for each candidate apex v (the
// vertices of C's boundary, by id, at most 16 of them), every face of C's boundary (with `remove`
// swapped for `add`) that does not contain v and that v does not see strictly takes the tet
// beyond it into C (never across the cell boundary: then v is given up), until v sees them all (at
// most max_growth rounds); C is then re-filled by the cone from v. Valid by the chain argument
// (recover_cell_boundary). `budget` counts orientation tests and tets visited.
bool recone(ImplicitGeometry& geo, CellMesh& m, const std::vector<Tri>& remove, const std::vector<Tri>& add,
            const std::array<Index, 2>* edge, int max_growth, std::int64_t& budget) {
  constexpr std::size_t max_apexes = 16;
  std::vector<std::size_t> c0;
  for (const Tri& f : remove) {
    const auto it = m.owner.find(f);
    if (it == m.owner.end()) return false;
    c0.push_back(it->second);
  }
  if (edge) {
    // Every tet around the edge: from the first one, across faces containing the edge.
    for (std::size_t q = 0; q < c0.size(); ++q) {
      const auto& t = m.tets[c0[q]];
      for (const Tri& f : outward_faces(t)) {
        const bool has0 = std::find(f.begin(), f.end(), (*edge)[0]) != f.end();
        const bool has1 = std::find(f.begin(), f.end(), (*edge)[1]) != f.end();
        if (!has0 || !has1) continue;
        const std::int64_t n = m.beyond(f);
        if (n >= 0 && std::find(c0.begin(), c0.end(), static_cast<std::size_t>(n)) == c0.end())
          c0.push_back(static_cast<std::size_t>(n));
      }
    }
  }
  std::sort(c0.begin(), c0.end());
  c0.erase(std::unique(c0.begin(), c0.end()), c0.end());
  auto boundary_of = [&](const std::vector<std::size_t>& ids) {
    budget -= static_cast<std::int64_t>(ids.size());
    std::vector<Tri> bnd;
    for (const Tri& f : chain_boundary(m.tets, ids))
      if (!std::binary_search(remove.begin(), remove.end(), f)) bnd.push_back(f);
    bnd.insert(bnd.end(), add.begin(), add.end());
    return bnd;
  };
  std::vector<Index> cand;
  for (const Tri& f : boundary_of(c0))
    for (Index v : f) cand.push_back(v);
  std::sort(cand.begin(), cand.end());
  cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
  if (cand.size() > max_apexes) cand.resize(max_apexes);
  std::vector<std::array<Index, 4>> fill;
  for (Index v : cand) {
    std::vector<std::size_t> c = c0;
    for (int round = 0; round <= max_growth; ++round) {
      if (budget < 0) return false;
      const std::vector<Tri> bnd = boundary_of(c);
      fill.clear();
      std::vector<Tri> unseen;
      for (const Tri& f : bnd) {
        if (f[0] == v || f[1] == v || f[2] == v) continue;  // a flat cone; the face stays (chain argument)
        const std::array<Index, 4> t{{f[0], f[2], f[1], v}};
        --budget;
        if (geo.orient3d(t[0], t[1], t[2], t[3]) == Sign::kPositive)
          fill.push_back(t);
        else
          unseen.push_back(f);
      }
      if (unseen.empty()) {
        for (std::size_t i : c) m.kill(i);
        for (const auto& t : fill) m.add_tet(t);
        for (const Tri& f : remove) m.hull.erase(f);
        for (const Tri& f : add) m.hull.insert(f);
        return true;
      }
      bool stuck = false;
      for (const Tri& f : unseen) {
        if (m.hull.count(f) || std::find(add.begin(), add.end(), f) != add.end()) {
          stuck = true;  // a face of the cell boundary: cannot grow across it
          break;
        }
        const std::int64_t n = m.beyond(f);
        if (n < 0) {
          stuck = true;
          break;
        }
        c.push_back(static_cast<std::size_t>(n));
      }
      if (stuck) break;
      std::sort(c.begin(), c.end());
      c.erase(std::unique(c.begin(), c.end()), c.end());
    }
  }
  return false;
}

}  // namespace

bool recover_cell_boundary(ImplicitGeometry& geo, std::vector<std::array<Index, 4>>& tets,
                           const std::vector<std::pair<std::array<Index, 3>, Index>>& want, int max_growth) {
  std::vector<Index> planes;
  for (const auto& w : want) planes.push_back(w.second);
  std::sort(planes.begin(), planes.end());
  planes.erase(std::unique(planes.begin(), planes.end()), planes.end());
  std::vector<Tri> want_all;
  for (const auto& w : want) want_all.push_back(canonical_tri(w.first));
  std::sort(want_all.begin(), want_all.end());
  auto on_plane = [&](const Tri& t, Index p) {
    return geo.known_on_plane(t[0], p) && geo.known_on_plane(t[1], p) && geo.known_on_plane(t[2], p);
  };
  CellMesh m;
  for (const auto& t : tets) m.add_tet(t);
  for (const Tri& f : all_boundary(tets)) m.hull.insert(f);
  // Work limit (tets visited and orientation tests), so that a large cell that cannot be repaired
  // costs about as much as one that can: then it falls back.
  std::int64_t budget = 20000 + 60 * static_cast<std::int64_t>(tets.size());
  for (Index p : planes) {
    std::vector<Tri> want_p;
    for (const auto& w : want)
      if (w.second == p) want_p.push_back(canonical_tri(w.first));
    std::sort(want_p.begin(), want_p.end());
    std::vector<Tri> have;
    for (const Tri& t : m.hull)
      if (on_plane(t, p)) have.push_back(t);
    if (have == want_p) continue;
    const int axis = geo.projection_axis(p);
    // Sloan's edge insertion on P, each 2D flip done in 3D by a small cavity: for every edge (c, d)
    // of the wanted triangulation that is missing, flip edges crossing it (strictly convex quads)
    // until it appears. Edges of the wanted triangulation never cross, so none is flipped away.
    bool flips_ok = true;
    for (const Tri& w : want_p) {
      for (int k = 0; k < 3 && flips_ok; ++k) {
        const Index c = w[k], d = w[(k + 1) % 3];
        std::map<Index, Sign> side_of;  // orient2d(c, d, v), per target edge
        auto side_cd = [&](Index v) {
          const auto it = side_of.find(v);
          if (it != side_of.end()) return it->second;
          --budget;
          return side_of[v] = geo.orient2d(c, d, v, axis);
        };
        std::size_t guard = 0;
        while (flips_ok) {
          budget -= static_cast<std::int64_t>(have.size());
          if (budget < 0) return false;
          // Directed edge -> opposite vertex, sorted.
          std::vector<std::pair<std::pair<Index, Index>, Index>> third;
          for (const Tri& t : have)
            for (int q = 0; q < 3; ++q) third.push_back({{t[q], t[(q + 1) % 3]}, t[(q + 2) % 3]});
          std::sort(third.begin(), third.end());
          auto find_third = [&](Index u, Index w) {
            const auto key = std::make_pair(std::make_pair(u, w), Index(-1));
            const auto it = std::lower_bound(third.begin(), third.end(), key);
            return it != third.end() && it->first == std::make_pair(u, w) ? it->second : Index(-1);
          };
          if (find_third(c, d) >= 0 || find_third(d, c) >= 0) break;
          if (++guard > 4 * have.size() + 16) {
            flips_ok = false;
            break;
          }
          bool flipped = false;
          for (const auto& [ab, x] : third) {
            const Index a = ab.first, b = ab.second;
            if (a > b || a == c || a == d || b == c || b == d) continue;  // each edge once
            const Sign sa = side_cd(a), sb = side_cd(b);
            if (sa == Sign::kZero || sb == Sign::kZero || sa == sb) continue;
            const Index y = find_third(b, a);
            if (y < 0) continue;
            budget -= 4;
            const Sign sc = geo.orient2d(a, b, c, axis), sd = geo.orient2d(a, b, d, axis);
            if (sc == Sign::kZero || sd == Sign::kZero || sc == sd) continue;
            const Sign s0 = geo.orient2d(a, b, x, axis);
            if (geo.orient2d(a, y, x, axis) != s0 || geo.orient2d(y, b, x, axis) != s0) continue;
            std::vector<Tri> remove{canonical_tri({a, b, x}), canonical_tri({b, a, y})};
            std::sort(remove.begin(), remove.end());
            const std::vector<Tri> add{canonical_tri({a, y, x}), canonical_tri({y, b, x})};
            const std::array<Index, 2> e{{a, b}};
            if (recone(geo, m, remove, add, &e, max_growth, budget)) {
              std::vector<Tri> h;
              std::set_difference(have.begin(), have.end(), remove.begin(), remove.end(), std::back_inserter(h));
              h.insert(h.end(), add.begin(), add.end());
              std::sort(h.begin(), h.end());
              have.swap(h);
              flipped = true;
              break;
            }
            if (budget < 0) return false;
          }
          if (!flipped) flips_ok = false;
        }
      }
      if (!flips_ok) break;
    }
    if (have == want_p) continue;
    // Whole facet at once.
    if (!recone(geo, m, have, want_p, nullptr, max_growth, budget)) return false;
  }
  tets.clear();
  for (std::size_t i = 0; i < m.tets.size(); ++i)
    if (m.alive[i]) tets.push_back(m.tets[i]);
  for (const auto& t : tets)
    if (geo.orient3d(t[0], t[1], t[2], t[3]) != Sign::kPositive) return false;
  return all_boundary(tets) == want_all;
}

}  // namespace bsptet
