#include "bsptet/cell_classify.h"

#include <deque>
#include <limits>
#include <string>

#include "bsptet/errors.h"

namespace bsptet {

namespace {

// True when some edge line of polygon A (projected orientation oa) leaves all of B's vertices on
// its closed outer side.
bool separated_by_edges_of(ImplicitGeometry& geo, const std::vector<Index>& a, int oa, const std::vector<Index>& b,
                           int axis) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Index p = a[i], q = a[(i + 1) % a.size()];
    bool all_out = true;
    for (Index y : b)
      if (oa * to_int(geo.orient2d(p, q, y, axis)) > 0) {
        all_out = false;
        break;
      }
    if (all_out) return true;
  }
  return false;
}

}  // namespace

CellLabels classify_cells(BspComplex& bsp) {
  ImplicitGeometry& geo = bsp.geometry();
  const auto& faces = bsp.faces();
  const auto& cells = bsp.cells();
  CellLabels out;
  out.coverage.assign(faces.size(), 0);
  std::vector<Index> cover_tri(faces.size(), -1);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const BspFace& face = faces[f];
    if (!face.alive || face.coplanar.empty()) continue;
    Sign ns = Sign::kZero;
    const int axis = geo.projection_axis(face.plane, &ns);
    for (Index t : face.coplanar) {
      // Input triangle t as three explicit vertices (vertex id == input point id).
      const std::vector<Index> tv = {bsp.triangle_vertex(t, 0), bsp.triangle_vertex(t, 1),
                                     bsp.triangle_vertex(t, 2)};
      const int ot = to_int(geo.orient2d(tv[0], tv[1], tv[2], axis));
      if (separated_by_edges_of(geo, face.verts, to_int(ns), tv, axis) ||
          separated_by_edges_of(geo, tv, ot, face.verts, axis))
        continue;
      const int cov = (ot == to_int(ns)) ? 1 : -1;
      if (out.coverage[f] != 0 && out.coverage[f] != cov)
        throw InputError(ErrorCode::kSelfIntersection, "classify", t,
                         "input triangles " + std::to_string(cover_tri[f]) + " and " + std::to_string(t) +
                             " overlap with opposite orientations (a zero-thickness fold or overlapping shells)");
      out.coverage[f] = cov;
      cover_tri[f] = t;
    }
  }

  constexpr int kUnset = std::numeric_limits<int>::min();
  out.winding.assign(cells.size(), kUnset);
  std::deque<Index> queue;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (!faces[f].alive) continue;
    for (int s = 0; s < 2; ++s)
      if (faces[f].cell[s] < 0 && faces[f].cell[1 - s] >= 0 && out.winding[faces[f].cell[1 - s]] == kUnset) {
        out.winding[faces[f].cell[1 - s]] = 0;
        queue.push_back(faces[f].cell[1 - s]);
      }
  }
  auto blame = [&](Index f) -> Index {
    if (cover_tri[f] >= 0) return cover_tri[f];
    return faces[f].coplanar.empty() ? -1 : faces[f].coplanar[0];
  };
  while (!queue.empty()) {
    const Index c = queue.front();
    queue.pop_front();
    for (Index f : cells[c].faces) {
      const BspFace& face = faces[f];
      if (face.cell[0] < 0 || face.cell[1] < 0) continue;
      const int w0 = out.winding[face.cell[0]], w1 = out.winding[face.cell[1]];
      const int cov = out.coverage[f];
      Index other = -1;
      int expect = 0;
      if (face.cell[0] == c) {
        other = face.cell[1];
        expect = w0 + cov;
      } else {
        other = face.cell[0];
        expect = w1 - cov;
      }
      if (out.winding[other] == kUnset) {
        out.winding[other] = expect;
        queue.push_back(other);
      } else if (out.winding[other] != expect) {
        const Index t = blame(f);
        throw InputError(ErrorCode::kInconsistentOrientation, "classify", t,
                         "the surface does not bound a solid near input triangle " + std::to_string(t) +
                             ": it is open, inconsistently oriented, or self-intersecting there");
      }
    }
  }
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!cells[c].alive) {
      out.winding[c] = 0;
      continue;
    }
    if (out.winding[c] == kUnset)
      throw MeshingError(ErrorCode::kInternal, "classify", static_cast<std::int64_t>(c), "cell not reached");
    if (out.winding[c] != 0 && out.winding[c] != 1) {
      Index t = -1;
      for (Index f : cells[c].faces)
        if (out.coverage[f] != 0) t = blame(f);
      throw InputError(out.winding[c] < 0 ? ErrorCode::kInwardFacing : ErrorCode::kSelfIntersection, "classify", t,
                       out.winding[c] < 0
                           ? "the surface faces inward near input triangle " + std::to_string(t) +
                                 " (its triangles are oriented clockwise seen from outside; re-orient them)"
                           : "the surface overlaps itself near input triangle " + std::to_string(t) +
                                 " (nested or intersecting shells: winding number " +
                                 std::to_string(out.winding[c]) + ")");
    }
  }
  return out;
}

}  // namespace bsptet
