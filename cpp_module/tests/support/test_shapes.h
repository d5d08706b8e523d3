// SPDX-License-Identifier: LGPL-2.1-or-later
// Small closed surfaces built in the tests (shared by several test files).
#pragma once

#include "bsptet/mesh/types.h"

namespace bsptet_test {

// An axis-aligned cube [x0, x0 + s]^3 appended to m: 8 points and 12 triangles, outward
// (counter-clockwise seen from outside) unless `inward`.
inline void add_box(bsptet::SurfaceMesh& m, double x0, double s, bool inward = false) {
  using bsptet::Index;
  const Index base = m.num_points();
  for (int i = 0; i < 8; ++i)
    m.xyz.insert(m.xyz.end(), {x0 + s * (i & 1), x0 + s * ((i >> 1) & 1), x0 + s * ((i >> 2) & 1)});
  const Index f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : f) {
    if (inward) m.tri.insert(m.tri.end(), {base + t[0], base + t[2], base + t[1]});
    else m.tri.insert(m.tri.end(), {base + t[0], base + t[1], base + t[2]});
  }
}

}  // namespace bsptet_test
