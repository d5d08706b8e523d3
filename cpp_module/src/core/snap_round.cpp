// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/snap_round.h"

#include <string>

#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

TetMesh snap_round(ImplicitGeometry& geo, const std::vector<std::array<Index, 4>>& tets, Index num_input_points,
                   std::int64_t* steiner_points) {
  const Index nv = geo.num_vertices();
  std::vector<Index> out_id(nv, -1);
  std::vector<char> used(nv, 0);
  for (const auto& t : tets)
    for (Index v : t) used[v] = 1;
  TetMesh m;
  Index next = 0;
  for (Index v = 0; v < num_input_points; ++v)
    if (used[v]) {
      out_id[v] = next++;
      const Vec3 p = geo.explicit_point(v);
      m.xyz.insert(m.xyz.end(), {p.x, p.y, p.z});
    }
  std::int64_t steiner = 0;
  for (const auto& t : tets)
    for (Index v : t)
      if (out_id[v] < 0) {
        out_id[v] = next++;
        const Vec3 p = geo.rounded(v);
        m.xyz.insert(m.xyz.end(), {p.x, p.y, p.z});
        ++steiner;
      }
  m.tet.reserve(tets.size() * 4);
  for (std::size_t k = 0; k < tets.size(); ++k) {
    const auto& t = tets[k];
    const Index a = out_id[t[0]], b = out_id[t[1]], c = out_id[t[2]], d = out_id[t[3]];
    if (orient3d(m.point(a), m.point(b), m.point(c), m.point(d)) != Sign::kPositive)
      throw MeshingError(ErrorCode::kInternal, "snap_round", static_cast<std::int64_t>(k),
                         "rounding the Steiner points to doubles inverted or flattened tet " + std::to_string(k) +
                             " (local repair is not implemented yet)");
    m.tet.insert(m.tet.end(), {a, b, c, d});
  }
  if (steiner_points) *steiner_points = steiner;
  return m;
}

}  // namespace bsptet
