// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet FEM pipeline, 2D: the CAD faces as triangles, mid-nodes on the CAD (see fem_faces.h).
#include "bsptet/fem/fem_faces.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "bsptet/cad/cad_projection.h"
#include "bsptet/cad/cad_surface.h"
#include "bsptet/numerics/errors.h"

namespace bsptet::fem {
namespace {

using Clock = std::chrono::steady_clock;

Vec3 sub(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 lerp_control(const Vec3& mid, const Vec3& a, const Vec3& b) {  // 2 m - (a + b) / 2
  return {2 * mid.x - 0.5 * (a.x + b.x), 2 * mid.y - 0.5 * (a.y + b.y), 2 * mid.z - 0.5 * (a.z + b.z)};
}
bool finite(const Vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

/// True when the 6-node triangle (corners p, mid-nodes m01 m12 m20) has a Jacobian whose component
/// along its straight triangle's normal has positive Bezier coefficients (fem_faces.h).
bool curved_triangle_positive(const std::array<Vec3, 3>& p, const std::array<Vec3, 3>& m) {
  const Vec3 n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
  // Quadratic Bezier control points: corners, and 2 m_ij - (p_i + p_j) / 2 on the edges.
  const Vec3 c01 = lerp_control(m[0], p[0], p[1]), c12 = lerp_control(m[1], p[1], p[2]),
             c20 = lerp_control(m[2], p[2], p[0]);
  // Linear Bezier control points (at L0, L1, L2) of the derivatives along xi = L1 and eta = L2.
  const std::array<Vec3, 3> dxi = {sub(c01, p[0]), sub(p[1], c01), sub(c12, c20)};
  const std::array<Vec3, 3> deta = {sub(c20, p[0]), sub(c12, c01), sub(p[2], c20)};
  auto w = [&](int i, int j) { return dot(n, cross(dxi[i], deta[j])); };
  for (int i = 0; i < 3; ++i) {
    if (!(w(i, i) > 0)) return false;
    for (int j = i + 1; j < 3; ++j)
      if (!(w(i, j) + w(j, i) > 0)) return false;
  }
  return true;
}

}  // namespace

FemMesh mesh_cad_faces(const cad::CadModel& model, const FemOptions& options, FemStats* stats) {
  const auto start = Clock::now();
  check_fem_options(options);
  FemStats st;
  st.solids = model.num_solids();
  st.faces = model.num_faces();
  cad::CadSurfaceOptions so = cad_surface_options(options);
  so.progress = [&](const std::string& stage, double f) {
    if (options.progress) options.progress("surface: " + stage, std::clamp(0.9 * f, 0.0, 1.0));
  };
  cad::CadSurfaceStats sst;
  const cad::CadSurface surface = cad::mesh_cad_surface(model, so, &sst);
  st.seconds_surface = std::chrono::duration<double>(Clock::now() - start).count();
  st.size = sst.size;
  st.min_size = sst.min_size;
  st.surface_nodes = sst.nodes;

  FemMesh out;
  out.solid_names = model.solid_names;
  out.face_names = model.face_names;
  out.mesh.xyz = surface.xyz;
  out.tri_face = surface.face_tag;
  const Index n_tri = static_cast<Index>(surface.face_tag.size());
  st.surface_triangles = n_tri;
  auto node = [&](Index v) {
    return Vec3{surface.xyz[3 * v], surface.xyz[3 * v + 1], surface.xyz[3 * v + 2]};
  };
  auto corner = [&](Index t, int k) { return surface.face_tri[static_cast<std::size_t>(3 * t + k)]; };

  if (options.order == 1) {
    out.nodes_per_triangle = 3;
    out.tri = surface.face_tri;
  } else {
    // Triangle edges (sorted corner pairs) in first-met order, with the faces of their triangles.
    std::map<std::array<Index, 2>, Index> edge_id;
    std::vector<std::array<Index, 2>> edge_nodes;
    std::vector<std::vector<std::int32_t>> edge_faces;
    std::vector<Index> tri_edge(static_cast<std::size_t>(3 * n_tri));
    for (Index t = 0; t < n_tri; ++t)
      for (int k = 0; k < 3; ++k) {
        const Index a = corner(t, k), b = corner(t, (k + 1) % 3);
        const std::array<Index, 2> key{std::min(a, b), std::max(a, b)};
        auto [it, fresh] = edge_id.emplace(key, static_cast<Index>(edge_nodes.size()));
        if (fresh) {
          edge_nodes.push_back(key);
          edge_faces.emplace_back();
        }
        edge_faces[static_cast<std::size_t>(it->second)].push_back(surface.face_tag[static_cast<std::size_t>(t)]);
        tri_edge[static_cast<std::size_t>(3 * t + k)] = it->second;
      }

    // CAD edges by their end vertices (for the free borders).
    std::multimap<std::array<int, 2>, int> edges_between;
    for (int e = 0; e < model.num_edges(); ++e) {
      const auto v = model.edge_ends(e);
      edges_between.emplace(std::array<int, 2>{std::min(v[0], v[1]), std::max(v[0], v[1])}, e);
    }

    std::shared_ptr<cad::CadProjector> projector;
    const ProjectionHook hook = cad::make_projection_hook(model, &projector);
    const std::size_t n_edges = edge_nodes.size();
    std::vector<Vec3> chord(n_edges), mid(n_edges);
    for (std::size_t e = 0; e < n_edges; ++e) {
      if (options.cancelled && options.cancelled())
        throw MeshingError(ErrorCode::kCancelled, "fem", -1, "cancelled");
      const auto [a, b] = edge_nodes[e];
      const Vec3 pa = node(a), pb = node(b);
      chord[e] = {0.5 * (pa.x + pb.x), 0.5 * (pa.y + pb.y), 0.5 * (pa.z + pb.z)};
      const auto& faces = edge_faces[e];
      Vec3 q{NAN, NAN, NAN};
      if (faces.size() >= 2) {
        q = hook(chord[e], faces[0], faces[1]);  // the faces' common edge, or the face itself
      } else {
        int cad_edge = -1;
        for (const Index v : {a, b})
          if (cad_edge < 0 && surface.node_dim[static_cast<std::size_t>(v)] == 1)
            cad_edge = surface.node_entity[static_cast<std::size_t>(v)];
        if (cad_edge < 0 && surface.node_dim[static_cast<std::size_t>(a)] == 0 &&
            surface.node_dim[static_cast<std::size_t>(b)] == 0) {
          const int va = surface.node_entity[static_cast<std::size_t>(a)];
          const int vb = surface.node_entity[static_cast<std::size_t>(b)];
          double best = std::numeric_limits<double>::infinity();
          const auto range = edges_between.equal_range({std::min(va, vb), std::max(va, vb)});
          for (auto it = range.first; it != range.second; ++it) {
            const Vec3 p = projector->to_edge(chord[e], it->second);
            const Vec3 d = sub(p, chord[e]);
            if (dot(d, d) < best) best = dot(d, d), q = p;
          }
        } else if (cad_edge >= 0) {
          q = projector->to_edge(chord[e], cad_edge);
        }
      }
      mid[e] = finite(q) ? q : chord[e];
      if (finite(q)) ++st.midnodes_projected;
    }

    // Curved triangles that do not pass get their mid-nodes back on the chords, until all pass.
    std::vector<char> curved(n_edges);
    for (std::size_t e = 0; e < n_edges; ++e)
      curved[e] = mid[e].x != chord[e].x || mid[e].y != chord[e].y || mid[e].z != chord[e].z;
    for (bool changed = true; changed;) {
      changed = false;
      for (Index t = 0; t < n_tri; ++t) {
        const Index* te = &tri_edge[static_cast<std::size_t>(3 * t)];
        if (!curved[te[0]] && !curved[te[1]] && !curved[te[2]]) continue;
        const std::array<Vec3, 3> p{node(corner(t, 0)), node(corner(t, 1)), node(corner(t, 2))};
        const std::array<Vec3, 3> m{mid[te[0]], mid[te[1]], mid[te[2]]};
        if (curved_triangle_positive(p, m)) continue;
        for (int k = 0; k < 3; ++k)
          if (curved[te[k]]) {
            curved[te[k]] = 0;
            mid[te[k]] = chord[te[k]];
            ++st.midnodes_straightened;
            changed = true;
          }
      }
    }

    // Mid-nodes after the surface nodes, in first-met edge order.
    const Index n_corner = static_cast<Index>(surface.node_dim.size());
    for (const Vec3& p : mid) out.mesh.xyz.insert(out.mesh.xyz.end(), {p.x, p.y, p.z});
    out.nodes_per_triangle = 6;
    out.tri.reserve(static_cast<std::size_t>(6 * n_tri));
    for (Index t = 0; t < n_tri; ++t) {
      for (int k = 0; k < 3; ++k) out.tri.push_back(corner(t, k));
      for (int k = 0; k < 3; ++k) out.tri.push_back(n_corner + tri_edge[static_cast<std::size_t>(3 * t + k)]);
    }
  }
  out.mesh.nodes_per_tet = 4;  // no tets
  st.corner_nodes = st.surface_nodes;
  st.nodes = out.mesh.num_points();
  st.boundary_triangles = out.num_triangles();
  st.seconds_total = std::chrono::duration<double>(Clock::now() - start).count();
  if (options.progress) options.progress("done", 1.0);
  if (stats) *stats = st;
  return out;
}

}  // namespace bsptet::fem
