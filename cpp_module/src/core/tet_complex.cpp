// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/tet_complex.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "bsptet/mesh/ring_triangulation.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

namespace {

// The Chebyshev centre of a convex polytope {u : m_j . u >= d_j for all j} (m_j unit normals,
// coordinates relative to some origin) clipped to the box |u_k| <= R: the point u that maximizes
// its clearance s = min_j (m_j . u - d_j). Solved in doubles (a heuristic: every use is followed by
// an exact check) as the dual LP, min sum b_j y_j subject to sum y_j A_j = (0, 0, 0, 1), y >= 0,
// with primal rows A_j = (-m_j, 1), b_j = -d_j, by a two-phase tableau simplex with 4 rows; the
// primal optimum (u, s) is the simplex multiplier vector of the optimal basis. Returns s (-inf when
// the simplex fails).
double chebyshev_centre(const std::vector<std::pair<Vec3, double>>& hs, double R, Vec3* out) {
  std::vector<std::array<double, 4>> A;
  std::vector<double> b;
  for (const auto& [m, d] : hs) A.push_back({-m.x, -m.y, -m.z, 1.0}), b.push_back(-d);
  for (int k = 0; k < 3; ++k)
    for (double sg : {1.0, -1.0}) {
      std::array<double, 4> row{0, 0, 0, 0};
      row[k] = sg;
      A.push_back(row), b.push_back(R);
    }
  A.push_back({0, 0, 0, 1}), b.push_back(R);
  const std::size_t n = A.size(), cols = n + 4;  // y_j, then 4 artificials
  std::vector<std::array<double, 4>> col(cols);  // tableau columns (B^-1 A_j)
  for (std::size_t j = 0; j < n; ++j) col[j] = A[j];
  for (int i = 0; i < 4; ++i) col[n + i] = {0, 0, 0, 0}, col[n + i][i] = 1.0;
  std::array<double, 4> rhs{0, 0, 0, 1};
  std::array<std::size_t, 4> basis{n, n + 1, n + 2, n + 3};
  auto pivot = [&](int r, std::size_t e) {
    const std::array<double, 4> pc = col[e];
    const double p = pc[r];
    for (auto& c : col) {
      const double f = c[r] / p;
      if (f == 0) continue;
      for (int i = 0; i < 4; ++i) c[i] = i == r ? f : c[i] - f * pc[i];
    }
    const double f = rhs[r] / p;
    for (int i = 0; i < 4; ++i) rhs[i] = i == r ? f : rhs[i] - f * pc[i];
    basis[r] = e;
  };
  auto run = [&](const std::vector<double>& cost, bool allow_artificial) {
    for (int iter = 0; iter < 500; ++iter) {
      std::size_t enter = cols;
      double best = -1e-12;
      for (std::size_t j = 0; j < cols; ++j) {
        if (!allow_artificial && j >= n) continue;
        double red = cost[j];
        for (int i = 0; i < 4; ++i) red -= cost[basis[i]] * col[j][i];
        if (red < best) best = red, enter = j;
      }
      if (enter == cols) return true;
      int leave = -1;
      double ratio = INFINITY;
      for (int i = 0; i < 4; ++i)
        if (col[enter][i] > 1e-12 && rhs[i] / col[enter][i] < ratio) ratio = rhs[i] / col[enter][i], leave = i;
      if (leave < 0) return false;  // unbounded dual: the polytope is empty
      pivot(leave, enter);
    }
    return false;
  };
  std::vector<double> cost(cols, 0.0);
  for (int i = 0; i < 4; ++i) cost[n + i] = 1.0;
  if (!run(cost, true) || rhs[0] + rhs[1] + rhs[2] + rhs[3] > 1e-9) {
    // artificial values left: infeasible dual (cannot happen with the box rows) or failure
    double art = 0;
    for (int i = 0; i < 4; ++i) art += basis[i] >= n ? rhs[i] : 0.0;
    if (art > 1e-9) return -INFINITY;
  }
  for (int i = 0; i < 4; ++i)
    if (basis[i] >= n) {
      std::size_t e = cols;
      for (std::size_t j = 0; j < n && e == cols; ++j)
        if (std::fabs(col[j][i]) > 1e-9) e = j;
      if (e == cols) return -INFINITY;
      pivot(i, e);
    }
  for (std::size_t j = 0; j < n; ++j) cost[j] = b[j];
  for (int i = 0; i < 4; ++i) cost[n + i] = 0.0;
  if (!run(cost, false)) return -INFINITY;
  // Multipliers: B^T pi = c_B (Gaussian elimination with partial pivoting).
  double M[4][5];
  for (int i = 0; i < 4; ++i) {
    for (int k = 0; k < 4; ++k) M[i][k] = A[basis[i]][k];
    M[i][4] = b[basis[i]];
  }
  for (int c = 0; c < 4; ++c) {
    int piv = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::fabs(M[r][c]) > std::fabs(M[piv][c])) piv = r;
    if (M[piv][c] == 0) return -INFINITY;
    for (int k = 0; k < 5; ++k) std::swap(M[c][k], M[piv][k]);
    for (int r = 0; r < 4; ++r)
      if (r != c) {
        const double f = M[r][c] / M[c][c];
        for (int k = c; k < 5; ++k) M[r][k] -= f * M[c][k];
      }
  }
  *out = {M[0][4] / M[0][0], M[1][4] / M[1][1], M[2][4] / M[2][2]};
  double s = INFINITY;  // the clearance actually reached (recomputed, not trusted from the LP)
  for (const auto& [m, d] : hs) s = std::min(s, m.x * out->x + m.y * out->y + m.z * out->z - d);
  return s;
}

// The direction d (|d|_inf <= 1) that maximizes min_j m_j . d: the Chebyshev centre of the cone
// {u : m_j . u >= 0} clipped to the box |u_k| <= 1 (the same LP; its extra row s <= 1 only caps a
// margin no unit normal reaches beyond sqrt 3). A heuristic in doubles: every candidate it yields
// is checked exactly. Returns the margin (<= 0, or -inf when the simplex fails: no direction).
double best_direction(const std::vector<Vec3>& ms, Vec3* best) {
  std::vector<std::pair<Vec3, double>> hs;
  hs.reserve(ms.size());
  for (const Vec3& m : ms) hs.push_back({m, 0.0});
  return chebyshev_centre(hs, 1.0, best);
}

// A hash of a vertex triple (faces keyed by their vertices).
inline std::size_t triple_hash(const std::array<Index, 3>& f) {
  std::uint64_t h = static_cast<std::uint32_t>(f[0]);
  h = h * 0x9E3779B97F4A7C15ull + static_cast<std::uint32_t>(f[1]);
  h = h * 0x9E3779B97F4A7C15ull + static_cast<std::uint32_t>(f[2]);
  return static_cast<std::size_t>(h ^ (h >> 29));
}
// The four faces of tet t, each oriented with t on its negative side (outward, for a positive t).
inline std::array<std::array<Index, 3>, 4> outward_faces(const std::array<Index, 4>& t) {
  return {{{t[0], t[2], t[1]}, {t[0], t[1], t[3]}, {t[0], t[3], t[2]}, {t[1], t[2], t[3]}}};
}

