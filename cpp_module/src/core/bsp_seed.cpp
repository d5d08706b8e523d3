// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: seeding the BSP complex with a Delaunay tetrahedralization of the input points
// (the idea of Diazzi & Attene's BSP complex, 2021), see bsp_complex.h.
//
// Instead of one box cell cut by every input plane, the complex starts as the tets of the exact
// (perturbed) Delaunay tetrahedralization of the input points and the 8 box corners. Each tet is a
// convex cell; its conflict list holds the input triangles that may cross its interior, found by
// a walk from the triangle's first vertex and decided by a separating-axis test
// (seed_tet_triangle.h: exact on the face planes, certified intervals on the edge-pair axes;
// conservative: a triangle is left out only when the interiors are proved disjoint). The build
// then splits only those cells, by the planes of their conflict triangles, as with the box. On a
// fine surface most input triangles are Delaunay faces already and cut nothing: the cells, BSP
// points and Steiner points no longer grow with the number of planes a cell sees (the
// auto-partition's peeling chain).
//
// Faces of the seed lie on an input plane when their three corners do (known from the input
// triangles around each corner, or decided exactly against the planes of any corner's
// triangles); such a face takes that plane's id and lists the plane's triangles that may overlap
// it (`coplanar`), so that refine_covered_faces and the classification see it as with the box.
// Any other face gets a plane of its own through its three corners; the walk of step 3 gives it
// an input plane after all when it lies on the plane of a triangle that touches it (its corners
// may lie on an input plane without being corners of that plane's triangles).
//
// Input edges and faces missing from the Delaunay tets are recovered by flips before step 2
// (seed_flips.h).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "bsptet/core/bsp_complex.h"
#include "bsptet/core/cell_delaunay.h"
#include "bsptet/numerics/errors.h"
#include "bsptet/core/point_delaunay.h"
#include "bsptet/core/seed_flips.h"
#include "bsptet/core/seed_tet_triangle.h"
#include "bsptet/numerics/splitmix.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

