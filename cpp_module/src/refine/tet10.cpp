// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/refine/tet10.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include "bsptet/mesh/tet_shape.h"

namespace bsptet {

namespace {

// Local corner pairs of the six mid-nodes, in types.h order: m12 m23 m31 m14 m24 m34.
constexpr int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// make_second_order: rounds of point insertion for the tets the relaxation leaves invalid, and
// the smallest min dihedral angle (degrees) such an insertion may make.
constexpr int kMendRounds = 3;
constexpr double kMendFloorDeg = 1.0;

// The scaled Bezier coefficients c_a / j0 of a tet10's Jacobian determinant (j0: 6 times the
// straight tet's volume, so that a straight element has all 20 equal to 1), in double: they only
// rank candidate positions, certify_tet10 decides.
void scaled_coefficients(const double* x, double j0, double* out20) {
  tet10_jacobian_bezier(x, out20);
  for (int a = 0; a < 20; ++a) out20[a] /= j0;
}

// det[n2 - n1, n3 - n1, n4 - n1] of the corners of a tet10 (6 times the straight tet's volume).
double straight_jacobian(const double* x) {
  const double ux = x[3] - x[0], uy = x[4] - x[1], uz = x[5] - x[2];
  const double vx = x[6] - x[0], vy = x[7] - x[1], vz = x[8] - x[2];
  const double wx = x[9] - x[0], wy = x[10] - x[1], wz = x[11] - x[2];
  return ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx);
}

// Solves the n by n system a x = b (row-major) by Gaussian elimination with partial
// pivoting; false when a pivot is 0.
bool solve_dense(std::vector<double> a, std::vector<double> b, int n, std::vector<double>* x) {
  for (int k = 0; k < n; ++k) {
    int piv = k;
    for (int i = k + 1; i < n; ++i)
      if (std::fabs(a[static_cast<std::size_t>(i * n + k)]) > std::fabs(a[static_cast<std::size_t>(piv * n + k)])) piv = i;
    if (a[static_cast<std::size_t>(piv * n + k)] == 0) return false;
    if (piv != k) {
      for (int j = 0; j < n; ++j) std::swap(a[static_cast<std::size_t>(k * n + j)], a[static_cast<std::size_t>(piv * n + j)]);
      std::swap(b[static_cast<std::size_t>(k)], b[static_cast<std::size_t>(piv)]);
    }
    for (int i = k + 1; i < n; ++i) {
      const double f = a[static_cast<std::size_t>(i * n + k)] / a[static_cast<std::size_t>(k * n + k)];
      if (f == 0) continue;
      for (int j = k; j < n; ++j) a[static_cast<std::size_t>(i * n + j)] -= f * a[static_cast<std::size_t>(k * n + j)];
      b[static_cast<std::size_t>(i)] -= f * b[static_cast<std::size_t>(k)];
    }
  }
  x->assign(static_cast<std::size_t>(n), 0.0);
  for (int i = n - 1; i >= 0; --i) {
    double v = b[static_cast<std::size_t>(i)];
    for (int j = i + 1; j < n; ++j) v -= a[static_cast<std::size_t>(i * n + j)] * (*x)[static_cast<std::size_t>(j)];
    (*x)[static_cast<std::size_t>(i)] = v / a[static_cast<std::size_t>(i * n + i)];
  }
  return true;
}

// How a mid-node may move while the relaxation looks for valid curved elements.
enum class MidMove : char {
  kFixed,     ///< stays (a boundary mid-node the hook did not place, or on a face kept as input)
  kFree,      ///< anywhere: the mid-node of an interior edge
  kOnFace,    ///< along its CAD face: moved in the plane of its edge and the face normal's
              ///< complement, then put back on the face by the hook
  kOnCurve,   ///< along its CAD edge: moved along its chord, then put back on the edge by the hook
};

// Mid-nodes of a 10-node mesh moved so that curved elements become valid (make_second_order).
// Works on `mesh` in place. Mid-node m (0-based among the mid-nodes, node np + m) moves as
// move[m] says; tets_of_mid[m] lists the tets that use it; for kOnFace and kOnCurve, tags[m] are
// the hook's arguments and normal[m] a unit normal of a boundary triangle of its edge.
class MidnodeRelaxer {
 public:
  MidnodeRelaxer(TetMesh& mesh, Index np, const std::vector<std::array<Index, 2>>& edges,
                 const std::vector<MidMove>& move, const std::vector<std::vector<Index>>& tets_of_mid,
                 const std::vector<std::array<std::int32_t, 2>>& tags, const std::vector<Vec3>& normal,
                 const ProjectionHook& hook)
      : m_(mesh), np_(np), edges_(edges), move_(move), tets_of_mid_(tets_of_mid), tags_(tags), normal_(normal),
        hook_(hook) {}

