// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/tet10.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <vector>

namespace bsptet {

namespace {

// Local corner pairs of the six mid-nodes, in types.h order: m12 m23 m31 m14 m24 m34.
constexpr int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

}  // namespace

TetMesh make_second_order(RefineMesh& mesh, const ProjectionHook& hook, SecondOrderStats* stats) {
  std::vector<Index> renum;
  TetMesh lin = mesh.to_tet_mesh(&renum);

  // Boundary edges and their parent triangles' tags (new indices).
  std::map<std::array<Index, 2>, std::array<std::int32_t, 2>> boundary_edge_tags;
  for (const auto& [face, parent] : mesh.boundary_faces())
    for (int k = 0; k < 3; ++k) {
      Index a = renum[static_cast<std::size_t>(face[k])], b = renum[static_cast<std::size_t>(face[(k + 1) % 3])];
      const std::array<Index, 2> key{std::min(a, b), std::max(a, b)};
      const std::int32_t tag = mesh.tag_of(parent);
      auto it = boundary_edge_tags.find(key);
      if (it == boundary_edge_tags.end())
        boundary_edge_tags.emplace(key, std::array<std::int32_t, 2>{tag, tag});
      else
        it->second[1] = tag;
    }

  std::vector<std::array<Index, 2>> edges;
  const Index nk = lin.num_tets();
  for (Index t = 0; t < nk; ++t)
    for (const auto& e : kEdge) {
      const Index a = lin.tet[static_cast<std::size_t>(4 * t + e[0])], b = lin.tet[static_cast<std::size_t>(4 * t + e[1])];
      edges.push_back({std::min(a, b), std::max(a, b)});
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

  const Index np = lin.num_points();
  TetMesh out;
  out.nodes_per_tet = 10;
  out.xyz = lin.xyz;
  std::vector<Vec3> straight(edges.size());
  std::vector<char> curved(edges.size(), 0);
  SecondOrderStats st;
  // Every node's coordinates: a projected mid-node that lands exactly on another node (the hook
  // clamps to a CAD vertex when the edge is not along the CAD edge of its two faces) stays on its
  // chord, or the mesh would have two nodes at one place (not conforming).
  std::set<std::array<double, 3>> taken;
  for (Index v = 0; v < np; ++v) {
    const Vec3 q = lin.point(v);
    taken.insert({q.x, q.y, q.z});
  }
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const Vec3 a = lin.point(edges[i][0]), b = lin.point(edges[i][1]);
    straight[i] = {0.5 * (a.x + b.x), 0.5 * (a.y + b.y), 0.5 * (a.z + b.z)};
    Vec3 p = straight[i];
    auto it = boundary_edge_tags.find(edges[i]);
    if (hook && it != boundary_edge_tags.end()) {
      const auto tags = it->second;
      const Vec3 q = hook(p, tags[0], tags[1] != tags[0] ? tags[1] : -1);
      if (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && !taken.count({q.x, q.y, q.z})) {
        curved[i] = q.x != p.x || q.y != p.y || q.z != p.z;  // a straight edge of the surface: 0
        p = q;
        ++st.projected;
      }
    }
    taken.insert({p.x, p.y, p.z});
    out.xyz.insert(out.xyz.end(), {p.x, p.y, p.z});
  }
  auto edge_id = [&](Index a, Index b) {
    const std::array<Index, 2> key{std::min(a, b), std::max(a, b)};
    return static_cast<Index>(std::lower_bound(edges.begin(), edges.end(), key) - edges.begin());
  };
  out.tet.resize(static_cast<std::size_t>(nk) * 10);
  for (Index t = 0; t < nk; ++t) {
    for (int k = 0; k < 4; ++k) out.tet[static_cast<std::size_t>(10 * t + k)] = lin.tet[static_cast<std::size_t>(4 * t + k)];
    for (int e = 0; e < 6; ++e)
      out.tet[static_cast<std::size_t>(10 * t + 4 + e)] =
          np + edge_id(lin.tet[static_cast<std::size_t>(4 * t + kEdge[e][0])], lin.tet[static_cast<std::size_t>(4 * t + kEdge[e][1])]);
  }
  // Straighten the mid-nodes of curved tets that are not certified valid, until all are. Tets
  // without a curved mid-node are not checked: nothing here could change them (they are the
  // linear tet up to the rounding of their midpoints).
  auto has_curved = [&](Index t) {
    for (int e = 0; e < 6; ++e)
      if (curved[static_cast<std::size_t>(out.tet[static_cast<std::size_t>(10 * t + 4 + e)] - np)]) return true;
    return false;
  };
  std::vector<Index> to_check;
  for (Index t = 0; t < nk; ++t)
    if (has_curved(t)) to_check.push_back(t);
  for (bool changed = true; changed;) {
    changed = false;
    for (Index t : to_check) {
      if (!has_curved(t)) continue;
      double x[30];
      for (int k = 0; k < 10; ++k)
        for (int c = 0; c < 3; ++c) x[3 * k + c] = out.xyz[static_cast<std::size_t>(3 * out.tet[static_cast<std::size_t>(10 * t + k)] + c)];
      if (certify_tet10(x) == Tet10Validity::kCertified) continue;
      ++st.not_certified;
      for (int e = 0; e < 6; ++e) {
        const std::size_t id = static_cast<std::size_t>(out.tet[static_cast<std::size_t>(10 * t + 4 + e)] - np);
        if (!curved[id]) continue;
        curved[id] = 0;
        ++st.straightened;
        changed = true;
        const std::size_t at = static_cast<std::size_t>(3 * (np + static_cast<Index>(id)));
        out.xyz[at] = straight[id].x;
        out.xyz[at + 1] = straight[id].y;
        out.xyz[at + 2] = straight[id].z;
      }
    }
  }
  st.curved_tets = 0;
  for (Index t : to_check) st.curved_tets += has_curved(t);
  st.midnodes = static_cast<std::int64_t>(edges.size());
  if (stats) *stats = st;
  return out;
}

}  // namespace bsptet
