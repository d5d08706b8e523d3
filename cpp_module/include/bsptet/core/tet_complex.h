// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the tet complex that Steiner point removal edits (steiner_removal.h states each
// operation and why it keeps the complex valid; remove_steiner_points is its one user).
//
// What it holds: tets, each four vertex ids of an ImplicitGeometry (explicit or TPI points), and
// surface faces, each three vertex ids with a label, the input triangle that contains the face;
// per vertex, the tets and surface faces at it. Ids below surface.num_points() are the input
// points.
//
// Contract:
//  * Valid complex: every tet is positively oriented (exact orient3d, mesh/types.h), two tets
//    share a face only with opposite orientations, and the faces that belong to one tet only
//    are the surface faces, outward. The complex is built valid by add_tet and add_face (the
//    cells' tets and their boundary faces); those two and kill_tet/kill_face check nothing.
//  * Every edit (try_substitute as stated there, relocate, push, cone_from_vertex, remove_edge,
//    retetrahedralize) either returns true and leaves a valid complex that covers the same region
//    as before (so the same volume), with the surface faces of each label covering the same part
//    of their input triangle, or returns false and leaves the tets and surface faces as they
//    were. (relocate and push may add explicit points to the geometry either way; relocate says
//    why it failed in `why`.) Input points are never moved or removed; a Steiner point leaves the
//    surface only through relocate.
//  * Every decision is an exact predicate of the geometry; double arithmetic only proposes
//    candidate points. Results depend only on the calls made, in their order: ids, not
//    addresses, order every choice. `work` counts the exact tests and cavity growth done, the
//    measure of the callers' budgets.
//  * Not thread-safe. The geometry, the surface and tri_plane must outlive the complex.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bsptet/mesh/types.h"
#include "bsptet/numerics/implicit_geometry.h"

namespace bsptet {

class TetComplex {
 public:
  /// An empty complex over the vertices of `geo` (ids below surface.num_points() are the input
  /// points); `tri_plane[t]` is the plane (in `geo`) of input triangle t. All three must outlive it.
  TetComplex(ImplicitGeometry& geo, const SurfaceMesh& surface, const std::vector<Index>& tri_plane);
  ~TetComplex();
  TetComplex(const TetComplex&) = delete;
  TetComplex& operator=(const TetComplex&) = delete;