  /// Moves the movable mid-nodes of tet t (then, when that is not enough, also those of the tets
  /// sharing a movable mid-node with t) to lower the shortfall of the scaled Bezier coefficients
  /// of every tet using them below kTarget (Levenberg-Marquardt steps, derivatives by forward
  /// differences; a mid-node on the surface is put back on it by the hook after each step). Kept
  /// when t is then certified and no tet around that was certified stops being so; else every
  /// node goes back. `moved` marks the mid-nodes left off their first place. True when kept.
  bool relax(Index t, std::vector<char>& moved) {
    std::vector<Index> vars;
    for (int e = 0; e < 6; ++e) {
      const Index m = mid(t, e);
      if (move_[static_cast<std::size_t>(m)] != MidMove::kFixed) vars.push_back(m);
    }
    std::sort(vars.begin(), vars.end());
    for (int widen = 0; widen < 2 && !vars.empty(); ++widen) {
      if (widen == 1) {
        std::vector<Index> more = vars;
        for (Index m : vars)
          for (Index s : tets_of_mid_[static_cast<std::size_t>(m)])
            for (int e = 0; e < 6; ++e) {
              const Index w = mid(s, e);
              if (move_[static_cast<std::size_t>(w)] != MidMove::kFixed) more.push_back(w);
            }
        std::sort(more.begin(), more.end());
        more.erase(std::unique(more.begin(), more.end()), more.end());
        if (more.size() == vars.size() || more.size() > kMaxVars) return false;
        vars = more;
      }
      if (solve(t, vars, moved)) return true;
    }
    return false;
  }

 private:
  // Scaled coefficients below this count as short: a margin over 0 so that the first, cheap test
  // of certify_tet10 usually passes.
  static constexpr double kTarget = 0.1;
  static constexpr std::size_t kMaxVars = 24;

  Index mid(Index t, int e) const { return m_.tet[static_cast<std::size_t>(10 * t + 4 + e)] - np_; }
  Vec3 node(Index v) const { return m_.point(v); }
  Vec3 get(Index m) const { return m_.point(np_ + m); }
  void set(Index m, const Vec3& p) {
    const std::size_t at = 3 * static_cast<std::size_t>(np_ + m);
    m_.xyz[at] = p.x, m_.xyz[at + 1] = p.y, m_.xyz[at + 2] = p.z;
  }
  void gather(Index t, double* x) const {
    for (int k = 0; k < 10; ++k) {
      const Vec3 p = node(m_.tet[static_cast<std::size_t>(10 * t + k)]);
      x[3 * k] = p.x, x[3 * k + 1] = p.y, x[3 * k + 2] = p.z;
    }
  }

  // Directions along which mid-node m moves (1 to 3 unit vectors).
  std::vector<Vec3> directions(Index m) const {
    const MidMove k = move_[static_cast<std::size_t>(m)];
    if (k == MidMove::kFree) return {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const auto& e = edges_[static_cast<std::size_t>(m)];
    const Vec3 a = node(e[0]), b = node(e[1]);
    Vec3 u{b.x - a.x, b.y - a.y, b.z - a.z};
    const double lu = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
    u = {u.x / lu, u.y / lu, u.z / lu};
    if (k == MidMove::kOnCurve) return {u};
    const Vec3& n = normal_[static_cast<std::size_t>(m)];
    Vec3 w{n.y * u.z - n.z * u.y, n.z * u.x - n.x * u.z, n.x * u.y - n.y * u.x};
    const double lw = std::sqrt(w.x * w.x + w.y * w.y + w.z * w.z);
    if (!(lw > 0)) return {u};
    return {u, {w.x / lw, w.y / lw, w.z / lw}};
  }

  // Mid-node m's place for the trial point p: p itself for a free one, else the hook's point of
  // its face or curve near p; false when the hook has none.
  bool place(Index m, const Vec3& p, Vec3* out) const {
    if (move_[static_cast<std::size_t>(m)] == MidMove::kFree) {
      *out = p;
      return true;
    }
    const auto& tg = tags_[static_cast<std::size_t>(m)];
    const Vec3 q = hook_(p, tg[0], tg[1] != tg[0] ? tg[1] : -1);
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) return false;
    *out = q;
    return true;
  }