// Exact orient3d(f[0], f[2], f[1], apex) for one apex and many faces f, remembered per face (a
// hash map: a tree map's lookups cost more than the predicates they saved) when `remember`: a
// cavity that grows keeps most of its boundary faces, which need not be decided again.
class SeesFace {
 public:
  SeesFace(ImplicitGeometry& geo, Index apex, bool remember, std::int64_t* work)
      : geo_(geo), apex_(apex), remember_(remember), work_(work) {}
  bool operator()(const std::array<Index, 3>& f) {
    if (!remember_) return decide(f);
    auto it = known_.find(f);
    if (it == known_.end()) it = known_.emplace(f, decide(f)).first;
    return it->second;
  }

 private:
  bool decide(const std::array<Index, 3>& f) {
    ++*work_;
    return geo_.orient3d(f[0], f[2], f[1], apex_) == Sign::kPositive;
  }
  struct Hash {
    std::size_t operator()(const std::array<Index, 3>& f) const { return triple_hash(f); }
  };
  ImplicitGeometry& geo_;
  Index apex_;
  bool remember_;
  std::int64_t* work_;
  std::unordered_map<std::array<Index, 3>, bool, Hash> known_;
};

}  // namespace

// The boundary of a cavity that grows by whole tets: its outward faces, in a flat hash table
// keyed by the sorted vertex triple. Adding a tet toggles its four faces (a face it shares with
// the cavity goes inside, the others join the boundary), so a growth step costs the faces it
// adds, not the whole boundary: relocate's cavities grow to thousands of tets in up to 64 steps,
// and merging a sorted boundary at every step took a third of the run on thingi10k_472042.
// Faces are kept in the order they came (those gone inside stay, marked dead).
class TetComplex::CavityBoundary {
 public:
  struct Face {
    std::array<Index, 3> key;   ///< sorted vertices
    std::array<Index, 3> face;  ///< outward orientation
    bool alive;                 ///< on the boundary (not gone inside)
  };
  void clear() {
    faces_.clear();
    slots_.assign(16, kEmpty);
    live_ = used_ = 0;
  }
  /// Adds the outward face f, or removes it when its triple is already there.
  void toggle(const std::array<Index, 3>& f) {
    std::array<Index, 3> key = f;
    std::sort(key.begin(), key.end());
    if (2 * (used_ + 1) > slots_.size()) rehash();
    const std::size_t mask = slots_.size() - 1;
    std::size_t i = triple_hash(key) & mask, tomb = kNone;
    for (;; i = (i + 1) & mask) {
      const std::int32_t s = slots_[i];
      if (s == kEmpty) break;
      if (s == kTomb) {
        if (tomb == kNone) tomb = i;
        continue;
      }
      if (faces_[static_cast<std::size_t>(s)].key == key) {
        faces_[static_cast<std::size_t>(s)].alive = false;
        slots_[i] = kTomb;
        --live_;
        return;
      }
    }
    if (tomb == kNone) ++used_, tomb = i;
    slots_[tomb] = static_cast<std::int32_t>(faces_.size());
    faces_.push_back({key, f, true});
    ++live_;
  }
  std::vector<Face>& faces() { return faces_; }
  /// Faces on the boundary now.
  std::size_t size() const { return live_; }

 private:
  static constexpr std::int32_t kEmpty = -1, kTomb = -2;
  static constexpr std::size_t kNone = ~std::size_t{0};
  void rehash() {
    std::size_t cap = 16;
    while (cap < 4 * (live_ + 1)) cap *= 2;
    slots_.assign(cap, kEmpty);
    for (std::size_t n = 0; n < faces_.size(); ++n) {
      if (!faces_[n].alive) continue;
      std::size_t i = triple_hash(faces_[n].key) & (cap - 1);
      while (slots_[i] != kEmpty) i = (i + 1) & (cap - 1);
      slots_[i] = static_cast<std::int32_t>(n);
    }
    used_ = live_;
  }
  std::vector<Face> faces_;
  std::vector<std::int32_t> slots_;
  std::size_t live_ = 0, used_ = 0;  ///< faces alive; slots not empty (alive or tombstones)
};

TetComplex::TetComplex(ImplicitGeometry& geo, const SurfaceMesh& surface, const std::vector<Index>& tri_plane)
    : geo_(geo), surface_(surface), tri_plane_(tri_plane), np_(surface.num_points()),
      bnd_(std::make_unique<CavityBoundary>()) {}

TetComplex::~TetComplex() = default;

template <class InCavity>
Index TetComplex::tet_beyond_if(const std::array<Index, 3>& f, InCavity&& in_cavity) const {
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (vt_[f[i]].size() < vt_[f[k]].size()) k = i;
  const Index a = f[(k + 1) % 3], b = f[(k + 2) % 3];
  for (Index id : vt_[f[k]]) {
    const auto& t = tets_[id];
    if (std::find(t.begin(), t.end(), a) != t.end() && std::find(t.begin(), t.end(), b) != t.end() &&
        !in_cavity(id))
      return id;
  }
  return -1;
}

void TetComplex::grow() {
  const std::size_t nv = static_cast<std::size_t>(geo_.num_vertices());
  if (vt_.size() < nv) vt_.resize(nv), vb_.resize(nv), version_.resize(nv);
}

Index TetComplex::add_tet(const std::array<Index, 4>& t) {
  grow();
  const Index id = static_cast<Index>(tets_.size());
  tets_.push_back(t);
  talive_.push_back(1);
  for (Index v : t) vt_[v].push_back(id), ++version_[v];
  return id;
}

void TetComplex::kill_tet(Index id) {
  talive_[id] = 0;
  for (Index v : tets_[id]) erase(vt_[v], id), ++version_[v];
}

Index TetComplex::add_face(const std::array<Index, 3>& f, Index label) {
  grow();
  const Index id = static_cast<Index>(faces_.size());
  faces_.push_back(f);
  label_.push_back(label);
  falive_.push_back(1);
  for (Index v : f) vb_[v].push_back(id), ++version_[v];
  return id;
}

void TetComplex::kill_face(Index id) {
  falive_[id] = 0;
  for (Index v : faces_[id]) erase(vb_[v], id), ++version_[v];
}

std::pair<std::uint64_t, std::uint64_t> TetComplex::signature(Index v, const std::vector<Index>& nbrs) const {
  std::uint64_t sum = 0;
  for (Index u : nbrs) sum += version_[u];
  return {version_[v], sum};
}

