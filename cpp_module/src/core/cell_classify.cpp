// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/cell_classify.h"

#include <deque>
#include <limits>
#include <string>

#include "bsptet/numerics/errors.h"

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
  // Nodes of the propagation: cells 0..#cells-1, then the untouched seed tets.
  const UntouchedSeedTets& ut = bsp.untouched();
  const Index nc = static_cast<Index>(cells.size());
  const Index nu = static_cast<Index>(ut.tets.size());
  std::vector<int> w(static_cast<std::size_t>(nc + nu), kUnset);
  std::deque<Index> queue;
  auto reach = [&](Index node, int value, Index blame_tri) {
    if (w[node] == kUnset) {
      w[node] = value;
      queue.push_back(node);
    } else if (w[node] != value) {
      throw InputError(ErrorCode::kInconsistentOrientation, "classify", blame_tri,
                       "the surface does not bound a solid near input triangle " + std::to_string(blame_tri) +
                           ": it is open, inconsistently oriented, or self-intersecting there");
    }
  };
  auto blame = [&](Index f) -> Index {
    if (cover_tri[f] >= 0) return cover_tri[f];
    return faces[f].coplanar.empty() ? -1 : faces[f].coplanar[0];
  };
  // Winding 0 next to the box: cells with a face whose other side is outside the box, untouched
  // tets with a face on the box's hull.
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (!faces[f].alive || bsp.face_untouched(static_cast<Index>(f)) >= 0) continue;
    for (int s = 0; s < 2; ++s)
      if (faces[f].cell[s] < 0 && faces[f].cell[1 - s] >= 0 && w[faces[f].cell[1 - s]] == kUnset) {
        w[faces[f].cell[1 - s]] = 0;
        queue.push_back(faces[f].cell[1 - s]);
      }
  }
  for (Index u = 0; u < nu; ++u)
    for (int i = 0; i < 4; ++i)
      if (ut.adj[u][i] == -1 && w[nc + u] == kUnset) {
        w[nc + u] = 0;
        queue.push_back(nc + u);
      }
  while (!queue.empty()) {
    const Index node = queue.front();
    queue.pop_front();
    if (node >= nc) {
      const Index u = node - nc;
      for (int i = 0; i < 4; ++i) {
        const Index a = ut.adj[u][i];
        if (a == -1) continue;
        if (a >= 0) {
          reach(nc + a, w[node] + ut.step[u][i], ut.cover[u][i]);
          continue;
        }
        // A complex face with this tet on its cell -1 side.
        const Index f = -2 - a;
        const BspFace& face = faces[f];
        const int cov = out.coverage[f];
        if (face.cell[1] < 0)
          reach(face.cell[0], w[node] - cov, blame(f));
        else
          reach(face.cell[1], w[node] + cov, blame(f));
      }
      continue;
    }
    const Index c = node;
    for (Index f : cells[c].faces) {
      const BspFace& face = faces[f];
      const int cov = out.coverage[f];
      const Index u = bsp.face_untouched(f);
      if (face.cell[0] < 0 || face.cell[1] < 0) {
        if (u < 0) continue;  // outside the box
        if (face.cell[0] == c)
          reach(nc + u, w[c] + cov, blame(f));
        else
          reach(nc + u, w[c] - cov, blame(f));
        continue;
      }
      if (face.cell[0] == c)
        reach(face.cell[1], w[c] + cov, blame(f));
      else
        reach(face.cell[0], w[c] - cov, blame(f));
    }
  }
  auto check_winding = [&](int wn, Index t) {
    if (wn != 0 && wn != 1)
      throw InputError(wn < 0 ? ErrorCode::kInwardFacing : ErrorCode::kSelfIntersection, "classify", t,
                       wn < 0 ? "the surface faces inward near input triangle " + std::to_string(t) +
                                    " (its triangles are oriented clockwise seen from outside; re-orient them)"
                              : "the surface overlaps itself near input triangle " + std::to_string(t) +
                                    " (nested or intersecting shells: winding number " + std::to_string(wn) + ")");
  };
  out.untouched_winding.assign(w.begin() + nc, w.end());
  w.resize(static_cast<std::size_t>(nc));
  out.winding = std::move(w);
  for (Index u = 0; u < nu; ++u) {
    if (out.untouched_winding[u] == kUnset)
      throw MeshingError(ErrorCode::kInternal, "classify", u, "untouched seed tet not reached");
    Index t = -1;
    for (int i = 0; i < 4; ++i)
      if (ut.cover[u][i] >= 0) t = ut.cover[u][i];
    check_winding(out.untouched_winding[u], t);
  }
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!cells[c].alive) {
      out.winding[c] = 0;
      continue;
    }
    if (out.winding[c] == kUnset)
      throw MeshingError(ErrorCode::kInternal, "classify", static_cast<std::int64_t>(c), "cell not reached");
    Index t = -1;
    for (Index f : cells[c].faces)
      if (out.coverage[f] != 0) t = blame(f);
    check_winding(out.winding[c], t);
  }
  return out;
}

}  // namespace bsptet