  bool solve(Index t, const std::vector<Index>& vars, std::vector<char>& moved) {
    std::vector<Index> around;
    for (Index m : vars)
      for (Index s : tets_of_mid_[static_cast<std::size_t>(m)]) around.push_back(s);
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    const std::size_t na = around.size();
    std::vector<double> j0(na);
    std::vector<char> certified_before(na);
    for (std::size_t i = 0; i < na; ++i) {
      double x[30];
      gather(around[i], x);
      j0[i] = straight_jacobian(x);
      certified_before[i] = certify_tet10(x) == Tet10Validity::kCertified;
    }
    double length = 0;
    {
      double x[30];
      gather(t, x);
      for (const auto& e : kEdge) {
        const double dx = x[3 * e[0]] - x[3 * e[1]], dy = x[3 * e[0] + 1] - x[3 * e[1] + 1];
        const double dz = x[3 * e[0] + 2] - x[3 * e[1] + 2];
        length += std::sqrt(dx * dx + dy * dy + dz * dz) / 6;
      }
    }
    // Residuals: for every tet around and coefficient a, max(0, kTarget - c_a / J0).
    std::vector<double> r, r2;
    auto residuals = [&](std::vector<double>& out) {
      out.assign(na * 20, 0.0);
      double sum = 0;
      for (std::size_t i = 0; i < na; ++i) {
        double x[30], q[20];
        gather(around[i], x);
        scaled_coefficients(x, j0[i], q);
        for (int a = 0; a < 20; ++a) {
          const double v = q[a] < kTarget ? kTarget - q[a] : 0.0;
          out[20 * i + static_cast<std::size_t>(a)] = v;
          sum += v * v;
        }
      }
      return sum;
    };
    std::vector<Vec3> start(vars.size());
    for (std::size_t k = 0; k < vars.size(); ++k) start[k] = get(vars[k]);
    double f = residuals(r);
    const double h = 1e-7 * length;
    double lambda = 1e-3;
    for (int iter = 0; iter < 40 && f > 0; ++iter) {
      // Directions of this step (the surface's moves depend on where the nodes are).
      std::vector<std::pair<std::size_t, Vec3>> dirs;  // (var, direction)
      for (std::size_t k = 0; k < vars.size(); ++k)
        for (const Vec3& d : directions(vars[k])) dirs.emplace_back(k, d);
      const int n = static_cast<int>(dirs.size());
      // Jacobian of the residuals by forward differences along the directions (in the tangent
      // plane: first order for the surface's mid-nodes), (na * 20) by n.
      std::vector<double> jac(r.size() * static_cast<std::size_t>(n), 0.0);
      for (int v = 0; v < n; ++v) {
        const Index m = vars[dirs[static_cast<std::size_t>(v)].first];
        const Vec3 p = get(m), d = dirs[static_cast<std::size_t>(v)].second;
        set(m, {p.x + h * d.x, p.y + h * d.y, p.z + h * d.z});
        residuals(r2);
        set(m, p);
        for (std::size_t i = 0; i < r.size(); ++i)
          jac[i * static_cast<std::size_t>(n) + static_cast<std::size_t>(v)] = (r2[i] - r[i]) / h;
      }
      std::vector<double> jtj(static_cast<std::size_t>(n * n), 0.0), jtr(static_cast<std::size_t>(n), 0.0);
      for (std::size_t i = 0; i < r.size(); ++i) {
        const double* row = &jac[i * static_cast<std::size_t>(n)];
        for (int a = 0; a < n; ++a) {
          if (row[a] == 0) continue;
          jtr[static_cast<std::size_t>(a)] -= row[a] * r[i];
          for (int b = 0; b < n; ++b) jtj[static_cast<std::size_t>(a * n + b)] += row[a] * row[b];
        }
      }
      double diag = 0;
      for (int k = 0; k < n; ++k) diag = std::max(diag, jtj[static_cast<std::size_t>(k * n + k)]);
      if (!(diag > 0)) break;
      bool improved = false;
      for (int tries = 0; tries < 12 && !improved; ++tries) {
        std::vector<double> a = jtj, dx;
        for (int k = 0; k < n; ++k) a[static_cast<std::size_t>(k * n + k)] += lambda * diag;
        if (!solve_dense(a, jtr, n, &dx)) {
          lambda *= 10;
          continue;
        }
        // No mid-node moves by more than a tenth of t's mean edge in one step.
        double big = 0;
        for (double d : dx) big = std::max(big, std::fabs(d));
        if (!(big < kInfinity)) break;
        const double cap = big > 0.1 * length ? 0.1 * length / big : 1.0;
        std::vector<Vec3> trial(vars.size());
        for (std::size_t k = 0; k < vars.size(); ++k) trial[k] = get(vars[k]);
        for (int v = 0; v < n; ++v) {
          const auto& [k, d] = dirs[static_cast<std::size_t>(v)];
          const double s = cap * dx[static_cast<std::size_t>(v)];
          trial[k] = {trial[k].x + s * d.x, trial[k].y + s * d.y, trial[k].z + s * d.z};
        }
        std::vector<Vec3> keep(vars.size());
        bool placed = true;
        for (std::size_t k = 0; k < vars.size() && placed; ++k) {
          keep[k] = get(vars[k]);
          placed = place(vars[k], trial[k], &trial[k]);
        }
        if (placed) {
          for (std::size_t k = 0; k < vars.size(); ++k) set(vars[k], trial[k]);
          const double g = residuals(r2);
          if (g < f) {
            f = g;
            r.swap(r2);
            lambda = std::max(lambda / 4, 1e-12);
            improved = true;
            continue;
          }
          for (std::size_t k = 0; k < vars.size(); ++k) set(vars[k], keep[k]);
        }
        lambda *= 8;
      }
      if (!improved) break;
    }
    // The certificate decides.
    bool ok = true;
    for (std::size_t i = 0; i < na && ok; ++i) {
      double x[30];
      gather(around[i], x);
      const bool cert = certify_tet10(x) == Tet10Validity::kCertified;
      if (around[i] == t ? !cert : (certified_before[i] && !cert)) ok = false;
    }
    if (!ok) {
      for (std::size_t k = 0; k < vars.size(); ++k) set(vars[k], start[k]);
      return false;
    }
    for (std::size_t k = 0; k < vars.size(); ++k) {
      const Vec3 p = get(vars[k]);
      if (p.x != start[k].x || p.y != start[k].y || p.z != start[k].z) moved[static_cast<std::size_t>(vars[k])] = 1;
    }
    return true;
  }