std::vector<Index> TetComplex::labels(Index v) const {
  std::vector<Index> out;
  for (Index f : vb_[v]) out.push_back(label_[f]);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool TetComplex::is_corner(Index u, Index t) const {
  return surface_.tri[3 * t] == u || surface_.tri[3 * t + 1] == u || surface_.tri[3 * t + 2] == u;
}

std::vector<Index> TetComplex::neighbours(Index v) const {
  std::vector<Index> out;
  for (Index t : vt_[v])
    for (Index u : tets_[t])
      if (u != v) out.push_back(u);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;  // ids below np_ (input points) already come first
}

bool TetComplex::may_move_onto(Index v, const std::vector<Index>& lv, Index u) const {
  if (v < np_) return false;
  if (lv.empty()) return true;
  if (u < np_) {
    for (Index t : lv)
      if (!is_corner(u, t)) return false;
    return true;
  }
  const std::vector<Index> lu = labels(u);
  if (lv.size() == 1) return std::binary_search(lu.begin(), lu.end(), lv[0]);
  if (lv.size() == 2) return lu == lv;
  return false;
}

bool TetComplex::try_substitute(Index v, Index u) {
  grow();  // u may be a vertex just added to the geometry
  std::vector<std::array<Index, 4>> repl;
  const std::vector<Index> star = vt_[v];
  for (Index id : star) {
    std::array<Index, 4> t = tets_[id];
    if (std::find(t.begin(), t.end(), u) != t.end()) continue;
    for (Index& x : t)
      if (x == v) x = u;
    ++work;
    if (geo_.orient3d(t[0], t[1], t[2], t[3]) != Sign::kPositive) return false;
    repl.push_back(t);
  }
  std::vector<Index> sorted_star = star;
  std::sort(sorted_star.begin(), sorted_star.end());
  if (!tets_are_new(repl, sorted_star)) return false;
  for (Index id : star) kill_tet(id);
  for (const auto& t : repl) add_tet(t);
  const std::vector<Index> fstar = vb_[v];
  for (Index id : fstar) {
    std::array<Index, 3> f = faces_[id];
    const Index lab = label_[id];
    kill_face(id);
    if (std::find(f.begin(), f.end(), u) != f.end()) continue;
    for (Index& x : f)
      if (x == v) x = u;
    add_face(f, lab);
  }
  return true;
}

bool TetComplex::relocate(Index v, const std::vector<Index>& also) {
  std::vector<Index> removed{v};
  for (Index z : also)
    if (z >= np_ && z != v) removed.push_back(z);
  std::sort(removed.begin(), removed.end());
  removed.erase(std::unique(removed.begin(), removed.end()), removed.end());
  auto is_removed = [&](Index x) { return std::binary_search(removed.begin(), removed.end(), x); };
  // Surface faces touching a removed point, per input triangle.
  std::vector<Index> fset;
  for (Index z : removed)
    for (Index id : vb_[z]) fset.push_back(id);
  std::sort(fset.begin(), fset.end());
  fset.erase(std::unique(fset.begin(), fset.end()), fset.end());
  std::map<Index, std::vector<std::array<Index, 3>>> groups;
  for (Index id : fset) groups[label_[id]].push_back(faces_[id]);
  std::vector<std::array<Index, 3>> new_faces;
  std::vector<Index> new_labels;
  Vec3 dir{0, 0, 0};
  for (const auto& [t, fs] : groups) {
    const Index plane = tri_plane_[t];
    const int axis = geo_.projection_axis(plane);
    const Sign s0 = geo_.orient2d(fs[0][0], fs[0][1], fs[0][2], axis);
    std::set<std::pair<Index, Index>> edges;
    for (const auto& f : fs)
      for (int k = 0; k < 3; ++k) edges.insert({f[k], f[(k + 1) % 3]});
    std::map<Index, Index> next;
    for (const auto& [x, y] : edges)
      if (!edges.count({y, x})) {
        if (next.count(x)) return fail("its surface region touches itself at a vertex");
        next[x] = y;
      }
    if (next.empty()) return fail("its surface region has no boundary");
    std::vector<Index> cycle{next.begin()->first};
    for (Index x = next.begin()->first;;) {
      auto it = next.find(x);
      if (it == next.end()) return fail("its surface region's boundary is not closed");
      x = it->second;
      if (x == cycle[0]) break;
      cycle.push_back(x);
      if (cycle.size() > next.size()) return fail("its surface region's boundary is not one cycle");
    }
    if (cycle.size() != next.size()) return fail("its surface region has a hole");
    // Drop removed points from the boundary: only where they are flat (on an input edge).
    std::vector<Index> poly;
    const std::size_t nc = cycle.size();
    for (std::size_t i = 0; i < nc; ++i) {
      const Index x = cycle[i];
      if (!is_removed(x)) {
        poly.push_back(x);
        continue;
      }
      // Its neighbours on the cycle that stay.
      std::size_t pi = (i + nc - 1) % nc, ni = (i + 1) % nc;
      while (is_removed(cycle[pi]) && pi != i) pi = (pi + nc - 1) % nc;
      while (is_removed(cycle[ni]) && ni != i) ni = (ni + 1) % nc;
      if (pi == i || geo_.orient2d(cycle[pi], x, cycle[ni], axis) != Sign::kZero)
        return fail("a removed point is a corner of its surface region");
    }
    if (poly.size() < 3) return fail("its surface polygon has fewer than 3 vertices");
    // Ear clipping of a simple polygon (possibly with flat vertices): an ear is strictly convex
    // and its closed triangle holds no other polygon vertex.
    while (poly.size() > 3) {
      const std::size_t n = poly.size();
      bool clipped = false;
      for (std::size_t i = 0; i < n && !clipped; ++i) {
        const Index p = poly[(i + n - 1) % n], c = poly[i], q = poly[(i + 1) % n];
        if (geo_.orient2d(p, c, q, axis) != s0) continue;
        bool empty = true;
        for (std::size_t j = 0; j < n && empty; ++j) {
          const Index y = poly[j];
          if (y == p || y == c || y == q) continue;
          if (geo_.orient2d(p, c, y, axis) != opposite(s0) && geo_.orient2d(c, q, y, axis) != opposite(s0) &&
              geo_.orient2d(q, p, y, axis) != opposite(s0))
            empty = false;
        }
        if (!empty) continue;
        new_faces.push_back({p, c, q});
        new_labels.push_back(t);
        poly.erase(poly.begin() + static_cast<std::ptrdiff_t>(i));
        clipped = true;
      }
      if (!clipped) return fail("no ear in its surface polygon");
    }
    if (geo_.orient2d(poly[0], poly[1], poly[2], axis) != s0) return fail("degenerate last ear");
    new_faces.push_back({poly[0], poly[1], poly[2]});
    new_labels.push_back(t);
    // Inward unit normal of input triangle t (for the faces at v).
    bool at_v = false;
    for (const auto& f : fs) at_v = at_v || f[0] == v || f[1] == v || f[2] == v;
    if (!at_v) continue;
    const Vec3 a = surface_.point(surface_.tri[3 * t]), b = surface_.point(surface_.tri[3 * t + 1]),
               c = surface_.point(surface_.tri[3 * t + 2]);
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, wx = c.x - a.x, wy = c.y - a.y, wz = c.z - a.z;
    double nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    dir.x -= nx / len, dir.y -= ny / len, dir.z -= nz / len;
  }
  // The cavity: the tets of the removed points. Its boundary faces without a removed point, and
  // the new surface triangles, are coned from w.
  std::vector<Index> cavity;
  for (Index z : removed)
    for (Index id : vt_[z]) cavity.push_back(id);
  std::sort(cavity.begin(), cavity.end());
  cavity.erase(std::unique(cavity.begin(), cavity.end()), cavity.end());
  auto cavity_bases = [&](const std::vector<FacePair>& boundary) {
    // Outward faces of the cavity without a removed point, and the new surface triangles.
    std::vector<std::array<Index, 3>> out;
    for (const auto& [key, f] : boundary)
      if (!is_removed(f[0]) && !is_removed(f[1]) && !is_removed(f[2])) out.push_back(f);
    for (const auto& f : new_faces) out.push_back(f);
    return out;
  };
  const std::vector<FacePair> cavity_boundary = boundary_pairs(cavity);
  std::vector<std::array<Index, 3>> bases = cavity_bases(cavity_boundary);

  // Candidate points w = v + eps * d, found in doubles, decided exactly below. Every cavity face
  // (v's link faces and the new surface triangles) is a half-space m . (w - a) > 0 (m unit). Faces
  // whose plane passes (nearly) through v constrain the direction d; the others bound eps.
  const Vec3 vr = geo_.rounded(v);
  struct HalfSpace {
    Vec3 m, a;
    double dist;
  };
  std::vector<HalfSpace> hs;
  auto add_half_space = [&](const Vec3& a, const Vec3& b, const Vec3& c, double sign) {
    // (a, b, c, X) positive: ((b - a) x (c - a)) . (X - a) > 0
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, wx = c.x - a.x, wy = c.y - a.y, wz = c.z - a.z;
    Vec3 m{sign * (uy * wz - uz * wy), sign * (uz * wx - ux * wz), sign * (ux * wy - uy * wx)};
    const double len = std::sqrt(m.x * m.x + m.y * m.y + m.z * m.z);
    if (!(len > 0)) return;
    m = {m.x / len, m.y / len, m.z / len};
    hs.push_back({m, a, m.x * (vr.x - a.x) + m.y * (vr.y - a.y) + m.z * (vr.z - a.z)});
  };
  double lref = 0;
  for (const auto& f : bases) {
    // Outward face (a, b, c): w must make (a, c, b, w) positive.
    const Vec3 a = geo_.rounded(f[0]), b = geo_.rounded(f[2]), c = geo_.rounded(f[1]);
    add_half_space(a, b, c, 1.0);
    for (const Vec3& q : {a, b, c})
      lref = std::max(lref, std::sqrt((q.x - vr.x) * (q.x - vr.x) + (q.y - vr.y) * (q.y - vr.y) +
                                      (q.z - vr.z) * (q.z - vr.z)));
  }
  auto unit = [](Vec3 d) {
    const double len = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    return len > 0 ? Vec3{d.x / len, d.y / len, d.z / len} : Vec3{0, 0, 0};
  };
  // Two tolerances for "through v": rounding noise only (the surface planes and faces through v's
  // edge), then a coarser one for planes that pass within a sliver's width of v.
  const double mag = std::max({std::fabs(vr.x), std::fabs(vr.y), std::fabs(vr.z), lref});
  std::vector<Vec3> candidates;
  for (const double tau : {256 * 2.220446049250313e-16 * mag, 1e-9 * lref}) {
    // The normals of the faces v nearly lies on, one per direction: the faces of a large
    // re-triangulated surface polygon all share (up to rounding) their plane's normal, and the
    // pairwise sums below would otherwise make O(k^2) directions scored against k normals.
    std::vector<Vec3> near;
    for (const auto& h : hs)
      if (h.dist <= tau &&
          std::none_of(near.begin(), near.end(), [&](const Vec3& m) {
            return m.x * h.m.x + m.y * h.m.y + m.z * h.m.z > 1 - 1e-12;
          }))
        near.push_back(h.m);
    std::vector<Vec3> dirs{unit(dir)};
    Vec3 sum{0, 0, 0};
    for (const Vec3& m : near) {
      dirs.push_back(m);
      sum = {sum.x + m.x, sum.y + m.y, sum.z + m.z};
    }
    dirs.push_back(unit(sum));
    for (std::size_t i = 0; i < near.size(); ++i)
      for (std::size_t j = i + 1; j < near.size(); ++j)
        dirs.push_back(unit({near[i].x + near[j].x, near[i].y + near[j].y, near[i].z + near[j].z}));
    if (near.size() <= 30) {
      Vec3 d;
      if (best_direction(near, &d) > 0) dirs.push_back(unit(d));
    }
    // The 6 best-scoring directions with a positive score (score: min_m m . d), best first, ties
    // in the order of dirs. There are O(|near|^2) directions: a score is abandoned as soon as it
    // drops to the 6th best so far (or to 0), which cannot change the 6 kept.
    std::vector<std::pair<double, Vec3>> scored;
    for (const Vec3& d : dirs) {
      const double bar = scored.size() < 6 ? 0.0 : std::max(0.0, scored.back().first);
      double score = INFINITY;
      for (const Vec3& m : near) {
        score = std::min(score, m.x * d.x + m.y * d.y + m.z * d.z);
        if (score <= bar) break;
      }
      if (!(score > bar)) continue;
      auto at = std::find_if(scored.begin(), scored.end(), [&](const auto& p) { return score > p.first; });
      scored.insert(at, {score, d});
      if (scored.size() > 6) scored.pop_back();
    }
    for (const auto& [score, d] : scored) {
      double eps_max = lref;
      for (const auto& h : hs) {
        const double md = h.m.x * d.x + h.m.y * d.y + h.m.z * d.z;
        if (h.dist > tau && md < 0) eps_max = std::min(eps_max, h.dist / -md);
      }
      for (double f : {0.5, 0.2, 0.05, 0.01, 1e-3})
        candidates.push_back({vr.x + f * eps_max * d.x, vr.y + f * eps_max * d.y, vr.z + f * eps_max * d.z});
    }
  }
  // Fallbacks for a v inside a slab thinner than a double's precision: points towards its
  // neighbours off the surface, and towards the centroids of its tets.
  if (removed.size() > 1) {
    Vec3 c{0, 0, 0};
    for (Index z : removed) {
      const Vec3 q = geo_.rounded(z);
      c = {c.x + q.x / removed.size(), c.y + q.y / removed.size(), c.z + q.z / removed.size()};
    }
    candidates.push_back(c);
    for (double f : {0.5, 0.1})
      candidates.push_back({vr.x + f * (c.x - vr.x), vr.y + f * (c.y - vr.y), vr.z + f * (c.z - vr.z)});
  }
  for (Index id : cavity) {
    Vec3 c{0, 0, 0};
    for (Index x : tets_[id]) {
      const Vec3 q = geo_.rounded(x);
      c = {c.x + 0.25 * q.x, c.y + 0.25 * q.y, c.z + 0.25 * q.z};
    }
    for (double f : {0.5, 0.1, 0.01})
      candidates.push_back({vr.x + f * (c.x - vr.x), vr.y + f * (c.y - vr.y), vr.z + f * (c.z - vr.z)});
  }
  for (Index x : neighbours(v)) {
    if (!labels(x).empty()) continue;
    const Vec3 q = geo_.rounded(x);
    for (double f : {0.5, 0.1, 0.01})
      candidates.push_back({vr.x + f * (q.x - vr.x), vr.y + f * (q.y - vr.y), vr.z + f * (q.z - vr.z)});
  }
  if (candidates.empty() || !(lref > 0)) return fail("no direction into the solid sees all its faces");
  std::size_t num_fat = 0;  // candidates with a clearance of at least 1e-3 of the star's size
  // Deepest first: a point that hugs a face becomes an obstacle for the next relocation (a plane
  // a few ulps away), so order by the clearance to the cavity faces, estimated in doubles (the
  // exact checks below decide). Candidates that look outside go last, in their order.
  {
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const Vec3& w = candidates[i];
      double clearance = INFINITY;
      for (const auto& h : hs)
        clearance = std::min(clearance, h.m.x * (w.x - h.a.x) + h.m.y * (w.y - h.a.y) + h.m.z * (w.z - h.a.z));
      order.push_back({clearance > 0 ? -clearance : INFINITY, i});
    }
    std::stable_sort(order.begin(), order.end());
    std::vector<Vec3> sorted;
    for (const auto& [key, i] : order) {
      if (-key >= 1e-3 * lref) ++num_fat;
      sorted.push_back(candidates[i]);
    }
    candidates.swap(sorted);
  }
  if (candidates.size() > max_candidates) candidates.resize(max_candidates);
  num_fat = std::min(num_fat, candidates.size());
  // Deep candidates, tried last with a larger cavity growth: points well inside the solid (the
  // centroids of v's tets and of the cavity's vertices) are not blocked by earlier relocated
  // points that hug the surface; the faces they do not see are removed by growing the cavity.
  const std::size_t first_deep = candidates.size();
  if (deep_grow_limit > 0) {
    Vec3 c{0, 0, 0};
    std::size_t nc = 0;
    for (const auto& f : bases)
      for (Index x : f) {
        const Vec3 q = geo_.rounded(x);
        c = {c.x + q.x, c.y + q.y, c.z + q.z};
        ++nc;
      }
    c = {c.x / nc, c.y / nc, c.z / nc};
    for (double f : {1.0, 0.5, 0.25})
      candidates.push_back({vr.x + f * (c.x - vr.x), vr.y + f * (c.y - vr.y), vr.z + f * (c.z - vr.z)});
    const Vec3 d = unit(dir);
    for (double f : {0.5, 0.25, 0.1})
      candidates.push_back({vr.x + f * lref * d.x, vr.y + f * lref * d.y, vr.z + f * lref * d.z});
    for (Index id : vt_[v]) {
      Vec3 tc{0, 0, 0};
      for (Index x : tets_[id]) {
        const Vec3 q = geo_.rounded(x);
        tc = {tc.x + 0.25 * q.x, tc.y + 0.25 * q.y, tc.z + 0.25 * q.z};
      }
      candidates.push_back(tc);
    }
    if (candidates.size() > first_deep + 24) candidates.resize(first_deep + 24);
  }
  // Order: fat candidates, then deep ones (with growth), then the shallow ones: a point left a
  // few ulps under the surface blocks the relocations around it.
  const std::size_t num_deep = candidates.size() - first_deep;
  std::rotate(candidates.begin() + static_cast<std::ptrdiff_t>(num_fat),
              candidates.begin() + static_cast<std::ptrdiff_t>(first_deep), candidates.end());
  auto is_deep = [&](std::size_t attempt) { return attempt >= num_fat && attempt < num_fat + num_deep; };
  for (std::size_t attempt = 0; attempt < candidates.size(); ++attempt) {
    const Vec3 w = candidates[attempt];
    // Double pre-checks are not exact; everything is decided on the new vertex below.
    const Index wid = geo_.add_explicit_point(w);
    // Cone from w; a face w does not see is removed from the cavity's boundary by taking the tet
    // beyond it into the cavity (never across the surface), a few times at most. The cavity's
    // tets are stamped (start_cavity); its boundary is a CavityBoundary. Whether w sees a
    // boundary face is decided once, when the face joins the boundary, in the order of the
    // sorted triples: a face w does not see has its tet beyond taken at once, so the faces that
    // stay are the ones w sees. The new surface faces' answers are kept (seen_new).
    std::vector<Index> cav = cavity;
    start_cavity(cav);
    bnd_->clear();
    for (const auto& pr : cavity_boundary) bnd_->toggle(pr.second);
    std::vector<signed char> seen_new(new_faces.size(), -1);
    std::vector<std::size_t> fresh;  // boundary faces not decided yet (indices)
    std::size_t first_fresh = 0;
    std::vector<std::array<Index, 3>> bad;
    bool ok = false;
    const int max_grow = is_deep(attempt) ? deep_grow_limit : attempt < 12 ? grow_limit : 0;  // bounded work
    auto sees = [&](const std::array<Index, 3>& f) {
      ++work;
      return geo_.orient3d(f[0], f[2], f[1], wid) == Sign::kPositive;
    };
    for (int grow = 0; grow <= max_grow; ++grow) {
      // The faces that joined the boundary (all of them at first), in the order of their
      // triples, then the new surface faces; every face w does not see is bad. With no growth
      // left one bad face decides.
      bad.clear();
      bool stop = false;
      std::vector<CavityBoundary::Face>& faces = bnd_->faces();
      fresh.clear();
      for (std::size_t n = first_fresh; n < faces.size(); ++n)
        if (faces[n].alive) fresh.push_back(n);
      first_fresh = faces.size();
      if (grow > 0)
        std::sort(fresh.begin(), fresh.end(), [&](std::size_t a, std::size_t b) { return faces[a].key < faces[b].key; });
      for (std::size_t n : fresh) {
        const auto& f = faces[n].face;
        if (is_removed(f[0]) || is_removed(f[1]) || is_removed(f[2])) continue;
        if (!sees(f)) {
          bad.push_back(f);
          if (grow == max_grow) {
            stop = true;
            break;
          }
        }
      }
      for (std::size_t i = 0; i < new_faces.size() && !stop; ++i) {
        if (seen_new[i] < 0) seen_new[i] = sees(new_faces[i]) ? 1 : 0;
        if (seen_new[i] == 0) {
          bad.push_back(new_faces[i]);
          if (grow == max_grow) stop = true;
        }
      }
      if (bad.empty()) {
        ok = true;
        break;
      }
      if (grow == max_grow) break;
      std::vector<Index> add;
      for (const auto& f : bad) {
        const Index beyond = tet_beyond_stamped(f);
        if (beyond < 0) {  // a surface face (or a new one): w is on its wrong side
          add.clear();
          break;
        }
        add.push_back(beyond);
      }
      if (add.empty() || cav.size() + add.size() > max_cavity) break;
      std::sort(add.begin(), add.end());
      add.erase(std::unique(add.begin(), add.end()), add.end());
      for (Index id : add) {
        cav_stamp_[static_cast<std::size_t>(id)] = stamp_;
        for (const auto& g : outward_faces(tets_[id])) bnd_->toggle(g);
      }
      cav.insert(cav.end(), add.begin(), add.end());
      work += static_cast<std::int64_t>(bnd_->size() + cav.size());  // the growth's own cost
    }
    if (!ok) continue;
    // The cone from w over the boundary faces without a removed point (in the order of their
    // triples), then over the new surface faces.
    std::vector<const CavityBoundary::Face*> cone;
    for (const auto& bf : bnd_->faces())
      if (bf.alive && !is_removed(bf.face[0]) && !is_removed(bf.face[1]) && !is_removed(bf.face[2]))
        cone.push_back(&bf);
    std::sort(cone.begin(), cone.end(), [](const auto* a, const auto* b) { return a->key < b->key; });
    std::vector<std::array<Index, 4>> repl;
    repl.reserve(cone.size() + new_faces.size());
    for (const auto* bf : cone) repl.push_back({bf->face[0], bf->face[2], bf->face[1], wid});
    for (const auto& f : new_faces) repl.push_back({f[0], f[2], f[1], wid});
    std::sort(cav.begin(), cav.end());
    for (Index id : cav) kill_tet(id);
    for (const auto& t : repl) add_tet(t);
    for (Index id : fset) kill_face(id);
    for (std::size_t i = 0; i < new_faces.size(); ++i) add_face(new_faces[i], new_labels[i]);
    merged += static_cast<std::int64_t>(removed.size()) - 1;
    return true;
  }
  return fail("no double-precision point just inside keeps its tets positive");
}

