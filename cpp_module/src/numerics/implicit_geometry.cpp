// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/numerics/implicit_geometry.h"

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "bsptet/numerics/errors.h"

namespace bsptet {

namespace {

// Plane coefficients n = (b - a) x (c - a), d = n . a, in any exact-enough number type T.
template <class T>
void plane_coefficients(const Vec3& a, const Vec3& b, const Vec3& c, std::array<T, 3>& n, T& d) {
  const T ax(a.x), ay(a.y), az(a.z);
  const T ux = T(b.x) - ax, uy = T(b.y) - ay, uz = T(b.z) - az;
  const T vx = T(c.x) - ax, vy = T(c.y) - ay, vz = T(c.z) - az;
  n = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
  d = n[0] * ax + n[1] * ay + n[2] * az;
}

template <class T>
std::array<T, 3> cross(const T* p, const T* q) {
  return {p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
}

// Homogeneous TPI: x = (d1 n2 x n3 + d2 n3 x n1 + d3 n1 x n2) / (n1 . n2 x n3).
template <class T>
std::array<T, 4> tpi(const T* n1, const T& d1, const T* n2, const T& d2, const T* n3, const T& d3) {
  const auto c23 = cross(n2, n3), c31 = cross(n3, n1), c12 = cross(n1, n2);
  std::array<T, 4> h;
  for (int k = 0; k < 3; ++k) h[k] = d1 * c23[k] + d2 * c31[k] + d3 * c12[k];
  h[3] = n1[0] * c23[0] + n1[1] * c23[1] + n1[2] * c23[2];
  return h;
}

// side of homogeneous point h against plane (n, d): sign(n . X - d W) * sign(W)
template <class T>
T side_value(const T* nd, const std::array<T, 4>& h) {
  return nd[0] * h[0] + nd[1] * h[1] + nd[2] * h[2] - nd[3] * h[3];
}

template <class T>
T det3_homog(const std::array<T, 4>& p, const std::array<T, 4>& q, const std::array<T, 4>& r, int u, int v) {
  // | p_u p_v p_w ; q_u q_v q_w ; r_u r_v r_w | with w = homogeneous weight (index 3)
  return p[u] * (q[v] * r[3] - q[3] * r[v]) - p[v] * (q[u] * r[3] - q[3] * r[u]) +
         p[3] * (q[u] * r[v] - q[v] * r[u]);
}

// 4x4 determinant of homogeneous rows, by 2x2 minors of rows (0, 1) and (2, 3).
template <class T>
T det4_homog(const std::array<T, 4>& r0, const std::array<T, 4>& r1, const std::array<T, 4>& r2,
             const std::array<T, 4>& r3) {
  auto m = [](const std::array<T, 4>& p, const std::array<T, 4>& q, int i, int j) { return p[i] * q[j] - p[j] * q[i]; };
  return m(r0, r1, 0, 1) * m(r2, r3, 2, 3) - m(r0, r1, 0, 2) * m(r2, r3, 1, 3) + m(r0, r1, 0, 3) * m(r2, r3, 1, 2) +
         m(r0, r1, 1, 2) * m(r2, r3, 0, 3) - m(r0, r1, 1, 3) * m(r2, r3, 0, 2) + m(r0, r1, 2, 3) * m(r2, r3, 0, 1);
}

template <class T>
T det3(const std::array<T, 3>& r0, const std::array<T, 3>& r1, const std::array<T, 3>& r2) {
  return r0[0] * (r1[1] * r2[2] - r1[2] * r2[1]) - r0[1] * (r1[0] * r2[2] - r1[2] * r2[0]) +
         r0[2] * (r1[0] * r2[1] - r1[1] * r2[0]);
}

Sign to_sign(int s) { return s > 0 ? Sign::kPositive : (s < 0 ? Sign::kNegative : Sign::kZero); }

}  // namespace

ImplicitGeometry::ImplicitGeometry(std::vector<Vec3> explicit_points) : points_(std::move(explicit_points)) {
  // Every explicit point usually becomes a vertex, and the BSP adds about as many: no regrowth of
  // the (large) vertex records on the way.
  verts_.reserve(2 * points_.size() + 16);
}

Index ImplicitGeometry::add_plane(Index a, Index b, Index c) {
  const Index id = static_cast<Index>(planes_.size());
  planes_.push_back({a, b, c});
  plane_cache_.emplace_back();  // null until prepare_plane: most planes (seed faces) never need it
  if (projection_axis(id) < 0)
    throw MeshingError(ErrorCode::kInternal, "geometry", id, "plane through collinear points");
  return id;
}

Index ImplicitGeometry::add_explicit_point(const Vec3& p) {
  points_.push_back(p);
  return add_explicit_vertex(static_cast<Index>(points_.size() - 1));
}

Index ImplicitGeometry::add_explicit_vertex(Index point) {
  Vertex v;
  v.explicit_id = point;
  verts_.push_back(std::move(v));
  return static_cast<Index>(verts_.size() - 1);
}

Index ImplicitGeometry::add_tpi_vertex(Index p, Index q, Index r) {
  Vertex v;
  v.planes = {p, q, r};
  v.on_planes = {p, q, r};
  verts_.push_back(std::move(v));
  return static_cast<Index>(verts_.size() - 1);
}

Index ImplicitGeometry::add_centroid_vertex(const std::array<Index, 4>& of) {
  Vertex v;
  v.centroid_of = of;
  verts_.push_back(std::move(v));
  return static_cast<Index>(verts_.size() - 1);
}

namespace {
// Homogeneous centroid of four homogeneous points: (sum_i X_i prod_{j != i} W_j, 4 prod_j W_j).
template <class T>
std::array<T, 4> centroid4(const std::array<const std::array<T, 4>*, 4>& h) {
  std::array<T, 4> out;
  for (int k = 0; k < 3; ++k) {
    T sum = T(0.0);
    for (int i = 0; i < 4; ++i) {
      T term = (*h[i])[k];
      for (int j = 0; j < 4; ++j)
        if (j != i) term = term * (*h[j])[3];
      sum = sum + term;
    }
    out[k] = sum;
  }
  out[3] = T(4.0) * (*h[0])[3] * (*h[1])[3] * (*h[2])[3] * (*h[3])[3];
  return out;
}
}  // namespace

void ImplicitGeometry::note_on_plane(Index v, Index p) {
  auto& on = verts_[v].on_planes;
  if (std::find(on.begin(), on.end(), p) == on.end()) on.push_back(p);
}

void ImplicitGeometry::prepare_plane(Index p) {
  if (!plane_cache_[p]) plane_cache_[p] = std::make_unique<PlaneCache>();
  PlaneCache& c = *plane_cache_[p];
  if (c.ready) return;
  const PlaneDef& pd = planes_[p];
  plane_coefficients<Interval>(points_[pd.a], points_[pd.b], points_[pd.c], c.n_iv, c.d_iv);
  c.ready = true;
}

const std::array<ExactFloat, 4>& ImplicitGeometry::plane_exact(Index p) {
  prepare_plane(p);
  PlaneCache& c = *plane_cache_[p];
  if (!c.exact) {
    const PlaneDef& pd = planes_[p];
    std::array<ExactFloat, 3> n;
    ExactFloat d;
    plane_coefficients<ExactFloat>(points_[pd.a], points_[pd.b], points_[pd.c], n, d);
    c.exact = std::make_unique<std::array<ExactFloat, 4>>(std::array<ExactFloat, 4>{n[0], n[1], n[2], d});
  }
  return *c.exact;
}

const std::array<Interval, 4>& ImplicitGeometry::vertex_interval(Index v) {
  Vertex& vx = verts_[v];
  if (!vx.iv_ready) {
    if (vx.explicit_id >= 0) {
      const Vec3& p = points_[vx.explicit_id];
      vx.iv = {Interval(p.x), Interval(p.y), Interval(p.z), Interval(1.0)};
    } else if (vx.centroid_of[0] >= 0) {
      const std::array<Index, 4> of = vx.centroid_of;
      std::array<std::array<Interval, 4>, 4> hs;
      for (int i = 0; i < 4; ++i) hs[i] = vertex_interval(of[i]);
      verts_[v].iv = centroid4<Interval>({&hs[0], &hs[1], &hs[2], &hs[3]});
    } else {
      Interval nd[3][4];
      for (int i = 0; i < 3; ++i) {
        prepare_plane(vx.planes[i]);
        const PlaneCache& c = *plane_cache_[vx.planes[i]];
        for (int k = 0; k < 3; ++k) nd[i][k] = c.n_iv[k];
        nd[i][3] = c.d_iv;
      }
      vx.iv = tpi<Interval>(nd[0], nd[0][3], nd[1], nd[1][3], nd[2], nd[2][3]);
    }
    vx.iv_ready = true;
  }
  return vx.iv;
}

const std::array<ExactFloat, 4>& ImplicitGeometry::vertex_exact(Index v) {
  Vertex& vx = verts_[v];
  if (!vx.exact) {
    std::array<ExactFloat, 4> h;
    if (vx.explicit_id >= 0) {
      const Vec3& p = points_[vx.explicit_id];
      h = {ExactFloat(p.x), ExactFloat(p.y), ExactFloat(p.z), ExactFloat(1.0)};
    } else if (vx.centroid_of[0] >= 0) {
      const std::array<Index, 4> of = vx.centroid_of;
      std::array<std::array<ExactFloat, 4>, 4> hs;
      for (int i = 0; i < 4; ++i) hs[i] = vertex_exact(of[i]);
      h = centroid4<ExactFloat>({&hs[0], &hs[1], &hs[2], &hs[3]});
    } else {
      const auto& a = plane_exact(vx.planes[0]);
      const auto& b = plane_exact(vx.planes[1]);
      const auto& c = plane_exact(vx.planes[2]);
      h = tpi<ExactFloat>(a.data(), a[3], b.data(), b[3], c.data(), c[3]);
      if (h[3].sign() == 0)
        throw MeshingError(ErrorCode::kInternal, "geometry", v, "three planes without a common point");
    }
    vx.exact = std::make_unique<std::array<ExactFloat, 4>>(std::move(h));
  }
  return *vx.exact;
}

Sign ImplicitGeometry::side(Index p, Index v) {
  const Vertex& vx = verts_[v];
  for (Index q : vx.on_planes)
    if (q == p) return Sign::kZero;
  const PlaneDef& pd = planes_[p];
  if (vx.explicit_id >= 0) {
    if (vx.explicit_id == pd.a || vx.explicit_id == pd.b || vx.explicit_id == pd.c) return Sign::kZero;
    return ::bsptet::orient3d(points_[pd.a], points_[pd.b], points_[pd.c], points_[vx.explicit_id]);
  }
  {
    // side = orient3d(a, b, c, v) over the plane's explicit points; v within r of m.
    Vec3 m;
    double r;
    Sign s;
    if (approximate(v, &m, &r) &&
        orient3d_uncertain(points_[pd.a], 0, points_[pd.b], 0, points_[pd.c], 0, m, r, s))
      return s;
  }
  prepare_plane(p);
  const PlaneCache& c = *plane_cache_[p];
  const auto& h = vertex_interval(v);
  const Interval nd[4] = {c.n_iv[0], c.n_iv[1], c.n_iv[2], c.d_iv};
  const int s = side_value<Interval>(nd, h).certain_sign();
  const int w = h[3].certain_sign();
  if (s != 0 && w != 0) return to_sign(s * w);
  ++exact_fallbacks_;
  const auto& e = plane_exact(p);
  const auto& he = vertex_exact(v);
  const int se = side_value<ExactFloat>(e.data(), he).sign() * he[3].sign();
  if (se == 0) note_on_plane(v, p);
  return to_sign(se);
}

Sign ImplicitGeometry::side_of_box(Index p, const std::array<Interval, 3>& b) {
  prepare_plane(p);
  const PlaneCache& c = *plane_cache_[p];
  // Bounds of n . x - d over the box in plain doubles, then one error bound for all the rounding:
  // each of the (at most) 7 operations per bound errs by at most 2^-53 of a partial result, and
  // every partial result is at most M = sum of the terms' magnitudes, so 2^-50 M covers it; 1e-300
  // covers underflowing products. A normal component whose interval contains 0 takes the interval
  // arithmetic below.
  double lo = 0, hi = 0, mag = 0;
  bool fast = true;
  for (int k = 0; k < 3 && fast; ++k) {
    const double nl = c.n_iv[k].lo(), nh = c.n_iv[k].hi(), xl = b[k].lo(), xh = b[k].hi();
    double tl, th;
    if (nl >= 0) {
      tl = std::min(nl * xl, nh * xl);
      th = std::max(nl * xh, nh * xh);
    } else if (nh <= 0) {
      tl = std::min(nl * xh, nh * xh);
      th = std::max(nl * xl, nh * xl);
    } else {
      fast = false;
      break;
    }
    lo += tl;
    hi += th;
    mag += std::max(std::fabs(tl), std::fabs(th));
  }
  if (fast) {
    const double dl = c.d_iv.lo(), dh = c.d_iv.hi();
    lo -= dh;
    hi -= dl;
    mag += std::max(std::fabs(dl), std::fabs(dh));
    if (!std::isfinite(mag) || !std::isfinite(lo) || !std::isfinite(hi)) return Sign::kZero;
    const double err = mag * 0x1p-50 + 1e-300;
    if (lo - err > 0) return Sign::kPositive;
    if (hi + err < 0) return Sign::kNegative;
    return Sign::kZero;
  }
  const int s = (c.n_iv[0] * b[0] + c.n_iv[1] * b[1] + c.n_iv[2] * b[2] - c.d_iv).certain_sign();
  return s > 0 ? Sign::kPositive : s < 0 ? Sign::kNegative : Sign::kZero;
}

bool ImplicitGeometry::approximate(Index v, Vec3* m, double* r) {
  const Vertex& vx = verts_[v];
  if (vx.explicit_id >= 0) {
    *m = points_[vx.explicit_id];
    *r = 0;
    return true;
  }
  const auto* b = box(v);
  if (!b) return false;
  // m in [lo, hi] (halving is exact but for subnormals, and rounding is monotone), so its distance
  // to the exact coordinate is at most hi - lo (plus 2^-1073 for the subnormal case); fl(hi - lo)
  // errs by at most u, covered by the factor.
  double width = 0, c[3];
  for (int k = 0; k < 3; ++k) {
    const double lo = (*b)[k].lo(), hi = (*b)[k].hi();
    c[k] = 0.5 * lo + 0.5 * hi;
    width = std::max(width, hi - lo);
  }
  *m = {c[0], c[1], c[2]};
  *r = width * (1 + 0x1p-50) + 0x1p-1060;
  return std::isfinite(*r) && std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
}

template <std::size_t N>
bool ImplicitGeometry::approximate_all(const std::array<Index, N>& ids, std::array<Vec3, N>& m,
                                       std::array<double, N>& r) {
  for (std::size_t i = 0; i < N; ++i)
    if (!approximate(ids[i], &m[i], &r[i])) return false;
  return true;
}

Sign ImplicitGeometry::orient3d(Index a, Index b, Index c, Index d) {
  const Vertex &va = verts_[a], &vb = verts_[b], &vc = verts_[c], &vd = verts_[d];
  if (va.explicit_id >= 0 && vb.explicit_id >= 0 && vc.explicit_id >= 0 && vd.explicit_id >= 0)
    return ::bsptet::orient3d(points_[va.explicit_id], points_[vb.explicit_id], points_[vc.explicit_id],
                            points_[vd.explicit_id]);
  {
    // First filter: doubles with the points' error radii (no interval arithmetic).
    std::array<Vec3, 4> m;
    std::array<double, 4> r;
    Sign s;
    if (approximate_all<4>({a, b, c, d}, m, r) && orient3d_uncertain(m[0], r[0], m[1], r[1], m[2], r[2], m[3], r[3], s))
      return s;
  }
  {
    const auto *ba = box(a), *bb = box(b), *bc = box(c), *bd = box(d);
    if (ba && bb && bc && bd) {
      // det[b - a, c - a, d - a] on the coordinate intervals.
      std::array<Interval, 3> r0, r1, r2;
      for (int k = 0; k < 3; ++k) {
        r0[k] = (*bb)[k] - (*ba)[k];
        r1[k] = (*bc)[k] - (*ba)[k];
        r2[k] = (*bd)[k] - (*ba)[k];
      }
      const int s = det3<Interval>(r0, r1, r2).certain_sign();
      if (s != 0) return to_sign(s);
    }
  }
  // det[[a 1]; [b 1]; [c 1]; [d 1]] = -det[b - a, c - a, d - a]; homogeneous rows scale it by the
  // product of the weights.
  const auto &ha = vertex_interval(a), &hb = vertex_interval(b), &hc = vertex_interval(c), &hd = vertex_interval(d);
  const int s = det4_homog<Interval>(ha, hb, hc, hd).certain_sign();
  const int w = ha[3].certain_sign() * hb[3].certain_sign() * hc[3].certain_sign() * hd[3].certain_sign();
  if (s != 0 && w != 0) return to_sign(-s * w);
  ++exact_fallbacks_;
  if (known_coplanar(a, b, c, d)) return Sign::kZero;
  Vec3 pa, pb, pc, pd;
  if (exact_double(a, &pa) && exact_double(b, &pb) && exact_double(c, &pc) && exact_double(d, &pd))
    return ::bsptet::orient3d(pa, pb, pc, pd);
  // Three of the four on a known plane P: the sign is side(P, fourth) times the orientation of
  // the three in P (cheaper exact predicates than the 4 x 4 homogeneous determinant). With m the
  // right-hand normal of (x, y, z) and n P's normal, m = lambda n, sign(lambda) = orient2d(x, y, z,
  // axis) * sign(n[axis]) (orient2d's convention), and orient3d(x, y, z, w) = sign(m . (w - x)).
  // The triples and the signs of the row permutations: (a, b, c | d) +, (a, b, d | c) -,
  // (a, c, d | b) +, (b, c, d | a) -.
  {
    const std::array<std::array<Index, 4>, 4> triples = {{{a, b, c, d}, {a, b, d, c}, {a, c, d, b}, {b, c, d, a}}};
    const int parity[4] = {1, -1, 1, -1};
    for (int k = 0; k < 4; ++k) {
      const auto& [x, y, z, w] = triples[k];
      for (Index q : verts_[x].on_planes) {
        if (!known_on_plane(y, q) || !known_on_plane(z, q)) continue;
        const int s1 = to_int(side(q, w));
        if (s1 == 0) return Sign::kZero;
        Sign nsign = Sign::kZero;
        const int axis = projection_axis(q, &nsign);
        const int s2 = to_int(orient2d(x, y, z, axis));
        return to_sign(parity[k] * s1 * s2 * to_int(nsign));
      }
    }
  }
  const auto &ea = vertex_exact(a), &eb = vertex_exact(b), &ec = vertex_exact(c), &ed = vertex_exact(d);
  return to_sign(-det4_homog<ExactFloat>(ea, eb, ec, ed).sign() * ea[3].sign() * eb[3].sign() * ec[3].sign() *
                 ed[3].sign());
}

Sign ImplicitGeometry::orient2d(Index a, Index b, Index c, int axis) {
  const Vertex &va = verts_[a], &vb = verts_[b], &vc = verts_[c];
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  if (va.explicit_id >= 0 && vb.explicit_id >= 0 && vc.explicit_id >= 0)
    return orient2d_projected(points_[va.explicit_id], points_[vb.explicit_id], points_[vc.explicit_id], axis);
  {
    std::array<Vec3, 3> m;
    std::array<double, 3> r;
    Sign s;
    if (approximate_all<3>({a, b, c}, m, r) && orient2d_uncertain(m[0], r[0], m[1], r[1], m[2], r[2], axis, s))
      return s;
  }
  {
    const auto *ba = box(a), *bb = box(b), *bc = box(c);
    if (ba && bb && bc) {
      const int s = (((*bb)[u] - (*ba)[u]) * ((*bc)[v] - (*ba)[v]) - ((*bb)[v] - (*ba)[v]) * ((*bc)[u] - (*ba)[u]))
                        .certain_sign();
      if (s != 0) return to_sign(s);
    }
  }
  const auto &ha = vertex_interval(a), &hb = vertex_interval(b), &hc = vertex_interval(c);
  const int s = det3_homog<Interval>(ha, hb, hc, u, v).certain_sign();
  const int w = ha[3].certain_sign() * hb[3].certain_sign() * hc[3].certain_sign();
  if (s != 0 && w != 0) return to_sign(s * w);
  if (known_collinear(a, b, c)) return Sign::kZero;
  ++exact_fallbacks_;
  Vec3 pa, pb, pc;
  if (exact_double(a, &pa) && exact_double(b, &pb) && exact_double(c, &pc)) return orient2d_projected(pa, pb, pc, axis);
  const auto &ea = vertex_exact(a), &eb = vertex_exact(b), &ec = vertex_exact(c);
  return to_sign(det3_homog<ExactFloat>(ea, eb, ec, u, v).sign() * ea[3].sign() * eb[3].sign() * ec[3].sign());
}

int ImplicitGeometry::projection_axis(Index p, Sign* normal_sign) {
  const PlaneDef& pd = planes_[p];
  const Vec3 &a = points_[pd.a], &b = points_[pd.b], &c = points_[pd.c];
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z, vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  const double n[3] = {std::fabs(uy * vz - uz * vy), std::fabs(uz * vx - ux * vz), std::fabs(ux * vy - uy * vx)};
  int order[3] = {0, 1, 2};
  std::stable_sort(order, order + 3, [&](int i, int j) { return n[i] > n[j]; });
  for (int axis : order) {
    const Sign s = orient2d_projected(a, b, c, axis);
    if (s != Sign::kZero) {
      if (normal_sign) *normal_sign = s;
      return axis;
    }
  }
  return -1;
}

namespace {


// Vertex p relative to vertex e, both homogeneous (X, Y, Z, W): D = X_p W_e - X_e W_p (per
// coordinate) and Q = W_p W_e, so p - e = D / Q.
template <class T>
void relative(const std::array<T, 4>& p, const std::array<T, 4>& e, std::array<T, 3>& d, T& q) {
  for (int k = 0; k < 3; ++k) d[k] = p[k] * e[3] - e[k] * p[3];
  q = p[3] * e[3];
}

// Lifted 3D row of p relative to e, scaled by Q^2 > 0: (Dx Q, Dy Q, Dz Q, |D|^2).
template <class T>
std::array<T, 4> lifted_row3(const std::array<T, 4>& p, const std::array<T, 4>& e) {
  std::array<T, 3> d;
  T q;
  relative(p, e, d, q);
  return {d[0] * q, d[1] * q, d[2] * q, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]};
}

// An interval enclosing each exact entry (to_double truncates: within one ulp).
template <std::size_t N>
std::array<Interval, N> enclose(const std::array<ExactFloat, N>& r) {
  std::array<Interval, N> out;
  for (std::size_t k = 0; k < N; ++k) {
    const double d = r[k].to_double();
    out[k] = r[k].sign() == 0 ? Interval(0.0)
                              : Interval(std::nextafter(d, -INFINITY), std::nextafter(d, INFINITY));
  }
  return out;
}

// Lifted 2D row of p relative to e, scaled by Q^2 > 0: (Du Q, Dv Q, |D|^2) (3D squared length).
template <class T>
std::array<T, 3> lifted_row2(const std::array<T, 4>& p, const std::array<T, 4>& e, int u, int v) {
  std::array<T, 3> d;
  T q;
  relative(p, e, d, q);
  return {d[u] * q, d[v] * q, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]};
}

}  // namespace

