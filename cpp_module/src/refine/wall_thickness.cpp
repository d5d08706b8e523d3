// SPDX-License-Identifier: LGPL-2.1-or-later
// Wall thickness (see wall_thickness.h).
#include "bsptet/refine/wall_thickness.h"

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

WallThickness::WallThickness(const SurfaceMesh& surface) : s_(surface) {
  const Index nt = surface.num_triangles();
  normal_.resize(static_cast<std::size_t>(nt));
  centroid_.resize(static_cast<std::size_t>(nt));
  seen_.assign(static_cast<std::size_t>(nt), 0);
  for (Index t = 0; t < nt; ++t) {
    const Vec3 a = surface.point(surface.tri[3 * t]), b = surface.point(surface.tri[3 * t + 1]),
               c = surface.point(surface.tri[3 * t + 2]);
    const Vec3 u = sub(b, a), v = sub(c, a);
    const Vec3 n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
    const double len = std::sqrt(dot(n, n));
    centroid_[static_cast<std::size_t>(t)] = {(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3, (a.z + b.z + c.z) / 3};
    if (!(len > 0) || !std::isfinite(len)) continue;  // never opposes anything: left out
    normal_[static_cast<std::size_t>(t)] = {n.x / len, n.y / len, n.z / len};
    tris_.push_back(t);
  }
  if (!tris_.empty()) {
    nodes_.reserve(2 * tris_.size());
    build(0, static_cast<Index>(tris_.size()));
  }
}

// Node over tris_[first, first + count): its box, then (more than 4 triangles) the two halves by
// the median centroid along the box's longest axis (ties broken by triangle index: deterministic).
Index WallThickness::build(Index first, Index count) {
  const Index id = static_cast<Index>(nodes_.size());
  nodes_.push_back(Node{});
  Node nd;
  for (int k = 0; k < 3; ++k) {
    nd.lo[k] = std::numeric_limits<double>::infinity();
    nd.hi[k] = -std::numeric_limits<double>::infinity();
  }
  for (Index i = first; i < first + count; ++i) {
    const Index t = tris_[static_cast<std::size_t>(i)];
    for (int c = 0; c < 3; ++c) {
      const Vec3 q = s_.point(s_.tri[3 * t + c]);
      for (int k = 0; k < 3; ++k) {
        nd.lo[k] = std::min(nd.lo[k], q[k]);
        nd.hi[k] = std::max(nd.hi[k], q[k]);
      }
    }
  }
  nd.first = first;
  nd.count = count;
  nd.left = nd.right = -1;
  if (count > 4) {
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (nd.hi[k] - nd.lo[k] > nd.hi[axis] - nd.lo[axis]) axis = k;
    const Index half = count / 2;
    auto begin = tris_.begin() + first;
    std::nth_element(begin, begin + half, begin + count, [&](Index a, Index b) {
      const double ca = centroid_[static_cast<std::size_t>(a)][axis], cb = centroid_[static_cast<std::size_t>(b)][axis];
      return ca < cb || (ca == cb && a < b);
    });
    nd.count = -1;
    nd.left = build(first, half);
    nd.right = build(first + half, count - half);
  }
  nodes_[static_cast<std::size_t>(id)] = nd;
  return id;
}

double WallThickness::at(const Vec3& p, const Vec3& n, const std::vector<Index>& own, double reach) const {
  if (nodes_.empty() || !(reach > 0)) return std::numeric_limits<double>::infinity();
  double best2 = reach * reach;  // infinite reach: every triangle is looked at
  bool found = false;
  if (++stamp_ == 0) {
    std::fill(seen_.begin(), seen_.end(), 0);
    stamp_ = 1;
  }
  for (Index t : own)
    if (t >= 0 && static_cast<std::size_t>(t) < seen_.size()) seen_[static_cast<std::size_t>(t)] = stamp_;
  auto box_distance2 = [&](const Node& nd) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = p[k] < nd.lo[k] ? nd.lo[k] - p[k] : (p[k] > nd.hi[k] ? p[k] - nd.hi[k] : 0);
      d2 += d * d;
    }
    return d2;
  };
  std::vector<Index> stack{0};
  while (!stack.empty()) {
    const Node& nd = nodes_[static_cast<std::size_t>(stack.back())];
    stack.pop_back();
    if (!(box_distance2(nd) < best2)) continue;
    if (nd.count < 0) {
      // Nearer child last (visited first), so the bound tightens early.
      const Node& l = nodes_[static_cast<std::size_t>(nd.left)];
      const Node& r = nodes_[static_cast<std::size_t>(nd.right)];
      if (box_distance2(l) < box_distance2(r)) {
        stack.push_back(nd.right);
        stack.push_back(nd.left);
      } else {
        stack.push_back(nd.left);
        stack.push_back(nd.right);
      }
      continue;
    }
    for (Index i = nd.first; i < nd.first + nd.count; ++i) {
      const Index t = tris_[static_cast<std::size_t>(i)];
      if (seen_[static_cast<std::size_t>(t)] == stamp_) continue;
      const Vec3& m = normal_[static_cast<std::size_t>(t)];
      if (!(dot(m, n) < -0.5)) continue;
      Vec3 q;
      const double d2 = point_triangle_squared_distance(p, s_.point(s_.tri[3 * t]), s_.point(s_.tri[3 * t + 1]),
                                                        s_.point(s_.tri[3 * t + 2]), &q);
      if (!(d2 > 0) || !(d2 < best2)) continue;
      const Vec3 pq = sub(q, p);
      if (!(dot(pq, n) < 0) || !(dot(pq, m) > 0)) continue;
      best2 = d2;
      found = true;
    }
  }
  return found ? std::sqrt(best2) : std::numeric_limits<double>::infinity();
}

}  // namespace bsptet