std::vector<std::pair<Vec3, double>> TetComplex::seeing_half_spaces(const std::vector<std::array<Index, 3>>& fs,
                                                                    const Vec3& origin, double* size) {
  std::vector<std::pair<Vec3, double>> hs;
  *size = 0;
  for (const auto& f : fs) {
    const Vec3 a = geo_.rounded(f[0]), b = geo_.rounded(f[2]), c = geo_.rounded(f[1]);
    const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, wx = c.x - a.x, wy = c.y - a.y, wz = c.z - a.z;
    Vec3 m{uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx};
    const double len = std::sqrt(m.x * m.x + m.y * m.y + m.z * m.z);
    if (!(len > 0)) continue;
    m = {m.x / len, m.y / len, m.z / len};
    hs.push_back({m, m.x * (a.x - origin.x) + m.y * (a.y - origin.y) + m.z * (a.z - origin.z)});
    for (const Vec3& q : {a, b, c})
      *size = std::max(*size, std::max({std::fabs(q.x - origin.x), std::fabs(q.y - origin.y), std::fabs(q.z - origin.z)}));
  }
  return hs;
}

bool TetComplex::push(Index z) {
  if (z < np_ || !vb_[z].empty() || vt_[z].empty()) return false;
  std::vector<Index> st = vt_[z];
  std::sort(st.begin(), st.end());
  std::vector<std::array<Index, 3>> link;
  for (const auto& f : boundary_faces(st))
    if (f[0] != z && f[1] != z && f[2] != z) link.push_back(f);
  const Vec3 o = geo_.rounded(z);
  double size = 0;
  const auto hs = seeing_half_spaces(link, o, &size);
  if (!(size > 0)) return false;
  double now = INFINITY;
  for (const auto& [m, d] : hs) now = std::min(now, -d);
  Vec3 u;
  const double s = chebyshev_centre(hs, size, &u);
  if (!(s > 2 * std::max(now, 0.0)) || !(s > 0)) return false;
  const Index w = geo_.add_explicit_point({o.x + u.x, o.y + u.y, o.z + u.z});
  return try_substitute(z, w);
}