  TetMesh& m_;
  Index np_;
  const std::vector<std::array<Index, 2>>& edges_;
  const std::vector<MidMove>& move_;
  const std::vector<std::vector<Index>>& tets_of_mid_;
  const std::vector<std::array<std::int32_t, 2>>& tags_;
  const std::vector<Vec3>& normal_;
  const ProjectionHook& hook_;
};

// The hook's answers by (point, tag, other tag): a lift made again after insertions asks again
// for the edges it kept.
using ProjectionCache = std::map<std::tuple<double, double, double, std::int32_t, std::int32_t>, Vec3>;

// One lift of `mesh` to 10 nodes: projection, relaxation (MidnodeRelaxer), then, with
// `straighten`, the mid-nodes of the tets still not certified back on their chords until every
// curved tet is certified. Without `straighten`, `failing` receives the tets (output order) still
// not certified after the relaxation; when there are any, the result is not to be used.
TetMesh lift_once(RefineMesh& mesh, const ProjectionHook& hook, ProjectionCache& cache, SecondOrderStats& st,
                  bool straighten, std::vector<Index>* failing) {
  std::vector<Index> renum;
  TetMesh lin = mesh.to_tet_mesh(&renum);

  // Boundary edges and their parent triangles' tags (new indices).
  const EdgeMap<std::array<std::int32_t, 2>> boundary_edge_tags = mesh.boundary_edge_tags(&renum);

  std::vector<std::array<Index, 2>> edges;
  const Index nk = lin.num_tets();
  for (Index t = 0; t < nk; ++t)
    for (const auto& e : kEdge) {
      const Index a = lin.tet[static_cast<std::size_t>(4 * t + e[0])], b = lin.tet[static_cast<std::size_t>(4 * t + e[1])];
      edges.push_back({std::min(a, b), std::max(a, b)});
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

  const Index np = lin.num_points();
  TetMesh out;
  out.nodes_per_tet = 10;
  out.xyz = lin.xyz;
  std::vector<Vec3> straight(edges.size());
  std::vector<char> curved(edges.size(), 0);
  std::vector<char> placed(edges.size(), 0);  // a boundary mid-node the hook placed
  // Every node's coordinates: a projected mid-node that lands exactly on another node (the hook
  // clamps to a CAD vertex when the edge is not along the CAD edge of its two faces) stays on its
  // chord, or the mesh would have two nodes at one place (not conforming).
  std::set<std::array<double, 3>> taken;
  for (Index v = 0; v < np; ++v) {
    const Vec3 q = lin.point(v);
    taken.insert({q.x, q.y, q.z});
  }
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const Vec3 a = lin.point(edges[i][0]), b = lin.point(edges[i][1]);
    straight[i] = {0.5 * (a.x + b.x), 0.5 * (a.y + b.y), 0.5 * (a.z + b.z)};
    Vec3 p = straight[i];
    const auto* found = boundary_edge_tags.find(edge_key(edges[i][0], edges[i][1]));
    if (hook && found) {
      const auto tags = *found;
      const std::int32_t other = tags[1] != tags[0] ? tags[1] : -1;
      auto [at, fresh] = cache.try_emplace({p.x, p.y, p.z, tags[0], other});
      if (fresh) at->second = hook(p, tags[0], other);
      const Vec3 q = at->second;
      if (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && !taken.count({q.x, q.y, q.z})) {
        curved[i] = q.x != p.x || q.y != p.y || q.z != p.z;  // a straight edge of the surface: 0
        p = q;
        ++st.projected;
        placed[i] = 1;
      }
    }
    taken.insert({p.x, p.y, p.z});
    out.xyz.insert(out.xyz.end(), {p.x, p.y, p.z});
  }
  auto edge_id = [&](Index a, Index b) {
    const std::array<Index, 2> key{std::min(a, b), std::max(a, b)};
    return static_cast<Index>(std::lower_bound(edges.begin(), edges.end(), key) - edges.begin());
  };
  out.tet.resize(static_cast<std::size_t>(nk) * 10);
  for (Index t = 0; t < nk; ++t) {
    for (int k = 0; k < 4; ++k) out.tet[static_cast<std::size_t>(10 * t + k)] = lin.tet[static_cast<std::size_t>(4 * t + k)];
    for (int e = 0; e < 6; ++e)
      out.tet[static_cast<std::size_t>(10 * t + 4 + e)] =
          np + edge_id(lin.tet[static_cast<std::size_t>(4 * t + kEdge[e][0])], lin.tet[static_cast<std::size_t>(4 * t + kEdge[e][1])]);
  }
  // Straighten the mid-nodes of curved tets that are not certified valid, until all are. Tets
  // without a curved mid-node are not checked: nothing here could change them (they are the
  // linear tet up to the rounding of their midpoints).
  auto has_curved = [&](Index t) {
    for (int e = 0; e < 6; ++e)
      if (curved[static_cast<std::size_t>(out.tet[static_cast<std::size_t>(10 * t + 4 + e)] - np)]) return true;
    return false;
  };
  std::vector<Index> to_check;
  for (Index t = 0; t < nk; ++t)
    if (has_curved(t)) to_check.push_back(t);
  // First the mid-nodes of the tets that are not certified move (MidnodeRelaxer): interior ones
  // anywhere, the hook's ones along their CAD face or edge (not on faces kept as input, which a
  // neighbouring solid shares). The tets around a moved one are checked as curved tets from then on.
  {
    const std::vector<std::int32_t>& fixed = mesh.fixed_tags();
    auto is_fixed = [&](std::int32_t tag) { return std::binary_search(fixed.begin(), fixed.end(), tag); };
    std::vector<MidMove> move(edges.size(), MidMove::kFree);
    std::vector<std::array<std::int32_t, 2>> tags(edges.size(), {-1, -1});
    std::vector<Vec3> normal(edges.size());
    for (const auto& [face, parent] : mesh.boundary_faces()) {
      std::array<Index, 3> f{};
      for (int k = 0; k < 3; ++k) f[k] = renum[static_cast<std::size_t>(face[k])];
      const Vec3 a = lin.point(f[0]), b = lin.point(f[1]), c = lin.point(f[2]);
      const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
      Vec3 n{uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
      const double ln = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
      if (ln > 0) n = {n.x / ln, n.y / ln, n.z / ln};
      for (int k = 0; k < 3; ++k) {
        const std::array<Index, 2> key{std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])};
        const std::size_t id = static_cast<std::size_t>(std::lower_bound(edges.begin(), edges.end(), key) - edges.begin());
        normal[id] = n;
      }
    }
    for (std::size_t i = 0; i < edges.size(); ++i) {
      const auto* found = boundary_edge_tags.find(edge_key(edges[i][0], edges[i][1]));
      if (!found) continue;
      tags[i] = *found;
      if (!hook || !placed[i] || is_fixed((*found)[0]) || is_fixed((*found)[1]))
        move[i] = MidMove::kFixed;
      else
        move[i] = (*found)[0] != (*found)[1] ? MidMove::kOnCurve : MidMove::kOnFace;
    }
    std::vector<std::vector<Index>> tets_of_mid(edges.size());
    for (Index t = 0; t < nk; ++t)
      for (int e = 0; e < 6; ++e)
        tets_of_mid[static_cast<std::size_t>(out.tet[static_cast<std::size_t>(10 * t + 4 + e)] - np)].push_back(t);
    std::vector<char> moved(edges.size(), 0);
    MidnodeRelaxer relaxer(out, np, edges, move, tets_of_mid, tags, normal, hook);
    for (Index t : to_check) {
      double x[30];
      for (int k = 0; k < 10; ++k)
        for (int c = 0; c < 3; ++c) x[3 * k + c] = out.xyz[static_cast<std::size_t>(3 * out.tet[static_cast<std::size_t>(10 * t + k)] + c)];
      if (certify_tet10(x) == Tet10Validity::kCertified) continue;
      ++st.relax_tried;
      if (relaxer.relax(t, moved)) ++st.relaxed;
    }
    for (std::size_t i = 0; i < edges.size(); ++i)
      if (moved[i]) {
        curved[i] = 1;
        if (move[i] == MidMove::kFree) ++st.interior_moved; else ++st.surface_moved;
        for (Index t : tets_of_mid[i]) to_check.push_back(t);
      }
    std::sort(to_check.begin(), to_check.end());
    to_check.erase(std::unique(to_check.begin(), to_check.end()), to_check.end());
  }
  if (!straighten) {
    for (Index t : to_check) {
      double x[30];
      for (int k = 0; k < 10; ++k)
        for (int c = 0; c < 3; ++c) x[3 * k + c] = out.xyz[static_cast<std::size_t>(3 * out.tet[static_cast<std::size_t>(10 * t + k)] + c)];
      if (certify_tet10(x) != Tet10Validity::kCertified) failing->push_back(t);
    }
    if (!failing->empty()) return out;
  }
  for (bool changed = true; changed;) {
    changed = false;
    for (Index t : to_check) {
      if (!has_curved(t)) continue;
      double x[30];
      for (int k = 0; k < 10; ++k)
        for (int c = 0; c < 3; ++c) x[3 * k + c] = out.xyz[static_cast<std::size_t>(3 * out.tet[static_cast<std::size_t>(10 * t + k)] + c)];
      if (certify_tet10(x) == Tet10Validity::kCertified) continue;
      ++st.not_certified;
      for (int e = 0; e < 6; ++e) {
        const std::size_t id = static_cast<std::size_t>(out.tet[static_cast<std::size_t>(10 * t + 4 + e)] - np);
        if (!curved[id]) continue;
        curved[id] = 0;
        if (boundary_edge_tags.find(edge_key(edges[id][0], edges[id][1]))) ++st.straightened;
        changed = true;
        const std::size_t at = static_cast<std::size_t>(3 * (np + static_cast<Index>(id)));
        out.xyz[at] = straight[id].x;
        out.xyz[at + 1] = straight[id].y;
        out.xyz[at + 2] = straight[id].z;
      }
    }
  }
  st.curved_tets = 0;
  for (Index t : to_check) st.curved_tets += has_curved(t);
  st.midnodes = static_cast<std::int64_t>(edges.size());
  return out;
}

