// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/core/steiner_removal.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <tuple>
#include <utility>

#include "bsptet/core/tet_complex.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

std::vector<std::array<Index, 4>> remove_steiner_points(ImplicitGeometry& geo, const SurfaceMesh& surface,
                                                        const std::vector<Index>& tri_plane, const CellTets& cells,
                                                        const SteinerRemovalOptions& options,
                                                        SteinerRemovalStats* stats_out) {
  SteinerRemovalStats st;
  const Index np = surface.num_points();
  TetComplex mesh(geo, surface, tri_plane);
  for (const auto& t : cells.tets) mesh.add_tet(t);
  for (std::size_t i = 0; i < cells.boundary.size(); ++i) mesh.add_face(cells.boundary[i], cells.boundary_triangle[i]);

  auto steiner_vertices = [&]() {
    std::vector<Index> out;
    for (Index v = np; v < geo.num_vertices(); ++v)
      if (mesh.used(v)) out.push_back(v);
    return out;
  };
  auto check_cancel = [&]() {
    if (options.cancelled && options.cancelled())
      throw MeshingError(ErrorCode::kCancelled, "steiner", -1, "cancelled");
  };
  auto progress = [&](double f) {
    if (options.progress) options.progress(f);
  };
  auto timed = [&](const char* phase, auto&& body) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto before = static_cast<std::int64_t>(steiner_vertices().size());
    body();
    st.seconds_by_phase[phase] += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    st.removed_by_phase[phase] += before - static_cast<std::int64_t>(steiner_vertices().size());
  };
  // The optional phases (merge .. retetrahedralize: interior Steiner points may stay) give each
  // point at most options.interior_work_per_point work units in all (TetComplex::work), so that a
  // few points no local operation removes cannot cost minutes (a cube-sphere of 10^4 triangles
  // spent 12 s in edge removals for 4 points). Counted in work, not seconds: deterministic.
  std::unordered_map<Index, std::int64_t> spent;
  auto affordable = [&](Index v) {
    return options.interior_work_per_point <= 0 || spent[v] < options.interior_work_per_point;
  };
  auto charged = [&](Index v, auto&& attempt) {
    const std::int64_t w0 = mesh.work;
    const bool ok = attempt();
    spent[v] += mesh.work - w0;
    return ok;
  };
  {
    const auto sv = steiner_vertices();
    st.steiner_before = static_cast<std::int64_t>(sv.size());
    for (Index v : sv) st.boundary_steiner_before += !mesh.labels(v).empty();
  }
  // Collapse attempts that failed, with the signature they failed under: skipped until it changes
  // (they would fail again; the collapses made are the same, only the repeated failures go).
  // The neighbours are kept too: while v's own counter is unchanged so is its star, hence its
  // neighbours, and the signature is re-checked without recomputing them.
  struct FailedCollapse {
    std::pair<std::uint64_t, std::uint64_t> signature;
    std::vector<Index> neighbours;
  };
  std::unordered_map<Index, FailedCollapse> failed_collapse;
  auto collapse_passes = [&](double f0, double f1) {
    for (int pass = 0; pass < 50; ++pass) {
      bool changed = false;
      const auto sv = steiner_vertices();
      for (std::size_t i = 0; i < sv.size(); ++i) {
        const Index v = sv[i];
        if ((i & 255) == 0) {
          check_cancel();
          progress(f0 + (f1 - f0) * (pass + static_cast<double>(i) / sv.size()) / (pass + 2));
        }
        if (!mesh.used(v)) continue;
        const auto known = failed_collapse.find(v);
        if (known != failed_collapse.end() &&
            mesh.signature(v, known->second.neighbours) == known->second.signature)
          continue;
        std::vector<Index> nbrs = mesh.neighbours(v);
        const auto sig = mesh.signature(v, nbrs);
        const std::vector<Index> lv = mesh.labels(v);
        bool done = false;
        for (Index u : nbrs) {
          if (!mesh.may_move_onto(v, lv, u)) continue;
          if (mesh.try_substitute(v, u)) {
            ++st.collapsed;
            changed = done = true;
            break;
          }
        }
        if (!done) failed_collapse[v] = FailedCollapse{sig, std::move(nbrs)};
      }
      if (!changed) break;
    }
  };
  timed("collapse", [&] { collapse_passes(0.0, 0.5); });

  // Surface Steiner points that remain: kept only when allowed and exactly doubles; otherwise moved
  // inside.
  // A point that cannot move yet may be able to once its neighbours have moved or collapsed: retry
  // in rounds while anything changes.
  timed("relocate", [&] {
    std::map<Index, int> attempts;  // bounded work: a point gets at most 3 tries
    for (int round = 0;; ++round) {
      std::int64_t moved = 0;
      Index stuck = -1;
      std::string why;
      const std::vector<Index> sv = steiner_vertices();
      for (std::size_t i = 0; i < sv.size(); ++i) {
        const Index v = sv[i];
        check_cancel();
        if ((i & 63) == 0) progress(0.5 + 0.1 * static_cast<double>(i) / sv.size());
        const std::vector<Index> lv = mesh.labels(v);
        if (lv.empty()) continue;
        if (options.allow_boundary_steiner) {
          const Index w = geo.add_explicit_point(geo.rounded(v));
          // Kept only where the double is the point itself (a rounded point could leave its triangle
          // for a coplanar neighbour, or the plane).
          bool on = true;
          if (!geo.is_explicit(v))
            for (Index p : geo.tpi_planes(v)) on = on && p >= 0 && geo.side(p, w) == Sign::kZero;
          if (on && mesh.try_substitute(v, w)) {
            ++st.rounded;
            ++moved;
            continue;
          }
        }
        if (++attempts[v] > 3) {
          if (stuck < 0) stuck = v, why = mesh.why;
          continue;
        }
        bool ok = mesh.relocate(v);
        if (!ok && attempts[v] == 1) {
          // Take the interior Steiner points around v along (one ring, then two): a slab thinner
          // than a double between them and v disappears with them.
          for (const bool with_surface : {false, true}) {
            std::vector<Index> ring{v};
            for (int k = 1; k <= 1 && !ok; ++k) {
              std::vector<Index> grown = ring;
              for (Index z : ring)
                for (Index y : mesh.neighbours(z))
                  if (y >= np && (with_surface || mesh.labels(y).empty())) grown.push_back(y);
              std::sort(grown.begin(), grown.end());
              grown.erase(std::unique(grown.begin(), grown.end()), grown.end());
              if (grown.size() == ring.size()) break;
              ring = grown;
              ok = mesh.relocate(v, ring);
            }
            if (ok) break;
          }
        }
        if (!ok) {
          // PUSH the interior Steiner points around v deeper (header comment), then try again: points
          // left a few ulps from a surface plane through v close v's kernel.
          bool pushed = false;
          for (Index z : mesh.neighbours(v))
            if (z >= np && mesh.labels(z).empty() && mesh.push(z)) pushed = true, ++st.pushed;
          if (pushed) ok = mesh.relocate(v);
        }
        if (ok) {
          ++st.relocated;
          ++moved;
        } else if (stuck < 0) {
          stuck = v;
          why = mesh.why;
        }
      }
      if (stuck < 0) break;
      const std::int64_t collapsed_before = st.collapsed;
      collapse_passes(0.5, 0.6);
      if (moved == 0 && st.collapsed == collapsed_before) {
        const Vec3 p = geo.rounded(stuck);
        throw MeshingError(ErrorCode::kInternal, "steiner", stuck,
                           "could not move the surface Steiner point at (" + std::to_string(p.x) + ", " +
                               std::to_string(p.y) + ", " + std::to_string(p.z) + ") on input triangle " +
                               std::to_string(mesh.labels(stuck)[0]) + " inside the solid: " + why);
      }
    }
    collapse_passes(0.5, 0.8);
  });
  // Merge: an interior Steiner point that cannot collapse is replaced, with its interior Steiner
  // neighbours, by one new point (a cavity re-coned from it), then collapses are tried again.
  timed("merge", [&] {
    mesh.grow_limit = 0;
    mesh.deep_grow_limit = 0;
    mesh.max_candidates = 8;
    std::unordered_map<Index, std::pair<std::uint64_t, std::uint64_t>> failed_merge;
    for (int pass = 0; pass < 3; ++pass) {
      std::int64_t merged_before = mesh.merged;
      for (Index z : steiner_vertices()) {
        check_cancel();
        if (!mesh.used(z) || !mesh.labels(z).empty()) continue;
        std::vector<Index> ring;
        for (Index y : mesh.neighbours(z))
          if (y >= np && mesh.labels(y).empty()) ring.push_back(y);
        if (ring.size() > 6) ring.resize(6);  // bounded work: the six lowest ids
        if (ring.empty()) continue;
        // A merge depends only on the stars of z and its ring (no cavity growth here): skip it while
        // they are as they were when it failed.
        const auto sig = mesh.signature(z, ring);
        const auto known = failed_merge.find(z);
        if (known != failed_merge.end() && known->second == sig) continue;
        if (!affordable(z)) continue;
        if (!charged(z, [&] { return mesh.relocate(z, ring); })) failed_merge[z] = sig;
      }
      if (mesh.merged == merged_before) break;
      collapse_passes(0.8 + 0.03 * pass, 0.83 + 0.03 * pass);
    }
  });

  // Interior Steiner points left: re-cone a grown cavity from a neighbour (a collapse that may
  // first take neighbouring tets, and the interior Steiner points among them, into v's star).
  timed("cone_neighbours", [&] {
    for (int pass = 0; pass < 4; ++pass) {
      const std::int64_t merged_before = mesh.merged;
      std::int64_t removed = 0;
      for (Index v : steiner_vertices()) {
        check_cancel();
        if (!mesh.used(v) || !mesh.labels(v).empty()) continue;
        for (Index u : mesh.neighbours(v)) {
          if (!affordable(v)) break;
          if (charged(v, [&] { return mesh.cone_from_vertex(v, u, 6, 400); })) {
            ++removed;
            break;
          }
        }
      }
      st.collapsed += removed;
      if (removed == 0 && mesh.merged == merged_before) break;
      collapse_passes(0.9, 0.95);
    }
  });
  // Those left: lower their degree by edge removals (each one takes a neighbour away from v), and
  // collapse or re-cone after each one.
  timed("edge_removal", [&] {
    for (Index v : steiner_vertices()) {
      check_cancel();
      if (!mesh.used(v) || !mesh.labels(v).empty()) continue;
      bool gone = false;
      for (int flips = 0; flips < 64 && !gone && affordable(v); ++flips) {
        std::vector<std::pair<std::size_t, Index>> by_ring;
        for (Index x : mesh.neighbours(v)) {
          std::size_t ring = 0;
          for (Index id : mesh.star(v)) {
            const auto& t = mesh.tet(id);
            ring += std::find(t.begin(), t.end(), x) != t.end();
          }
          by_ring.push_back({ring, x});
        }
        std::sort(by_ring.begin(), by_ring.end());
        bool flipped = false;
        for (const auto& [ring, x] : by_ring)
          if ((flipped = charged(v, [&] { return mesh.remove_edge(v, x); }))) break;
        if (!flipped) break;
        for (Index u : mesh.neighbours(v))
          if (charged(v, [&] { return mesh.try_substitute(v, u) || mesh.cone_from_vertex(v, u, 6, 400); })) {
            gone = true;
            ++st.collapsed;
            break;
          }
      }
    }
  });
  // The few left: cones from farther vertices (the nearest 48, input points among them first
  // when equally near) over cavities grown further.
  timed("cone_nearest", [&] {
    for (Index v : steiner_vertices()) {
      check_cancel();
      if (!mesh.used(v) || !mesh.labels(v).empty()) continue;
      const Vec3 pv = geo.rounded(v);
      std::vector<std::pair<double, Index>> near;
      for (Index u = 0; u < geo.num_vertices(); ++u) {
        if (u == v || !mesh.used(u)) continue;
        const Vec3 q = geo.rounded(u);
        near.push_back({(q.x - pv.x) * (q.x - pv.x) + (q.y - pv.y) * (q.y - pv.y) + (q.z - pv.z) * (q.z - pv.z), u});
      }
      const std::size_t k = std::min<std::size_t>(48, near.size());
      std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(k), near.end());
      for (std::size_t i = 0; i < k && affordable(v); ++i)
        if (charged(v, [&] { return mesh.cone_from_vertex(v, near[i].second, 24, 2000); })) {
          ++st.collapsed;
          break;
        }
    }
  });

  // The last ones: re-tetrahedralize a grown cavity without them (up to five layers).
  timed("retetrahedralize", [&] {
    for (Index v : steiner_vertices()) {
      check_cancel();
      if (!mesh.used(v) || !mesh.labels(v).empty()) continue;
      std::size_t steps = 1000;  // shared by the six searches (steiner_removal.h)
      for (int layers = 0; layers <= 5 && affordable(v) && steps > 0; ++layers)
        if (charged(v, [&] { return mesh.retetrahedralize(v, layers, 120, steps); })) {
          ++st.collapsed;
          break;
        }
    }
  });

  // Round the implicit points left.
  timed("round", [&] {
    for (Index v : steiner_vertices()) {
      if (geo.is_explicit(v)) continue;
      check_cancel();
      const Vec3 r = geo.rounded(v);
      bool done = mesh.try_substitute(v, geo.add_explicit_point(r));
      if (done) {
        ++st.rounded;
        continue;
      }
      Vec3 centroid{0, 0, 0};
      const auto nb = mesh.neighbours(v);
      for (Index u : nb) {
        const Vec3 p = geo.rounded(u);
        centroid.x += p.x / nb.size(), centroid.y += p.y / nb.size(), centroid.z += p.z / nb.size();
      }
      for (double a : {0.05, 0.2, 0.4, 0.6, 0.8, 0.95}) {
        const Vec3 p{(1 - a) * r.x + a * centroid.x, (1 - a) * r.y + a * centroid.y, (1 - a) * r.z + a * centroid.z};
        if ((done = mesh.try_substitute(v, geo.add_explicit_point(p)))) break;
      }
      if (!done)
        throw MeshingError(ErrorCode::kInternal, "steiner", v,
                           "no double-precision position keeps the tets around the Steiner point at (" +
                               std::to_string(r.x) + ", " + std::to_string(r.y) + ", " + std::to_string(r.z) +
                               ") positive");
      ++st.rounded;
      ++st.rounded_moved;
    }
  });
  for (Index v : steiner_vertices()) st.boundary_steiner_after += !mesh.labels(v).empty();
  st.collapsed += mesh.merged;
  progress(1.0);
  if (stats_out) *stats_out = st;
  return mesh.alive_tets();
}

}  // namespace bsptet