bool TetComplex::retetrahedralize(Index v, int layers, std::size_t max_tets, std::size_t& steps_left) {
  const std::size_t max_nodes = steps_left;
  if (v < np_ || !vb_[v].empty() || vt_[v].empty()) return false;
  std::vector<Index> cav = vt_[v];
  std::sort(cav.begin(), cav.end());
  for (int layer = 0; layer < layers; ++layer) {
    std::vector<Index> add;
    for (const auto& f : boundary_faces(cav)) {
      const Index beyond = tet_beyond(f, cav);
      if (beyond >= 0) add.push_back(beyond);
    }
    if (add.empty()) break;
    cav.insert(cav.end(), add.begin(), add.end());
    std::sort(cav.begin(), cav.end());
    cav.erase(std::unique(cav.begin(), cav.end()), cav.end());
    if (cav.size() > max_tets) return false;
  }
  const std::vector<std::array<Index, 3>> bnd = boundary_faces(cav);
  std::vector<Index> verts;
  for (const auto& f : bnd)
    for (Index x : f) verts.push_back(x);
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  // Vertices inside the cavity vanish: they must be interior Steiner points (v among them).
  for (Index id : cav)
    for (Index x : tets_[id])
      if (!std::binary_search(verts.begin(), verts.end(), x) && (x < np_ || !vb_[x].empty())) return false;
  // Front faces are stored rotated so that the smallest id comes first (orientation kept).
  auto canon = [](std::array<Index, 3> f) {
    const int i = f[0] < f[1] ? (f[0] < f[2] ? 0 : 2) : (f[1] < f[2] ? 1 : 2);
    return std::array<Index, 3>{f[i], f[(i + 1) % 3], f[(i + 2) % 3]};
  };
  std::map<std::array<Index, 3>, std::vector<Index>> apexes;  // face -> vertices on its inner side
  auto candidates = [&](const std::array<Index, 3>& f) -> const std::vector<Index>& {
    auto it = apexes.find(f);
    if (it != apexes.end()) return it->second;
    std::vector<Index> out;
    for (Index p : verts)
      if (p != f[0] && p != f[1] && p != f[2] && (++work, geo_.orient3d(f[0], f[2], f[1], p) == Sign::kPositive))
        out.push_back(p);
    return apexes.emplace(f, std::move(out)).first->second;
  };
  // The front: a few dozen faces, each with its number of apexes, in a flat array (scans beat
  // tree nodes at this size). The search fills next the face with the fewest apexes, among
  // equals the smallest face.
  struct FrontFace {
    std::array<Index, 3> face;
    std::size_t apexes;
  };
  std::vector<FrontFace> front;
  auto front_find = [&](const std::array<Index, 3>& f) {
    for (std::size_t i = 0; i < front.size(); ++i)
      if (front[i].face == f) return static_cast<std::ptrdiff_t>(i);
    return std::ptrdiff_t{-1};
  };
  auto front_insert = [&](const std::array<Index, 3>& f) { front.push_back({f, candidates(f).size()}); };
  auto front_erase = [&](std::ptrdiff_t i) {
    front[static_cast<std::size_t>(i)] = front.back();
    front.pop_back();
  };
  for (const auto& f : bnd) {
    const auto c = canon(f);
    if (front_find(c) < 0) front_insert(c);
  }
  std::vector<std::array<Index, 4>> repl;
  std::size_t nodes = 0;
  std::function<bool()> search = [&]() -> bool {
    if (front.empty()) return true;
    if (++nodes > max_nodes) return false;
    std::size_t best = 0;
    for (std::size_t i = 1; i < front.size(); ++i)
      if (std::tie(front[i].apexes, front[i].face) < std::tie(front[best].apexes, front[best].face)) best = i;
    if (front[best].apexes == 0) return false;  // a face no tet can fill: a dead end
    const std::array<Index, 3> f = front[best].face;
    const std::vector<Index>& cs = candidates(f);  // map nodes stay put as others are added
    for (Index p : cs) {
      const std::array<Index, 4> t{f[0], f[2], f[1], p};
      // Fill t: the front loses t's faces that are on it and gains the reverse of the others.
      const std::array<std::array<Index, 3>, 4> tf = outward_faces(t);
      std::array<std::pair<bool, std::array<Index, 3>>, 4> undo;  // (removed?, face)
      int undone = 0;
      bool fits = true;
      for (const auto& g : tf) {
        const auto k = canon(g), r = canon({g[0], g[2], g[1]});
        if (const std::ptrdiff_t i = front_find(k); i >= 0) {
          front_erase(i);
          undo[undone++] = {true, k};
        } else if (front_find(r) >= 0) {
          fits = false;  // t would lie on the filled side of r
          break;
        } else {
          front_insert(r);
          undo[undone++] = {false, r};
        }
      }
      if (fits) {
        repl.push_back(t);
        if (search()) return true;
        repl.pop_back();
      }
      for (int u = undone - 1; u >= 0; --u)
        if (undo[u].first) front_insert(undo[u].second);
        else front_erase(front_find(undo[u].second));
      if (nodes > max_nodes) return false;
    }
    return false;
  };
  const bool filled = search();
  steps_left -= std::min(nodes, max_nodes);
  if (!filled) return false;
  if (!tets_are_new(repl, cav)) return false;
  std::int64_t gone = 0;
  {
    std::set<Index> before;
    for (Index id : cav)
      for (Index x : tets_[id])
        if (!std::binary_search(verts.begin(), verts.end(), x)) before.insert(x);
    gone = static_cast<std::int64_t>(before.size());
  }
  for (Index id : cav) kill_tet(id);
  for (const auto& t : repl) add_tet(t);
  merged += gone - 1;  // v itself counts as a collapse
  return true;
}