// A new interior point in each tet of `mesh` listed in `failing` (indices among the live tets, in
// slot order: make_second_order's output order), so that no tet keeps the boundary faces, or the
// boundary corners, that kept its curved element invalid. Candidates: the tet's centroid and the
// points a quarter and half of the way from it to each corner, edge midpoint and face centroid;
// each is tried without being applied, and the one whose new tets have the largest smallest
// dihedral angle goes in (RefineMesh::insert_point, the tet forced into the cavity), when that
// angle is at least kMendFloorDeg. Returns the points inserted.
std::int64_t insert_for_curving(RefineMesh& mesh, const std::vector<Index>& failing) {
  std::vector<Index> slot;
  for (Index t = 0; t < mesh.num_tet_slots(); ++t)
    if (mesh.tet_alive(t)) slot.push_back(t);
  std::vector<Index> targets;
  for (Index k : failing) targets.push_back(slot[static_cast<std::size_t>(k)]);
  std::int64_t inserted = 0;
  for (Index t : targets) {
    if (!mesh.tet_alive(t)) continue;  // replaced by an earlier insertion's cavity
    const auto q = mesh.tet(t);
    const Vec3 P[4] = {mesh.point(q[0]), mesh.point(q[1]), mesh.point(q[2]), mesh.point(q[3])};
    const Vec3 g{(P[0].x + P[1].x + P[2].x + P[3].x) / 4, (P[0].y + P[1].y + P[2].y + P[3].y) / 4,
                 (P[0].z + P[1].z + P[2].z + P[3].z) / 4};
    // Candidates: g, and g moved a quarter or half of the way to each corner, edge midpoint and
    // face centroid.
    std::vector<Vec3> toward(P, P + 4);
    for (const auto& e : kEdge)
      toward.push_back({0.5 * (P[e[0]].x + P[e[1]].x), 0.5 * (P[e[0]].y + P[e[1]].y), 0.5 * (P[e[0]].z + P[e[1]].z)});
    for (const auto& f : kTetOppositeFace)
      toward.push_back({(P[f[0]].x + P[f[1]].x + P[f[2]].x) / 3, (P[f[0]].y + P[f[1]].y + P[f[2]].y) / 3,
                        (P[f[0]].z + P[f[1]].z + P[f[2]].z) / 3});
    std::vector<Vec3> cand{g};
    for (double f : {0.25, 0.5})
      for (const Vec3& c : toward) cand.push_back({g.x + f * (c.x - g.x), g.y + f * (c.y - g.y), g.z + f * (c.z - g.z)});
    double best = kMendFloorDeg;
    int best_at = -1;
    for (std::size_t i = 0; i < cand.size(); ++i) {
      double worst = 180;
      auto probe = [&](const std::vector<std::array<Index, 4>>& cone, const Vec3& p) {
        for (const auto& c4 : cone) {
          const Vec3 C[4] = {c4[0] < 0 ? p : mesh.point(c4[0]), c4[1] < 0 ? p : mesh.point(c4[1]),
                             c4[2] < 0 ? p : mesh.point(c4[2]), c4[3] < 0 ? p : mesh.point(c4[3])};
          worst = std::min(worst, tet_min_dihedral_deg(C[0], C[1], C[2], C[3]));
        }
        return false;  // only measures
      };
      mesh.insert_point(t, cand[i], 0.0, nullptr, 256, false, probe, t);
      if (worst < 180 && worst > best) {
        best = worst;
        best_at = static_cast<int>(i);
      }
    }
    if (best_at < 0) continue;
    if (mesh.insert_point(t, cand[static_cast<std::size_t>(best_at)], 0.0, nullptr, 256, false, {}, t) ==
        InsertOutcome::kInserted)
      ++inserted;
  }
  return inserted;
}

}  // namespace

TetMesh make_second_order(RefineMesh& mesh, const ProjectionHook& hook, SecondOrderStats* stats) {
  SecondOrderStats st;
  std::int64_t inserted = 0;
  ProjectionCache cache;
  for (int round = 0; hook && round < kMendRounds; ++round) {
    std::vector<Index> failing;
    st = SecondOrderStats{};
    TetMesh out = lift_once(mesh, hook, cache, st, false, &failing);
    if (failing.empty()) {
      st.points_inserted = inserted;
      if (stats) *stats = st;
      return out;
    }
    const std::int64_t made = insert_for_curving(mesh, failing);
    inserted += made;
    if (made == 0) break;
  }
  st = SecondOrderStats{};
  TetMesh out = lift_once(mesh, hook, cache, st, true, nullptr);
  st.points_inserted = inserted;
  if (stats) *stats = st;
  return out;
}

}  // namespace bsptet
