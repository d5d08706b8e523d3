// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: one solid cut in two by a plane (see cad_split.h).
#include "bsptet/cad/cad_split.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>

#include <BRepAlgoAPI_Splitter.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <Bnd_Box.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <gp_Pln.hxx>

#include "bsptet/numerics/errors.h"

namespace bsptet::cad {
namespace {

constexpr double kPi = 3.14159265358979323846;
/// Positions tried per axis, evenly spread over the surface's extent.
constexpr int kPositions = 128;
/// The share of the work each side must keep.
constexpr double kMinShare = 0.45;


using P3 = std::array<double, 3>;

P3 node(const CadSurface& s, Index i) {
  const std::size_t k = 3 * static_cast<std::size_t>(i);
  return {s.xyz[k], s.xyz[k + 1], s.xyz[k + 2]};
}

double length(const P3& p, const P3& q) {
  return std::sqrt((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) + (q[2] - p[2]) * (q[2] - p[2]));
}

// The integral of (x_a - c) n_a over triangle (x, y, z) (outward): the a-component of its vector
// area, 1/2 (y - x) x (z - x), times the mean of x_a - c.
double triangle_integral(const P3& x, const P3& y, const P3& z, int a, double c) {
  const int b = (a + 1) % 3, d = (a + 2) % 3;
  const double area_a = 0.5 * ((y[b] - x[b]) * (z[d] - x[d]) - (y[d] - x[d]) * (z[b] - x[b]));
  return area_a * ((x[a] + y[a] + z[a]) / 3.0 - c);
}

// Over the part of triangle (p, q, r) (outward) with x_a < c: the integral of (x_a - c) n_a, and
// (added to *area_a) the a-component of its vector area.
double below_integral(const P3& p, const P3& q, const P3& r, int a, double c, double* area_a) {
  P3 poly[4];
  int n = 0;
  const P3* v[3] = {&p, &q, &r};
  for (int i = 0; i < 3; ++i) {  // Sutherland-Hodgman against x_a < c
    const P3& s = *v[i];
    const P3& e = *v[(i + 1) % 3];
    const bool s_in = s[a] < c, e_in = e[a] < c;
    if (s_in) poly[n++] = s;
    if (s_in != e_in) {
      const double t = (c - s[a]) / (e[a] - s[a]);
      P3 x{s[0] + t * (e[0] - s[0]), s[1] + t * (e[1] - s[1]), s[2] + t * (e[2] - s[2])};
      x[a] = c;
      poly[n++] = x;
    }
  }
  double sum = 0;
  const int b = (a + 1) % 3, d = (a + 2) % 3;
  for (int i = 1; i + 1 < n; ++i) {
    const P3 &x = poly[0], &y = poly[i], &z = poly[i + 1];
    *area_a += 0.5 * ((y[b] - x[b]) * (z[d] - x[d]) - (y[d] - x[d]) * (z[b] - x[b]));
    sum += triangle_integral(x, y, z, a, c);
  }
  return sum;
}

}  // namespace

double enclosed_volume(const CadSurface& surface, int solid) {
  const std::vector<Index>& tri = surface.solid_tri[static_cast<std::size_t>(solid)];
  const std::size_t nt = tri.size() / 3;
  // sum of (x_0 - c) n_0 dA, c at the least x_0 (which keeps the terms small)
  double c = std::numeric_limits<double>::infinity();
  for (Index v : tri) c = std::min(c, node(surface, v)[0]);
  double volume = 0;
  for (std::size_t t = 0; t < nt; ++t)
    volume += triangle_integral(node(surface, tri[3 * t]), node(surface, tri[3 * t + 1]), node(surface, tri[3 * t + 2]),
                                0, c);
  return volume;
}

CutPlane choose_cut_plane(const CadModel& model, const CadSurface& surface, double size) {
  CutPlane best;
  if (model.num_solids() != 1 || surface.solid_tri.size() != 1 || !(size > 0)) return best;
  const std::vector<Index>& tri = surface.solid_tri[0];
  const std::vector<std::int32_t>& tag = surface.solid_tag[0];
  const std::size_t nt = tag.size();
  const Index nn = static_cast<Index>(surface.node_dim.size());
  const double volume = enclosed_volume(surface, 0);
  if (!(volume > 0)) return best;
  const double min_cos = std::cos(kMinCutAngleDeg * kPi / 180.0);  // |n_a| at most: faces
  const double min_sin = std::sin(kMinCutAngleDeg * kPi / 180.0);  // |d_a| / |d| at least: CAD edges
  // Unit normals, and the triangle edges that run along a CAD edge (both ends on it).
  std::vector<P3> normal(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const P3 p = node(surface, tri[3 * t]), q = node(surface, tri[3 * t + 1]), r = node(surface, tri[3 * t + 2]);
    const P3 u{q[0] - p[0], q[1] - p[1], q[2] - p[2]}, w{r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    P3 n{u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    normal[t] = l > 0 ? P3{n[0] / l, n[1] / l, n[2] / l} : P3{0, 0, 0};
  }
  const auto on_edge = [&](Index v, int e) {
    const std::size_t k = static_cast<std::size_t>(v);
    if (surface.node_dim[k] == 1) return surface.node_entity[k] == e;
    if (surface.node_dim[k] != 0) return false;
    const std::array<int, 2> ends = model.edge_ends(e);
    return surface.node_entity[k] == ends[0] || surface.node_entity[k] == ends[1];
  };
  std::vector<std::array<Index, 2>> cad_edge_segments;
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const Index u = tri[3 * t + static_cast<std::size_t>(k)], v = tri[3 * t + static_cast<std::size_t>((k + 1) % 3)];
      if (u > v) continue;  // each edge once (from one of its two triangles)
      int e = -1;
      for (Index w : {u, v})
        if (surface.node_dim[static_cast<std::size_t>(w)] == 1) e = surface.node_entity[static_cast<std::size_t>(w)];
      if (e < 0) {  // two CAD vertices: the segment is an edge of one mesh segment when an edge joins them
        if (surface.node_dim[static_cast<std::size_t>(u)] != 0 || surface.node_dim[static_cast<std::size_t>(v)] != 0)
          continue;
        for (int f = 0; f < model.num_edges() && e < 0; ++f)
          if (on_edge(u, f) && on_edge(v, f)) e = f;
      }
      if (e >= 0 && on_edge(u, e) && on_edge(v, e)) cad_edge_segments.push_back({u, v});
    }

  // The CAD vertices' nodes and their local size: the mean length of the mesh edges at them.
  std::vector<Index> vertex_nodes;
  std::vector<double> vertex_size;
  {
    std::vector<double> sum(static_cast<std::size_t>(nn), 0.0);
    std::vector<int> count(static_cast<std::size_t>(nn), 0);
    for (std::size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) {
        const Index u = tri[3 * t + static_cast<std::size_t>(k)], v = tri[3 * t + static_cast<std::size_t>((k + 1) % 3)];
        const double l = length(node(surface, u), node(surface, v));
        for (Index w : {u, v}) sum[static_cast<std::size_t>(w)] += l, ++count[static_cast<std::size_t>(w)];
      }
    for (Index i = 0; i < nn; ++i)
      if (surface.node_dim[static_cast<std::size_t>(i)] == 0 && count[static_cast<std::size_t>(i)] > 0) {
        vertex_nodes.push_back(i);
        vertex_size.push_back(sum[static_cast<std::size_t>(i)] / count[static_cast<std::size_t>(i)]);
      }
  }
  const double tet_volume = size * size * size / (6 * std::sqrt(2.0));
  std::vector<double> tmin(nt), tmax(nt);  // each triangle's extent along the axis
  for (int a = 0; a < 3; ++a) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (Index i = 0; i < nn; ++i) lo = std::min(lo, node(surface, i)[a]), hi = std::max(hi, node(surface, i)[a]);
    if (!(hi > lo)) continue;
    for (std::size_t t = 0; t < nt; ++t) {
      tmin[t] = std::numeric_limits<double>::infinity(), tmax[t] = -tmin[t];
      for (int j = 0; j < 3; ++j) {
        const double x = node(surface, tri[3 * t + static_cast<std::size_t>(j)])[a];
        tmin[t] = std::min(tmin[t], x), tmax[t] = std::max(tmax[t], x);
      }
    }
    for (int k = 0; k < kPositions; ++k) {
      const double c = lo + (hi - lo) * (k + 0.5) / kPositions;
      // The share of the work below: triangles by their centroid, and the volume.
      // The cut's area: the surface below and the cut close the part below, and e_a has no
      // divergence, so the cut's area is minus the a-component of the vector area below.
      double volume_below = 0, area_below = 0;
      std::int64_t triangles_below = 0;
      for (std::size_t t = 0; t < nt; ++t) {
        if (tmin[t] >= c) continue;  // wholly above: nothing below, centroid above
        const P3 p = node(surface, tri[3 * t]), q = node(surface, tri[3 * t + 1]), r = node(surface, tri[3 * t + 2]);
        volume_below += below_integral(p, q, r, a, c, &area_below);
        triangles_below += p[a] + q[a] + r[a] < 3 * c;
      }
      const double below = (kTetsPerTriangle * static_cast<double>(triangles_below) + volume_below / tet_volume) /
                           (kTetsPerTriangle * static_cast<double>(nt) + volume / tet_volume);
      if (below < kMinShare || below > 1 - kMinShare) continue;
      // Every CAD vertex at least half its local size from the plane; the clearance reported is
      // the least distance in units of that size.
      double clearance = std::numeric_limits<double>::infinity();
      for (std::size_t k = 0; k < vertex_nodes.size(); ++k)
        clearance = std::min(clearance, std::abs(node(surface, vertex_nodes[k])[a] - c) / vertex_size[k]);
      if (clearance < 0.5) continue;
      bool ok = true;
      std::set<std::int32_t> crossed;
      for (std::size_t t = 0; t < nt && ok; ++t) {
        if (tmin[t] > c || tmax[t] < c) continue;
        crossed.insert(tag[t]);
        ok = std::abs(normal[t][static_cast<std::size_t>(a)]) <= min_cos;
      }
      for (std::size_t i = 0; i < cad_edge_segments.size() && ok; ++i) {
        const P3 p = node(surface, cad_edge_segments[i][0]), q = node(surface, cad_edge_segments[i][1]);
        if ((p[a] - c) * (q[a] - c) > 0) continue;
        const double l = length(p, q);
        ok = l > 0 && std::abs(q[a] - p[a]) >= min_sin * l;
      }
      if (!ok) continue;
      const int faces = static_cast<int>(crossed.size());
      const double area = -area_below;
      // Fewest faces crossed, then the smallest cut (fewer tets on the seam), areas within 1%
      // counting as equal, then the best balance.
      const bool better =
          !best.found || faces < best.faces_crossed ||
          (faces == best.faces_crossed &&
           (area < 0.99 * best.area ||
            (area <= 1.01 * best.area && std::abs(below - 0.5) < std::abs(best.below - 0.5))));
      if (better) {
        best.area = area;
        best.found = true;
        best.axis = a;
        best.position = c;
        best.below = below;
        best.faces_crossed = faces;
        best.clearance = clearance;
      }
    }
  }
  return best;
}

std::vector<std::pair<Vec3, double>> cut_size_sources(const CadSurface& surface, const CutPlane& plane, double size,
                                                      double grading) {
  std::vector<std::pair<Vec3, double>> out;
  if (!plane.found || surface.solid_tri.empty() || !(grading > 0)) return out;
  const std::vector<Index>& tri = surface.solid_tri[0];
  std::vector<double> t(surface.node_dim.size(), std::numeric_limits<double>::infinity());
  for (std::size_t k = 0; k + 2 < tri.size(); k += 3) {
    double mean = 0;
    for (int i = 0; i < 3; ++i) {
      mean += length(node(surface, tri[k + static_cast<std::size_t>(i)]),
                     node(surface, tri[k + static_cast<std::size_t>((i + 1) % 3)])) / 3;
    }
    for (int i = 0; i < 3; ++i) {
      double& s = t[static_cast<std::size_t>(tri[k + static_cast<std::size_t>(i)])];
      s = std::min(s, mean);
    }
  }
  for (std::size_t v = 0; v < t.size(); ++v) {
    if (!(t[v] < size)) continue;
    const P3 p = node(surface, static_cast<Index>(v));
    if (std::abs(p[static_cast<std::size_t>(plane.axis)] - plane.position) * grading < size - t[v])
      out.emplace_back(Vec3{p[0], p[1], p[2]}, t[v]);
  }
  return out;
}

CadSplit split_by_plane(const CadModel& model, const CutPlane& plane) {
  CadSplit out;
  if (!plane.found || model.num_solids() != 1) return out;
  Bnd_Box box;
  BRepBndLib::Add(model.shape, box, /*useTriangulation=*/false);
  if (box.IsVoid()) return out;
  double x0, y0, z0, x1, y1, z1;
  box.Get(x0, y0, z0, x1, y1, z1);
  std::array<double, 3> centre{0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1)};
  centre[static_cast<std::size_t>(plane.axis)] = plane.position;  // exactly: the cut's nodes are coplanar
  const double half = 2 * model.diagonal() + 1;
  const gp_Pln pln(gp_Pnt(centre[0], centre[1], centre[2]),
                   gp_Dir(plane.axis == 0 ? 1 : 0, plane.axis == 1 ? 1 : 0, plane.axis == 2 ? 1 : 0));
  try {
    const TopoDS_Face tool = BRepBuilderAPI_MakeFace(pln, -half, half, -half, half).Face();
    TopTools_ListOfShape arguments, tools;
    arguments.Append(model.shape);
    tools.Append(tool);
    BRepAlgoAPI_Splitter splitter;
    splitter.SetArguments(arguments);
    splitter.SetTools(tools);
    splitter.SetRunParallel(false);
    splitter.Build();
    if (!splitter.IsDone() || splitter.HasErrors()) return out;
    CadModel cut = make_cad_model(splitter.Shape(), model.source);
    if (cut.num_solids() < 2) return out;
    std::vector<int> face_origin(static_cast<std::size_t>(cut.num_faces()), -1);
    for (int f = 0; f < model.num_faces(); ++f) {
      const TopoDS_Shape& face = model.faces(f + 1);
      const TopTools_ListOfShape& images = splitter.Modified(face);
      int found = 0;
      if (images.IsEmpty()) {
        const int g = cut.face_index(face);
        if (g >= 0) face_origin[static_cast<std::size_t>(g)] = f, ++found;
      } else {
        for (TopTools_ListIteratorOfListOfShape it(images); it.More(); it.Next()) {
          const int g = cut.face_index(it.Value());
          if (g >= 0) face_origin[static_cast<std::size_t>(g)] = f, ++found;
        }
      }
      if (found == 0) return out;  // an original face lost: do not cut
    }
    // The faces that come from no original face are the cut: each must bound both halves.
    TopTools_IndexedDataMapOfShapeListOfShape solids_of_face;
    TopExp::MapShapesAndAncestors(cut.shape, TopAbs_FACE, TopAbs_SOLID, solids_of_face);
    int cut_faces = 0;
    for (int g = 0; g < cut.num_faces(); ++g) {
      if (face_origin[static_cast<std::size_t>(g)] >= 0) continue;
      ++cut_faces;
      const TopTools_ListOfShape* solids = solids_of_face.Seek(cut.faces(g + 1));
      TopTools_IndexedMapOfShape distinct;
      if (solids)
        for (TopTools_ListIteratorOfListOfShape it(*solids); it.More(); it.Next()) distinct.Add(it.Value());
      if (distinct.Extent() != 2) return out;
    }
    if (cut_faces == 0) return out;
    out.cut = true;
    out.model = std::move(cut);
    out.face_origin = std::move(face_origin);
    out.solid_origin.assign(static_cast<std::size_t>(out.model.num_solids()), 0);
  } catch (const Standard_Failure&) {
    return CadSplit{};
  } catch (const Error&) {  // make_cad_model refused the result (a face outside every solid)
    return CadSplit{};
  }
  return out;
}

}  // namespace bsptet::cad
