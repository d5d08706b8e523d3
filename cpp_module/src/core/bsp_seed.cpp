// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: seeding the BSP complex with a Delaunay tetrahedralization of the input points
// (the idea of Diazzi & Attene's BSP complex, 2021), see bsp_complex.h.
//
// Instead of one box cell cut by every input plane, the complex starts as the tets of the exact
// (perturbed) Delaunay tetrahedralization of the input points and the 8 box corners. Each tet is a
// convex cell; its conflict list holds the input triangles that may cross its interior, found by
// a walk from the triangle's first vertex and decided by a separating-axis test (exact on the
// face planes, certified intervals on the edge-pair axes; conservative: a triangle is left out
// only when the interiors are proved disjoint). The build then splits only those cells, by the
// planes of their conflict triangles, as with the box. On a fine surface most input triangles
// are Delaunay faces already and cut nothing: the cells, BSP points and Steiner points no longer
// grow with the number of planes a cell sees (the auto-partition's peeling chain).
//
// Faces of the seed lie on an input plane when their three corners do (known from the input
// triangles around each corner, or decided exactly against the planes of any corner's
// triangles); such a face takes that plane's id and lists the plane's triangles that may overlap
// it (`coplanar`), so that refine_covered_faces and the classification see it as with the box.
// Any other face gets a plane of its own through its three corners; the walk of step 3 gives it
// an input plane after all when it lies on the plane of a triangle that touches it (its corners
// may lie on an input plane without being corners of that plane's triangles).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "bsptet/core/bsp_complex.h"
#include "bsptet/core/cell_delaunay.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/exact_float.h"
#include "bsptet/numerics/interval.h"
#include "bsptet/core/point_delaunay.h"
#include "bsptet/numerics/splitmix.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

