// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: flips of the seed tetrahedralization that recover missing input edges and faces
// (BspComplex::seed_delaunay, bsp_seed.cpp, is the one user).
//
// Contract:
//  * Takes a tetrahedralization (tets positively oriented by exact orient3d on the vertices'
//    doubles, two tets sharing a face only with opposite orientations) and the input triangles to
//    protect. Every flip (2-3, 3-2, edge removal n -> 2(n - 2), 3 <= n <= 10, and its one-level
//    spoke retries) replaces the tets of a star by tets strictly positive by orient3d with the
//    same outer faces: the result is again a tetrahedralization of the same points (vertices are
//    never added or removed) over the same region, so the same volume and the same hull.
//  * No flip removes a protected triangle (as a face) or a protected edge: a protected triangle
//    that is a face stays one, a protected edge that is an edge stays one.
//  * recover_edge / recover_face return true exactly when the edge / face is there afterwards; a
//    failed attempt may keep some of its flips (see recover_edge).
//  * Only exact predicates decide; ties are broken by vertex and tet order. Deterministic: the
//    same calls in the same order give the same tets.
//
// The seed need not be Delaunay: any tetrahedralization of the points gives convex cells. Input
// edges missing from it (a nearly planar quad whose Delaunay diagonal is not the input's, the
// common case on tessellated curved faces) make their triangles cross seed tets, and every
// crossing costs BSP points and Steiner points later. So missing input edges are recovered by
// flips where a few suffice, each decided exactly (every new tet strictly positive by orient3d
// on the explicit doubles), never removing an input triangle or an input edge:
//  * 2-3 flip of the face the segment ab leaves its first tet through (adds edge a-f, removes no
//    edge), repeated towards b a bounded number of times;
//  * where ab lies in the plane of a face at a and crosses seed edges of that plane (a tessellated
//    planar CAD face whose fan is not the Delaunay triangulation of its points): edge removal
//    (n tets around a crossed edge -> 2(n - 2), the 4-4 flip when n = 4) of the first crossed
//    edge whose other diagonal clears ab, one crossing fewer each time (planar_flip), up to
//    kMaxFlipsPerEdge flips (bsp_seed.cpp). On thingi10k_112932 (an extruded profile, fans of long triangles on
//    its planar faces) this made the recovered edges 110 -> 750 of ~3600 and the BSP points
//    113,000 -> 59,000 (31 s -> 17 s). Edges still missing are blocked in 3D: the cones over
//    the ring from the removed edge's ends are not all positive (thin slabs of tets over the
//    plane), which needs flips off the plane first:
//  * where the 2-3 flip is blocked (the two tets' union is not convex at an edge of their common
//    face) or ab passes through a seed edge that planar_flip cannot replace, that edge is removed
//    by EDGE REMOVAL over any triangulation of its ring, or where none is valid, after the
//    removal of one of its spokes (remove_edge_deep: Si's flipnm, as in TetGen, one level deep).
//    Measured: edge removal raises the recovered edges 863 -> 1090 of 1102 on triceratops, 124 -> 246 of 264 on
//    couplingdown, 54 -> 144 of 180 on joint (whose seed the auto choice had dropped for the
//    box); core time 0.4 to 0.6 of what it was on these.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "bsptet/mesh/types.h"
#include "bsptet/numerics/predicates.h"

namespace bsptet {

class SeedFlips {
 public:
  using Tet = std::array<Index, 4>;
  /// Takes the tets (each positively oriented, exact orient3d on point_of's doubles; a valid
  /// tetrahedralization) over vertices 0 .. num_vertices - 1, and point_of(v) -> Vec3. `tets` must
  /// outlive the flips: they append their new tets to it (result() gives the alive ones).
  template <class PointOf>
  SeedFlips(std::vector<Tet>& tets, Index num_vertices, PointOf point_of)
      : tets_(tets), inc_(num_vertices), changes_(static_cast<std::size_t>(num_vertices), 0) {
    pts_.resize(static_cast<std::size_t>(num_vertices));
    for (Index v = 0; v < num_vertices; ++v) pts_[v] = point_of(v);
    alive_.assign(tets_.size(), 1);
    for (Index t = 0; t < static_cast<Index>(tets_.size()); ++t)
      for (Index v : tets_[t]) inc_[v].push_back(t);
  }

  /// Input triangle (a, b, c): no flip removes it (as a face) or its edges.
  void protect_triangle(Index a, Index b, Index c);