// The unperturbed determinant: subtracting e's row from the others (x, y, z columns) and
// |e|^2 - 2 p.e from H (column operations, determinant unchanged) makes e's row (0, 0, 0, 0, 1),
// so det5 = det4 over the rows a..d of (p - e, |p - e|^2). Each row is then scaled by a positive
// factor (homogeneous weights), which keeps the sign. Perturbation: det5 is affine in each H_i, with
// coefficient (-1)^i det4(rows != i; x, y, z, 1) = (-1)^i orient3d(the other four, in order)
// (det[[p 1]] = -orient3d); minors do not change under the column operations. So when the
// unperturbed value is zero, the sign is that of the first non-zero coefficient in decreasing
// vertex id.
Sign ImplicitGeometry::lifted_det3(Index a, Index b, Index c, Index d, Index e) {
  const std::array<Index, 5> ids{{a, b, c, d, e}};
  {
    // First filter: plain doubles when all five are explicit, else doubles with error radii.
    std::array<Vec3, 5> m;
    std::array<double, 5> r;
    Sign s;
    if (approximate_all(ids, m, r)) {
      const bool exact = r[0] == 0 && r[1] == 0 && r[2] == 0 && r[3] == 0 && r[4] == 0;
      if ((exact ? lifted_det3_filter(m[0], m[1], m[2], m[3], m[4], s)
                 : lifted_det3_uncertain(m.data(), r.data(), m[4], r[4], s)) &&
          s != Sign::kZero)
        return s;
      // Five doubles (the Delaunay seed's case), which the double filter cannot decide: points
      // rounded onto a sphere or a cylinder mostly. The same filter in extended precision.
      if (exact && lifted_det3_filter_extended(m[0], m[1], m[2], m[3], m[4], s) && s != Sign::kZero) return s;
    }
  }
  int s0 = 0;
  const auto *b0 = box(a), *b1 = box(b), *b2 = box(c), *b3 = box(d), *b4 = box(e);
  if (b0 && b1 && b2 && b3 && b4) {
    const std::array<const std::array<Interval, 3>*, 4> rows{{b0, b1, b2, b3}};
    std::array<std::array<Interval, 4>, 4> r;
    for (int i = 0; i < 4; ++i) {
      const Interval dx = (*rows[i])[0] - (*b4)[0], dy = (*rows[i])[1] - (*b4)[1], dz = (*rows[i])[2] - (*b4)[2];
      r[i] = {dx, dy, dz, dx * dx + dy * dy + dz * dz};
    }
    s0 = det4_homog<Interval>(r[0], r[1], r[2], r[3]).certain_sign();
  } else {
    const auto& he = vertex_interval(e);
    const auto r0 = lifted_row3<Interval>(vertex_interval(a), he), r1 = lifted_row3<Interval>(vertex_interval(b), he),
               r2 = lifted_row3<Interval>(vertex_interval(c), he), r3 = lifted_row3<Interval>(vertex_interval(d), he);
    s0 = det4_homog<Interval>(r0, r1, r2, r3).certain_sign();
  }
  if (s0 == 0) {
    ++exact_fallbacks_;
    std::array<Vec3, 5> q;
    bool dbl = true;
    for (int i = 0; i < 5 && dbl; ++i) dbl = exact_double(ids[i], &q[i]);
    if (dbl) {
      std::array<std::array<ExactFloat, 4>, 4> r;
      for (int i = 0; i < 4; ++i) {
        const ExactFloat dx = ExactFloat(q[i].x) - ExactFloat(q[4].x), dy = ExactFloat(q[i].y) - ExactFloat(q[4].y),
                         dz = ExactFloat(q[i].z) - ExactFloat(q[4].z);
        r[i] = {dx, dy, dz, dx * dx + dy * dy + dz * dz};
      }
      s0 = det4_homog<ExactFloat>(r[0], r[1], r[2], r[3]).sign();
    } else {
    const auto& he = vertex_exact(e);
    const auto r0 = lifted_row3<ExactFloat>(vertex_exact(a), he), r1 = lifted_row3<ExactFloat>(vertex_exact(b), he),
               r2 = lifted_row3<ExactFloat>(vertex_exact(c), he), r3 = lifted_row3<ExactFloat>(vertex_exact(d), he);
    // Second filter: the rows are exact (no cancellation left in them), the determinant in intervals.
    s0 = det4_homog<Interval>(enclose(r0), enclose(r1), enclose(r2), enclose(r3)).certain_sign();
    if (s0 == 0) s0 = det4_homog<ExactFloat>(r0, r1, r2, r3).sign();
    }
  }
  if (s0 != 0) return to_sign(s0);
  std::array<int, 5> order{{0, 1, 2, 3, 4}};
  std::sort(order.begin(), order.end(), [&](int i, int j) { return ids[i] > ids[j]; });
  for (int i : order) {
    std::array<Index, 4> o;
    int n = 0;
    for (int j = 0; j < 5; ++j)
      if (j != i) o[n++] = ids[j];
    const int m = to_int(orient3d(o[0], o[1], o[2], o[3]));
    if (m != 0) return to_sign(i % 2 == 0 ? m : -m);
  }
  return Sign::kZero;
}