bool TetComplex::cone_from_vertex(Index v, Index u, int max_grow, std::size_t max_tets) {
  if (!vb_[v].empty() || v < np_) return false;
  // v's star (sorted) and its boundary, kept for the next call while v's star is unchanged
  // (callers try one v with many u in a row).
  if (star_boundary_of_ != v || star_boundary_version_ != version_[v]) {
    star_sorted_ = vt_[v];
    std::sort(star_sorted_.begin(), star_sorted_.end());
    star_boundary_ = boundary_pairs(star_sorted_);
    star_boundary_of_ = v;
    star_boundary_version_ = version_[v];
  }
  std::vector<Index> cav = star_sorted_;
  std::vector<std::array<Index, 4>> repl;
  std::vector<FacePair> boundary = star_boundary_;
  SeesFace sees(geo_, u, max_grow > 0, &work);
  for (int grow = 0; grow <= max_grow; ++grow) {
    repl.clear();
    std::vector<Index> add;
    bool stop = false;
    for (const auto& [key, f] : boundary) {
      if (f[0] == u || f[1] == u || f[2] == u) continue;
      const std::array<Index, 4> t{f[0], f[2], f[1], u};
      if (sees(f)) {
        repl.push_back(t);
        continue;
      }
      if (grow == max_grow) return false;
      const Index beyond = tet_beyond(f, cav);
      if (beyond < 0) {
        stop = true;
        break;
      }
      add.push_back(beyond);
    }
    if (stop) return false;
    if (add.empty()) break;
    if (cav.size() + add.size() > max_tets) return false;
    std::sort(add.begin(), add.end());
    add.erase(std::unique(add.begin(), add.end()), add.end());
    boundary = merge_boundaries(boundary, boundary_pairs(add));
    cav.insert(cav.end(), add.begin(), add.end());
    std::inplace_merge(cav.begin(), cav.end() - static_cast<std::ptrdiff_t>(add.size()), cav.end());
    work += static_cast<std::int64_t>(boundary.size() + cav.size());  // the growth's own cost
  }
  // Vertices that vanish (strictly inside the cavity) must be interior Steiner points.
  std::vector<Index> before, after;
  for (Index id : cav)
    for (Index x : tets_[id]) before.push_back(x);
  for (const auto& t : repl)
    for (Index x : t) after.push_back(x);
  std::sort(before.begin(), before.end());
  before.erase(std::unique(before.begin(), before.end()), before.end());
  std::sort(after.begin(), after.end());
  after.erase(std::unique(after.begin(), after.end()), after.end());
  std::int64_t gone = 0;
  for (Index x : before)
    if (!std::binary_search(after.begin(), after.end(), x)) {
      if (x < np_ || !vb_[x].empty()) return false;
      ++gone;
    }
  if (!tets_are_new(repl, cav)) return false;
  for (Index id : cav) kill_tet(id);
  for (const auto& t : repl) add_tet(t);
  merged += gone - 1;  // v itself counts as a collapse
  return true;
}

