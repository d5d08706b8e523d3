// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/input/surface_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <numeric>
#include <tuple>
#include <utility>

#include "bsptet/numerics/exact_float.h"
#include "bsptet/numerics/predicates.h"
#include "bsptet/input/self_intersection.h"
#include "bsptet/input/triangle_intersection.h"

namespace bsptet {

namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string tri_str(const std::vector<Index>& tri, Index t) {
  return "triangle " + std::to_string(t) + " (vertices " + std::to_string(tri[3 * t]) + " " +
         std::to_string(tri[3 * t + 1]) + " " + std::to_string(tri[3 * t + 2]) + ")";
}

std::string point_str(const SurfaceMesh& s, Index v) {
  return "(" + num(s.xyz[3 * v]) + ", " + num(s.xyz[3 * v + 1]) + ", " + num(s.xyz[3 * v + 2]) + ")";
}

std::string in_all(std::int64_t count, const char* what) {
  return count > 1 ? " (" + std::to_string(count) + " " + what + " in all)" : std::string();
}

[[noreturn]] void fail(ErrorCode code, std::int64_t index, const std::string& message) {
  throw InputError(code, "input", index, message);
}

struct UnionFind {
  std::vector<Index> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  Index find(Index x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(Index a, Index b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // smallest index is the root: deterministic
  }
};

// One use of an undirected edge {lo, hi} by triangle t; forward when t runs lo -> hi.
struct EdgeUse {
  Index lo, hi, t;
  bool forward;
};

// Sorts `v` as std::sort(v, less) would, for a `less` that orders first by bucket(x) in [0, n):
// a counting sort into the buckets, then each bucket (a vertex's edges or corners: a few) sorted.
// Linear in |v| + n: on a structured surface of 10^6 triangles std::sort fell back to heap sort
// and made most of this check's time.
template <class T, class Bucket, class Less>
void sort_by_buckets(std::vector<T>& v, std::size_t n, Bucket bucket, Less less) {
  std::vector<std::size_t> start(n + 1, 0);
  for (const T& x : v) ++start[static_cast<std::size_t>(bucket(x)) + 1];
  for (std::size_t b = 0; b < n; ++b) start[b + 1] += start[b];
  std::vector<T> out(v.size());
  std::vector<std::size_t> fill(start.begin(), start.end() - 1);
  for (const T& x : v) out[fill[static_cast<std::size_t>(bucket(x))]++] = x;
  for (std::size_t b = 0; b < n; ++b)
    if (start[b + 1] - start[b] > 1)
      std::sort(out.begin() + static_cast<std::ptrdiff_t>(start[b]), out.begin() + static_cast<std::ptrdiff_t>(start[b + 1]), less);
  v = std::move(out);
}

// Sign of the signed volume enclosed by the triangles `tris` of `s` (6 x volume, in any case the
// sign): sum of det[a - o, b - o, c - o] over the triangles, o a fixed point. A floating-point sum
// with a bound on its error decides when it can; otherwise the sum is exact.
int volume_sign(const SurfaceMesh& s, const std::vector<Index>& tri, const std::vector<Index>& tris) {
  const Vec3 o = s.point(tri[3 * tris[0]]);
  double sum = 0, abs_sum = 0, perm_sum = 0;
  for (Index t : tris) {
    const Vec3 a = s.point(tri[3 * t]), b = s.point(tri[3 * t + 1]), c = s.point(tri[3 * t + 2]);
    const double ax = a.x - o.x, ay = a.y - o.y, az = a.z - o.z;
    const double bx = b.x - o.x, by = b.y - o.y, bz = b.z - o.z;
    const double cx = c.x - o.x, cy = c.y - o.y, cz = c.z - o.z;
    const double m1 = by * cz, m2 = bz * cy, m3 = bx * cz, m4 = bz * cx, m5 = bx * cy, m6 = by * cx;
    const double det = ax * (m1 - m2) - ay * (m3 - m4) + az * (m5 - m6);
    sum += det;
    abs_sum += std::fabs(det);
    perm_sum += std::fabs(ax) * (std::fabs(m1) + std::fabs(m2)) + std::fabs(ay) * (std::fabs(m3) + std::fabs(m4)) +
                std::fabs(az) * (std::fabs(m5) + std::fabs(m6));
  }
  constexpr double u = 1.1102230246251565e-16;
  const double n = static_cast<double>(tris.size());
  // Each det within 8u * its permanent (as in orient3d; the differences to o are rounded too, which
  // the factor 2 below covers), then the summation error, at most 2n u times the sum of |det|.
  const double bound = 16 * u * perm_sum + 2 * (n + 2) * u * (abs_sum + 16 * u * perm_sum);
  if (std::isfinite(perm_sum) && perm_sum > 1e-250 && std::fabs(sum) > bound) return sum > 0 ? 1 : -1;
  const ExactFloat ox(o.x), oy(o.y), oz(o.z);
  ExactFloat total;
  for (Index t : tris) {
    const Vec3 a = s.point(tri[3 * t]), b = s.point(tri[3 * t + 1]), c = s.point(tri[3 * t + 2]);
    const ExactFloat ax = ExactFloat(a.x) - ox, ay = ExactFloat(a.y) - oy, az = ExactFloat(a.z) - oz;
    const ExactFloat bx = ExactFloat(b.x) - ox, by = ExactFloat(b.y) - oy, bz = ExactFloat(b.z) - oz;
    const ExactFloat cx = ExactFloat(c.x) - ox, cy = ExactFloat(c.y) - oy, cz = ExactFloat(c.z) - oz;
    total += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
  }
  return total.sign();
}

struct Shell {
  std::vector<Index> tris;  // ascending
  double lo[3], hi[3];      // bounding box
  Index sample_vertex;      // a vertex of the shell (the first corner of its first triangle)
};

bool box_contains(const Shell& outer, const Shell& inner) {
  for (int k = 0; k < 3; ++k)
    if (inner.lo[k] < outer.lo[k] || inner.hi[k] > outer.hi[k]) return false;
  return true;
}

// Whether point p (not on the shell) lies inside the closed shell `sh`: the parity of the
// crossings of a segment from p to a point outside the shell's box. Directions are tried in a
// fixed order until one meets no edge, vertex or plane degenerately.
bool inside_shell(const SurfaceMesh& s, const std::vector<Index>& tri, const Shell& sh, const Vec3& p) {
  double extent = 0;
  for (int k = 0; k < 3; ++k) extent = std::max(extent, sh.hi[k] - sh.lo[k]);
  const double len = 4 * extent;
  for (int attempt = 0; attempt < 256; ++attempt) {
    // Fixed irrational-looking slopes: the golden-ratio sequence in [-1, 1].
    const double a = 2 * std::fmod(0.6180339887498949 * (attempt + 1), 1.0) - 1;
    const double b = 2 * std::fmod(0.7548776662466927 * (attempt + 1), 1.0) - 1;
    const int axis = attempt % 3;
    const double sign = (attempt / 3) % 2 == 0 ? 1.0 : -1.0;
    double d[3];
    d[axis] = sign;
    d[(axis + 1) % 3] = a;
    d[(axis + 2) % 3] = b;
    const Vec3 q{p.x + d[0] * len, p.y + d[1] * len, p.z + d[2] * len};
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) continue;
    // q must be outside the box (strictly beyond it along `axis`).
    if (!(q[axis] > sh.hi[axis] || q[axis] < sh.lo[axis])) continue;
    int crossings = 0;
    bool degenerate = false;
    for (Index t : sh.tris) {
      const Vec3 ta = s.point(tri[3 * t]), tb = s.point(tri[3 * t + 1]), tc = s.point(tri[3 * t + 2]);
      const SegmentTriangleContact c = classify_segment_triangle(p, q, ta, tb, tc);
      if (c == SegmentTriangleContact::kDegenerate) {
        degenerate = true;
        break;
      }
      if (c == SegmentTriangleContact::kCrossing) ++crossings;
    }
    if (!degenerate) return crossings % 2 == 1;
  }
  throw MeshingError(ErrorCode::kInternal, "input", -1,
                     "could not find a ray that decides whether a shell lies inside another; please report it");
}

// Step 9 on the surface `m` whose coincident points are merged; `input_tri` are the caller's
// triangles (the message names their vertex indices).
void self_intersections_of_merged(const SurfaceMesh& m, const std::vector<Index>& input_tri,
                                  const SurfaceCheckOptions& options) {
  bool complete = true;
  auto pairs = find_self_intersections(m, std::max<std::int64_t>(1, options.max_reported_pairs), &complete);
  if (!pairs.empty()) {
    std::string list;
    for (std::size_t i = 0; i < pairs.size() && i < 5; ++i)
      list += (i ? ", " : "") + std::to_string(pairs[i][0]) + " and " + std::to_string(pairs[i][1]);
    if (pairs.size() > 5) list += ", ...";
    const std::string count = (complete ? "" : "at least ") + std::to_string(pairs.size());
    const Index first = pairs[0][0];
    // The message first: the pairs are moved into the exception.
    const std::string message =
        "the surface intersects itself: " + count + (pairs.size() == 1 ? " pair" : " pairs") +
        " of triangles cross or touch (triangles " + list + "); " + tri_str(input_tri, pairs[0][0]) + " meets " +
        tri_str(input_tri, pairs[0][1]) + ". Repair the surface (fembsptet mesh --write-intersections FILE "
        "writes these triangles out for viewing)";
    throw SelfIntersectionError(first, message, std::move(pairs), complete);
  }
}

}  // namespace