// The same construction one dimension down: det4 over rows (u, v, H, 1) = det3 over the rows a..c
// of (p - d) projected, |p - d|^2; perturbation coefficient of H_i: (-1)^i orient2d(the other
// three, in order).
Sign ImplicitGeometry::lifted_det2(Index a, Index b, Index c, Index d, int axis) {
  const std::array<Index, 4> ids{{a, b, c, d}};
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  {
    std::array<Vec3, 4> m;
    std::array<double, 4> r;
    Sign s;
    if (approximate_all(ids, m, r)) {
      const bool exact = r[0] == 0 && r[1] == 0 && r[2] == 0 && r[3] == 0;
      if ((exact ? lifted_det2_filter(m[0], m[1], m[2], m[3], axis, s)
                 : lifted_det2_uncertain(m.data(), r.data(), m[3], r[3], axis, s)) &&
          s != Sign::kZero)
        return s;
      if (exact && lifted_det2_filter_extended(m[0], m[1], m[2], m[3], axis, s) && s != Sign::kZero) return s;
    }
  }
  int s0 = 0;
  const auto *b0 = box(a), *b1 = box(b), *b2 = box(c), *b3 = box(d);
  if (b0 && b1 && b2 && b3) {
    const std::array<const std::array<Interval, 3>*, 3> rows{{b0, b1, b2}};
    std::array<std::array<Interval, 3>, 3> r;
    for (int i = 0; i < 3; ++i) {
      const Interval dd[3] = {(*rows[i])[0] - (*b3)[0], (*rows[i])[1] - (*b3)[1], (*rows[i])[2] - (*b3)[2]};
      r[i] = {dd[u], dd[v], dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]};
    }
    s0 = det3<Interval>(r[0], r[1], r[2]).certain_sign();
  } else {
    const auto& hd = vertex_interval(d);
    s0 = det3<Interval>(lifted_row2<Interval>(vertex_interval(a), hd, u, v),
                        lifted_row2<Interval>(vertex_interval(b), hd, u, v),
                        lifted_row2<Interval>(vertex_interval(c), hd, u, v))
             .certain_sign();
  }
  if (s0 == 0) {
    ++exact_fallbacks_;
    std::array<Vec3, 4> q;
    bool dbl = true;
    for (int i = 0; i < 4 && dbl; ++i) dbl = exact_double(ids[i], &q[i]);
    if (dbl) {
      std::array<std::array<ExactFloat, 3>, 3> r;
      for (int i = 0; i < 3; ++i) {
        const ExactFloat dx = ExactFloat(q[i].x) - ExactFloat(q[3].x), dy = ExactFloat(q[i].y) - ExactFloat(q[3].y),
                         dz = ExactFloat(q[i].z) - ExactFloat(q[3].z);
        const ExactFloat dd[3] = {dx, dy, dz};
        r[i] = {dd[u], dd[v], dx * dx + dy * dy + dz * dz};
      }
      s0 = det3<ExactFloat>(r[0], r[1], r[2]).sign();
    } else {
    const auto& hd = vertex_exact(d);
    const auto r0 = lifted_row2<ExactFloat>(vertex_exact(a), hd, u, v),
               r1 = lifted_row2<ExactFloat>(vertex_exact(b), hd, u, v),
               r2 = lifted_row2<ExactFloat>(vertex_exact(c), hd, u, v);
    s0 = det3<Interval>(enclose(r0), enclose(r1), enclose(r2)).certain_sign();
    if (s0 == 0) s0 = det3<ExactFloat>(r0, r1, r2).sign();
    }
  }
  if (s0 != 0) return to_sign(s0);
  std::array<int, 4> order{{0, 1, 2, 3}};
  std::sort(order.begin(), order.end(), [&](int i, int j) { return ids[i] > ids[j]; });
  for (int i : order) {
    std::array<Index, 3> o;
    int n = 0;
    for (int j = 0; j < 4; ++j)
      if (j != i) o[n++] = ids[j];
    const int m = to_int(orient2d(o[0], o[1], o[2], axis));
    if (m != 0) return to_sign(i % 2 == 0 ? m : -m);
  }
  return Sign::kZero;
}