bool TetComplex::remove_edge(Index v, Index x) {
  std::vector<Index> around;
  for (Index id : vt_[v]) {
    const auto& t = tets_[id];
    if (std::find(t.begin(), t.end(), x) != t.end()) around.push_back(id);
  }
  const std::size_t n = around.size();
  if (n < 3 || n > 7) return false;
  std::map<Index, Index> next;
  for (Index id : around) {
    const std::array<Index, 4>& t = tets_[id];
    // The other two, p and q, ordered so that (v, x, p, q) is an even permutation of the stored
    // (positive) tet.
    int pos[4], k = 2;
    Index pq[2] = {-1, -1};
    for (int i = 0; i < 4; ++i) {
      if (t[i] == v) pos[0] = i;
      else if (t[i] == x) pos[1] = i;
      else pq[k - 2] = t[i], pos[k++] = i;
    }
    int inversions = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) inversions += pos[i] > pos[j];
    if (inversions % 2) std::swap(pq[0], pq[1]);
    if (next.count(pq[0])) return false;
    next[pq[0]] = pq[1];
  }
  std::vector<Index> ring{next.begin()->first};
  while (ring.size() < n) {
    auto it = next.find(ring.back());
    if (it == next.end()) return false;
    ring.push_back(it->second);
  }
  if (next[ring.back()] != ring[0]) return false;
  // The first triangulation of the ring polygon whose triangles (p, q, r) give positive tets
  // (p, q, r, x) and (p, r, q, v), in apex order (mesh/ring_triangulation.h); each triangle
  // tested costs 2 of work.
  const int m = static_cast<int>(n);
  auto ring_polygon = make_ring_triangulation(
      m, 0.0, 1.0,
      [&](int i, int k, int j, double) {
        work += 2;
        const Index p = ring[static_cast<std::size_t>(i)], q = ring[static_cast<std::size_t>(k)],
                    r = ring[static_cast<std::size_t>(j)];
        return geo_.orient3d(p, q, r, x) == Sign::kPositive && geo_.orient3d(p, r, q, v) == Sign::kPositive ? 1.0 : -1.0;
      },
      [](int, int) { return true; });
  if (ring_polygon.best(0, m - 1) <= 0) return false;
  std::vector<std::array<Index, 4>> repl;
  ring_polygon.for_each_triangle(0, m - 1, [&](int i, int k, int j) {
    const Index p = ring[static_cast<std::size_t>(i)], q = ring[static_cast<std::size_t>(k)],
                r = ring[static_cast<std::size_t>(j)];
    repl.push_back({p, q, r, x});
    repl.push_back({p, r, q, v});
  });
  std::sort(around.begin(), around.end());
  if (!tets_are_new(repl, around)) return false;
  for (Index id : around) kill_tet(id);
  for (const auto& t : repl) add_tet(t);
  return true;
}

