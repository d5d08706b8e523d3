// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/point_delaunay.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "bsptet/numerics/predicates.h"
#include "bsptet/numerics/splitmix.h"

namespace bsptet {

namespace {

constexpr int kInf = -1;  // the ghost vertex (a ghost tet has it at corner 3, and only there)
constexpr auto& kFace = kTetOppositeFace;

// Bowyer-Watson with ghost tets: a ghost (a, b, c, INF) carries hull face (a, b, c), the outside
// on its positive side. Local ids 0..n-1 index pts_ and ids_.
class Builder {
 public:
  Builder(ImplicitGeometry& geo, const std::vector<Index>& order) : geo_(geo), ids_(order) {
    std::uint64_t s = 0x5eedULL;  // the walk's face order
    rng_ = splitmix64(s);
    pts_.reserve(order.size());
    for (Index v : order) pts_.push_back(geo.explicit_point(geo.explicit_id(v)));
    const std::size_t cap = 7 * order.size() + 64;
    v_.reserve(cap);
    nb_.reserve(cap);
    mark_.reserve(cap);
  }

  bool run() {
    const int n = static_cast<int>(pts_.size());
    if (n < 4) return false;
    // First tet: points 0 and 1, the first not collinear with them, the first off their plane.
    int c = -1, d = -1;
    for (int i = 2; i < n && c < 0; ++i)
      if (!collinear(0, 1, i)) c = i;
    if (c < 0) return false;
    Sign o = Sign::kZero;
    for (int i = 2; i < n && d < 0; ++i) {
      if (i == c) continue;
      o = orient(0, 1, c, i);
      if (o != Sign::kZero) d = i;
    }
    if (d < 0) return false;
    const std::array<int, 4> first = o == Sign::kPositive ? std::array<int, 4>{0, 1, c, d} : std::array<int, 4>{1, 0, c, d};
    const int t0 = alloc(first);
    int ghost[4];
    for (int i = 0; i < 4; ++i) {
      const int* f = kFace[i];
      ghost[i] = alloc({first[f[0]], first[f[2]], first[f[1]], kInf});  // reversed: the outside positive
      nb_[t0][i] = ghost[i];
      nb_[ghost[i]][3] = t0;
    }
    // Ghosts share their faces through INF: ghost i and ghost j meet along the edge of the
    // first tet they have in common.
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 3; ++k) {
        // The face of ghost i opposite its corner k holds INF and the other two corners.
        const int a = v_[ghost[i]][(k + 1) % 3], b = v_[ghost[i]][(k + 2) % 3];
        for (int j = 0; j < 4; ++j) {
          if (j == i) continue;
          if (contains(v_[ghost[j]], a) && contains(v_[ghost[j]], b)) nb_[ghost[i]][k] = ghost[j];
        }
      }
    hint_ = t0;
    for (int e = 0; e < n; ++e) {
      if (e == 0 || e == 1 || e == c || e == d) continue;
      if (!insert(e)) return false;
    }
    return true;
  }

  bool collect(PointDelaunay& out) {
    std::vector<Index> local(v_.size(), -1);
    Index m = 0;
    for (std::size_t t = 0; t < v_.size(); ++t)
      if (!dead(t) && v_[t][3] != kInf) local[t] = m++;
    out.tets.clear();
    out.nb.clear();
    out.tets.reserve(static_cast<std::size_t>(m));
    out.nb.reserve(static_cast<std::size_t>(m));
    for (std::size_t t = 0; t < v_.size(); ++t) {
      if (local[t] < 0) continue;
      const auto& v = v_[t];
      if (orient(v[0], v[1], v[2], v[3]) != Sign::kPositive) return false;
      out.tets.push_back({ids_[v[0]], ids_[v[1]], ids_[v[2]], ids_[v[3]]});
      std::array<Index, 4> nb;
      for (int i = 0; i < 4; ++i) nb[i] = local[nb_[t][i]];  // a ghost: -1
      out.nb.push_back(nb);
    }
    return true;
  }

 private:
  static bool contains(const std::array<int, 4>& v, int x) { return v[0] == x || v[1] == x || v[2] == x || v[3] == x; }
  bool dead(std::size_t t) const { return v_[t][0] == kDead; }

  int alloc(const std::array<int, 4>& v) {
    if (!free_.empty()) {
      const int id = free_.back();
      free_.pop_back();
      v_[id] = v;
      nb_[id] = {-1, -1, -1, -1};
      return id;
    }
    v_.push_back(v);
    nb_.push_back({-1, -1, -1, -1});
    mark_.push_back(0);
    return static_cast<int>(v_.size() - 1);
  }

