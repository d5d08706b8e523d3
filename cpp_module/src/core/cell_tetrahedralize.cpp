// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/cell_tetrahedralize.h"

#include <algorithm>
#include <string>

#include "bsptet/core/cell_delaunay.h"
#include "bsptet/numerics/errors.h"

namespace bsptet {

std::vector<std::array<Index, 3>> triangulate_face(ImplicitGeometry& geo, const BspFace& face) {
  Sign ns = Sign::kZero;
  const int axis = geo.projection_axis(face.plane, &ns);
  std::vector<Index> poly = face.verts;
  std::vector<std::array<Index, 3>> out;
  // Ear clipping on a convex polygon that may have collinear (flat) vertices: clip a strictly
  // convex vertex only if the rest is not degenerate (all on one line), so that every flat vertex
  // stays a vertex of the triangulation.
  while (poly.size() > 3) {
    const std::size_t n = poly.size();
    bool clipped = false;
    for (std::size_t i = 0; i < n && !clipped; ++i) {
      const Index u = poly[(i + n - 1) % n], v = poly[i], w = poly[(i + 1) % n];
      if (geo.orient2d(u, v, w, axis) != ns) continue;  // flat vertex
      bool rest_degenerate = true;
      for (std::size_t j = 0; j < n && rest_degenerate; ++j) {
        const Index y = poly[j];
        if (y == u || y == v || y == w) continue;
        if (geo.orient2d(u, w, y, axis) != Sign::kZero) rest_degenerate = false;
      }
      if (rest_degenerate) continue;
      out.push_back({u, v, w});
      poly.erase(poly.begin() + static_cast<std::ptrdiff_t>(i));
      clipped = true;
    }
    if (!clipped) throw MeshingError(ErrorCode::kInternal, "triangulate", face.plane, "no ear in a convex face");
  }
  if (geo.orient2d(poly[0], poly[1], poly[2], axis) != ns)
    throw MeshingError(ErrorCode::kInternal, "triangulate", face.plane, "degenerate last ear");
  out.push_back({poly[0], poly[1], poly[2]});
  return out;
}

namespace {

// Fan from corner v of a convex face (v must not have a collinear neighbour: checked by the caller).
std::vector<std::array<Index, 3>> fan_face(const BspFace& face, Index v) {
  const auto& p = face.verts;
  const std::size_t n = p.size();
  const std::size_t k = static_cast<std::size_t>(std::find(p.begin(), p.end(), v) - p.begin());
  std::vector<std::array<Index, 3>> out;
  for (std::size_t i = 1; i + 1 < n; ++i) out.push_back({v, p[(k + i) % n], p[(k + i + 1) % n]});
  return out;
}

// An explicit point strictly inside convex cell c (the rounded centroid of its vertices `cv`, then
// points pulled towards each vertex), verified exactly against every face plane.
bool find_explicit_apex(ImplicitGeometry& geo, const std::vector<BspFace>& faces, const BspCell& cell, Index c,
                        const std::vector<Index>& cv, Vec3& apex) {
  std::vector<Vec3> approx;
  Vec3 centroid{0, 0, 0};
  for (Index v : cv) {
    approx.push_back(geo.rounded(v));
    centroid.x += approx.back().x / cv.size();
    centroid.y += approx.back().y / cv.size();
    centroid.z += approx.back().z / cv.size();
  }
  auto strictly_inside = [&](const Vec3& p) {
    for (Index f : cell.faces) {
      const Sign want = faces[f].cell[0] == c ? Sign::kPositive : Sign::kNegative;
      const PlaneDef& pd = geo.plane(faces[f].plane);
      if (orient3d(geo.explicit_point(pd.a), geo.explicit_point(pd.b), geo.explicit_point(pd.c), p) != want)
        return false;
    }
    return true;
  };
  if (strictly_inside(centroid)) {
    apex = centroid;
    return true;
  }
  for (std::size_t k = 0; k < approx.size(); ++k)
    for (double w : {0.5, 0.9, 0.99}) {
      const Vec3 p{w * centroid.x + (1 - w) * approx[k].x, w * centroid.y + (1 - w) * approx[k].y,
                   w * centroid.z + (1 - w) * approx[k].z};
      if (strictly_inside(p)) {
        apex = p;
        return true;
      }
    }
  return false;
}

// The implicit apex: the exact centroid of four non-coplanar vertices of the cell; -1 if none.
Index implicit_apex(ImplicitGeometry& geo, const std::vector<Index>& cv) {
  for (std::size_t h = 1; h < cv.size(); ++h)
    for (std::size_t i = h + 1; i < cv.size(); ++i)
      for (std::size_t j = i + 1; j < cv.size(); ++j)
        if (geo.orient3d(cv[0], cv[h], cv[i], cv[j]) != Sign::kZero)
          return geo.add_centroid_vertex({cv[0], cv[h], cv[i], cv[j]});
  return -1;
}

std::vector<Index> cell_vertices(const std::vector<BspFace>& faces, const BspCell& cell) {
  std::vector<Index> cv;
  for (Index f : cell.faces)
    for (Index v : faces[f].verts) cv.push_back(v);
  std::sort(cv.begin(), cv.end());
  cv.erase(std::unique(cv.begin(), cv.end()), cv.end());
  return cv;
}

// The tet of a cell with four vertices, oriented by one of its faces.
std::array<Index, 4> tet_cell(const std::vector<BspFace>& faces, const BspCell& cell, Index c) {
  const BspFace& face = faces[cell.faces[0]];
  Index d = -1;
  for (Index f : cell.faces)
    for (Index v : faces[f].verts)
      if (std::find(face.verts.begin(), face.verts.end(), v) == face.verts.end()) d = v;
  const auto& t = face.verts;
  if (face.cell[0] == c) return {t[0], t[1], t[2], d};
  return {t[0], t[2], t[1], d};
}

// The inside untouched seed tets, output in seed order among the cells' tets: call before(c)
// before cell c's tets, and rest() after the last cell.
class UntouchedOutput {
 public:
  UntouchedOutput(const BspComplex& bsp, const CellLabels& labels, CellTets& out)
      : ut_(bsp.untouched()), labels_(labels), out_(out) {}
  void before(std::size_t c) {
    while (next_ < ut_.tets.size() && static_cast<std::size_t>(ut_.before_cell[next_]) <= c) emit(next_++);
  }
  void rest() {
    while (next_ < ut_.tets.size()) emit(next_++);
  }

