// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/mesh/tet_shape.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace bsptet {

namespace {

struct V {
  double x, y, z;
};
V sub(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V cross(const V& a, const V& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(const V& a, const V& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr double kPi = 3.14159265358979323846;

}  // namespace

double squared_distance(const Vec3& a, const Vec3& b) {
  const V d = sub(a, b);
  return dot(d, d);
}

double tet_min_dihedral_deg(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  // Outward normals of the faces opposite a, b, c, d (tet positively oriented): (b, c, d),
  // (a, d, c), (a, b, d), (a, c, b). Written out rather than through a table of faces: this runs
  // tens of millions of times in the quality stage, and the straight-line form is twice as fast
  // with the same roundings.
  const V ab = sub(b, a), ac = sub(c, a), ad = sub(d, a), bc = sub(c, b), bd = sub(d, b);
  const V n[4] = {cross(bc, bd), cross(ad, ac), cross(ab, ad), cross(ac, ab)};
  double len[4];
  for (int i = 0; i < 4; ++i) {
    len[i] = std::sqrt(dot(n[i], n[i]));
    if (!(len[i] > 0)) return 0.0;
  }
  // The dihedral angle at the edge shared by faces i and j is pi minus the angle of their normals.
  // The smallest angle has the largest cosine: one acos per tet.
  double largest = -1.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) largest = std::max(largest, -dot(n[i], n[j]) / (len[i] * len[j]));
  return std::acos(std::max(-1.0, std::min(1.0, largest))) * 180.0 / kPi;
}

bool tet_circumsphere(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Vec3* center, double* radius2) {
  const V u = sub(b, a), v = sub(c, a), w = sub(d, a);
  const double det = dot(u, cross(v, w));
  if (det == 0) return false;
  const double uu = dot(u, u), vv = dot(v, v), ww = dot(w, w);
  const V vw = cross(v, w), wu = cross(w, u), uv = cross(u, v);
  const V off = {(uu * vw.x + vv * wu.x + ww * uv.x) / (2 * det), (uu * vw.y + vv * wu.y + ww * uv.y) / (2 * det),
                 (uu * vw.z + vv * wu.z + ww * uv.z) / (2 * det)};
  const double r2 = dot(off, off);
  const Vec3 p{a.x + off.x, a.y + off.y, a.z + off.z};
  if (!std::isfinite(r2) || !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  *center = p;
  *radius2 = r2;
  return true;
}

double tet_radius_edge_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const V u = sub(b, a), v = sub(c, a), w = sub(d, a);
  const double det = dot(u, cross(v, w));
  const double uu = dot(u, u), vv = dot(v, v), ww = dot(w, w);
  // Circumcentre offset from a: (|u|^2 (v x w) + |v|^2 (w x u) + |w|^2 (u x v)) / (2 det).
  const V vw = cross(v, w), wu = cross(w, u), uv = cross(u, v);
  const V num = {uu * vw.x + vv * wu.x + ww * uv.x, uu * vw.y + vv * wu.y + ww * uv.y,
                 uu * vw.z + vv * wu.z + ww * uv.z};
  if (det == 0) return std::numeric_limits<double>::infinity();
  const double radius = std::sqrt(dot(num, num)) / (2.0 * std::fabs(det));
  const double shortest2 = std::min({uu, vv, ww, squared_distance(b, c), squared_distance(c, d), squared_distance(b, d)});
  if (!(shortest2 > 0)) return std::numeric_limits<double>::infinity();
  return radius / std::sqrt(shortest2);
}

}  // namespace bsptet