const std::array<Interval, 3>* ImplicitGeometry::box(Index v) {
  Vertex& vx = verts_[v];
  if (vx.box_state < 0) {
    vx.box_state = 0;
    if (vx.explicit_id >= 0) {
      const Vec3& p = points_[vx.explicit_id];
      vx.box = {Interval(p.x), Interval(p.y), Interval(p.z)};
      vx.box_state = 1;
    } else {
      const std::array<Interval, 4> h = vertex_interval(v);  // copy: vertex_interval may touch verts_
      const Interval& w = h[3];
      if (w.certain_sign() != 0 && std::isfinite(w.lo()) && std::isfinite(w.hi())) {
        bool ok = true;
        std::array<Interval, 3> b;
        for (int k = 0; k < 3 && ok; ++k) {
          // X / W over the corners; each quotient is rounded to nearest (error <= half an ulp),
          // so one ulp outward encloses the exact range (W excludes zero: monotone in each).
          const double q[4] = {h[k].lo() / w.lo(), h[k].lo() / w.hi(), h[k].hi() / w.lo(), h[k].hi() / w.hi()};
          double lo = q[0], hi = q[0];
          for (double x : q) {
            if (!std::isfinite(x)) ok = false;
            lo = std::min(lo, x);
            hi = std::max(hi, x);
          }
          b[k] = Interval(std::nextafter(lo, -INFINITY), std::nextafter(hi, INFINITY));
        }
        if (ok) {
          verts_[v].box = b;
          verts_[v].box_state = 1;
        }
      }
    }
  }
  return verts_[v].box_state == 1 ? &verts_[v].box : nullptr;
}