 private:
  void emit(std::size_t u) {
    if (labels_.untouched_winding[u] != 1) return;
    ++out_.inside_cells;
    out_.tets.push_back(ut_.tets[u]);
  }
  const UntouchedSeedTets& ut_;
  const CellLabels& labels_;
  CellTets& out_;
  std::size_t next_ = 0;
};

// Boundary faces: between an inside and an outside cell; outward is -n when the inside cell is on
// the positive side. Then the untouched seed tets: the inside ones as they are, and their faces
// towards the outside.
template <class TrisOf>
void boundary_faces(const BspComplex& bsp, const CellLabels& labels, TrisOf&& tris_of, CellTets& out) {
  const std::vector<BspFace>& faces = bsp.faces();
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const BspFace& face = faces[f];
    if (!face.alive) continue;
    const int w0 = labels.side_winding(bsp, static_cast<Index>(f), 0);
    const int w1 = labels.side_winding(bsp, static_cast<Index>(f), 1);
    if (w0 == w1) continue;
    if (face.coplanar.empty() || labels.coverage[f] == 0)
      throw MeshingError(ErrorCode::kInternal, "tetrahedralize", static_cast<std::int64_t>(f),
                         "a face between inside and outside is not covered by an input triangle");
    for (const auto& t : tris_of(static_cast<Index>(f))) {
      if (w0 == 1)
        out.boundary.push_back({t[0], t[2], t[1]});
      else
        out.boundary.push_back(t);
      out.boundary_triangle.push_back(face.coplanar[0]);
    }
  }
  const UntouchedSeedTets& ut = bsp.untouched();
  for (std::size_t u = 0; u < ut.tets.size(); ++u) {
    if (labels.untouched_winding[u] != 1) continue;
    const auto& t = ut.tets[u];
    for (int i = 0; i < 4; ++i) {
      const Index a = ut.adj[u][i];
      if (a <= -2) continue;  // a complex face: done above
      if ((a >= 0 ? labels.untouched_winding[a] : 0) == 1) continue;
      if (ut.cover[u][i] < 0)
        throw MeshingError(ErrorCode::kInternal, "tetrahedralize", static_cast<std::int64_t>(u),
                           "a face between inside and outside is not covered by an input triangle");
      // The face's normal in kTetOppositeFace order points into t (inside): outward reverses it.
      const auto& fv = kTetOppositeFace[i];
      out.boundary.push_back({t[fv[0]], t[fv[2]], t[fv[1]]});
      out.boundary_triangle.push_back(ut.cover[u][i]);
    }
  }
}

// Cone from `apex` over the triangles of the cell's faces (skipping faces whose plane contains the
// apex when `skip_through_apex`, for a pulled cell).
template <class TrisOf>
void cone_cell(ImplicitGeometry& geo, const std::vector<BspFace>& faces, const BspCell& cell, Index c, Index apex,
               bool skip_through_apex, TrisOf&& tris_of, CellTets& out) {
  for (Index f : cell.faces) {
    const BspFace& face = faces[f];
    if (skip_through_apex && geo.side(face.plane, apex) == Sign::kZero) continue;
    const bool positive_side = face.cell[0] == c;
    for (const auto& t : tris_of(f)) {
      // Face triangles are CCW around n. On the positive side n points into the cell, so
      // (a, b, c, apex) is positive; on the negative side swap two vertices.
      if (positive_side)
        out.tets.push_back({t[0], t[1], t[2], apex});
      else
        out.tets.push_back({t[0], t[2], t[1], apex});
    }
  }
}

CellTets tetrahedralize_cells_cone(BspComplex& bsp, const CellLabels& labels) {
  ImplicitGeometry& geo = bsp.geometry();
  const auto& faces = bsp.faces();
  const auto& cells = bsp.cells();
  CellTets out;
  // Phase 1: how each inside cell is filled: kind 1 = tetrahedron, 2 = apex, 3 = pulled from a vertex.
  std::vector<int> kind(cells.size(), 0);
  std::vector<Index> apex_of(cells.size(), -1);
  std::vector<Index> fan_vertex(faces.size(), -1);
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!cells[c].alive || labels.winding[c] != 1) continue;
    ++out.inside_cells;
    std::vector<Index> cv;
    for (Index f : cells[c].faces)
      for (Index v : faces[f].verts) cv.push_back(v);
    std::sort(cv.begin(), cv.end());
    cv.erase(std::unique(cv.begin(), cv.end()), cv.end());
    if (cv.size() == 4) {
      kind[c] = 1;
      continue;
    }
    Vec3 apex;
    if (find_explicit_apex(geo, faces, cells[c], static_cast<Index>(c), cv, apex)) {
      kind[c] = 2;
      apex_of[c] = geo.add_explicit_point(apex);
      continue;
    }
    // Too thin for a double inside: pull from a vertex.
    for (Index v : cv) {
      bool ok = true;
      for (Index f : cells[c].faces) {
        const BspFace& face = faces[f];
        if (geo.side(face.plane, v) != Sign::kZero) continue;
        const auto it = std::find(face.verts.begin(), face.verts.end(), v);
        if (it == face.verts.end() || (fan_vertex[f] >= 0 && fan_vertex[f] != v)) {
          ok = false;
          break;
        }
        const std::size_t n = face.verts.size(), k = static_cast<std::size_t>(it - face.verts.begin());
        const int axis = geo.projection_axis(face.plane);
        if (geo.orient2d(v, face.verts[(k + 1) % n], face.verts[(k + 2) % n], axis) == Sign::kZero ||
            geo.orient2d(face.verts[(k + n - 2) % n], face.verts[(k + n - 1) % n], v, axis) == Sign::kZero) {
          ok = false;
          break;
        }
      }
      if (!ok) continue;
      kind[c] = 3;
      apex_of[c] = v;
      for (Index f : cells[c].faces)
        if (geo.side(faces[f].plane, v) == Sign::kZero) fan_vertex[f] = v;
      break;
    }
    if (kind[c] == 0) {
      // Last resort: an implicit apex, the exact centroid of four non-coplanar cell vertices
      // (strictly inside the convex cell). Removed or rounded with the other Steiner points.
      for (std::size_t h = 1; h < cv.size() && kind[c] == 0; ++h)
        for (std::size_t i = h + 1; i < cv.size() && kind[c] == 0; ++i)
          for (std::size_t j = i + 1; j < cv.size(); ++j)
            if (geo.orient3d(cv[0], cv[h], cv[i], cv[j]) != Sign::kZero) {
              kind[c] = 2;
              apex_of[c] = geo.add_centroid_vertex({cv[0], cv[h], cv[i], cv[j]});
              break;
            }
    }
    if (kind[c] == 0)
      throw MeshingError(ErrorCode::kInternal, "tetrahedralize", static_cast<std::int64_t>(c),
                         "cell " + std::to_string(c) +
                             " is too thin for a double-precision interior point and has no vertex to pull from");
  }
  // Phase 2: face triangulations (once per face), then the tets.
  std::vector<std::vector<std::array<Index, 3>>> face_tris(faces.size());
  std::vector<char> done(faces.size(), 0);
  auto tris_of = [&](Index f) -> const std::vector<std::array<Index, 3>>& {
    if (!done[f]) {
      if (faces[f].verts.size() == 3)
        face_tris[f] = {{faces[f].verts[0], faces[f].verts[1], faces[f].verts[2]}};
      else if (fan_vertex[f] >= 0)
        face_tris[f] = fan_face(faces[f], fan_vertex[f]);
      else
        face_tris[f] = triangulate_face(geo, faces[f]);
      done[f] = 1;
    }
    return face_tris[f];
  };
  UntouchedOutput untouched(bsp, labels, out);
  for (std::size_t c = 0; c < cells.size(); ++c) {
    untouched.before(c);
    if (kind[c] == 0) continue;
    if (kind[c] == 1) {
      // The cell is a tetrahedron (a convex cell with four vertices has four triangular faces and
      // no collinear vertex): output it as is, oriented by one of its faces.
      const BspFace& face = faces[cells[c].faces[0]];
      Index d = -1;
      for (Index f : cells[c].faces)
        for (Index v : faces[f].verts)
          if (std::find(face.verts.begin(), face.verts.end(), v) == face.verts.end()) d = v;
      const auto& t = face.verts;
      if (face.cell[0] == static_cast<Index>(c))
        out.tets.push_back({t[0], t[1], t[2], d});
      else
        out.tets.push_back({t[0], t[2], t[1], d});
      continue;
    }
    (kind[c] == 2 ? out.apex_cells : out.pulled_cells)++;
    const Index apex = apex_of[c];
    for (Index f : cells[c].faces) {
      const BspFace& face = faces[f];
      if (kind[c] == 3 && geo.side(face.plane, apex) == Sign::kZero) continue;
      const bool positive_side = face.cell[0] == static_cast<Index>(c);
      for (const auto& t : tris_of(f)) {
        // Face triangles are CCW around n. On the positive side n points into the cell, so
        // (a, b, c, apex) is positive; on the negative side swap two vertices.
        if (positive_side)
          out.tets.push_back({t[0], t[1], t[2], apex});
        else
          out.tets.push_back({t[0], t[2], t[1], apex});
      }
    }
  }
  untouched.rest();
  boundary_faces(bsp, labels, tris_of, out);
  return out;
}