  Sign orient(int a, int b, int c, int d) const { return orient3d(pts_[a], pts_[b], pts_[c], pts_[d]); }

  bool collinear(int a, int b, int c) const {
    for (int axis = 0; axis < 3; ++axis)
      if (orient2d_projected(pts_[a], pts_[b], pts_[c], axis) != Sign::kZero) return false;
    return true;
  }

  // In conflict: e strictly inside the perturbed circumsphere of real tet t, or beyond (or, on its
  // plane, inside the perturbed circumcircle of) the hull face of ghost t.
  bool conflict(int t, int e) {
    const auto& v = v_[t];
    if (v[3] != kInf) {
      Sign s;
      if (lifted_det3_filter(pts_[v[0]], pts_[v[1]], pts_[v[2]], pts_[v[3]], pts_[e], s) && s != Sign::kZero)
        return s == Sign::kNegative;
      return geo_.lifted_det3(ids_[v[0]], ids_[v[1]], ids_[v[2]], ids_[v[3]], ids_[e]) == Sign::kNegative;
    }
    const Sign o = orient(v[0], v[1], v[2], e);
    if (o != Sign::kZero) return o == Sign::kPositive;
    // e on the hull face's plane: an axis along which the face projects without degenerating.
    const Vec3 &pa = pts_[v[0]], &pb = pts_[v[1]], &pc = pts_[v[2]];
    const double ux = pb.x - pa.x, uy = pb.y - pa.y, uz = pb.z - pa.z, wx = pc.x - pa.x, wy = pc.y - pa.y,
                 wz = pc.z - pa.z;
    const double nrm[3] = {std::fabs(uy * wz - uz * wy), std::fabs(uz * wx - ux * wz), std::fabs(ux * wy - uy * wx)};
    int axes[3] = {0, 1, 2};
    std::stable_sort(axes, axes + 3, [&](int i, int j) { return nrm[i] > nrm[j]; });
    for (int axis : axes) {
      const Sign s = orient2d_projected(pa, pb, pc, axis);
      if (s == Sign::kZero) continue;
      return geo_.lifted_det2(ids_[v[0]], ids_[v[1]], ids_[v[2]], ids_[e], axis) == s;
    }
    return false;  // not reached: hull faces are not degenerate
  }

  // Visibility walk from hint_; a ghost when e is beyond the hull; -1 if it does not end.
  int locate(int e) {
    int t = hint_;
    if (dead(t) || v_[t][3] == kInf) {
      for (t = 0; t < static_cast<int>(v_.size()); ++t)
        if (!dead(t) && v_[t][3] != kInf) break;
    }
    const std::size_t cap = 4 * v_.size() + 64;
    for (std::size_t step = 0; step < cap; ++step) {
      if (v_[t][3] == kInf) return t;
      const auto& v = v_[t];
      const int r = static_cast<int>(splitmix64(rng_) & 3);
      int next = -1;
      for (int k = 0; k < 4 && next < 0; ++k) {
        const int i = (r + k) & 3;
        const int* f = kFace[i];
        if (orient(v[f[0]], v[f[1]], v[f[2]], e) == Sign::kNegative) next = nb_[t][i];
      }
      if (next < 0) return t;
      t = next;
    }
    return -1;
  }