  /// Adds tet t (positively oriented) and returns its id; ids are never reused.
  Index add_tet(const std::array<Index, 4>& t);
  /// Removes tet `id` from the complex (its id stays dead).
  void kill_tet(Index id);
  /// Adds the outward surface face f inside input triangle `label` and returns its id.
  Index add_face(const std::array<Index, 3>& f, Index label);
  /// Removes surface face `id`.
  void kill_face(Index id);
  /// What a collapse of v depends on besides fixed geometry: its star and surface faces, and its
  /// neighbours' surface faces (the support rule), as change counters (each tet or face added or
  /// removed counts at its vertices). Counters only grow, and the neighbours are fixed while v's
  /// counter is, so an equal signature means nothing a collapse attempt looks at has changed.
  std::pair<std::uint64_t, std::uint64_t> signature(Index v, const std::vector<Index>& nbrs) const;
  /// Whether v is a vertex of some tet.
  bool used(Index v) const { return v < static_cast<Index>(vt_.size()) && !vt_[v].empty(); }
  /// Input triangles containing the surface faces at v, sorted (empty: v is interior).
  std::vector<Index> labels(Index v) const;
  /// Whether u is a corner of input triangle t.
  bool is_corner(Index u, Index t) const;
  /// Neighbours of v: input points first, then by id.
  std::vector<Index> neighbours(Index v) const;
  /// The support rule (steiner_removal.h, COLLAPSE): may Steiner point v, whose labels() are `lv`, move onto
  /// vertex u?
  bool may_move_onto(Index v, const std::vector<Index>& lv, Index u) const;
  /// Puts u in place of v in every tet and surface face of v, if every new tet is positive. Tets
  /// and faces that already contain u vanish (a collapse along the edge v-u); for a new vertex u
  /// none do (v moves to u). Returns false, changing nothing, when a tet would not be positive.
  /// The region stays the same when v is a Steiner point that may_move_onto u allows (COLLAPSE),
  /// or when v is interior and u a new vertex.
  bool try_substitute(Index v, Index u);
  std::string why;  ///< why the last relocate() failed
  std::int64_t merged = 0;  ///< interior points removed with a relocated surface point
  int grow_limit = 16;      ///< cavity growth steps per candidate point (relocate)
  std::size_t max_cavity = 4000;  ///< tets in a grown cavity, at most
  int deep_grow_limit = 64;  ///< cavity growth steps per deep candidate (relocate; 0: no deep candidates)
  std::size_t max_candidates = 1000;
  /// Exact orientation tests made so far, plus the faces and tets a cavity growth handles (the
  /// work measure of the budgets).
  std::int64_t work = 0;
  /// Removes v and the Steiner points `also` (any of them may be on the surface) and cones their
  /// cavity from one new double point w (steiner_removal.h: RELOCATE). The surface faces that touch a
  /// removed point are re-triangulated per input triangle: the region's boundary cycle, removed
  /// points dropped (they must be collinear with their neighbours there: on an input edge), by
  /// exact ear clipping.
  bool relocate(Index v, const std::vector<Index>& also = {});
  /// PUSH (steiner_removal.h): moves the interior Steiner point z to the Chebyshev centre of its
  /// star's kernel (rounded to doubles) when that at least doubles its clearance from its link
  /// faces (estimated in doubles); taken only if every new tet is positive (decided exactly).
  bool push(Index z);
  /// RETETRAHEDRALIZE (steiner_removal.h): removes the interior Steiner point v by filling a cavity
  /// around it (v's star grown by `layers` layers of tets that share a face's three vertices with
  /// it) with new tets over the cavity's boundary vertices only, found by a depth-first search over
  /// the front (the boundary chain of what is left to fill) with at most `steps_left` steps, which
  /// it decreases by the steps taken.
  bool retetrahedralize(Index v, int layers, std::size_t max_tets, std::size_t& steps_left);
  /// Removes the interior Steiner point v by re-coning a cavity from its neighbour u: the cavity
  /// starts as v's star and takes the tet beyond every face u does not see (never across a surface
  /// face), at most `max_grow` times and up to `max_tets` tets. The cone from u over the cavity's
  /// boundary faces that do not contain u tiles the cavity when every cone tet is positive (the
  /// argument of COLLAPSE, which is the case without growth). Interior Steiner points strictly
  /// inside the grown cavity vanish with v. Returns false, changing nothing, otherwise.
  bool cone_from_vertex(Index v, Index u, int max_grow, std::size_t max_tets);
  /// EDGE REMOVAL (an n-to-2(n-2) flip): the n tets around the interior edge (v, x) are replaced by
  /// the cones from x and from v over a triangulation of their ring polygon a_0..a_{n-1} (oriented
  /// so that every (v, x, a_i, a_i+1) is positive): tets (p, q, r, x) and (p, r, q, v) for each
  /// triangle (p, q, r) in ring order. The outer faces (v or x, a_i, a_i+1) are kept, so the result
  /// is conforming; it is taken when every new tet is positive (the first triangulation found, in
  /// a fixed order). n <= 7. Returns false, changing nothing, otherwise.
  bool remove_edge(Index v, Index x);
  /// Outward boundary faces of a set of tets (sorted ids): the faces that appear once.
  std::vector<std::array<Index, 3>> boundary_faces(const std::vector<Index>& cav) const;
  /// The tets of the complex, in the order of their ids.
  std::vector<std::array<Index, 4>> alive_tets() const;
  /// The ids of the tets at v (in no particular order).
  const std::vector<Index>& star(Index v) const { return vt_[v]; }
  /// Tet `id` (alive or not).
  const std::array<Index, 4>& tet(Index id) const { return tets_[id]; }
  /// The surface faces (outward) with their labels (input triangles), in the order they were added.
  std::vector<std::pair<std::array<Index, 3>, Index>> alive_faces() const;