  /// True when (a, b) is an edge of an alive tet.
  bool has_edge(Index a, Index b) const;

  /// Tries to make (a, b) an edge with at most `max_flips` flips; true when it is one.
  /// The segment ab leaves a through a face (2-3 flip, or where that is blocked, the removal of
  /// the blocking edge: remove_blocking_edge) or through an edge (planar_flip, or its removal:
  /// remove_edge_deep). A failed attempt keeps its flips: each 2-3 or planar flip removed a
  /// crossing of an input edge, so the input triangles there cross fewer seed tets (fewer BSP
  /// points; undoing them measured worse). Undoing the edge removals of failed attempts measured
  /// worse too (joint, anchor, couplingdown: 1.5 to 3.5 times the BSP points), though they need
  /// not remove a crossing: at most kMaxRemovalsPerEdge per attempt (without a bound
  /// thingi10k_112932's seed made 139,000 flips, with it 41,000, for as many recovered edges).
  bool recover_edge(Index a, Index b, int max_flips);

  /// True when (a, b, c) is a face of an alive tet.
  bool has_face(Index a, Index b, Index c) const { return tet_with(a, b, c, -1) >= 0; }

  /// Input triangle (a, b, c) whose edges are seed edges but which is not a seed face: where one
  /// seed edge (d, e) pierces it with exactly the three tets (d, e, a, b), (d, e, b, c),
  /// (d, e, c, a) around it, a 3-2 flip makes it a face. True when it is one.
  bool recover_face(Index a, Index b, Index c);

  /// The alive tets, in order, and their neighbours (as PointDelaunay::nb): `nb` holds those of
  /// the first tets before any flip (the tets given to the constructor) and becomes those of the
  /// result. A neighbour that a flip replaced, and every neighbour of a new tet, is found through
  /// the vertex's tets.
  std::vector<Tet> result(std::vector<std::array<Index, 4>>& nb) const;
  /// Flips made (each 2-3, 3-2, edge removal; undone ones not counted).
  std::int64_t flips() const { return flips_; }

 private:
  static bool contains(const Tet& q, Index v) { return q[0] == v || q[1] == v || q[2] == v || q[3] == v; }
  static int index_of(const Tet& q, Index v) {
    for (int i = 0; i < 4; ++i)
      if (q[i] == v) return i;
    return -1;
  }
  static std::array<Index, 3> key3(std::array<Index, 3> k) {
    std::sort(k.begin(), k.end());
    return k;
  }
  // Sorted vectors, not hash sets: a tenth of the memory (the seed's peak), sorted once.
  void sort_protection();
  bool edge_protected(Index x, Index y);
  bool face_protected(Index x, Index y, Index z);
  /// The alive tet other than `not_t` with the three vertices, or -1.
  Index tet_with(Index x, Index y, Index z, Index not_t) const;
  /// The alive tets around edge (c, d).
  std::vector<Index> ring_around(Index c, Index d) const;
  /// The two vertices of tet t besides c and d.
  std::array<Index, 2> other_two(Index t, Index c, Index d) const;
  bool positive(const Tet& q) const { return orient3d(pts_[q[0]], pts_[q[1]], pts_[q[2]], pts_[q[3]]) == Sign::kPositive; }
  /// Tet q with vertex `from` replaced by `to`: a tet of the flip's new set that keeps q's faces
  /// through the other three vertices (so it must be positive in q's order, no reordering).
  static Tet substituted(Tet q, Index from, Index to) {
    for (Index& v : q)
      if (v == from) v = to;
    return q;
  }
  void replace(const std::vector<Index>& old_tets, const std::vector<Tet>& new_tets);
  /// Undoes the flips logged after the first `mark` (latest first): their new tets (the last ones
  /// made) go, their old tets come back.
  void undo_to(std::size_t mark);
  /// EDGE REMOVAL of (c, d) (any triangulation of its ring), and where that has none, first the
  /// removal of one spoke (x, p): x = c or d, p on the ring (itself with `level` - 1 such
  /// retries), which changes the ring (Si's flipnm, TetGen, to one level): the first spoke after
  /// which (c, d) can go is kept with it; the flips of the others are undone.
  bool remove_edge_deep(Index c, Index d, int level);
  /// The tet t2 across the face (c, d, e) of tet t opposite vertex ia, and its vertex f off that
  /// face; false when there is none (the seed's hull) or the face is an input triangle.
  bool across(Index t, int ia, Index& t2, Index& f);
  // Tet t and its neighbour across the face opposite vertex ia: three tets around the new edge.
  bool flip23(Index t, int ia);
  // Where flip23(t, ia) fails because the two tets' union is not convex at an edge of their
  // common face (a new tet would not be positive), that edge is removed instead (EDGE REMOVAL,
  // any triangulation of its ring): the segment then leaves t's successor through other faces.
  // The first such edge that can go, in the face's order.
  bool remove_blocking_edge(Index t, int ia);
  // Edge (d, e) with exactly three tets around it, whose other vertices are a, b, c: replaced by
  // the two tets over face (a, b, c).
  bool flip32(Index d, Index e, Index a, Index b, Index c);
  /// One flip towards input edge (a, b) when a, b and the seed edge (c, d) it crosses first are
  /// coplanar and the seed triangulates that plane along ab (each crossed edge has a coplanar
  /// ring vertex beyond it): the seed edges ab crosses are listed by walking the plane's
  /// triangles from a to b (exact orient2d in a projection that keeps the plane), and the first
  /// that EDGE REMOVAL can replace by the other diagonal (x, y) of its two plane triangles, a
  /// diagonal that does not cross ab, is replaced: one crossing fewer (Sloan's planar edge
  /// insertion without its flips that keep a crossing, so no flip is ever undone; the caller
  /// repeats, with a bounded number of flips). False when no listed edge can go, or the walk does
  /// not reach b (not a triangulated plane, or a vertex on ab).
  bool planar_flip(Index a, Index b, Index c, Index d);
  static constexpr int kMaxCrossed = 256;  // bounded work: longer walks are not tried

