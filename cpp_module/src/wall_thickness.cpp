// Wall thickness (see wall_thickness.h).
#include "bsptet/wall_thickness.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace bsptet {

namespace {

Vec3 sub(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 axpy(double s, const Vec3& d, const Vec3& a) { return {a.x + s * d.x, a.y + s * d.y, a.z + s * d.z}; }

}  // namespace

// Ericson, Real-Time Collision Detection, 5.1.5: the Voronoi regions of the triangle's features.
double point_triangle_squared_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3* q) {
  const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  Vec3 r;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    r = a;
  } else {
    const Vec3 bp = sub(p, b);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) {
      r = b;
    } else {
      const double vc = d1 * d4 - d3 * d2;
      if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        r = axpy(d1 / (d1 - d3), ab, a);
      } else {
        const Vec3 cp = sub(p, c);
        const double d5 = dot(ab, cp), d6 = dot(ac, cp);
        if (d6 >= 0 && d5 <= d6) {
          r = c;
        } else {
          const double vb = d5 * d2 - d1 * d6;
          if (vb <= 0 && d2 >= 0 && d6 <= 0) {
            r = axpy(d2 / (d2 - d6), ac, a);
          } else {
            const double va = d3 * d6 - d5 * d4;
            if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
              r = axpy((d4 - d3) / ((d4 - d3) + (d5 - d6)), sub(c, b), b);
            } else {
              const double denom = 1 / (va + vb + vc);
              r = axpy(vc * denom, ac, axpy(vb * denom, ab, a));
            }
          }
        }
      }
    }
  }
  if (q) *q = r;
  const Vec3 d = sub(p, r);
  return dot(d, d);
}

WallThickness::WallThickness(const SurfaceMesh& surface, double reach) : s_(surface), reach_(reach) {
  const Index nt = surface.num_triangles();
  normal_.resize(static_cast<std::size_t>(nt));
  seen_.assign(static_cast<std::size_t>(nt), 0);
  double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double hi[3] = {-lo[0], -lo[1], -lo[2]};
  for (Index i = 0; i < surface.num_points(); ++i)
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], surface.point(i)[c]);
      hi[c] = std::max(hi[c], surface.point(i)[c]);
    }
  double widest = 0;
  for (int c = 0; c < 3; ++c) widest = std::max(widest, hi[c] - lo[c]);
  if (!(widest > 0)) widest = 1;
  cell_ = std::max(reach_, widest / 256);
  for (int c = 0; c < 3; ++c) {
    origin_[c] = lo[c];
    dims_[c] = static_cast<std::int64_t>((hi[c] - lo[c]) / cell_) + 1;
  }
  for (Index t = 0; t < nt; ++t) {
    const Vec3 a = surface.point(surface.tri[3 * t]), b = surface.point(surface.tri[3 * t + 1]),
               c = surface.point(surface.tri[3 * t + 2]);
    const Vec3 u = sub(b, a), v = sub(c, a);
    Vec3 n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
    const double len = std::sqrt(dot(n, n));
    normal_[static_cast<std::size_t>(t)] = len > 0 ? Vec3{n.x / len, n.y / len, n.z / len} : Vec3{};
    std::int64_t from[3], to[3];
    for (int k = 0; k < 3; ++k) {
      const double mn = std::min({a[k], b[k], c[k]}), mx = std::max({a[k], b[k], c[k]});
      from[k] = std::clamp<std::int64_t>(static_cast<std::int64_t>((mn - origin_[k]) / cell_), 0, dims_[k] - 1);
      to[k] = std::clamp<std::int64_t>(static_cast<std::int64_t>((mx - origin_[k]) / cell_), 0, dims_[k] - 1);
    }
    for (std::int64_t i = from[0]; i <= to[0]; ++i)
      for (std::int64_t j = from[1]; j <= to[1]; ++j)
        for (std::int64_t k = from[2]; k <= to[2]; ++k) cells_[cell_key(i, j, k)].push_back(t);
  }
}

std::int64_t WallThickness::cell_key(std::int64_t i, std::int64_t j, std::int64_t k) const {
  return (i * dims_[1] + j) * dims_[2] + k;
}

double WallThickness::at(const Vec3& p, const Vec3& n, const std::vector<Index>& own) const {
  double best2 = reach_ * reach_;
  bool found = false;
  if (++stamp_ == 0) {
    std::fill(seen_.begin(), seen_.end(), 0);
    stamp_ = 1;
  }
  for (Index t : own)
    if (t >= 0 && static_cast<std::size_t>(t) < seen_.size()) seen_[static_cast<std::size_t>(t)] = stamp_;
  std::int64_t from[3], to[3];
  for (int k = 0; k < 3; ++k) {
    from[k] = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((p[k] - reach_ - origin_[k]) / cell_)), 0,
                                       dims_[k] - 1);
    to[k] = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((p[k] + reach_ - origin_[k]) / cell_)), 0,
                                     dims_[k] - 1);
  }
  for (std::int64_t i = from[0]; i <= to[0]; ++i)
    for (std::int64_t j = from[1]; j <= to[1]; ++j)
      for (std::int64_t k = from[2]; k <= to[2]; ++k) {
        const auto it = cells_.find(cell_key(i, j, k));
        if (it == cells_.end()) continue;
        for (Index t : it->second) {
          std::uint32_t& mark = seen_[static_cast<std::size_t>(t)];
          if (mark == stamp_) continue;
          mark = stamp_;
          const Vec3& m = normal_[static_cast<std::size_t>(t)];
          if (!(dot(m, n) < -0.5)) continue;
          Vec3 q;
          const double d2 = point_triangle_squared_distance(p, s_.point(s_.tri[3 * t]), s_.point(s_.tri[3 * t + 1]),
                                                            s_.point(s_.tri[3 * t + 2]), &q);
          if (!(d2 > 0) || d2 >= best2) continue;
          const Vec3 pq = sub(q, p);
          if (!(dot(pq, n) < 0) || !(dot(pq, m) > 0)) continue;
          best2 = d2;
          found = true;
        }
      }
  return found ? std::sqrt(best2) : std::numeric_limits<double>::infinity();
}

}  // namespace bsptet