 private:
  class CavityBoundary;  ///< relocate's cavity boundary (tet_complex.cpp)
  void grow();
  /// The half-spaces {u : m . u >= d} (m unit, u relative to `origin`) a point must be in to see
  /// the outward faces `fs` of a cavity from inside (w makes (a, c, b, w) positive for face (a, b, c)).
  std::vector<std::pair<Vec3, double>> seeing_half_spaces(const std::vector<std::array<Index, 3>>& fs,
                                                          const Vec3& origin, double* size);
  /// (sorted vertex triple, outward face)
  using FacePair = std::pair<std::array<Index, 3>, std::array<Index, 3>>;
  /// The outward faces of a set of tets that appear once, in the order of their sorted triples.
  std::vector<FacePair> boundary_pairs(const std::vector<Index>& ids) const;
  /// The boundary of the union of two sets of tets without common tets, from their boundaries
  /// (boundary_pairs order): the faces of one of them only (a face of both is now inside). A
  /// cavity that grows by a few tets updates its boundary this way instead of sorting it again.
  static std::vector<FacePair> merge_boundaries(const std::vector<FacePair>& a, const std::vector<FacePair>& b);
  /// The tet across face f from a cavity (`in_cavity(id)`), or -1 (a surface face).
  /// A face has at most two tets and one is in the cavity, so the answer does not depend on which
  /// vertex's list is searched: the shortest one (input points can have thousands of tets).
  template <class InCavity>
  Index tet_beyond_if(const std::array<Index, 3>& f, InCavity&& in_cavity) const;
  /// tet_beyond_if for the cavity `cav` (sorted).
  Index tet_beyond(const std::array<Index, 3>& f, const std::vector<Index>& cav) const;
  /// Stamps the tets of a cavity (relocate), for tet_beyond_stamped.
  void start_cavity(const std::vector<Index>& cav);
  /// tet_beyond_if for the cavity stamped by start_cavity (and the tets stamped since).
  Index tet_beyond_stamped(const std::array<Index, 3>& f) const;
  /// Topological safeguard: no new tet duplicates a tet outside the cavity.
  bool tets_are_new(const std::vector<std::array<Index, 4>>& repl, const std::vector<Index>& cav) const;
  bool fail(const std::string& reason) {
    why = reason;
    return false;
  }
  static void erase(std::vector<Index>& list, Index id);
  ImplicitGeometry& geo_;
  const SurfaceMesh& surface_;
  const std::vector<Index>& tri_plane_;
  const Index np_;
  std::vector<std::array<Index, 4>> tets_;
  std::vector<char> talive_;
  std::vector<std::vector<Index>> vt_;
  std::vector<std::array<Index, 3>> faces_;
  std::vector<Index> label_;
  std::vector<char> falive_;
  std::vector<std::vector<Index>> vb_;
  std::vector<std::uint64_t> version_;  ///< changes at each vertex (signature())
  std::unique_ptr<CavityBoundary> bnd_;  ///< relocate: the boundary of the cavity being grown
  std::vector<std::uint32_t> cav_stamp_;  ///< relocate: tets stamped stamp_ are in the cavity
  std::uint32_t stamp_ = 0;
  std::vector<Index> star_sorted_;       ///< cone_from_vertex: star_boundary_of_'s star, sorted
  std::vector<FacePair> star_boundary_;  ///< cone_from_vertex: boundary of star_boundary_of_'s star
  Index star_boundary_of_ = -1;
  std::uint64_t star_boundary_version_ = 0;
};

}  // namespace bsptet