  bool insert(int e) {
    // Two fresh stamps per insertion (never 0, the value of a new tet's mark).
    if (stamp_ >= 0xFFFFFFF0u) {
      std::fill(mark_.begin(), mark_.end(), 0u);
      stamp_ = 0;
    }
    const std::uint32_t in = ++stamp_, out_mark = ++stamp_;  // in the cavity / tested, not in it
    int t0 = locate(e);
    if (t0 < 0 || !conflict(t0, e)) {
      t0 = -1;
      for (int t = 0; t < static_cast<int>(v_.size()) && t0 < 0; ++t)
        if (!dead(t) && conflict(t, e)) t0 = t;
      if (t0 < 0) return false;
    }
    cavity_.clear();
    boundary_.clear();
    cavity_.push_back(t0);
    mark_[t0] = in;
    for (std::size_t q = 0; q < cavity_.size(); ++q) {
      const int t = cavity_[q];
      for (int i = 0; i < 4; ++i) {
        const int n = nb_[t][i];
        if (mark_[n] == in) continue;
        if (mark_[n] != out_mark) {
          if (conflict(n, e)) {
            mark_[n] = in;
            cavity_.push_back(n);
            continue;
          }
          mark_[n] = out_mark;
        }
        boundary_.push_back({t, i});
      }
    }
    // New tets: each boundary face with e in place of the cavity tet's corner across it. Their
    // other faces hold e and an edge of the boundary face; each such edge is shared by exactly
    // two new tets (the cavity boundary is a closed surface): paired by sorting on the edge.
    edges_.clear();
    int last_real = -1;
    for (const auto& [t, i] : boundary_) {
      std::array<int, 4> v = v_[t];
      v[i] = e;
      const int o = nb_[t][i];
      const int id = alloc(v);
      nb_[id][i] = o;
      for (int j = 0; j < 4; ++j)
        if (nb_[o][j] == t) nb_[o][j] = id;
      for (int k = 0; k < 4; ++k) {
        if (k == i) continue;
        int a = -2, b = -2;
        for (int j = 0; j < 4; ++j)
          if (j != i && j != k) (a == -2 ? a : b) = v[j];
        if (a > b) std::swap(a, b);
        const std::uint64_t key = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a + 1)) << 32) |
                                  static_cast<std::uint32_t>(b + 1);
        edges_.push_back({key, static_cast<std::uint64_t>(id) << 2 | static_cast<std::uint64_t>(k)});
      }
      if (v[3] != kInf) last_real = id;
    }
    if (!link_new_tets()) return false;
    for (int t : cavity_) {
      v_[t][0] = kDead;
      free_.push_back(t);
    }
    if (last_real >= 0) hint_ = last_real;
    return true;
  }

  // Pairs the new tets' faces listed in edges_ (each edge key twice). A small open-addressing
  // table with generation stamps (no clearing, no allocation); a sort for a huge cavity.
  bool link_new_tets() {
    auto join = [&](std::uint64_t a, std::uint64_t b) {
      const int ta = static_cast<int>(a >> 2), ka = static_cast<int>(a & 3);
      const int tb = static_cast<int>(b >> 2), kb = static_cast<int>(b & 3);
      nb_[ta][ka] = tb;
      nb_[tb][kb] = ta;
    };
    if (edges_.size() % 2) return false;
    if (2 * edges_.size() > kTable) {
      std::sort(edges_.begin(), edges_.end());
      for (std::size_t j = 0; j < edges_.size(); j += 2) {
        if (edges_[j].first != edges_[j + 1].first || (j + 2 < edges_.size() && edges_[j + 2].first == edges_[j].first))
          return false;
        join(edges_[j].second, edges_[j + 1].second);
      }
      return true;
    }
    if (++gen_ == 0) {
      table_gen_.fill(0);
      gen_ = 1;
    }
    std::size_t open = 0;
    for (const auto& [key, val] : edges_) {
      std::size_t h = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> 55) & (kTable - 1);
      for (;;) {
        if (table_gen_[h] != gen_) {  // empty: the first of the pair
          table_gen_[h] = gen_;
          table_key_[h] = key;
          table_val_[h] = val;
          ++open;
          break;
        }
        if (table_key_[h] == key && table_val_[h] != kPaired) {
          join(table_val_[h], val);
          table_val_[h] = kPaired;
          --open;
          break;
        }
        if (table_key_[h] == key) return false;  // a third face on one edge
        h = (h + 1) & (kTable - 1);
      }
    }
    return open == 0;
  }

  static constexpr std::size_t kTable = 512;
  static constexpr std::uint64_t kPaired = ~std::uint64_t(0);
  std::array<std::uint32_t, kTable> table_gen_{};
  std::array<std::uint64_t, kTable> table_key_{}, table_val_{};
  std::uint32_t gen_ = 0;
  static constexpr int kDead = -2;
  ImplicitGeometry& geo_;
  std::vector<Index> ids_;
  std::vector<Vec3> pts_;
  std::vector<std::array<int, 4>> v_, nb_;
  std::vector<std::uint32_t> mark_;
  std::vector<int> free_, cavity_;
  std::vector<std::pair<int, int>> boundary_;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> edges_;
  std::uint32_t stamp_ = 0;
  int hint_ = 0;
  std::uint64_t rng_ = 0;
};

}  // namespace

bool delaunay_explicit_points(ImplicitGeometry& geo, const std::vector<Index>& order, PointDelaunay& out) {
  Builder b(geo, order);
  return b.run() && b.collect(out);
}

}  // namespace bsptet