SurfaceMesh merge_coincident_points(const SurfaceMesh& in, std::int64_t* merged) {
  const Index np = in.num_points();
  std::vector<Index> order(static_cast<std::size_t>(np));
  for (Index i = 0; i < np; ++i) order[i] = i;
  auto coords = [&](Index i) {
    return std::array<double, 3>{in.xyz[3 * i] + 0.0, in.xyz[3 * i + 1] + 0.0, in.xyz[3 * i + 2] + 0.0};
  };
  std::sort(order.begin(), order.end(), [&](Index a, Index b) {
    const auto ca = coords(a), cb = coords(b);
    return ca != cb ? ca < cb : a < b;
  });
  std::vector<Index> canon(static_cast<std::size_t>(np));
  std::int64_t count = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const bool same = k > 0 && coords(order[k]) == coords(order[k - 1]);
    canon[order[k]] = same ? canon[order[k - 1]] : order[k];
    count += same;
  }
  if (merged) *merged = count;
  SurfaceMesh out = in;
  if (count > 0)
    for (auto& v : out.tri) v = canon[v];
  return out;
}

void check_self_intersections(const SurfaceMesh& surface, const SurfaceCheckOptions& options) {
  self_intersections_of_merged(merge_coincident_points(surface), surface.tri, options);
}

