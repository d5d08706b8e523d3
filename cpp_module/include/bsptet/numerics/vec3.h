// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet numerics: the point and the index type every layer works with. A point is three
// doubles; an index (of a point, triangle or tet) is 0-based and 32-bit. The mesh containers that
// hold them are in mesh/types.h.
#pragma once

#include <cstdint>

namespace bsptet {

using Index = std::int32_t;

struct Vec3 {
  double x = 0, y = 0, z = 0;
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

}  // namespace bsptet
