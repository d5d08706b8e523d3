// SPDX-License-Identifier: LGPL-2.1-or-later
// Fuzz target: the input surface check (surface_check.h) on small arbitrary triangle soups: up to
// 12 points on a small grid (ties, collinear and coplanar points on purpose) and up to 24
// triangles with indices that may be out of range. Only InputError may come out. When the check
// passes, its promises are verified independently: every edge in exactly two triangles, in opposite
// directions. The self-intersection search (a hierarchy) is compared with all pairs.
#include <algorithm>
#include <map>
#include <utility>

#include "bsptet/numerics/errors.h"
#include "bsptet/input/self_intersection.h"
#include "bsptet/input/surface_check.h"
#include "bsptet/input/triangle_intersection.h"
#include "fuzz_input.h"

using namespace bsptet;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bsptet_fuzz::Bytes in(data, size);
  const int np = 1 + in.byte() % 12, nt = 1 + in.byte() % 24;
  const bool reorient = in.byte() & 1;
  SurfaceMesh s;
  for (int i = 0; i < 3 * np; ++i) s.xyz.push_back(bsptet_fuzz::coordinate(in));
  for (int i = 0; i < 3 * nt; ++i) s.tri.push_back(static_cast<Index>(in.byte() % (np + 2)) - 1);
  // Differential: the hierarchy finds exactly the pairs all-pairs testing finds (on valid indices,
  // merged points, no degenerate triangle: the preconditions).
  bool indices_ok = true;
  for (Index v : s.tri) indices_ok = indices_ok && v >= 0 && v < np;
  if (indices_ok) {
    std::map<std::array<double, 3>, Index> first;
    SurfaceMesh m = s;
    for (auto& v : m.tri) v = first.emplace(std::array<double, 3>{s.xyz[3 * v], s.xyz[3 * v + 1], s.xyz[3 * v + 2]}, v).first->second;
    bool degenerate = false;
    for (Index t = 0; t < nt && !degenerate; ++t) {
      const Vec3 a = m.point(m.tri[3 * t]), b = m.point(m.tri[3 * t + 1]), c = m.point(m.tri[3 * t + 2]);
      try {
        SurfaceMesh one;
        one.xyz = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
        one.tri = {0, 1, 2};
        check_surface(one);
      } catch (const InputError& e) {
        degenerate = e.code() == ErrorCode::kDegenerateTriangle;
      }
    }
    if (!degenerate) {
      std::vector<std::array<Index, 2>> brute;
      for (Index a = 0; a < nt; ++a)
        for (Index b = a + 1; b < nt; ++b) {
          IndexedTriangle ta, tb;
          for (int k = 0; k < 3; ++k) {
            ta.id[k] = m.tri[3 * a + k];
            ta.p[k] = m.point(ta.id[k]);
            tb.id[k] = m.tri[3 * b + k];
            tb.p[k] = m.point(tb.id[k]);
          }
          // Symmetric by definition: the test must not depend on the order.
          const bool ab = triangles_intersect(ta, tb), ba = triangles_intersect(tb, ta);
          fuzz_require(ab == ba);
          if (ab) brute.push_back({a, b});
        }
      bool complete = false;
      const auto found = find_self_intersections(m, 1000, &complete);
      fuzz_require(complete);
      fuzz_require(found == brute);
    }
  }
  try {
    SurfaceCheckOptions o;
    o.reorient = reorient;
    const SurfaceCheckResult r = check_surface(s, o);
    fuzz_require(r.tri.size() == s.tri.size());
    std::map<std::pair<Index, Index>, int> directed;
    std::map<std::array<double, 3>, Index> first;
    std::vector<Index> canon(np);
    for (int i = 0; i < np; ++i)
      canon[i] = first.emplace(std::array<double, 3>{s.xyz[3 * i] + 0.0, s.xyz[3 * i + 1] + 0.0, s.xyz[3 * i + 2] + 0.0}, i)
                     .first->second;
    for (int t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) ++directed[{canon[r.tri[3 * t + k]], canon[r.tri[3 * t + (k + 1) % 3]]}];
    for (const auto& [e, n] : directed) {
      fuzz_require(n == 1);
      const auto back = directed.find({e.second, e.first});
      fuzz_require(back != directed.end() && back->second == 1);
    }
    if (!reorient) fuzz_require(r.flipped_triangles == 0 && r.tri == s.tri);
  } catch (const InputError&) {
  }
  return 0;
}