SurfaceCheckResult check_surface(const SurfaceMesh& in, const SurfaceCheckOptions& options) {
  if (in.tri.size() % 3 != 0 || in.xyz.size() % 3 != 0)
    fail(ErrorCode::kBadArgument, -1, "the point and triangle arrays must have 3 columns");
  const Index np = in.num_points(), nt = in.num_triangles();
  if (nt == 0) fail(ErrorCode::kBadArgument, -1, "the surface has no triangles");
  // 2. finite coordinates
  for (Index i = 0; i < np; ++i)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(in.xyz[3 * i + k])) {
        std::int64_t count = 0;
        for (Index j = 0; j < np; ++j)
          count += !(std::isfinite(in.xyz[3 * j]) && std::isfinite(in.xyz[3 * j + 1]) &&
                     std::isfinite(in.xyz[3 * j + 2]));
        fail(ErrorCode::kNonFiniteCoordinate, i,
             "vertex " + std::to_string(i) + " has a non-finite coordinate " + point_str(in, i) +
                 in_all(count, "such vertices") + "; every coordinate must be a finite number");
      }
  // 3. indices
  for (Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const Index v = in.tri[3 * t + k];
      if (v < 0)
        fail(ErrorCode::kBadArgument, t,
             "triangle " + std::to_string(t) + " refers to negative vertex index " + std::to_string(v));
      if (v >= np)
        fail(ErrorCode::kBadArgument, t,
             "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                 ", which is out of range: the surface has " + std::to_string(np) + " vertices (0.." +
                 std::to_string(np - 1) + ")");
    }
  SurfaceCheckResult result;
  result.tri = in.tri;
  // Points with identical coordinates are one vertex (first index wins); -0.0 equals 0.0.
  const SurfaceMesh m = merge_coincident_points(in, &result.merged_points);
  // 4. degenerate triangles
  {
    Index first_bad = -1;
    std::int64_t count = 0;
    bool repeated = false;
    for (Index t = 0; t < nt; ++t) {
      const Index a = m.tri[3 * t], b = m.tri[3 * t + 1], c = m.tri[3 * t + 2];
      const bool same = a == b || b == c || a == c;
      bool flat = same;
      if (!same) {
        const Vec3 pa = m.point(a), pb = m.point(b), pc = m.point(c);
        flat = orient2d_projected(pa, pb, pc, 0) == Sign::kZero && orient2d_projected(pa, pb, pc, 1) == Sign::kZero &&
               orient2d_projected(pa, pb, pc, 2) == Sign::kZero;
      }
      if (flat) {
        if (first_bad < 0) {
          first_bad = t;
          repeated = same;
        }
        ++count;
      }
    }
    if (first_bad >= 0)
      fail(ErrorCode::kDegenerateTriangle, first_bad,
           tri_str(in.tri, first_bad) + " is degenerate (zero area: " +
               (repeated ? "two of its corners are the same point" : "its corners are collinear") + ")" +
               in_all(count, "degenerate triangles") + "; remove it or repair the surface");
  }
  // 5. duplicates (either orientation)
  {
    std::vector<std::pair<std::array<Index, 3>, Index>> keys(nt);
    for (Index t = 0; t < nt; ++t) {
      std::array<Index, 3> k = {m.tri[3 * t], m.tri[3 * t + 1], m.tri[3 * t + 2]};
      std::sort(k.begin(), k.end());
      keys[t] = {k, t};
    }
    sort_by_buckets(keys, static_cast<std::size_t>(np), [](const auto& kt) { return kt.first[0]; }, std::less<>());
    Index dup = -1, of = -1;
    std::int64_t count = 0;
    for (std::size_t i = 1; i < keys.size(); ++i)
      if (keys[i].first == keys[i - 1].first) {
        ++count;
        if (dup < 0 || keys[i].second < dup) {
          dup = keys[i].second;
          std::size_t j = i;
          while (j > 0 && keys[j - 1].first == keys[i].first) --j;
          of = keys[j].second;
        }
      }
    if (dup >= 0)
      fail(ErrorCode::kDuplicateTriangle, dup,
           tri_str(in.tri, dup) + " duplicates triangle " + std::to_string(of) + " (same three vertices)" +
               in_all(count, "duplicate triangles") + "; remove one of them");
  }
  // 6. edges: exactly two triangles each
  std::vector<EdgeUse> uses;
  uses.reserve(static_cast<std::size_t>(nt) * 3);
  for (Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const Index a = m.tri[3 * t + k], b = m.tri[3 * t + (k + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), t, a < b});
    }
  sort_by_buckets(uses, static_cast<std::size_t>(np), [](const EdgeUse& u) { return u.lo; },
                  [](const EdgeUse& x, const EdgeUse& y) { return std::tie(x.lo, x.hi, x.t) < std::tie(y.lo, y.hi, y.t); });
  struct EdgeRun {
    std::size_t begin, end;
  };
  std::vector<EdgeRun> edges;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    edges.push_back({i, j});
    i = j;
  }
  auto edge_str = [&](const EdgeRun& e) {
    return "edge (" + std::to_string(uses[e.begin].lo) + " " + std::to_string(uses[e.begin].hi) + ")";
  };
  {
    // Report the problem edge whose lowest triangle index is smallest (deterministic, and near the
    // start of the file).
    const EdgeRun* open = nullptr;
    const EdgeRun* over = nullptr;
    std::int64_t open_count = 0, over_count = 0;
    for (const EdgeRun& e : edges) {
      const std::size_t n = e.end - e.begin;
      if (n == 1) {
        ++open_count;
        if (!open || uses[e.begin].t < uses[open->begin].t) open = &e;
      } else if (n > 2) {
        ++over_count;
        if (!over || uses[e.begin].t < uses[over->begin].t) over = &e;
      }
    }
    if (open)
      fail(ErrorCode::kOpenBoundary, uses[open->begin].t,
           edge_str(*open) + " of " + tri_str(in.tri, uses[open->begin].t) +
               " is used by only one triangle: the surface is open there" + in_all(open_count, "open edges") +
               "; close the hole so that every edge has two triangles");
    if (over) {
      std::string list;
      for (std::size_t i = over->begin; i < over->end && i < over->begin + 6; ++i)
        list += (i > over->begin ? ", " : "") + std::to_string(uses[i].t);
      if (over->end - over->begin > 6) list += ", ...";
      fail(ErrorCode::kNonManifold, uses[over->begin].t,
           edge_str(*over) + " is a non-manifold edge: it is shared by " + std::to_string(over->end - over->begin) +
               " triangles (" + list + ")" + in_all(over_count, "non-manifold edges") +
               "; every edge of a solid's surface must belong to exactly two triangles");
    }
  }
  // Shells: triangles connected through edges.
  UnionFind shell_of(static_cast<std::size_t>(nt));
  for (const EdgeRun& e : edges) shell_of.unite(uses[e.begin].t, uses[e.begin + 1].t);
  // 7. orientation
  std::vector<char> flip(nt, 0);
  {
    const EdgeRun* bad = nullptr;
    std::int64_t count = 0;
    for (const EdgeRun& e : edges)
      if (uses[e.begin].forward == uses[e.begin + 1].forward) {
        ++count;
        if (!bad || uses[bad->begin].t > uses[e.begin].t) bad = &e;
      }
    if (bad && !options.reorient)
      fail(ErrorCode::kInconsistentOrientation, uses[bad->begin + 1].t,
           "triangles " + std::to_string(uses[bad->begin].t) + " and " + std::to_string(uses[bad->begin + 1].t) +
               " use " + edge_str(*bad) + " in the same direction: their orientations are inconsistent" +
               in_all(count, "such edges") + "; re-orient the surface (fembsptet mesh --reorient)");
    if (bad) {
      // Breadth-first over each shell from its smallest triangle, which keeps its orientation.
      std::vector<std::vector<std::pair<Index, bool>>> nbr(nt);  // (neighbour, same direction on the edge)
      for (const EdgeRun& e : edges) {
        const EdgeUse &x = uses[e.begin], &y = uses[e.begin + 1];
        nbr[x.t].push_back({y.t, x.forward == y.forward});
        nbr[y.t].push_back({x.t, x.forward == y.forward});
      }
      std::vector<char> seen(nt, 0);
      std::vector<Index> queue;
      for (Index root = 0; root < nt; ++root) {
        if (seen[root]) continue;
        seen[root] = 1;
        queue.assign(1, root);
        for (std::size_t qi = 0; qi < queue.size(); ++qi) {
          const Index t = queue[qi];
          for (const auto& [u, same] : nbr[t]) {
            const char want = static_cast<char>(flip[t] ^ (same ? 1 : 0));
            if (!seen[u]) {
              seen[u] = 1;
              flip[u] = want;
              queue.push_back(u);
            } else if (flip[u] != want) {
              fail(ErrorCode::kInconsistentOrientation, u,
                   "the shell of " + tri_str(in.tri, root) + " cannot be oriented consistently (it is one-sided, "
                   "like a Moebius strip), found at " + tri_str(in.tri, u) + "; it cannot bound a solid");
            }
          }
        }
      }
    }
  }
  // 8. non-manifold vertices: the corners at a vertex must form one fan through shared edges.
  {
    UnionFind corners(static_cast<std::size_t>(nt) * 3);
    auto corner = [&](Index t, Index v) {
      for (int k = 0; k < 3; ++k)
        if (m.tri[3 * t + k] == v) return 3 * t + k;
      return 3 * t;  // unreachable
    };
    for (const EdgeRun& e : edges) {
      const EdgeUse &x = uses[e.begin], &y = uses[e.begin + 1];
      corners.unite(corner(x.t, x.lo), corner(y.t, x.lo));
      corners.unite(corner(x.t, x.hi), corner(y.t, x.hi));
    }
    std::vector<std::pair<Index, Index>> vertex_fan;  // (vertex, fan root)
    vertex_fan.reserve(static_cast<std::size_t>(nt) * 3);
    for (Index c = 0; c < 3 * nt; ++c) vertex_fan.push_back({m.tri[c], corners.find(c)});
    sort_by_buckets(vertex_fan, static_cast<std::size_t>(np), [](const auto& vf) { return vf.first; }, std::less<>());
    vertex_fan.erase(std::unique(vertex_fan.begin(), vertex_fan.end()), vertex_fan.end());
    Index bad = -1;
    std::int64_t count = 0, fans = 0;
    std::array<Index, 2> example{-1, -1};
    for (std::size_t i = 0; i < vertex_fan.size();) {
      std::size_t j = i;
      while (j < vertex_fan.size() && vertex_fan[j].first == vertex_fan[i].first) ++j;
      if (j - i > 1) {
        ++count;
        if (bad < 0) {
          bad = vertex_fan[i].first;
          fans = static_cast<std::int64_t>(j - i);
          example = {vertex_fan[i].second / 3, vertex_fan[i + 1].second / 3};
        }
      }
      i = j;
    }
    if (bad >= 0)
      fail(ErrorCode::kNonManifold, bad,
           "vertex " + std::to_string(bad) + " " + point_str(m, bad) + " is a non-manifold vertex: the triangles around it form " +
               std::to_string(fans) + " separate fans (e.g. triangles " + std::to_string(example[0]) + " and " +
               std::to_string(example[1]) + "); the surface pinches there" + in_all(count, "non-manifold vertices") +
               "; separate the parts or join them along a face");
  }
  // 9. self-intersections
  if (options.self_intersections) self_intersections_of_merged(m, in.tri, options);
  // 10. shells face the right way
  {
    std::map<Index, std::size_t> shell_index;  // root -> position (roots ascend with their smallest triangle)
    std::vector<Shell> shells;
    for (Index t = 0; t < nt; ++t) {
      const Index r = shell_of.find(t);
      auto it = shell_index.find(r);
      if (it == shell_index.end()) {
        it = shell_index.emplace(r, shells.size()).first;
        Shell sh;
        sh.sample_vertex = m.tri[3 * t];
        for (int k = 0; k < 3; ++k) sh.lo[k] = sh.hi[k] = m.xyz[3 * sh.sample_vertex + k];
        shells.push_back(sh);
      }
      Shell& sh = shells[it->second];
      sh.tris.push_back(t);
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) {
          sh.lo[k] = std::min(sh.lo[k], m.xyz[3 * m.tri[3 * t + c] + k]);
          sh.hi[k] = std::max(sh.hi[k], m.xyz[3 * m.tri[3 * t + c] + k]);
        }
    }
    result.shells = static_cast<std::int64_t>(shells.size());
    // The triangles as they will be: flipped ones reversed (for the volume sign).
    std::vector<Index> oriented = m.tri;
    for (Index t = 0; t < nt; ++t)
      if (flip[t]) std::swap(oriented[3 * t + 1], oriented[3 * t + 2]);
    for (std::size_t i = 0; i < shells.size(); ++i) {
      const Shell& sh = shells[i];
      int depth = 0;
      std::size_t container = shells.size();
      if (shells.size() > 1) {
        const Vec3 p = m.point(sh.sample_vertex);
        for (std::size_t j = 0; j < shells.size(); ++j)
          if (j != i && box_contains(shells[j], sh) && inside_shell(m, oriented, shells[j], p)) {
            ++depth;
            if (container == shells.size()) container = j;
          }
      }
      const int sign = volume_sign(m, oriented, sh.tris);
      const int want = depth % 2 == 0 ? 1 : -1;
      if (sign == want) continue;
      if (options.reorient) {
        for (Index t : sh.tris) flip[t] ^= 1;
        continue;
      }
      const Index t0 = sh.tris[0];
      const std::string which = "the shell of " + tri_str(in.tri, t0) + " (" + std::to_string(sh.tris.size()) +
                                " triangles" + (shells.size() > 1 ? ", shell " + std::to_string(i + 1) + " of " +
                                                                        std::to_string(shells.size())
                                                                  : std::string()) +
                                ")";
      if (depth == 0)
        fail(ErrorCode::kInwardFacing, t0,
             which + " faces inward: its triangles turn clockwise seen from outside (negative enclosed volume); "
                     "flip them (fembsptet mesh --reorient does)");
      fail(ErrorCode::kInwardFacing, t0,
           which + " lies inside the shell of " + tri_str(in.tri, shells[container].tris[0]) +
               (depth % 2 == 1 ? " but faces outward: a cavity's triangles must face into the cavity, or the two "
                                 "solids overlap; flip it if it is a cavity (fembsptet mesh --reorient does)"
                               : " and a cavity around it, but faces inward; flip it (fembsptet mesh --reorient does)"));
    }
  }
  for (Index t = 0; t < nt; ++t)
    if (flip[t]) {
      std::swap(result.tri[3 * t + 1], result.tri[3 * t + 2]);
      ++result.flipped_triangles;
    }
  return result;
}

}  // namespace bsptet