std::vector<TetComplex::FacePair> TetComplex::boundary_pairs(const std::vector<Index>& ids) const {
  std::vector<FacePair> all;
  all.reserve(4 * ids.size());
  for (Index id : ids) {
    for (const auto& f : outward_faces(tets_[id])) {
      std::array<Index, 3> key = f;
      std::sort(key.begin(), key.end());
      all.push_back({key, f});
    }
  }
  std::sort(all.begin(), all.end());
  std::vector<FacePair> out;
  for (std::size_t i = 0; i < all.size();) {
    std::size_t j = i + 1;
    while (j < all.size() && all[j].first == all[i].first) ++j;
    if (j - i == 1) out.push_back(all[i]);
    i = j;
  }
  return out;
}

std::vector<TetComplex::FacePair> TetComplex::merge_boundaries(const std::vector<FacePair>& a,
                                                              const std::vector<FacePair>& b) {
  std::vector<FacePair> out;
  out.reserve(a.size() + b.size());
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i].first < b[j].first) out.push_back(a[i++]);
    else if (b[j].first < a[i].first) out.push_back(b[j++]);
    else ++i, ++j;
  }
  out.insert(out.end(), a.begin() + static_cast<std::ptrdiff_t>(i), a.end());
  out.insert(out.end(), b.begin() + static_cast<std::ptrdiff_t>(j), b.end());
  return out;
}

std::vector<std::array<Index, 3>> TetComplex::boundary_faces(const std::vector<Index>& cav) const {
  std::vector<std::array<Index, 3>> out;
  for (const auto& p : boundary_pairs(cav)) out.push_back(p.second);
  return out;
}

Index TetComplex::tet_beyond(const std::array<Index, 3>& f, const std::vector<Index>& cav) const {
  return tet_beyond_if(f, [&](Index id) { return std::binary_search(cav.begin(), cav.end(), id); });
}

void TetComplex::start_cavity(const std::vector<Index>& cav) {
  if (cav_stamp_.size() < tets_.size()) cav_stamp_.resize(tets_.size(), 0);
  if (++stamp_ == 0) std::fill(cav_stamp_.begin(), cav_stamp_.end(), 0), stamp_ = 1;
  for (Index id : cav) cav_stamp_[static_cast<std::size_t>(id)] = stamp_;
}

Index TetComplex::tet_beyond_stamped(const std::array<Index, 3>& f) const {
  return tet_beyond_if(f, [&](Index id) { return cav_stamp_[static_cast<std::size_t>(id)] == stamp_; });
}

bool TetComplex::tets_are_new(const std::vector<std::array<Index, 4>>& repl, const std::vector<Index>& cav) const {
  for (const auto& t : repl) {
    std::array<Index, 4> key = t;
    std::sort(key.begin(), key.end());
    for (Index id : vt_[t[0]]) {
      if (std::binary_search(cav.begin(), cav.end(), id)) continue;
      std::array<Index, 4> k2 = tets_[id];
      std::sort(k2.begin(), k2.end());
      if (k2 == key) return false;
    }
  }
  return true;
}

std::vector<std::array<Index, 4>> TetComplex::alive_tets() const {
  std::vector<std::array<Index, 4>> out;
  for (std::size_t i = 0; i < tets_.size(); ++i)
    if (talive_[i]) out.push_back(tets_[i]);
  return out;
}

void TetComplex::erase(std::vector<Index>& list, Index id) {
  auto it = std::find(list.begin(), list.end(), id);
  if (it != list.end()) {
    *it = list.back();
    list.pop_back();
  }
}

std::vector<std::pair<std::array<Index, 3>, Index>> TetComplex::alive_faces() const {
  std::vector<std::pair<std::array<Index, 3>, Index>> out;
  for (std::size_t i = 0; i < faces_.size(); ++i)
    if (falive_[i]) out.push_back({faces_[i], label_[i]});
  return out;
}

}  // namespace bsptet