namespace {

constexpr auto& kFace = kTetOppositeFace;  // types.h
constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
// Flips tried per missing input edge (SeedFlips::recover_edge), from each end.
constexpr int kMaxFlipsPerEdge = 64;

std::uint64_t spread3(std::uint64_t x) {  // 21 bits -> every third bit of 63
  x &= 0x1fffffULL;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

// p . n with a bound on its rounding error: the exact value lies in [d - err, d + err]
// (|fl(dot3) - dot3| <= gamma_3 sum |p_i n_i|, gamma_3 < 4u; plus underflow).
void dot_bounds(const Vec3& p, const Vec3& n, double& lo, double& hi) {
  const double a = p.x * n.x, b = p.y * n.y, c = p.z * n.z;
  const double d = a + b + c;
  const double err = (std::fabs(a) + std::fabs(b) + std::fabs(c)) * (4.0 * 0x1p-53) + 0x1p-1020;
  lo = d - err;
  hi = d + err;
}

template <class T>
std::array<T, 3> difference(const Vec3& a, const Vec3& b) {
  return {T(a.x) - T(b.x), T(a.y) - T(b.y), T(a.z) - T(b.z)};
}
template <class T>
std::array<T, 3> cross(const std::array<T, 3>& u, const std::array<T, 3>& v) {
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}
template <class T>
T dot(const std::array<T, 3>& u, const std::array<T, 3>& v) {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

// The direction n = (e1 - e0) x (f1 - f0) of an edge pair, for exact signs of n . (x - y):
// intervals first, the exact cross product only when they cannot tell.
class EdgePairDirection {
 public:
  EdgePairDirection(const Vec3& e0, const Vec3& e1, const Vec3& f0, const Vec3& f1)
      : e0_(e0), e1_(e1), f0_(f0), f1_(f1),
        approx_(cross(difference<Interval>(e1, e0), difference<Interval>(f1, f0))) {}
  /// n = 0 (parallel edges), exactly.
  bool vanishes() {
    for (const Interval& c : approx_)
      if (c.certain_sign() != 0) return false;
    for (const ExactFloat& c : exact())
      if (c.sign() != 0) return false;
    return true;
  }
  /// sign of n . (x - y) = det[e1 - e0, f1 - f0, x - y], exactly: intervals, then expansions
  /// when the three differences are exact in doubles (nearby points), else ExactFloat.
  int sign(const Vec3& x, const Vec3& y) {
    const int s = dot(approx_, difference<Interval>(x, y)).certain_sign();
    if (s != 0) return s;
    Vec3 u, v, w;
    Sign d;
    if (exact_difference(e1_, e0_, u) && exact_difference(f1_, f0_, v) && exact_difference(x, y, w) &&
        det3_expansion(u, v, w, d))
      return to_int(d);
    return dot(exact(), difference<ExactFloat>(x, y)).sign();
  }

 private:
  const std::array<ExactFloat, 3>& exact() {
    if (!have_exact_) {
      exact_ = cross(difference<ExactFloat>(e1_, e0_), difference<ExactFloat>(f1_, f0_));
      have_exact_ = true;
    }
    return exact_;
  }
  Vec3 e0_, e1_, f0_, f1_;
  std::array<Interval, 3> approx_;
  std::array<ExactFloat, 3> exact_;
  bool have_exact_ = false;
};

// True when the edge pair (tet edge e0 e1, triangle edge f0 f1) gives a plane that weakly
// separates the tet (p) from the triangle (q, with f0 = q[k], f1 = q[(k + 1) % 3], g = the third
// corner): every tet corner on one closed side, every triangle corner on the other. Exact. The
// direction n = (e1 - e0) x (f1 - f0) must not vanish (parallel edges: no plane).
bool edge_pair_separates(const std::array<Vec3, 4>& p, const Vec3& e0, const Vec3& e1, const Vec3& f0,
                         const Vec3& f1, const Vec3& g) {
  EdgePairDirection n(e0, e1, f0, f1);
  if (n.vanishes()) return false;
  // n . f0 = n . f1; the triangle's lowest and highest corners along n.
  const int sg = n.sign(g, f0);
  const Vec3& low = sg >= 0 ? f0 : g;
  const Vec3& high = sg <= 0 ? f0 : g;
  bool below = true, above = true;  // the tet below the triangle's lowest / above its highest corner
  for (const Vec3& x : p) {
    if (below && n.sign(x, low) > 0) below = false;
    if (above && n.sign(x, high) < 0) above = false;
    if (!below && !above) return false;
  }
  return true;
}

// How a tet (positive, corners p) and a triangle (q) meet: 0 when the closed sets are proved
// disjoint, 1 when the triangle is proved to miss the tet's interior (they may touch), 2 when it
// crosses the interior (exact: see the last step). Separating axes: the tet's face planes and the triangle's plane
// (exact orient3d), then the 18 edge-pair directions (rounded, with certified bounds on the
// projections: any direction proves a separation its projections show). `share_vertex`: the two
// have a common corner (so they touch).
int tet_triangle_relation(const std::array<Vec3, 4>& p, const std::array<Index, 4>& pid, const std::array<Vec3, 3>& q,
                          const std::array<Index, 3>& qid) {
  bool share_vertex = false;
  for (Index a : pid)
    for (Index b : qid) share_vertex = share_vertex || a == b;
  // Bounding boxes (exact comparisons of doubles).
  for (int k = 0; k < 3; ++k) {
    auto coord = [k](const Vec3& x) { return k == 0 ? x.x : (k == 1 ? x.y : x.z); };
    double plo = INFINITY, phi = -INFINITY, qlo = INFINITY, qhi = -INFINITY;
    for (const Vec3& x : p) {
      plo = std::min(plo, coord(x));
      phi = std::max(phi, coord(x));
    }
    for (const Vec3& x : q) {
      qlo = std::min(qlo, coord(x));
      qhi = std::max(qhi, coord(x));
    }
    if (phi < qlo || qhi < plo) return 0;
  }
  bool weak = false;
  for (int i = 0; i < 4; ++i) {
    const Vec3 &a = p[kFace[i][0]], &b = p[kFace[i][1]], &c = p[kFace[i][2]];
    int mx = -1;
    for (int k = 0; k < 3; ++k) {
      // A corner of the face is on its plane: no arithmetic (an exact zero is the slow case).
      const bool corner = qid[k] == pid[kFace[i][0]] || qid[k] == pid[kFace[i][1]] || qid[k] == pid[kFace[i][2]];
      mx = std::max(mx, corner ? 0 : to_int(orient3d(a, b, c, q[k])));
      if (mx > 0) break;
    }
    if (mx < 0) return 0;
    if (mx == 0) weak = true;
  }
  {
    int mn = 1, mx = -1;
    for (int j = 0; j < 4; ++j) {
      const bool corner = pid[j] == qid[0] || pid[j] == qid[1] || pid[j] == qid[2];
      const int s = corner ? 0 : to_int(orient3d(q[0], q[1], q[2], p[j]));
      mn = std::min(mn, s);
      mx = std::max(mx, s);
    }
    if (mn > 0 || mx < 0) return 0;
    if (mn >= 0 || mx <= 0) weak = true;
  }
  // Touching at a common vertex: never strictly apart, so nothing more to learn.
  if (weak && share_vertex) return 1;
  for (const auto& e : kEdge) {
    const Vec3 u{p[e[1]].x - p[e[0]].x, p[e[1]].y - p[e[0]].y, p[e[1]].z - p[e[0]].z};
    for (int k = 0; k < 3; ++k) {
      const Vec3 &f0 = q[k], &f1 = q[(k + 1) % 3];
      const Vec3 v{f1.x - f0.x, f1.y - f0.y, f1.z - f0.z};
      const Vec3 n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
      if (n.x == 0 && n.y == 0 && n.z == 0) continue;
      double tlo = INFINITY, thi = -INFINITY, qlo = INFINITY, qhi = -INFINITY;
      for (const Vec3& x : p) {
        double lo, hi;
        dot_bounds(x, n, lo, hi);
        tlo = std::min(tlo, lo);
        thi = std::max(thi, hi);
      }
      for (const Vec3& x : q) {
        double lo, hi;
        dot_bounds(x, n, lo, hi);
        qlo = std::min(qlo, lo);
        qhi = std::max(qhi, hi);
      }
      if (!(std::isfinite(tlo) && std::isfinite(thi) && std::isfinite(qlo) && std::isfinite(qhi))) continue;
      if (thi < qlo || qhi < tlo) return 0;
      if (thi <= qlo || qhi <= tlo) weak = true;
    }
  }
  if (weak) return 1;
  // The rounded projections cannot show a separation in which the two touch (a shared corner
  // projects to the same value on both sides): decide the edge pairs exactly. With the face
  // planes above they are every facet direction of the Minkowski difference tet - triangle, so
  // the triangle misses the tet's interior iff one of them separates weakly. Nearly coplanar
  // input triangles (a rotated CAD tessellation) made many seed tets that only touch a triangle
  // along an edge look crossed, and the BSP cut each of them by the triangle's plane.
  for (const auto& e : kEdge)
    for (int k = 0; k < 3; ++k)
      if (edge_pair_separates(p, p[e[0]], p[e[1]], q[k], q[(k + 1) % 3], q[(k + 2) % 3])) return 1;
  return 2;
}

// The seed need not be Delaunay: any tetrahedralization of the points gives convex cells. Input
// edges missing from it (a nearly planar quad whose Delaunay diagonal is not the input's, the
// common case on tessellated curved faces) make their triangles cross seed tets, and every
// crossing costs BSP points and Steiner points later. So missing input edges are recovered by
// flips where a few suffice, each decided exactly (every new tet strictly positive by orient3d
// on the explicit doubles), never removing an input triangle or an input edge:
//  * 2-3 flip of the face the segment ab leaves its first tet through (adds edge a-f, removes no
//    edge), repeated towards b a bounded number of times;
//  * where ab lies in the plane of a face at a and crosses seed edges of that plane (a tessellated
//    planar CAD face whose fan is not the Delaunay triangulation of its points): edge removal
//    (n tets around a crossed edge -> 2(n - 2), the 4-4 flip when n = 4) of the first crossed
//    edge whose other diagonal clears ab, one crossing fewer each time (planar_flip), up to
//    kMaxFlipsPerEdge flips. On thingi10k_112932 (an extruded profile, fans of long triangles on
//    its planar faces) this made the recovered edges 110 -> 750 of ~3600 and the BSP points
//    113,000 -> 59,000 (31 s -> 17 s). Edges still missing are blocked in 3D: the cones over
//    the ring from the removed edge's ends are not all positive (thin slabs of tets over the
//    plane), which needs flips off the plane first:
//  * where the 2-3 flip is blocked (the two tets' union is not convex at an edge of their common
//    face) or ab passes through a seed edge that planar_flip cannot replace, that edge is removed
//    by EDGE REMOVAL over any triangulation of its ring, or where none is valid, after the
//    removal of one of its spokes (remove_edge_deep: Si's flipnm, as in TetGen, one level deep).
//    Measured: edge removal raises the recovered edges 863 -> 1090 of 1102 on triceratops, 124 -> 246 of 264 on
//    couplingdown, 54 -> 144 of 180 on joint (whose seed the auto choice had dropped for the
//    box); core time 0.4 to 0.6 of what it was on these.
class SeedFlips {
 public:
  using Tet = std::array<Index, 4>;
  template <class PointOf>
  SeedFlips(std::vector<Tet>& tets, Index num_vertices, PointOf point_of)
      : tets_(tets), inc_(num_vertices), changes_(static_cast<std::size_t>(num_vertices), 0) {
    pts_.resize(static_cast<std::size_t>(num_vertices));
    for (Index v = 0; v < num_vertices; ++v) pts_[v] = point_of(v);
    alive_.assign(tets_.size(), 1);
    for (Index t = 0; t < static_cast<Index>(tets_.size()); ++t)
      for (Index v : tets_[t]) inc_[v].push_back(t);
  }

  void protect_triangle(Index a, Index b, Index c) {
    std::array<Index, 3> k{{a, b, c}};
    std::sort(k.begin(), k.end());
    protected_faces_.push_back(key3(k));
    protected_edges_.push_back(edge_key(a, b));
    protected_edges_.push_back(edge_key(b, c));
    protected_edges_.push_back(edge_key(a, c));
    protection_sorted_ = false;
  }

  bool has_edge(Index a, Index b) const {
    for (Index t : inc_[a])
      if (alive_[t] && contains(tets_[t], b)) return true;
    return false;
  }

  /// Tries to make (a, b) an edge with at most `max_flips` flips; true when it is one.
  /// The segment ab leaves a through a face (2-3 flip, or where that is blocked, the removal of
  /// the blocking edge: remove_blocking_edge) or through an edge (planar_flip, or its removal:
  /// remove_edge_deep). A failed attempt keeps its flips: each 2-3 or planar flip removed a
  /// crossing of an input edge, so the input triangles there cross fewer seed tets (fewer BSP
  /// points; undoing them measured worse). Undoing the edge removals of failed attempts measured
  /// worse too (joint, anchor, couplingdown: 1.5 to 3.5 times the BSP points), though they need
  /// not remove a crossing: at most kMaxRemovalsPerEdge per attempt (without a bound
  /// thingi10k_112932's seed made 139,000 flips, with it 41,000, for as many recovered edges).
  bool recover_edge(Index a, Index b, int max_flips) {
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

  bool has_face(Index a, Index b, Index c) const { return tet_with(a, b, c, -1) >= 0; }

  /// Input triangle (a, b, c) whose edges are seed edges but which is not a seed face: where one
  /// seed edge (d, e) pierces it with exactly the three tets (d, e, a, b), (d, e, b, c),
  /// (d, e, c, a) around it, a 3-2 flip makes it a face. True when it is one.
  bool recover_face(Index a, Index b, Index c) {
    if (has_face(a, b, c)) return true;
    for (const auto& [u, w, o] : {std::tuple{a, b, c}, std::tuple{b, c, a}, std::tuple{c, a, b}})
      for (Index t : ring_around(u, w)) {
        const auto [d, e] = other_two(t, u, w);
        if (d == o || e == o) continue;
        if (flip32(d, e, a, b, c)) return has_face(a, b, c);
      }
    return false;
  }

  /// The alive tets, in order, and their neighbours (as PointDelaunay::nb): `nb` holds those of
  /// the first tets before any flip (the tets given to the constructor) and becomes those of the
  /// result. A neighbour that a flip replaced, and every neighbour of a new tet, is found through
  /// the vertex's tets.
  std::vector<Tet> result(std::vector<std::array<Index, 4>>& nb) const {
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
  std::int64_t flips() const { return flips_; }

 private:
  static bool contains(const Tet& q, Index v) { return q[0] == v || q[1] == v || q[2] == v || q[3] == v; }
  static int index_of(const Tet& q, Index v) {
    for (int i = 0; i < 4; ++i)
      if (q[i] == v) return i;
    return -1;
  }
  static std::array<Index, 3> key3(std::array<Index, 3> k) {
    std::sort(k.begin(), k.end());
    return k;
  }
  // Sorted vectors, not hash sets: a tenth of the memory (the seed's peak), sorted once.
  void sort_protection() {
    if (protection_sorted_) return;
    std::sort(protected_faces_.begin(), protected_faces_.end());
    protected_faces_.erase(std::unique(protected_faces_.begin(), protected_faces_.end()), protected_faces_.end());
    std::sort(protected_edges_.begin(), protected_edges_.end());
    protected_edges_.erase(std::unique(protected_edges_.begin(), protected_edges_.end()), protected_edges_.end());
    protection_sorted_ = true;
  }
  bool edge_protected(Index x, Index y) {
    sort_protection();
    return std::binary_search(protected_edges_.begin(), protected_edges_.end(), edge_key(x, y));
  }
  bool face_protected(Index x, Index y, Index z) {
    sort_protection();
    return std::binary_search(protected_faces_.begin(), protected_faces_.end(), key3({x, y, z}));
  }
  /// The alive tet other than `not_t` with the three vertices, or -1.
  Index tet_with(Index x, Index y, Index z, Index not_t) const {
    for (Index t : inc_[x])
      if (t != not_t && alive_[t] && contains(tets_[t], y) && contains(tets_[t], z)) return t;
    return -1;
  }
  /// The alive tets around edge (c, d).
  std::vector<Index> ring_around(Index c, Index d) const {
    std::vector<Index> ring;
    for (Index t : inc_[c])
      if (alive_[t] && contains(tets_[t], d)) ring.push_back(t);
    return ring;
  }
  /// The two vertices of tet t besides c and d.
  std::array<Index, 2> other_two(Index t, Index c, Index d) const {
    std::array<Index, 2> o{{-1, -1}};
    for (Index v : tets_[t])
      if (v != c && v != d) (o[0] < 0 ? o[0] : o[1]) = v;
    return o;
  }
  bool positive(const Tet& q) const { return orient3d(pts_[q[0]], pts_[q[1]], pts_[q[2]], pts_[q[3]]) == Sign::kPositive; }
  /// Tet q with vertex `from` replaced by `to`: a tet of the flip's new set that keeps q's faces
  /// through the other three vertices (so it must be positive in q's order, no reordering).
  static Tet substituted(Tet q, Index from, Index to) {
    for (Index& v : q)
      if (v == from) v = to;
    return q;
  }
  void replace(const std::vector<Index>& old_tets, const std::vector<Tet>& new_tets) {
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
  /// Undoes the flips logged after the first `mark` (latest first): their new tets (the last ones
  /// made) go, their old tets come back.
  void undo_to(std::size_t mark) {
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
  /// EDGE REMOVAL of (c, d) (any triangulation of its ring), and where that has none, first the
  /// removal of one spoke (x, p): x = c or d, p on the ring (itself with `level` - 1 such
  /// retries), which changes the ring (Si's flipnm, TetGen, to one level): the first spoke after
  /// which (c, d) can go is kept with it; the flips of the others are undone.
  bool remove_edge_deep(Index c, Index d, int level) {
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
  /// The tet t2 across the face (c, d, e) of tet t opposite vertex ia, and its vertex f off that
  /// face; false when there is none (the seed's hull) or the face is an input triangle.
  bool across(Index t, int ia, Index& t2, Index& f) {
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
  // Tet t and its neighbour across the face opposite vertex ia: three tets around the new edge.
  bool flip23(Index t, int ia) {
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
  // Where flip23(t, ia) fails because the two tets' union is not convex at an edge of their
  // common face (a new tet would not be positive), that edge is removed instead (EDGE REMOVAL,
  // any triangulation of its ring): the segment then leaves t's successor through other faces.
  // The first such edge that can go, in the face's order.
  bool remove_blocking_edge(Index t, int ia) {
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
  // Edge (d, e) with exactly three tets around it, whose other vertices are a, b, c: replaced by
  // the two tets over face (a, b, c).
  bool flip32(Index d, Index e, Index a, Index b, Index c) {
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
  /// One flip towards input edge (a, b) when a, b and the seed edge (c, d) it crosses first are
  /// coplanar and the seed triangulates that plane along ab (each crossed edge has a coplanar
  /// ring vertex beyond it): the seed edges ab crosses are listed by walking the plane's
  /// triangles from a to b (exact orient2d in a projection that keeps the plane), and the first
  /// that EDGE REMOVAL can replace by the other diagonal (x, y) of its two plane triangles, a
  /// diagonal that does not cross ab, is replaced: one crossing fewer (Sloan's planar edge
  /// insertion without its flips that keep a crossing, so no flip is ever undone; the caller
  /// repeats, with a bounded number of flips). False when no listed edge can go, or the walk does
  /// not reach b (not a triangulated plane, or a vertex on ab).
  bool planar_flip(Index a, Index b, Index c, Index d) {
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
  static constexpr int kMaxCrossed = 256;  // bounded work: longer walks are not tried

  /// The other vertices of the tets around edge (c, d) (each once), or empty when the tets do not
  /// close a ring around it (a boundary edge of the seed).
  std::vector<Index> ring_apexes(Index c, Index d) const {
    std::vector<Index> out;
    for (Index t : ring_around(c, d))
      for (Index v : other_two(t, c, d))
        if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
    return out;
  }
  /// Sign of the side of x relative to line (c, d) compared with a's, in the plane of a, c, d, x
  /// (coplanar): +1 same side, -1 opposite, 0 on the line. By orient2d in the projection that
  /// keeps the plane non-degenerate.
  int orient2d_side(Index c, Index d, Index a, Index x) const {
    for (int axis = 0; axis < 3; ++axis) {
      const int sa = to_int(orient2d_projected(pts_[c], pts_[d], pts_[a], axis));
      if (sa == 0) continue;
      return sa * to_int(orient2d_projected(pts_[c], pts_[d], pts_[x], axis));
    }
    return 0;
  }
  // EDGE REMOVAL of the seed edge (c, d) (not an input edge) with n tets around it, whose other
  // vertices p_0 = a, ..., p_{n-1} form its ring (tets (c, d, p_i, p_i+1) in the ring's
  // orientation): the n tets are replaced by the cones from c and from d over a triangulation of
  // the ring polygon that has the diagonal (a, e), found by dynamic programming over sub-polygons
  // among the triangles whose two cone tets are strictly positive. Valid when all are: the ring's
  // outer faces (c, p_i, p_i+1) and (d, p_i, p_i+1) are kept, and positive cones over the two sides
  // of the polygon tile the edge's star (the 2-3, 3-2 and 4-4 flips are its cases n = 3, 4).
  bool remove_edge(Index c, Index d, Index a, Index e) {
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
    // ok[i][j] (i < j, j <= n; p_n = p_0): the sub-polygon p_i .. p_j has a triangulation of
    // valid triangles; via[i][j] its apex. Triangle (p_i, p_j, p_m) in ring order: tets
    // (c, p_i, p_j, p_m) and (d, p_j, p_i, p_m).
    auto at = [&](int i) { return p[i % n]; };
    std::array<std::array<signed char, kMaxRing + 1>, kMaxRing + 1> ok{}, via{};
    std::array<std::array<signed char, kMaxRing + 1>, kMaxRing + 1> known{};
    auto triangle_ok = [&](int i, int j, int m) {
      return positive({c, at(i), at(j), at(m)}) && positive({d, at(j), at(i), at(m)});
    };
    std::function<bool(int, int)> fill = [&](int i, int j) -> bool {
      if (j == i + 1) return true;
      if (known[i][j]) return ok[i][j] > 0;
      known[i][j] = 1;
      ok[i][j] = 0;
      for (int m = i + 1; m < j && !ok[i][j]; ++m)
        if (fill(i, m) && fill(m, j) && triangle_ok(i, m, j)) {
          ok[i][j] = 1;
          via[i][j] = static_cast<signed char>(m);
        }
      return ok[i][j] > 0;
    };
    if (!fill(0, k) || (e >= 0 && !fill(k, n))) return false;
    std::vector<Tet> made;
    std::function<void(int, int)> emit = [&](int i, int j) {
      if (j == i + 1) return;
      const int m = via[i][j];
      made.push_back({c, at(i), at(m), at(j)});
      made.push_back({d, at(m), at(i), at(j)});
      emit(i, m);
      emit(m, j);
    };
    emit(0, k);
    if (e >= 0) emit(k, n);
    replace(ring, made);
    return true;
  }
  /// True when (c, d, u, w) is an even permutation of tet q (so positive, as q is).
  static bool even_order(const Tet& q, Index c, Index d, Index u, Index w) {
    const std::array<Index, 4> want{{c, d, u, w}};
    std::array<int, 4> perm;
    for (int i = 0; i < 4; ++i) perm[i] = index_of(q, want[i]);
    int inversions = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) inversions += perm[i] > perm[j];
    return inversions % 2 == 0;
  }
  static constexpr int kMaxRing = 10;  // bounded work: rings of at most 10 tets
  static constexpr int kFlipLevels = 1;  // remove_edge_deep's levels of spoke removals
  static constexpr int kMaxRemovalsPerEdge = 8;  // recover_edge's edge removals per attempt
  struct FlipLog {
    std::vector<Index> old_tets;
    std::size_t first_new;  ///< the flip's new tets are tets_[first_new ..] when it is the latest
  };

  std::vector<Tet>& tets_;
  std::vector<std::vector<Index>> inc_;
  std::vector<Vec3> pts_;
  std::vector<char> alive_;
  std::vector<std::array<Index, 3>> protected_faces_;
  std::vector<std::uint64_t> protected_edges_;
  bool protection_sorted_ = true;
  std::int64_t flips_ = 0;
  std::vector<std::uint64_t> changes_;  ///< per vertex: how often its tets changed (flips, undos)
  std::vector<FlipLog> log_;  ///< flips made while logging_ (remove_edge_deep), for undo_to
  bool logging_ = false;
  /// remove_edge_deep's failures: edge -> (level, signature)
  std::unordered_map<std::uint64_t, std::pair<int, std::uint64_t>> failed_deep_;
};

}  // namespace

void BspComplex::seed_delaunay(std::int64_t max_conflicts) {
  corner0_ = geo_.num_explicit() - 8;
  const Index input_planes = geo_.num_planes();
  auto t0 = std::chrono::steady_clock::now();
  auto lap = [&](const char* step) {
    const auto t1 = std::chrono::steady_clock::now();
    stats_.seed_seconds[step] += std::chrono::duration<double>(t1 - t0).count();
    t0 = t1;
  };
  // Vertex ids of explicit points are their point ids here (mesher.cpp adds them in order).
  auto point_of = [&](Index v) -> const Vec3& { return geo_.explicit_point(geo_.explicit_id(v)); };
  // 1. The points: the box corners first (their hull is the box, so every walk stays inside),
  // then the input points that triangles use, in the order below (short walks, small cavities).
  std::vector<char> used(static_cast<std::size_t>(corner0_), 0);
  for (Index v : surface_.tri) used[v] = 1;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (Index c = corner0_; c < corner0_ + 8; ++c) {
    const Vec3& x = point_of(c);
    const double xs[3] = {x.x, x.y, x.z};
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], xs[k]);
      hi[k] = std::max(hi[k], xs[k]);
    }
  }
  std::vector<std::pair<std::uint64_t, Index>> keyed;
  for (Index v = 0; v < corner0_; ++v) {
    if (!used[v]) continue;
    const Vec3& x = point_of(v);
    const double xs[3] = {x.x, x.y, x.z};
    std::uint64_t code = 0;
    for (int k = 0; k < 3; ++k) {
      const double f = (xs[k] - lo[k]) / (hi[k] - lo[k]);
      const auto g = static_cast<std::uint64_t>(std::clamp(f, 0.0, 1.0) * 2097151.0);
      code |= spread3(g) << k;
    }
    keyed.push_back({code, v});
  }
  // Biased randomized insertion order (Amenta, Choi and Rote): the points shuffled by a fixed
  // generator, then split in rounds of doubling size (the last holds half of them), each round in
  // Morton order. Morton order alone inserts a surface's points one sheet after the other, and
  // each new point then conflicts with the long tets spanning the empty inside: cavities grew
  // with the input (the Delaunay of a 10^6-triangle CAD part took 17 times that of 10^5). The
  // triangulation itself does not depend on the order.
  {
    std::uint64_t rng = 0xB210ULL;
    for (std::size_t i = keyed.size(); i > 1; --i) std::swap(keyed[i - 1], keyed[splitmix64(rng) % i]);
    std::size_t end = keyed.size();
    while (end > 0) {
      const std::size_t begin = end > 2048 ? end / 2 : 0;
      std::sort(keyed.begin() + static_cast<std::ptrdiff_t>(begin), keyed.begin() + static_cast<std::ptrdiff_t>(end));
      end = begin;
    }
  }
  std::vector<Index> order;
  order.reserve(keyed.size() + 8);
  for (Index c = corner0_; c < corner0_ + 8; ++c) order.push_back(c);
  for (const auto& kv : keyed) order.push_back(kv.second);
  PointDelaunay dt;
  if (!delaunay_explicit_points(geo_, order, dt))
    throw MeshingError(ErrorCode::kInternal, "bsp", -1, "the Delaunay seed of the input points failed");
  std::vector<std::array<Index, 4>> tets = std::move(dt.tets);
  std::vector<std::array<Index, 4>> nb = std::move(dt.nb);
  decltype(keyed)().swap(keyed);
  std::vector<Index>().swap(order);
  std::vector<char>().swap(used);
  lap("seed_delaunay");
  // Is any input edge or input triangle missing from the seed? (Vertex -> tets incidence in one
  // array; flips never remove an input edge or triangle, so what is here now stays.) When nothing
  // is missing, the flips' bookkeeping is not built at all.
  bool all_present = true;
  {
    const std::size_t nv = static_cast<std::size_t>(corner0_ + 8);
    std::vector<Index> first(nv + 1, 0), inc(4 * tets.size());
    for (const auto& q : tets)
      for (Index v : q) ++first[v + 1];
    for (std::size_t v = 0; v < nv; ++v) first[v + 1] += first[v];
    std::vector<Index> fill(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < tets.size(); ++t)
      for (Index v : tets[t]) inc[fill[v]++] = static_cast<Index>(t);
    auto has = [&](Index a, Index b, Index c) {  // c < 0: edge (a, b)
      for (Index i = first[a]; i < first[a + 1]; ++i) {
        const auto& q = tets[inc[i]];
        const bool hb = q[0] == b || q[1] == b || q[2] == b || q[3] == b;
        if (hb && (c < 0 || q[0] == c || q[1] == c || q[2] == c || q[3] == c)) return true;
      }
      return false;
    };
    for (Index tr = 0; tr < surface_.num_triangles() && all_present; ++tr) {
      const Index a = triangle_vertex(tr, 0), b = triangle_vertex(tr, 1), c = triangle_vertex(tr, 2);
      all_present = has(a, b, -1) && has(b, c, -1) && has(c, a, -1) && has(a, b, c);
    }
  }
  if (!all_present) {
    SeedFlips flips(tets, corner0_ + 8, point_of);
    for (Index tr = 0; tr < surface_.num_triangles(); ++tr)
      flips.protect_triangle(triangle_vertex(tr, 0), triangle_vertex(tr, 1), triangle_vertex(tr, 2));
    auto recover = [&](Index a, Index b) {
      return flips.recover_edge(a, b, kMaxFlipsPerEdge) || flips.recover_edge(b, a, kMaxFlipsPerEdge);
    };
    std::vector<std::pair<Index, Index>> missing;  // edges not recovered yet, for two more passes
    for (Index tr = 0; tr < surface_.num_triangles(); ++tr)
      for (int k = 0; k < 3; ++k) {
        const Index a = triangle_vertex(tr, k), b = triangle_vertex(tr, (k + 1) % 3);
        if (a > b || flips.has_edge(a, b)) continue;  // each edge once (its other triangle has it reversed)
        ++stats_.seed_missing_edges;
        if (recover(a, b))
          ++stats_.seed_recovered_edges;
        else
          missing.push_back({a, b});
      }
    for (int pass = 0; pass < 2 && !missing.empty(); ++pass) {
      std::vector<std::pair<Index, Index>> still;
      for (const auto& [a, b] : missing)
        if (recover(a, b))
          ++stats_.seed_recovered_edges;
        else
          still.push_back({a, b});
      if (still.size() == missing.size()) break;
      missing.swap(still);
    }
    for (Index tr = 0; tr < surface_.num_triangles(); ++tr) {
      const Index a = triangle_vertex(tr, 0), b = triangle_vertex(tr, 1), c = triangle_vertex(tr, 2);
      if (flips.has_face(a, b, c) || !flips.has_edge(a, b) || !flips.has_edge(b, c) || !flips.has_edge(c, a)) continue;
      ++stats_.seed_missing_faces;
      if (flips.recover_face(a, b, c)) ++stats_.seed_recovered_faces;
    }
    stats_.seed_flips = flips.flips();
    if (flips.flips() > 0) tets = flips.result(nb);
  }
  const Index nt = static_cast<Index>(tets.size());
  stats_.seed_tets = nt;
  lap("seed_flips");

  // 2. Faces: one per distinct triangle of the tets, shared by its (one or two) tets. They are
  // light records here; only those of the tets that go into the complex (step 4) become BspFaces.
  // A seed face: verts CCW around its normal, tet[0] on the positive side (the normal points into
  // it), tet[1] on the negative side (-1: none). plane: the input plane it lies on, or -1 (not on
  // one: the complex gives it a plane of its own through its corners, in this vertex order).
  // coplanar: the input triangles of its plane that may overlap it, as an index into
  // `coplanar_lists` (-1: none; most faces have none).
  struct SeedFace {
    std::array<Index, 3> verts;
    Index plane;
    Index tet[2];
    Index coplanar = -1;
  };
  std::vector<SeedFace> sfaces;
  std::vector<std::vector<Index>> coplanar_lists;
  const std::vector<Index> no_triangles;
  auto coplanar_of = [&](const SeedFace& f) -> const std::vector<Index>& {
    return f.coplanar < 0 ? no_triangles : coplanar_lists[f.coplanar];
  };
  auto add_coplanar = [&](SeedFace& f, Index tr) {
    if (f.coplanar < 0) {
      f.coplanar = static_cast<Index>(coplanar_lists.size());
      coplanar_lists.emplace_back();
    }
    auto& list = coplanar_lists[f.coplanar];
    if (list.empty() || list.back() != tr) list.push_back(tr);
  };
  sfaces.reserve(2 * static_cast<std::size_t>(nt) + 8);
  std::vector<std::array<Index, 4>> tet_face(nt, {-1, -1, -1, -1});
  // The input plane a face lies on by its corners' triangles: every corner an input point known
  // on one plane (no arithmetic). A face whose corners lie on an input plane without all being
  // known on it keeps a plane of its own here; the walk of step 3 gives it the input plane when a
  // triangle of that plane touches it (the only case where its coverage matters).
  auto input_plane_of = [&](Index x, Index y, Index z) -> Index {
    if (x >= corner0_ || y >= corner0_ || z >= corner0_) return -1;
    for (Index q : geo_.known_planes(x))
      if (q < input_planes && geo_.known_on_plane(y, q) && geo_.known_on_plane(z, q)) return q;
    return -1;
  };
  // Input-plane faces by their sorted corners (an input triangle that is a face of the seed is
  // found here), sorted.
  std::vector<std::pair<std::array<Index, 3>, Index>> face_of_corners;
  for (Index t0 = 0; t0 < nt; ++t0)
    for (int i0 = 0; i0 < 4; ++i0) {
      const Index t1 = nb[t0][i0];
      if (t1 >= 0 && t1 < t0) continue;  // made from the neighbour
      const Index x = tets[t0][kFace[i0][0]], y = tets[t0][kFace[i0][1]], z = tets[t0][kFace[i0][2]];
      const Index apex = tets[t0][i0];  // on the positive side of (x, y, z)
      SeedFace f{{x, y, z}, -1, {t0, t1}, -1};
      const Index q = input_plane_of(x, y, z);
      const Index id = static_cast<Index>(sfaces.size());
      if (q >= 0) {
        f.plane = q;
        const Sign side = geo_.side(q, apex);
        if (side == Sign::kZero) throw MeshingError(ErrorCode::kInternal, "bsp", t0, "a flat Delaunay seed tet");
        if (side == Sign::kNegative) {
          f.verts = {x, z, y};
          f.tet[0] = t1;
          f.tet[1] = t0;
        }
        std::array<Index, 3> key{{x, y, z}};
        std::sort(key.begin(), key.end());
        face_of_corners.push_back({key, id});
      }
      sfaces.push_back(std::move(f));
      tet_face[t0][i0] = id;
      if (t1 >= 0) {
        int i1 = 0;
        while (i1 < 4 && nb[t1][i1] != t0) ++i1;
        if (i1 == 4) throw MeshingError(ErrorCode::kInternal, "bsp", t0, "Delaunay seed neighbours disagree");
        tet_face[t1][i1] = id;
      }
    }
  std::sort(face_of_corners.begin(), face_of_corners.end());
  std::vector<Index> vertex_tet(static_cast<std::size_t>(corner0_ + 8), -1);
  for (Index t = 0; t < nt; ++t)
    for (int i = 0; i < 4; ++i)
      if (vertex_tet[tets[t][i]] < 0) vertex_tet[tets[t][i]] = t;

  lap("seed_faces");
  // 3. Conflict lists and coplanar lists. An input triangle that is a face of the seed crosses
  // no tet (faces of a tetrahedralization never meet a tet's interior) and overlaps no other
  // face: it goes on that face's coplanar list, nothing more. Any other triangle walks over the
  // tets it meets; those whose interior it crosses (tet_triangle_relation, exact) get it on their
  // conflict list.
  // Crossings as (tet, triangle) pairs, sorted by tet after the walks (then each tet's triangles
  // are in increasing order, as they were found): a list per tet cost 24 bytes for every seed tet,
  // most of them never crossed (77 MB of the seed's peak at 10^6 triangles).
  std::vector<std::pair<Index, Index>> crossing;
  std::vector<std::uint32_t> seen(static_cast<std::size_t>(nt), 0);
  std::uint32_t stamp = 0;
  std::vector<Index> queue;
  for (Index tr = 0; tr < surface_.num_triangles(); ++tr) {
    const std::array<Vec3, 3> q{{surface_.point(triangle_vertex(tr, 0)), surface_.point(triangle_vertex(tr, 1)),
                                 surface_.point(triangle_vertex(tr, 2))}};
    const std::array<Index, 3> qid{{triangle_vertex(tr, 0), triangle_vertex(tr, 1), triangle_vertex(tr, 2)}};
    const Index plane = tri_plane_[tr];
    {
      std::array<Index, 3> key = qid;
      std::sort(key.begin(), key.end());
      const auto it = std::lower_bound(face_of_corners.begin(), face_of_corners.end(),
                                       std::pair<std::array<Index, 3>, Index>{key, -1});
      if (it != face_of_corners.end() && it->first == key && sfaces[it->second].plane == plane) {
        add_coplanar(sfaces[it->second], tr);
        ++stats_.seed_face_triangles;
        continue;
      }
    }
    ++stamp;
    queue.clear();
    const Index start = vertex_tet[triangle_vertex(tr, 0)];
    if (start < 0) throw MeshingError(ErrorCode::kInternal, "bsp", tr, "an input vertex is not in the Delaunay seed");
    queue.push_back(start);
    seen[start] = stamp;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      const Index t = queue[h];
      const std::array<Vec3, 4> p{{point_of(tets[t][0]), point_of(tets[t][1]), point_of(tets[t][2]),
                                   point_of(tets[t][3])}};
      const int rel = tet_triangle_relation(p, tets[t], q, qid);
      if (rel == 0) continue;
      if (rel == 2) {
        crossing.push_back({t, tr});
        if (++stats_.seed_conflicts > max_conflicts && max_conflicts >= 0) {
          stats_.seed_abandoned = true;
          lap("seed_walk");
          return;
        }
      }
      for (int i = 0; i < 4; ++i) {
        SeedFace& f = sfaces[tet_face[t][i]];
        // A face not on an input plane by its corners' triangles may still lie on this
        // triangle's plane (none of its corners is a corner of that plane's triangles, step 2):
        // then it takes the input plane, decided exactly, so that the coverage and the
        // classification see it.
        if (f.plane < 0 &&
            std::all_of(f.verts.begin(), f.verts.end(), [&](Index v) { return geo_.side(plane, v) == Sign::kZero; })) {
          const Sign apex_side = geo_.side(plane, tets[t][i]);
          if (apex_side == Sign::kZero) throw MeshingError(ErrorCode::kInternal, "bsp", t, "a flat Delaunay seed tet");
          if ((f.tet[0] == t) != (apex_side == Sign::kPositive)) {
            std::reverse(f.verts.begin(), f.verts.end());
            std::swap(f.tet[0], f.tet[1]);
          }
          f.plane = plane;
          ++stats_.seed_faces_relabelled;
        }
        if (f.plane == plane) add_coplanar(f, tr);
        const Index n = nb[t][i];
        if (n >= 0 && seen[n] != stamp) {
          seen[n] = stamp;
          queue.push_back(n);
        }
      }
    }
  }
  std::vector<std::uint32_t>().swap(seen);
  std::sort(crossing.begin(), crossing.end());
  // conflict_begin[t] .. conflict_begin[t + 1]: tet t's entries of `crossing`.
  std::vector<Index> conflict_begin(static_cast<std::size_t>(nt) + 1, 0);
  for (const auto& [t, tr] : crossing) ++conflict_begin[static_cast<std::size_t>(t) + 1];
  for (Index t = 0; t < nt; ++t) conflict_begin[t + 1] += conflict_begin[t];
  auto crossed = [&](Index t) { return conflict_begin[t + 1] > conflict_begin[t]; };
  lap("seed_walk");

  // 4. Which tets go into the complex (UntouchedSeedTets, bsp_complex.h): those with an edge of a
  // crossed tet or of a face on an input plane that is not exactly one input triangle (a face
  // refine_covered_faces would split).
  auto is_input_triangle = [&](std::array<Index, 3> a, const std::vector<Index>& coplanar) {
    if (coplanar.size() != 1) return false;
    std::array<Index, 3> b{{triangle_vertex(coplanar[0], 0), triangle_vertex(coplanar[0], 1),
                            triangle_vertex(coplanar[0], 2)}};
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    return a == b;
  };
  auto needs_refinement = [&](const SeedFace& f) {
    return f.plane >= 0 && !coplanar_of(f).empty() && !is_input_triangle(f.verts, coplanar_of(f));
  };
  // A crossed tet T is split only by the planes of its conflict triangles (choose_plane), and
  // its pieces' faces are refined only along lines inside them: a seed edge of T is cut only
  // when one of those planes crosses it or contains it (then refinement lines in the plane may
  // cross it). Such edges are hot, with the edges of the faces needing refinement; a seed tet
  // goes into the complex when it is crossed, shares a face with a crossed tet (T's faces are
  // split), or has a hot edge. (A split that reaches a tet left out throws, and the mesher
  // retries from the box: bsp_complex.cpp.)
  std::vector<std::uint64_t> hot;
  std::vector<char> near_crossed(static_cast<std::size_t>(nt), 0);
  std::vector<Index> planes_of;
  for (Index t = 0; t < nt; ++t) {
    if (!crossed(t)) continue;
    near_crossed[t] = 1;
    for (int i = 0; i < 4; ++i)
      if (nb[t][i] >= 0) near_crossed[nb[t][i]] = 1;
    planes_of.clear();
    for (Index k = conflict_begin[t]; k < conflict_begin[t + 1]; ++k) planes_of.push_back(tri_plane_[crossing[k].second]);
    std::sort(planes_of.begin(), planes_of.end());
    planes_of.erase(std::unique(planes_of.begin(), planes_of.end()), planes_of.end());
    for (const auto& ed : kEdge) {
      const Index a = tets[t][ed[0]], b = tets[t][ed[1]];
      for (Index p : planes_of) {
        const int sa = to_int(geo_.side(p, a)), sb = to_int(geo_.side(p, b));
        if (sa * sb < 0 || (sa == 0 && sb == 0)) {
          hot.push_back(edge_key(a, b));
          break;
        }
      }
    }
  }
  for (const SeedFace& f : sfaces)
    if (needs_refinement(f))
      for (int k = 0; k < 3; ++k) hot.push_back(edge_key(f.verts[k], f.verts[(k + 1) % 3]));
  std::sort(hot.begin(), hot.end());
  hot.erase(std::unique(hot.begin(), hot.end()), hot.end());
  std::vector<char> hot_vertex(static_cast<std::size_t>(corner0_ + 8), 0);
  for (std::uint64_t k : hot) {
    hot_vertex[static_cast<std::size_t>(k >> 32)] = 1;
    hot_vertex[static_cast<std::size_t>(k & 0xffffffffu)] = 1;
  }
  std::vector<Index> cell_of(static_cast<std::size_t>(nt), -1), untouched_of(static_cast<std::size_t>(nt), -1);
  Index num_cells = 0, num_untouched = 0;
  for (Index t = 0; t < nt; ++t) {
    bool in = near_crossed[t] != 0;
    for (int k = 0; k < 6 && !in; ++k) {
      const Index a = tets[t][kEdge[k][0]], b = tets[t][kEdge[k][1]];
      in = hot_vertex[a] && hot_vertex[b] && std::binary_search(hot.begin(), hot.end(), edge_key(a, b));
    }
    (in ? cell_of[t] = num_cells++ : untouched_of[t] = num_untouched++);
  }
  std::vector<std::uint64_t>().swap(hot);
  std::vector<char>().swap(hot_vertex);
  std::vector<char>().swap(near_crossed);
  stats_.untouched_tets = num_untouched;
  stats_.leaves += num_untouched;

  // 5. The complex: the cells of those tets and their faces. A face between a cell and an
  // untouched tet keeps cell -1 on that side and remembers the tet (face_untouched).
  auto in_complex = [&](const SeedFace& f) {
    return (f.tet[0] >= 0 && cell_of[f.tet[0]] >= 0) || (f.tet[1] >= 0 && cell_of[f.tet[1]] >= 0);
  };
  // The faces of the cells, in the order of their sorted corners (the refinements visit faces by
  // id: a fixed order that does not depend on how the seed's tets were numbered).
  std::vector<std::pair<std::array<Index, 3>, Index>> made;
  for (std::size_t i = 0; i < sfaces.size(); ++i)
    if (in_complex(sfaces[i])) {
      std::array<Index, 3> key = sfaces[i].verts;
      std::sort(key.begin(), key.end());
      made.push_back({key, static_cast<Index>(i)});
    }
  std::sort(made.begin(), made.end());
  {
    const std::size_t num_faces = made.size();
    // Capacity for the seed and an eighth more for the splits: growing a vector doubles it (and
    // holds old and new at once), which made these two vectors the peak of the BSP's memory.
    faces_.reserve(faces_.size() + num_faces + num_faces / 8);
    face_boxes_.reserve(faces_.capacity());
    const auto ncells = static_cast<std::size_t>(num_cells);
    cells_.reserve(ncells + ncells / 8);
    // Edges: about (faces + vertices) / 2 for the cells' part of a tetrahedralization (Euler), so
    // the edge maps never rehash while the faces register theirs.
    const std::size_t num_edges = num_faces / 2 + 4 * ncells / 3 + 8;
    edge_faces_.reserve(edge_faces_.size() + num_edges + num_edges / 8);
    edge_line_.reserve(edge_line_.size() + num_edges + num_edges / 8);
  }
  cells_.assign(static_cast<std::size_t>(num_cells), BspCell{});
  std::vector<Index> complex_face(sfaces.size(), -1);
  face_untouched_.assign(faces_.size() + made.size(), -1);
  for (const auto& [key, i] : made) {
    SeedFace& f = sfaces[i];
    const Index c0 = f.tet[0] >= 0 ? cell_of[f.tet[0]] : -1, c1 = f.tet[1] >= 0 ? cell_of[f.tet[1]] : -1;
    BspFace bf;
    bf.plane = f.plane >= 0 ? f.plane
                            : geo_.add_plane(geo_.explicit_id(f.verts[0]), geo_.explicit_id(f.verts[1]),
                                             geo_.explicit_id(f.verts[2]));
    bf.verts.assign(f.verts.begin(), f.verts.end());
    bf.cell[0] = c0;
    bf.cell[1] = c1;
    if (f.coplanar >= 0) bf.coplanar = std::move(coplanar_lists[f.coplanar]);
    const Index id = new_face(std::move(bf));
    complex_face[i] = id;
    const Index other = c0 < 0 ? f.tet[0] : (c1 < 0 ? f.tet[1] : -1);
    if (other >= 0) face_untouched_[id] = untouched_of[other];
  }
  // A cell's face boxes are left to split_cell, which builds them when they are out of step:
  // most seed tets are never split, and four boxes per tet were a fifth of the seed's memory.
  for (Index t = 0; t < nt; ++t) {
    if (cell_of[t] < 0) continue;
    BspCell& cell = cells_[cell_of[t]];
    for (int i = 0; i < 4; ++i) cell.faces.push_back(complex_face[tet_face[t][i]]);
    cell.conflict.reserve(static_cast<std::size_t>(conflict_begin[t + 1] - conflict_begin[t]));
    for (Index k = conflict_begin[t]; k < conflict_begin[t + 1]; ++k) cell.conflict.push_back(crossing[k].second);
  }
  untouched_.tets.reserve(static_cast<std::size_t>(num_untouched));
  untouched_.adj.reserve(static_cast<std::size_t>(num_untouched));
  untouched_.step.reserve(static_cast<std::size_t>(num_untouched));
  untouched_.cover.reserve(static_cast<std::size_t>(num_untouched));
  untouched_.before_cell.reserve(static_cast<std::size_t>(num_untouched));
  Index cells_before = 0;
  for (Index t = 0; t < nt; ++t) {
    if (untouched_of[t] < 0) {
      ++cells_before;
      continue;
    }
    std::array<Index, 4> adj, cover{{-1, -1, -1, -1}};
    std::array<signed char, 4> step{{0, 0, 0, 0}};
    for (int i = 0; i < 4; ++i) {
      const Index n = nb[t][i];
      adj[i] = n < 0 ? -1 : (cell_of[n] >= 0 ? -2 - complex_face[tet_face[t][i]] : untouched_of[n]);
      const Index fi = tet_face[t][i];
      // (A face shared with a cell handed its coplanar list to the complex.)
      const std::vector<Index>& cop =
          complex_face[fi] >= 0 ? faces_[complex_face[fi]].coplanar : coplanar_of(sfaces[fi]);
      if (sfaces[fi].plane < 0 || cop.empty()) continue;
      const Index tr = cop[0];
      if (!is_input_triangle(sfaces[fi].verts, cop))
        throw MeshingError(ErrorCode::kInternal, "bsp", tr, "an untouched seed tet has a face that needs refinement");
      // +1 when the triangle (a, b, c), outward, turns like the face (x, y, z) whose normal
      // points into t: then the outside is on t's side.
      const Index x = tets[t][kFace[i][0]], y = tets[t][kFace[i][1]];
      const Index a = triangle_vertex(tr, 0), b = triangle_vertex(tr, 1), c = triangle_vertex(tr, 2);
      const bool same_turn = (x == a && y == b) || (x == b && y == c) || (x == c && y == a);
      step[i] = same_turn ? 1 : -1;
      cover[i] = tr;
    }
    untouched_.tets.push_back(tets[t]);
    untouched_.before_cell.push_back(cells_before);
    untouched_.adj.push_back(adj);
    untouched_.step.push_back(step);
    untouched_.cover.push_back(cover);
  }
  lap("seed_cells");
  // 6. Edge lines of the cells: the planes of the two faces of a tet through the edge (never the
  // same geometric plane), taken after the walk, which may have given faces their input plane.
  for (Index t = 0; t < nt; ++t) {
    if (cell_of[t] < 0) continue;
    for (const auto& ed : kEdge) {
      const std::uint64_t key = edge_key(tets[t][ed[0]], tets[t][ed[1]]);
      if (edge_line_.contains(key)) continue;
      int other[2], m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != ed[0] && j != ed[1]) other[m++] = j;
      edge_line_[key] = {faces_[complex_face[tet_face[t][other[0]]]].plane,
                         faces_[complex_face[tet_face[t][other[1]]]].plane};
    }
  }
  lap("seed_lines");
}

int seed_tet_triangle_relation(const std::array<Vec3, 4>& p, const std::array<Index, 4>& pid,
                               const std::array<Vec3, 3>& q, const std::array<Index, 3>& qid) {
  return tet_triangle_relation(p, pid, q, qid);
}

}  // namespace bsptet