bool ImplicitGeometry::exact_double(Index v, Vec3* p) {
  if (verts_[v].explicit_id >= 0) {
    *p = points_[verts_[v].explicit_id];
    return true;
  }
  if (verts_[v].is_double < 0) {
    const Vec3 r = rounded(v);
    const auto& h = vertex_exact(v);
    const bool exact =
        ExactFloat(r.x) * h[3] == h[0] && ExactFloat(r.y) * h[3] == h[1] && ExactFloat(r.z) * h[3] == h[2];
    verts_[v].is_double = exact ? 1 : 0;
  }
  if (verts_[v].is_double == 0) return false;
  *p = verts_[v].rounded;
  return true;
}

bool ImplicitGeometry::known_collinear(Index x, Index y, Index z) const {
  // x, y, z are collinear when x is a TPI vertex and y, z lie on two of its three defining planes
  // (independent planes: they meet in a line). This is a vertex a split left on an edge, with
  // points of that edge.
  auto through = [&](Index t, Index u, Index w) {
    const Vertex& vt = verts_[t];
    if (vt.explicit_id >= 0 || vt.centroid_of[0] >= 0) return false;
    int common = 0;
    for (Index q : vt.planes)
      if (known_on_plane(u, q) && known_on_plane(w, q)) ++common;
    return common >= 2;
  };
  return through(x, y, z) || through(y, z, x) || through(z, x, y);
}