namespace {

constexpr auto& kFace = kTetOppositeFace;  // types.h
constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
// Flips tried per missing input edge (SeedFlips::recover_edge), from each end.
constexpr int kMaxFlipsPerEdge = 64;

std::uint64_t spread3(std::uint64_t x) {  // 21 bits -> every third bit of 63
  x &= 0x1fffffULL;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

void BspComplex::seed_delaunay(std::int64_t max_conflicts) {
  corner0_ = geo_.num_explicit() - 8;
  const Index input_planes = geo_.num_planes();
  auto t0 = std::chrono::steady_clock::now();
  auto lap = [&](const char* step) {
    const auto t1 = std::chrono::steady_clock::now();
    stats_.seed_seconds[step] += std::chrono::duration<double>(t1 - t0).count();
    t0 = t1;
  };
  // Vertex ids of explicit points are their point ids here (mesher.cpp adds them in order).
  auto point_of = [&](Index v) -> const Vec3& { return geo_.explicit_point(geo_.explicit_id(v)); };
  // 1. The points: the box corners first (their hull is the box, so every walk stays inside),
  // then the input points that triangles use, in the order below (short walks, small cavities).
  std::vector<char> used(static_cast<std::size_t>(corner0_), 0);
  for (Index v : surface_.tri) used[v] = 1;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (Index c = corner0_; c < corner0_ + 8; ++c) {
    const Vec3& x = point_of(c);
    const double xs[3] = {x.x, x.y, x.z};
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], xs[k]);
      hi[k] = std::max(hi[k], xs[k]);
    }
  }
  std::vector<std::pair<std::uint64_t, Index>> keyed;
  for (Index v = 0; v < corner0_; ++v) {
    if (!used[v]) continue;
    const Vec3& x = point_of(v);
    const double xs[3] = {x.x, x.y, x.z};
    std::uint64_t code = 0;
    for (int k = 0; k < 3; ++k) {
      const double f = (xs[k] - lo[k]) / (hi[k] - lo[k]);
      const auto g = static_cast<std::uint64_t>(std::clamp(f, 0.0, 1.0) * 2097151.0);
      code |= spread3(g) << k;
    }
    keyed.push_back({code, v});
  }
  // Biased randomized insertion order (Amenta, Choi and Rote): the points shuffled by a fixed
  // generator, then split in rounds of doubling size (the last holds half of them), each round in
  // Morton order. Morton order alone inserts a surface's points one sheet after the other, and
  // each new point then conflicts with the long tets spanning the empty inside: cavities grew
  // with the input (the Delaunay of a 10^6-triangle CAD part took 17 times that of 10^5). The
  // triangulation itself does not depend on the order.
  {
    std::uint64_t rng = 0xB210ULL;
    for (std::size_t i = keyed.size(); i > 1; --i) std::swap(keyed[i - 1], keyed[splitmix64(rng) % i]);
    std::size_t end = keyed.size();
    while (end > 0) {
      const std::size_t begin = end > 2048 ? end / 2 : 0;
      std::sort(keyed.begin() + static_cast<std::ptrdiff_t>(begin), keyed.begin() + static_cast<std::ptrdiff_t>(end));
      end = begin;
    }
  }
  std::vector<Index> order;
  order.reserve(keyed.size() + 8);
  for (Index c = corner0_; c < corner0_ + 8; ++c) order.push_back(c);
  for (const auto& kv : keyed) order.push_back(kv.second);
  PointDelaunay dt;
  if (!delaunay_explicit_points(geo_, order, dt))
    throw MeshingError(ErrorCode::kInternal, "bsp", -1, "the Delaunay seed of the input points failed");
  std::vector<std::array<Index, 4>> tets = std::move(dt.tets);
  std::vector<std::array<Index, 4>> nb = std::move(dt.nb);
  decltype(keyed)().swap(keyed);
  std::vector<Index>().swap(order);
  std::vector<char>().swap(used);
  lap("seed_delaunay");
  // Is any input edge or input triangle missing from the seed? (Vertex -> tets incidence in one
  // array; flips never remove an input edge or triangle, so what is here now stays.) When nothing
  // is missing, the flips' bookkeeping is not built at all.
  bool all_present = true;
  {
    const std::size_t nv = static_cast<std::size_t>(corner0_ + 8);
    std::vector<Index> first(nv + 1, 0), inc(4 * tets.size());
    for (const auto& q : tets)
      for (Index v : q) ++first[v + 1];
    for (std::size_t v = 0; v < nv; ++v) first[v + 1] += first[v];
    std::vector<Index> fill(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < tets.size(); ++t)
      for (Index v : tets[t]) inc[fill[v]++] = static_cast<Index>(t);
    auto has = [&](Index a, Index b, Index c) {  // c < 0: edge (a, b)
      for (Index i = first[a]; i < first[a + 1]; ++i) {
        const auto& q = tets[inc[i]];
        const bool hb = q[0] == b || q[1] == b || q[2] == b || q[3] == b;
        if (hb && (c < 0 || q[0] == c || q[1] == c || q[2] == c || q[3] == c)) return true;
      }
      return false;
    };
    for (Index tr = 0; tr < surface_.num_triangles() && all_present; ++tr) {
      const Index a = triangle_vertex(tr, 0), b = triangle_vertex(tr, 1), c = triangle_vertex(tr, 2);
      all_present = has(a, b, -1) && has(b, c, -1) && has(c, a, -1) && has(a, b, c);
    }
  }
  if (!all_present) {
    SeedFlips flips(tets, corner0_ + 8, point_of);
    for (Index tr = 0; tr < surface_.num_triangles(); ++tr)
      flips.protect_triangle(triangle_vertex(tr, 0), triangle_vertex(tr, 1), triangle_vertex(tr, 2));
    auto recover = [&](Index a, Index b) {
      return flips.recover_edge(a, b, kMaxFlipsPerEdge) || flips.recover_edge(b, a, kMaxFlipsPerEdge);
    };
    std::vector<std::pair<Index, Index>> missing;  // edges not recovered yet, for two more passes
    for (Index tr = 0; tr < surface_.num_triangles(); ++tr)
      for (int k = 0; k < 3; ++k) {
        const Index a = triangle_vertex(tr, k), b = triangle_vertex(tr, (k + 1) % 3);
        if (a > b || flips.has_edge(a, b)) continue;  // each edge once (its other triangle has it reversed)
        ++stats_.seed_missing_edges;
        if (recover(a, b))
          ++stats_.seed_recovered_edges;
        else
          missing.push_back({a, b});
      }
    for (int pass = 0; pass < 2 && !missing.empty(); ++pass) {
      std::vector<std::pair<Index, Index>> still;
      for (const auto& [a, b] : missing)
        if (recover(a, b))
          ++stats_.seed_recovered_edges;
        else
          still.push_back({a, b});
      if (still.size() == missing.size()) break;
      missing.swap(still);
    }
    for (Index tr = 0; tr < surface_.num_triangles(); ++tr) {
      const Index a = triangle_vertex(tr, 0), b = triangle_vertex(tr, 1), c = triangle_vertex(tr, 2);
      if (flips.has_face(a, b, c) || !flips.has_edge(a, b) || !flips.has_edge(b, c) || !flips.has_edge(c, a)) continue;
      ++stats_.seed_missing_faces;
      if (flips.recover_face(a, b, c)) ++stats_.seed_recovered_faces;
    }
    stats_.seed_flips = flips.flips();
    if (flips.flips() > 0) tets = flips.result(nb);
  }
  const Index nt = static_cast<Index>(tets.size());
  stats_.seed_tets = nt;
  lap("seed_flips");

  // 2. Faces: one per distinct triangle of the tets, shared by its (one or two) tets. They are
  // light records here; only those of the tets that go into the complex (step 4) become BspFaces.
  // A seed face: verts CCW around its normal, tet[0] on the positive side (the normal points into
  // it), tet[1] on the negative side (-1: none). plane: the input plane it lies on, or -1 (not on
  // one: the complex gives it a plane of its own through its corners, in this vertex order).
  // coplanar: the input triangles of its plane that may overlap it, as an index into
  // `coplanar_lists` (-1: none; most faces have none).
  struct SeedFace {
    std::array<Index, 3> verts;
    Index plane;
    Index tet[2];
    Index coplanar = -1;
  };
  std::vector<SeedFace> sfaces;
  std::vector<std::vector<Index>> coplanar_lists;
  const std::vector<Index> no_triangles;
  auto coplanar_of = [&](const SeedFace& f) -> const std::vector<Index>& {
    return f.coplanar < 0 ? no_triangles : coplanar_lists[f.coplanar];
  };
  auto add_coplanar = [&](SeedFace& f, Index tr) {
    if (f.coplanar < 0) {
      f.coplanar = static_cast<Index>(coplanar_lists.size());
      coplanar_lists.emplace_back();
    }
    auto& list = coplanar_lists[f.coplanar];
    if (list.empty() || list.back() != tr) list.push_back(tr);
  };
  sfaces.reserve(2 * static_cast<std::size_t>(nt) + 8);
  std::vector<std::array<Index, 4>> tet_face(nt, {-1, -1, -1, -1});
  // The input plane a face lies on by its corners' triangles: every corner an input point known
  // on one plane (no arithmetic). A face whose corners lie on an input plane without all being
  // known on it keeps a plane of its own here; the walk of step 3 gives it the input plane when a
  // triangle of that plane touches it (the only case where its coverage matters).
  auto input_plane_of = [&](Index x, Index y, Index z) -> Index {
    if (x >= corner0_ || y >= corner0_ || z >= corner0_) return -1;
    for (Index q : geo_.known_planes(x))
      if (q < input_planes && geo_.known_on_plane(y, q) && geo_.known_on_plane(z, q)) return q;
    return -1;
  };
  // Input-plane faces by their sorted corners (an input triangle that is a face of the seed is
  // found here), sorted.
  std::vector<std::pair<std::array<Index, 3>, Index>> face_of_corners;
  for (Index t0 = 0; t0 < nt; ++t0)
    for (int i0 = 0; i0 < 4; ++i0) {
      const Index t1 = nb[t0][i0];
      if (t1 >= 0 && t1 < t0) continue;  // made from the neighbour
      const Index x = tets[t0][kFace[i0][0]], y = tets[t0][kFace[i0][1]], z = tets[t0][kFace[i0][2]];
      const Index apex = tets[t0][i0];  // on the positive side of (x, y, z)
      SeedFace f{{x, y, z}, -1, {t0, t1}, -1};
      const Index q = input_plane_of(x, y, z);
      const Index id = static_cast<Index>(sfaces.size());
      if (q >= 0) {
        f.plane = q;
        const Sign side = geo_.side(q, apex);
        if (side == Sign::kZero) throw MeshingError(ErrorCode::kInternal, "bsp", t0, "a flat Delaunay seed tet");
        if (side == Sign::kNegative) {
          f.verts = {x, z, y};
          f.tet[0] = t1;
          f.tet[1] = t0;
        }
        std::array<Index, 3> key{{x, y, z}};
        std::sort(key.begin(), key.end());
        face_of_corners.push_back({key, id});
      }
      sfaces.push_back(std::move(f));
      tet_face[t0][i0] = id;
      if (t1 >= 0) {
        int i1 = 0;
        while (i1 < 4 && nb[t1][i1] != t0) ++i1;
        if (i1 == 4) throw MeshingError(ErrorCode::kInternal, "bsp", t0, "Delaunay seed neighbours disagree");
        tet_face[t1][i1] = id;
      }
    }
  std::sort(face_of_corners.begin(), face_of_corners.end());
  std::vector<Index> vertex_tet(static_cast<std::size_t>(corner0_ + 8), -1);
  for (Index t = 0; t < nt; ++t)
    for (int i = 0; i < 4; ++i)
      if (vertex_tet[tets[t][i]] < 0) vertex_tet[tets[t][i]] = t;

  lap("seed_faces");
  // 3. Conflict lists and coplanar lists. An input triangle that is a face of the seed crosses
  // no tet (faces of a tetrahedralization never meet a tet's interior) and overlaps no other
  // face: it goes on that face's coplanar list, nothing more. Any other triangle walks over the
  // tets it meets; those whose interior it crosses (seed_tet_triangle.h, exact) get it on their
  // conflict list.
  // Crossings as (tet, triangle) pairs, sorted by tet after the walks (then each tet's triangles
  // are in increasing order, as they were found): a list per tet cost 24 bytes for every seed tet,
  // most of them never crossed (77 MB of the seed's peak at 10^6 triangles).
  std::vector<std::pair<Index, Index>> crossing;
  std::vector<std::uint32_t> seen(static_cast<std::size_t>(nt), 0);
  std::uint32_t stamp = 0;
  std::vector<Index> queue;
  for (Index tr = 0; tr < surface_.num_triangles(); ++tr) {
    const std::array<Vec3, 3> q{{surface_.point(triangle_vertex(tr, 0)), surface_.point(triangle_vertex(tr, 1)),
                                 surface_.point(triangle_vertex(tr, 2))}};
    const std::array<Index, 3> qid{{triangle_vertex(tr, 0), triangle_vertex(tr, 1), triangle_vertex(tr, 2)}};
    const Index plane = tri_plane_[tr];
    {
      std::array<Index, 3> key = qid;
      std::sort(key.begin(), key.end());
      const auto it = std::lower_bound(face_of_corners.begin(), face_of_corners.end(),
                                       std::pair<std::array<Index, 3>, Index>{key, -1});
      if (it != face_of_corners.end() && it->first == key && sfaces[it->second].plane == plane) {
        add_coplanar(sfaces[it->second], tr);
        ++stats_.seed_face_triangles;
        continue;
      }
    }
    ++stamp;
    queue.clear();
    const Index start = vertex_tet[triangle_vertex(tr, 0)];
    if (start < 0) throw MeshingError(ErrorCode::kInternal, "bsp", tr, "an input vertex is not in the Delaunay seed");
    queue.push_back(start);
    seen[start] = stamp;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      const Index t = queue[h];
      const std::array<Vec3, 4> p{{point_of(tets[t][0]), point_of(tets[t][1]), point_of(tets[t][2]),
                                   point_of(tets[t][3])}};
      const int rel = seed_tet_triangle_relation(p, tets[t], q, qid);
      if (rel == 0) continue;
      if (rel == 2) {
        crossing.push_back({t, tr});
        if (++stats_.seed_conflicts > max_conflicts && max_conflicts >= 0) {
          stats_.seed_abandoned = true;
          lap("seed_walk");
          return;
        }
      }
      for (int i = 0; i < 4; ++i) {
        SeedFace& f = sfaces[tet_face[t][i]];
        // A face not on an input plane by its corners' triangles may still lie on this
        // triangle's plane (none of its corners is a corner of that plane's triangles, step 2):
        // then it takes the input plane, decided exactly, so that the coverage and the
        // classification see it.
        if (f.plane < 0 &&
            std::all_of(f.verts.begin(), f.verts.end(), [&](Index v) { return geo_.side(plane, v) == Sign::kZero; })) {
          const Sign apex_side = geo_.side(plane, tets[t][i]);
          if (apex_side == Sign::kZero) throw MeshingError(ErrorCode::kInternal, "bsp", t, "a flat Delaunay seed tet");
          if ((f.tet[0] == t) != (apex_side == Sign::kPositive)) {
            std::reverse(f.verts.begin(), f.verts.end());
            std::swap(f.tet[0], f.tet[1]);
          }
          f.plane = plane;
          ++stats_.seed_faces_relabelled;
        }
        if (f.plane == plane) add_coplanar(f, tr);
        const Index n = nb[t][i];
        if (n >= 0 && seen[n] != stamp) {
          seen[n] = stamp;
          queue.push_back(n);
        }
      }
    }
  }
  std::vector<std::uint32_t>().swap(seen);
  std::sort(crossing.begin(), crossing.end());
  // conflict_begin[t] .. conflict_begin[t + 1]: tet t's entries of `crossing`.
  std::vector<Index> conflict_begin(static_cast<std::size_t>(nt) + 1, 0);
  for (const auto& [t, tr] : crossing) ++conflict_begin[static_cast<std::size_t>(t) + 1];
  for (Index t = 0; t < nt; ++t) conflict_begin[t + 1] += conflict_begin[t];
  auto crossed = [&](Index t) { return conflict_begin[t + 1] > conflict_begin[t]; };
  lap("seed_walk");

  // 4. Which tets go into the complex (UntouchedSeedTets, bsp_complex.h): those with an edge of a
  // crossed tet or of a face on an input plane that is not exactly one input triangle (a face
  // refine_covered_faces would split).
  auto is_input_triangle = [&](std::array<Index, 3> a, const std::vector<Index>& coplanar) {
    if (coplanar.size() != 1) return false;
    std::array<Index, 3> b{{triangle_vertex(coplanar[0], 0), triangle_vertex(coplanar[0], 1),
                            triangle_vertex(coplanar[0], 2)}};
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    return a == b;
  };
  auto needs_refinement = [&](const SeedFace& f) {
    return f.plane >= 0 && !coplanar_of(f).empty() && !is_input_triangle(f.verts, coplanar_of(f));
  };
  // A crossed tet T is split only by the planes of its conflict triangles (choose_plane), and
  // its pieces' faces are refined only along lines inside them: a seed edge of T is cut only
  // when one of those planes crosses it or contains it (then refinement lines in the plane may
  // cross it). Such edges are hot, with the edges of the faces needing refinement; a seed tet
  // goes into the complex when it is crossed, shares a face with a crossed tet (T's faces are
  // split), or has a hot edge. (A split that reaches a tet left out throws, and the mesher
  // retries from the box: bsp_complex.cpp.)
  std::vector<std::uint64_t> hot;
  std::vector<char> near_crossed(static_cast<std::size_t>(nt), 0);
  std::vector<Index> planes_of;
  for (Index t = 0; t < nt; ++t) {
    if (!crossed(t)) continue;
    near_crossed[t] = 1;
    for (int i = 0; i < 4; ++i)
      if (nb[t][i] >= 0) near_crossed[nb[t][i]] = 1;
    planes_of.clear();
    for (Index k = conflict_begin[t]; k < conflict_begin[t + 1]; ++k) planes_of.push_back(tri_plane_[crossing[k].second]);
    std::sort(planes_of.begin(), planes_of.end());
    planes_of.erase(std::unique(planes_of.begin(), planes_of.end()), planes_of.end());
    for (const auto& ed : kEdge) {
      const Index a = tets[t][ed[0]], b = tets[t][ed[1]];
      for (Index p : planes_of) {
        const int sa = to_int(geo_.side(p, a)), sb = to_int(geo_.side(p, b));
        if (sa * sb < 0 || (sa == 0 && sb == 0)) {
          hot.push_back(edge_key(a, b));
          break;
        }
      }
    }
  }
  for (const SeedFace& f : sfaces)
    if (needs_refinement(f))
      for (int k = 0; k < 3; ++k) hot.push_back(edge_key(f.verts[k], f.verts[(k + 1) % 3]));
  std::sort(hot.begin(), hot.end());
  hot.erase(std::unique(hot.begin(), hot.end()), hot.end());
  std::vector<char> hot_vertex(static_cast<std::size_t>(corner0_ + 8), 0);
  for (std::uint64_t k : hot) {
    hot_vertex[static_cast<std::size_t>(k >> 32)] = 1;
    hot_vertex[static_cast<std::size_t>(k & 0xffffffffu)] = 1;
  }
  std::vector<Index> cell_of(static_cast<std::size_t>(nt), -1), untouched_of(static_cast<std::size_t>(nt), -1);
  Index num_cells = 0, num_untouched = 0;
  for (Index t = 0; t < nt; ++t) {
    bool in = near_crossed[t] != 0;
    for (int k = 0; k < 6 && !in; ++k) {
      const Index a = tets[t][kEdge[k][0]], b = tets[t][kEdge[k][1]];
      in = hot_vertex[a] && hot_vertex[b] && std::binary_search(hot.begin(), hot.end(), edge_key(a, b));
    }
    (in ? cell_of[t] = num_cells++ : untouched_of[t] = num_untouched++);
  }
  std::vector<std::uint64_t>().swap(hot);
  std::vector<char>().swap(hot_vertex);
  std::vector<char>().swap(near_crossed);
  stats_.untouched_tets = num_untouched;
  stats_.leaves += num_untouched;

  // 5. The complex: the cells of those tets and their faces. A face between a cell and an
  // untouched tet keeps cell -1 on that side and remembers the tet (face_untouched).
  auto in_complex = [&](const SeedFace& f) {
    return (f.tet[0] >= 0 && cell_of[f.tet[0]] >= 0) || (f.tet[1] >= 0 && cell_of[f.tet[1]] >= 0);
  };
  // The faces of the cells, in the order of their sorted corners (the refinements visit faces by
  // id: a fixed order that does not depend on how the seed's tets were numbered).
  std::vector<std::pair<std::array<Index, 3>, Index>> made;
  for (std::size_t i = 0; i < sfaces.size(); ++i)
    if (in_complex(sfaces[i])) {
      std::array<Index, 3> key = sfaces[i].verts;
      std::sort(key.begin(), key.end());
      made.push_back({key, static_cast<Index>(i)});
    }
  std::sort(made.begin(), made.end());
  {
    const std::size_t num_faces = made.size();
    // Capacity for the seed and an eighth more for the splits: growing a vector doubles it (and
    // holds old and new at once), which made these two vectors the peak of the BSP's memory.
    faces_.reserve(faces_.size() + num_faces + num_faces / 8);
    face_boxes_.reserve(faces_.capacity());
    const auto ncells = static_cast<std::size_t>(num_cells);
    cells_.reserve(ncells + ncells / 8);
    // Edges: about (faces + vertices) / 2 for the cells' part of a tetrahedralization (Euler), so
    // the edge maps never rehash while the faces register theirs.
    const std::size_t num_edges = num_faces / 2 + 4 * ncells / 3 + 8;
    edge_faces_.reserve(edge_faces_.size() + num_edges + num_edges / 8);
    edge_line_.reserve(edge_line_.size() + num_edges + num_edges / 8);
  }
  cells_.assign(static_cast<std::size_t>(num_cells), BspCell{});
  std::vector<Index> complex_face(sfaces.size(), -1);
  face_untouched_.assign(faces_.size() + made.size(), -1);
  for (const auto& [key, i] : made) {
    SeedFace& f = sfaces[i];
    const Index c0 = f.tet[0] >= 0 ? cell_of[f.tet[0]] : -1, c1 = f.tet[1] >= 0 ? cell_of[f.tet[1]] : -1;
    BspFace bf;
    bf.plane = f.plane >= 0 ? f.plane
                            : geo_.add_plane(geo_.explicit_id(f.verts[0]), geo_.explicit_id(f.verts[1]),
                                             geo_.explicit_id(f.verts[2]));
    bf.verts.assign(f.verts.begin(), f.verts.end());
    bf.cell[0] = c0;
    bf.cell[1] = c1;
    if (f.coplanar >= 0) bf.coplanar = std::move(coplanar_lists[f.coplanar]);
    const Index id = new_face(std::move(bf));
    complex_face[i] = id;
    const Index other = c0 < 0 ? f.tet[0] : (c1 < 0 ? f.tet[1] : -1);
    if (other >= 0) face_untouched_[id] = untouched_of[other];
  }
  // A cell's face boxes are left to split_cell, which builds them when they are out of step:
  // most seed tets are never split, and four boxes per tet were a fifth of the seed's memory.
  for (Index t = 0; t < nt; ++t) {
    if (cell_of[t] < 0) continue;
    BspCell& cell = cells_[cell_of[t]];
    for (int i = 0; i < 4; ++i) cell.faces.push_back(complex_face[tet_face[t][i]]);
    cell.conflict.reserve(static_cast<std::size_t>(conflict_begin[t + 1] - conflict_begin[t]));
    for (Index k = conflict_begin[t]; k < conflict_begin[t + 1]; ++k) cell.conflict.push_back(crossing[k].second);
  }
  untouched_.tets.reserve(static_cast<std::size_t>(num_untouched));
  untouched_.adj.reserve(static_cast<std::size_t>(num_untouched));
  untouched_.step.reserve(static_cast<std::size_t>(num_untouched));
  untouched_.cover.reserve(static_cast<std::size_t>(num_untouched));
  untouched_.before_cell.reserve(static_cast<std::size_t>(num_untouched));
  Index cells_before = 0;
  for (Index t = 0; t < nt; ++t) {
    if (untouched_of[t] < 0) {
      ++cells_before;
      continue;
    }
    std::array<Index, 4> adj, cover{{-1, -1, -1, -1}};
    std::array<signed char, 4> step{{0, 0, 0, 0}};
    for (int i = 0; i < 4; ++i) {
      const Index n = nb[t][i];
      adj[i] = n < 0 ? -1 : (cell_of[n] >= 0 ? -2 - complex_face[tet_face[t][i]] : untouched_of[n]);
      const Index fi = tet_face[t][i];
      // (A face shared with a cell handed its coplanar list to the complex.)
      const std::vector<Index>& cop =
          complex_face[fi] >= 0 ? faces_[complex_face[fi]].coplanar : coplanar_of(sfaces[fi]);
      if (sfaces[fi].plane < 0 || cop.empty()) continue;
      const Index tr = cop[0];
      if (!is_input_triangle(sfaces[fi].verts, cop))
        throw MeshingError(ErrorCode::kInternal, "bsp", tr, "an untouched seed tet has a face that needs refinement");
      // +1 when the triangle (a, b, c), outward, turns like the face (x, y, z) whose normal
      // points into t: then the outside is on t's side.
      const Index x = tets[t][kFace[i][0]], y = tets[t][kFace[i][1]];
      const Index a = triangle_vertex(tr, 0), b = triangle_vertex(tr, 1), c = triangle_vertex(tr, 2);
      const bool same_turn = (x == a && y == b) || (x == b && y == c) || (x == c && y == a);
      step[i] = same_turn ? 1 : -1;
      cover[i] = tr;
    }
    untouched_.tets.push_back(tets[t]);
    untouched_.before_cell.push_back(cells_before);
    untouched_.adj.push_back(adj);
    untouched_.step.push_back(step);
    untouched_.cover.push_back(cover);
  }
  lap("seed_cells");
  // 6. Edge lines of the cells: the planes of the two faces of a tet through the edge (never the
  // same geometric plane), taken after the walk, which may have given faces their input plane.
  for (Index t = 0; t < nt; ++t) {
    if (cell_of[t] < 0) continue;
    for (const auto& ed : kEdge) {
      const std::uint64_t key = edge_key(tets[t][ed[0]], tets[t][ed[1]]);
      if (edge_line_.contains(key)) continue;
      int other[2], m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != ed[0] && j != ed[1]) other[m++] = j;
      edge_line_[key] = {faces_[complex_face[tet_face[t][other[0]]]].plane,
                         faces_[complex_face[tet_face[t][other[1]]]].plane};
    }
  }
  lap("seed_lines");
}

}  // namespace bsptet
