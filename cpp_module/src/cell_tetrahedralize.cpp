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

std::vector<std::array<Index, 4>> tetrahedralize_cells(BspComplex& bsp, const CellLabels& labels,
                                                       std::int64_t* inside_cells) {
  ImplicitGeometry& geo = bsp.geometry();
  const auto& faces = bsp.faces();
  const auto& cells = bsp.cells();
  std::vector<std::vector<std::array<Index, 3>>> face_tris(faces.size());
  std::vector<char> done(faces.size(), 0);
  std::vector<std::array<Index, 4>> tets;
  std::int64_t inside = 0;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!cells[c].alive || labels.winding[c] != 1) continue;
    ++inside;
    // Apex: an explicit point strictly inside the cell (the rounded centroid of its vertices,
    // then points pulled towards each vertex), verified exactly against every face plane.
    std::vector<Index> cv;
    for (Index f : cells[c].faces)
      for (Index v : faces[f].verts) cv.push_back(v);
    std::sort(cv.begin(), cv.end());
    cv.erase(std::unique(cv.begin(), cv.end()), cv.end());
    if (cv.size() == 4) {
      // The cell is a tetrahedron (a convex cell with four vertices has four triangular faces and
      // no collinear vertex): output it as is, oriented by one of its faces.
      const BspFace& face = faces[cells[c].faces[0]];
      Index d = -1;
      for (Index v : cv)
        if (std::find(face.verts.begin(), face.verts.end(), v) == face.verts.end()) d = v;
      const auto& t = face.verts;
      if (face.cell[0] == static_cast<Index>(c))
        tets.push_back({t[0], t[1], t[2], d});
      else
        tets.push_back({t[0], t[2], t[1], d});
      for (Index f : cells[c].faces)
        if (!done[f]) face_tris[f] = {{faces[f].verts[0], faces[f].verts[1], faces[f].verts[2]}}, done[f] = 1;
      continue;
    }
    std::vector<Vec3> approx;
    Vec3 centroid{0, 0, 0};
    for (Index v : cv) {
      approx.push_back(geo.rounded(v));
      centroid.x += approx.back().x / cv.size();
      centroid.y += approx.back().y / cv.size();
      centroid.z += approx.back().z / cv.size();
    }
    auto strictly_inside = [&](const Vec3& p, Index& vid) {
      vid = geo.add_explicit_point(p);
      for (Index f : cells[c].faces) {
        const Sign want = faces[f].cell[0] == static_cast<Index>(c) ? Sign::kPositive : Sign::kNegative;
        if (geo.side(faces[f].plane, vid) != want) return false;
      }
      return true;
    };
    Index apex = -1;
    bool found = strictly_inside(centroid, apex);
    for (std::size_t k = 0; !found && k < approx.size(); ++k)
      for (double w : {0.5, 0.9, 0.99}) {
        const Vec3 p{w * centroid.x + (1 - w) * approx[k].x, w * centroid.y + (1 - w) * approx[k].y,
                     w * centroid.z + (1 - w) * approx[k].z};
        if ((found = strictly_inside(p, apex))) break;
      }
    if (!found)
      throw MeshingError(ErrorCode::kInternal, "tetrahedralize", static_cast<std::int64_t>(c),
                         "no double-precision point strictly inside a very thin cell");
    for (Index f : cells[c].faces) {
      const BspFace& face = faces[f];
      if (!done[f]) {
        face_tris[f] = triangulate_face(geo, face);
        done[f] = 1;
      }
      const bool positive_side = face.cell[0] == static_cast<Index>(c);
      for (const auto& t : face_tris[f]) {
        // Face triangles are CCW around n. On the positive side n points into the cell, so
        // (a, b, c, apex) is positive; on the negative side swap two vertices.
        if (positive_side)
          tets.push_back({t[0], t[1], t[2], apex});
        else
          tets.push_back({t[0], t[2], t[1], apex});
      }
    }
  }
  if (inside_cells) *inside_cells = inside;
  return tets;
}

}  // namespace bsptet