bool ImplicitGeometry::known_coplanar(Index a, Index b, Index c, Index d) const {
  for (Index q : verts_[a].on_planes)
    if (known_on_plane(b, q) && known_on_plane(c, q) && known_on_plane(d, q)) return true;
  // Three of them on one line are coplanar with any fourth.
  return known_collinear(b, c, d) || known_collinear(a, c, d) || known_collinear(a, b, d) || known_collinear(a, b, c);
}

Vec3 ImplicitGeometry::rounded(Index v) {
  const Vertex& vx = verts_[v];
  if (vx.explicit_id >= 0) return points_[vx.explicit_id];
  if (vx.rounded_ready) return vx.rounded;
  const auto& h = vertex_exact(v);
  const mpq_class w = h[3].to_mpq();
  double out[3];
  for (int k = 0; k < 3; ++k) {
    const mpq_class q = h[k].to_mpq() / w;
    // Round to nearest: get_d truncates, so compare the neighbours exactly.
    double best = q.get_d();
    mpq_class best_err = abs(q - mpq_class(best));
    for (double cand : {std::nextafter(best, -INFINITY), std::nextafter(best, INFINITY)}) {
      const mpq_class err = abs(q - mpq_class(cand));
      if (err < best_err) best = cand, best_err = err;
    }
    out[k] = best;
  }
  verts_[v].rounded = {out[0], out[1], out[2]};
  verts_[v].rounded_ready = true;
  return verts_[v].rounded;
}

}  // namespace bsptet
