#include "bsptet/cell_tetrahedralize.h"

#include <algorithm>
#include <string>

#include "bsptet/errors.h"

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

}  // namespace

CellTets tetrahedralize_cells(BspComplex& bsp, const CellLabels& labels) {
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
    // Apex: an explicit point strictly inside the cell (the rounded centroid of its vertices,
    // then points pulled towards each vertex), verified exactly against every face plane.
    std::vector<Vec3> approx;
    Vec3 centroid{0, 0, 0};
    for (Index v : cv) {
      approx.push_back(geo.rounded(v));
      centroid.x += approx.back().x / cv.size();
      centroid.y += approx.back().y / cv.size();
      centroid.z += approx.back().z / cv.size();
    }
    auto strictly_inside = [&](const Vec3& p) {
      for (Index f : cells[c].faces) {
        // Cheap double pre-test before creating a vertex.
        const Sign want = faces[f].cell[0] == static_cast<Index>(c) ? Sign::kPositive : Sign::kNegative;
        const PlaneDef& pd = geo.plane(faces[f].plane);
        if (orient3d(geo.explicit_point(pd.a), geo.explicit_point(pd.b), geo.explicit_point(pd.c), p) != want)
          return false;
      }
      return true;
    };
    bool found = strictly_inside(centroid);
    Vec3 apex = centroid;
    for (std::size_t k = 0; !found && k < approx.size(); ++k)
      for (double w : {0.5, 0.9, 0.99}) {
        const Vec3 p{w * centroid.x + (1 - w) * approx[k].x, w * centroid.y + (1 - w) * approx[k].y,
                     w * centroid.z + (1 - w) * approx[k].z};
        if ((found = strictly_inside(p))) {
          apex = p;
          break;
        }
      }
    if (found) {
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
  for (std::size_t c = 0; c < cells.size(); ++c) {
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
  // Boundary faces: between an inside and an outside cell; outward is -n when the inside cell is on
  // the positive side.
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const BspFace& face = faces[f];
    if (!face.alive) continue;
    const int w0 = face.cell[0] >= 0 ? labels.winding[face.cell[0]] : 0;
    const int w1 = face.cell[1] >= 0 ? labels.winding[face.cell[1]] : 0;
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
  return out;
}

}  // namespace bsptet