CellTets tetrahedralize_cells_delaunay(BspComplex& bsp, const CellLabels& labels) {
  ImplicitGeometry& geo = bsp.geometry();
  const auto& faces = bsp.faces();
  const auto& cells = bsp.cells();
  CellTets out;
  // Face triangulations: the perturbed Delaunay rule, once per face (cell_delaunay.h).
  std::vector<std::vector<std::array<Index, 3>>> face_tris(faces.size());
  std::vector<char> done(faces.size(), 0);
  auto tris_of = [&](Index f) -> const std::vector<std::array<Index, 3>>& {
    if (!done[f]) {
      if (faces[f].verts.size() == 3)
        face_tris[f] = {{faces[f].verts[0], faces[f].verts[1], faces[f].verts[2]}};
      else
        face_tris[f] = delaunay_face(geo, faces[f]);
      done[f] = 1;
    }
    return face_tris[f];
  };
  auto canonical = [](std::array<Index, 3> t) {
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
  };
  // Every vertex of a face lies on the face's plane: recorded, so that predicates on coplanar
  // points of one facet are decided without arithmetic (ImplicitGeometry::known_coplanar).
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!cells[c].alive || labels.winding[c] != 1) continue;
    for (Index f : cells[c].faces)
      for (Index v : faces[f].verts) geo.note_on_plane(v, faces[f].plane);
  }
  CellDelaunay dt;
  std::vector<std::array<Index, 3>> want;
  std::vector<Index> cell_planes;
  std::vector<std::pair<std::array<Index, 3>, Index>> want_planes;
  UntouchedOutput untouched(bsp, labels, out);
  for (std::size_t c = 0; c < cells.size(); ++c) {
    untouched.before(c);
    if (!cells[c].alive || labels.winding[c] != 1) continue;
    ++out.inside_cells;
    const Index ci = static_cast<Index>(c);
    const std::vector<Index> cv = cell_vertices(faces, cells[c]);
    if (cv.size() == 4) {
      out.tets.push_back(tet_cell(faces, cells[c], ci));
      continue;
    }
    // The cell's boundary as its faces triangulate it, outward and canonical.
    want.clear();
    for (Index f : cells[c].faces) {
      const bool positive_side = faces[f].cell[0] == ci;  // n points into the cell
      for (const auto& t : tris_of(f))
        want.push_back(canonical(positive_side ? std::array<Index, 3>{t[0], t[2], t[1]} : t));
    }
    std::sort(want.begin(), want.end());
    // Seed of the insertion order: the cell index and its vertex ids (deterministic, local).
    std::uint64_t seed = 0x243F6A8885A308D3ULL ^ (static_cast<std::uint64_t>(c) * 0x9E3779B97F4A7C15ULL);
    for (Index v : cv) seed = (seed ^ static_cast<std::uint64_t>(v)) * 0x100000001B3ULL;
    cell_planes.clear();
    for (Index f : cells[c].faces) cell_planes.push_back(faces[f].plane);
    if (delaunay_cell(geo, cv, cell_planes, seed, dt)) {
      for (auto& t : dt.hull) t = canonical(t);
      std::sort(dt.hull.begin(), dt.hull.end());
      if (dt.hull == want) {
        ++out.delaunay_cells;
        out.tets.insert(out.tets.end(), dt.tets.begin(), dt.tets.end());
        continue;
      }
      // Some facet made of several faces: recover the faces' triangulations.
      want_planes.clear();
      for (Index f : cells[c].faces) {
        const bool positive_side = faces[f].cell[0] == ci;
        for (const auto& t : tris_of(f))
          want_planes.push_back({positive_side ? std::array<Index, 3>{t[0], t[2], t[1]} : t, faces[f].plane});
      }
      if (recover_cell_boundary(geo, dt.tets, want_planes, 8)) {
        ++out.delaunay_cells;
        ++out.recovered_cells;
        out.tets.insert(out.tets.end(), dt.tets.begin(), dt.tets.end());
        continue;
      }
    }
    ++out.delaunay_fallback_cells;
    // Pulled from a vertex v: every face on a plane through v must already be triangulated by
    // triangles that all contain v (then it is a fan from v, and the cone from v over the other
    // faces tiles the cell with positive tets: v is strictly inside their planes' half-spaces).
    Index pull = -1;
    for (Index v : cv) {
      bool ok = true;
      for (Index f : cells[c].faces) {
        if (geo.side(faces[f].plane, v) != Sign::kZero) continue;
        for (const auto& t : tris_of(f))
          if (t[0] != v && t[1] != v && t[2] != v) {
            ok = false;
            break;
          }
        if (!ok) break;
      }
      if (ok) {
        pull = v;
        break;
      }
    }
    if (pull >= 0) {
      ++out.pulled_cells;
      cone_cell(geo, faces, cells[c], ci, pull, true, tris_of, out);
      continue;
    }
    Vec3 p;
    const Index apex =
        find_explicit_apex(geo, faces, cells[c], ci, cv, p) ? geo.add_explicit_point(p) : implicit_apex(geo, cv);
    if (apex < 0)
      throw MeshingError(ErrorCode::kInternal, "tetrahedralize", static_cast<std::int64_t>(c),
                         "cell " + std::to_string(c) + " has no four non-coplanar vertices");
    ++out.apex_cells;
    cone_cell(geo, faces, cells[c], ci, apex, false, tris_of, out);
  }
  untouched.rest();
  boundary_faces(bsp, labels, tris_of, out);
  return out;
}

}  // namespace

CellTets tetrahedralize_cells(BspComplex& bsp, const CellLabels& labels, CellFill fill) {
  return fill == CellFill::kCone ? tetrahedralize_cells_cone(bsp, labels) : tetrahedralize_cells_delaunay(bsp, labels);
}

}  // namespace bsptet