  /// The other vertices of the tets around edge (c, d) (each once), or empty when the tets do not
  /// close a ring around it (a boundary edge of the seed).
  std::vector<Index> ring_apexes(Index c, Index d) const;
  // EDGE REMOVAL of the seed edge (c, d) (not an input edge) with n tets around it, whose other
  // vertices p_0 = a, ..., p_{n-1} form its ring (tets (c, d, p_i, p_i+1) in the ring's
  // orientation): the n tets are replaced by the cones from c and from d over a triangulation of
  // the ring polygon that has the diagonal (a, e), found by dynamic programming over sub-polygons
  // among the triangles whose two cone tets are strictly positive. Valid when all are: the ring's
  // outer faces (c, p_i, p_i+1) and (d, p_i, p_i+1) are kept, and positive cones over the two sides
  // of the polygon tile the edge's star (the 2-3, 3-2 and 4-4 flips are its cases n = 3, 4).
  bool remove_edge(Index c, Index d, Index a, Index e);
  /// True when (c, d, u, w) is an even permutation of tet q (so positive, as q is).
  static bool even_order(const Tet& q, Index c, Index d, Index u, Index w) {
    const std::array<Index, 4> want{{c, d, u, w}};
    std::array<int, 4> perm;
    for (int i = 0; i < 4; ++i) perm[i] = index_of(q, want[i]);
    int inversions = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) inversions += perm[i] > perm[j];
    return inversions % 2 == 0;
  }
  static constexpr int kMaxRing = 10;  // bounded work: rings of at most 10 tets
  static constexpr int kFlipLevels = 1;  // remove_edge_deep's levels of spoke removals
  static constexpr int kMaxRemovalsPerEdge = 8;  // recover_edge's edge removals per attempt
  struct FlipLog {
    std::vector<Index> old_tets;
    std::size_t first_new;  ///< the flip's new tets are tets_[first_new ..] when it is the latest
  };

  std::vector<Tet>& tets_;
  std::vector<std::vector<Index>> inc_;
  std::vector<Vec3> pts_;
  std::vector<char> alive_;
  std::vector<std::array<Index, 3>> protected_faces_;
  std::vector<std::uint64_t> protected_edges_;
  bool protection_sorted_ = true;
  std::int64_t flips_ = 0;
  std::vector<std::uint64_t> changes_;  ///< per vertex: how often its tets changed (flips, undos)
  std::vector<FlipLog> log_;  ///< flips made while logging_ (remove_edge_deep), for undo_to
  bool logging_ = false;
  /// remove_edge_deep's failures: edge -> (level, signature)
  std::unordered_map<std::uint64_t, std::pair<int, std::uint64_t>> failed_deep_;
};

}  // namespace bsptet
