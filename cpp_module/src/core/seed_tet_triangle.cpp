// SPDX-License-Identifier: LGPL-2.1-or-later
// The seed's tet-triangle test (seed_tet_triangle.h).
#include "bsptet/core/seed_tet_triangle.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "bsptet/numerics/exact_float.h"
#include "bsptet/numerics/interval.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

namespace {

constexpr auto& kFace = kTetOppositeFace;  // types.h
constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

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

}  // namespace

int seed_tet_triangle_relation(const std::array<Vec3, 4>& p, const std::array<Index, 4>& pid,
                               const std::array<Vec3, 3>& q, const std::array<Index, 3>& qid) {
  return tet_triangle_relation(p, pid, q, qid);
}

}  // namespace bsptet
