// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet quality stage: an editable tetrahedral mesh of a closed input surface, changed only by
// local operations (edge split, edge collapse, 2-3 and 3-2 flips, edge removal, point relocation,
// point insertion) that are each
// decided EXACTLY before they are applied: every tet they create must have orient3d > 0 on the
// double coordinates (predicates.h), and every point they put on the surface must keep the boundary
// an exact refinement of the input triangulation (below). An operation that fails a check changes
// nothing and returns false (or a SplitOutcome saying why); the mesh is valid after every call.
//
// Surface exactness, exact mode (no projection hook):
//  * every boundary face remembers its PARENT input triangle, the one it lies on;
//  * a point inserted on a boundary edge interior to one parent must be exactly coplanar with the
//    parent (orient3d == 0); on an input edge (two parents) exactly collinear with the edge's ends;
//    with the new tets positive this makes the new boundary faces tile the old ones. A rounded
//    midpoint is generally NOT on the plane or line; when none of a few candidate doubles near the
//    midpoint is, the edge is not split (SplitOutcome::kNoExactPoint);
//  * boundary points move or disappear only within their support (Support below): a point inside
//    an input triangle only onto its closed triangle, a point on an input edge only along it.
// Rounded mode (SurfacePoints::kRounded, no hook): a new surface point is the rounded midpoint of its
// edge, so it lies within rounding (half an ulp per coordinate) of its facet, like TetGen's.
// Projection mode (a ProjectionHook is given): the hook moves every new surface point (chosen as the
// rounded midpoint) onto the true surface, e.g. a CAD face. In both modes the boundary no longer
// lies exactly on the input facets, on purpose. The boundary then no longer lies on the
// input facets, on purpose: only the combinatorics stay a refinement (each boundary face keeps its
// parent and face tag) and validity means positive tets, conforming faces and a closed boundary.
// A projected point that would make a tet non-positive is rejected (the edge is not split).
// Input points the caller flags may also slide along their face (slide_point_if), put back on it
// by the hook, under the same exact positivity check.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "bsptet/mesh/edge_map.h"
#include "bsptet/mesh/projection_hook.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

/// Where a mesh point lies with respect to the input surface.
enum class Support : std::uint8_t {
  kInputVertex,  ///< an input point: never removed; moved only along its true surface face when
                 ///< it slides (projection mode, set_sliding_points)
  kInputEdge,    ///< inside an input edge: moves only along it
  kInputFace,    ///< inside an input triangle: moves only within its closed triangle
  kInterior,     ///< strictly inside the solid
};

struct PointSupport {
  Support kind = Support::kInterior;
  Index tri = -1;        ///< kInputFace: its input triangle; kInputEdge: one triangle of the edge
  Index other_tri = -1;  ///< kInputEdge: the other triangle of the edge
  Index edge_from = -1;  ///< kInputEdge: the input edge's end points as MESH indices, from < to
  Index edge_to = -1;
};

/// Which points may be put on the surface when no projection hook is given.
enum class SurfacePoints {
  kExact,    ///< only doubles exactly on the facet or input edge (the output tiles the input exactly)
  kRounded,  ///< the rounded midpoint (the output's boundary is within rounding of the input)
};

/// Why an edge split did not happen.
enum class SplitOutcome {
  kSplit,         ///< done
  kNoEdge,        ///< (u, v) is not an edge of the mesh
  kNoExactPoint,  ///< exact mode: no candidate double lies exactly on the boundary edge's support
  kInverted,      ///< every candidate point made some new tet non-positive
  kBadProjection,  ///< the projection hook returned a non-finite point
  kFixedSurface    ///< a boundary edge on a triangle whose tag is fixed (RefineMesh::set_fixed_tags)
};

/// What became of an interior point insertion (RefineMesh::insert_point).
enum class InsertOutcome {
  kInserted,
  kOutside,        ///< the walk towards the point met the boundary: it is outside the solid or on it
  kWalkFailed,     ///< the point was not located within the step limit
  kTooClose,       ///< a vertex of the cavity is nearer than the asked clearance
  kNoStarCavity,   ///< no cavity around the point is star-shaped from it (it lies on a mesh face...)
  kNoImprovement,  ///< must_improve: the cone's worst tet would not be better than the cavity's
};

/// Kind of a mesh edge with respect to the boundary.
enum class EdgeKind { kInterior, kInFace, kOnInputEdge };

/// Asked by an operation before it is applied, with the tets it would remove and those it would
/// create (corner indices; every created tet already checked positive); false refuses it.
using TetsAccept = std::function<bool(const std::vector<std::array<Index, 4>>& removed,
                                      const std::vector<std::array<Index, 4>>& created)>;

class RefineMesh {
 public:
  /// Builds the editable mesh. Preconditions: `mesh` is a valid linear tet mesh of `surface` (as
  /// mesh_check.h decides; the core's output is): every boundary face lies on one input triangle.
  /// Input points are recognized by their coordinates. Throws MeshingError (stage "refine") naming
  /// the face when a boundary face lies on no input triangle.
  RefineMesh(const SurfaceMesh& surface, const TetMesh& mesh, ProjectionHook hook = {},
             SurfacePoints surface_points = SurfacePoints::kExact);

  // ---- Queries ---------------------------------------------------------------------------------
  Index num_points() const { return static_cast<Index>(xyz_.size()); }
  const Vec3& point(Index v) const { return xyz_[static_cast<std::size_t>(v)]; }
  const PointSupport& support(Index v) const { return support_[static_cast<std::size_t>(v)]; }
  bool point_alive(Index v) const { return point_alive_[static_cast<std::size_t>(v)] != 0; }
  /// Tet slots (dead slots included: check tet_alive).
  Index num_tet_slots() const { return static_cast<Index>(tets_.size()); }
  bool tet_alive(Index t) const { return tet_alive_[static_cast<std::size_t>(t)] != 0; }
  const std::array<Index, 4>& tet(Index t) const { return tets_[static_cast<std::size_t>(t)]; }
  /// Min dihedral angle of a live tet, degrees (cached).
  double tet_quality(Index t) const { return quality_[static_cast<std::size_t>(t)]; }
  /// Smallest min dihedral angle of the live tets, degrees (180 without tets).
  double worst_tet_quality() const;
  Index num_alive_tets() const { return alive_tets_; }
  /// Change stamps: clock() grows with every change (a tet added or removed, a point moved); a
  /// point's stamp is the clock of the last change to a tet containing it (added, removed or
  /// reshaped), tet_stamp(t) the largest of its corners'. When tet_stamp(t) has not grown since
  /// an operation on t failed, the tets around t's corners are the same and in the same place.
  std::uint64_t clock() const { return clock_; }
  std::uint64_t point_stamp(Index v) const { return stamp_[static_cast<std::size_t>(v)]; }
  std::uint64_t tet_stamp(Index t) const;
  /// Live tets incident to point v, in increasing id order (valid until the next change).
  const std::vector<Index>& tets_around_point(Index v);
  /// Live tets containing both u and v, in increasing id order (empty when (u, v) is no edge).
  std::vector<Index> tets_around_edge(Index u, Index v);
  void tets_around_edge(Index u, Index v, std::vector<Index>& out);
  /// Kind of edge (u, v); for boundary edges `tri_a`/`tri_b` receive the two parents (equal for
  /// kInFace). Precondition: (u, v) is an edge.
  EdgeKind edge_kind(Index u, Index v, Index* tri_a = nullptr, Index* tri_b = nullptr);
  /// True when (u, v) is an edge of a live tet.
  bool edge_exists(Index u, Index v);
  /// Every edge of the live tets once, as (min, max) pairs in lexicographic order.
  std::vector<std::array<Index, 2>> edges() const;
  /// Face tag of input triangle t (-1 when the surface has no tags).
  std::int32_t tag_of(Index tri) const;
  /// The input surface the mesh refines.
  const SurfaceMesh& surface() const { return surface_; }

  /// Face tags whose input triangulation is kept: split_edge refuses (kFixedSurface) every boundary
  /// edge with a parent triangle of one of these tags, inside such a face or on its border, and
  /// flip_boundary_edge refuses the edges inside such a face. No other operation changes boundary
  /// faces there (insertions and relocations are interior, collapses move only points that are
  /// not input points, and a fixed face has none), so its boundary faces stay the input triangles. This is what keeps a face shared by two solids
  /// conforming when each solid is refined on its own.
  void set_fixed_tags(std::vector<std::int32_t> tags);
  /// The tags set_fixed_tags kept, sorted.
  const std::vector<std::int32_t>& fixed_tags() const { return fixed_tags_; }

  /// Projection mode only: input points that may slide along their true surface face.
  /// `input_points` is indexed like the input surface's points; a flagged point slides when its
  /// input triangles all have one tag, not a fixed one (the caller flags only points inside one
  /// CAD face: a point on a CAD edge or vertex must stay). Without a hook nothing slides.
  void set_sliding_points(const std::vector<char>& input_points);
  /// Whether point v may slide (set_sliding_points).
  bool slides(Index v) const {
    return static_cast<std::size_t>(v) < slide_tag_.size() && slide_tag_[static_cast<std::size_t>(v)] >= 0;
  }

  // ---- Operations: each checked exactly, applied only when valid --------------------------------
  /// Splits edge (u, v) at a point near its midpoint (see the file comment for the surface rules).
  /// `min_quality`: the split is refused (kInverted) when a new tet's min dihedral would be below
  /// min(min_quality, the worst old tet's); pass 0 to accept any valid split. On success
  /// `new_point` (if given) receives the new point's index.
  SplitOutcome split_edge(Index u, Index v, double min_quality = 0, Index* new_point = nullptr);
  /// Removes point `from` by moving it onto its neighbour `to` (tets with both are deleted). Only
  /// for points that are not input points, within their support. Applied when every new tet is
  /// positive, its min dihedral is at least min(min_quality, the worst old tet's), and every new
  /// edge is at most sqrt(max_edge2) long (pass infinity for no limit), and `accept` (if given)
  /// agrees.
  bool collapse_edge(Index from, Index to, double min_quality, double max_edge2,
                     const TetsAccept& accept = {});
  /// 2-3 flip of the interior face of tet t opposite its vertex `opposite` (0..3), applied when
  /// valid and it raises the smallest min dihedral of the tets involved; with `accept`, when
  /// valid and `accept` agrees (the angle test is then the caller's).
  bool flip23(Index t, int opposite, const TetsAccept& accept = {});
  /// 3-2 flip of the interior edge (u, v) with exactly three tets, same acceptance as flip23
  /// (remove_edge on a ring of three).
  bool flip32(Index u, Index v, const TetsAccept& accept = {});
  /// Edge removal (Shewchuk's "n-to-2(n-2)" flip; flip32 is n = 3): the n tets around the interior
  /// edge (u, v), 3 <= n <= max_ring, are replaced by 2(n-2) tets: a triangulation of the ring of
  /// their other corners (w_0 .. w_{n-1}, in order around the edge), each triangle joined to u and
  /// to v. The triangulation is the one that maximizes the smallest min dihedral angle of its tets
  /// (dynamic programming over the ring, Klincsek), among those whose tets are all positive
  /// (exact) and whose diagonals are not edges of the mesh yet. Applied when that angle is above
  /// the worst old tet's; with `accept`, when `accept` agrees (the angle test is then the
  /// caller's). Why the result is valid: the new tets are positive and, as a chain, have the same
  /// boundary as the old ones (the faces (u, w_i, w_i+1) and (v, w_i, w_i+1)), so they cover the
  /// old tets' union exactly once; the boundary of the solid is never touched (the edge is
  /// interior, the ring faces stay). Shells of fewer than `min_ring` tets are left (callers that
  /// tried flip32 first pass 4).
  bool remove_edge(Index u, Index v, int max_ring = 7, const TetsAccept& accept = {}, int min_ring = 3);
  /// Flip of a boundary edge (u, v) inside one input triangle (EdgeKind::kInFace): its boundary
  /// faces (u, v, a) and (v, u, b) become (a, b, u) and (b, a, v), same parent, and the n tets
  /// around it (2 <= n <= max_ring; their other corners form the open chain a = w_0 .. w_n = b)
  /// are replaced by the best triangulation of the polygon w_0 .. w_n, closed by the new edge
  /// (a, b), each triangle joined to u and to v (the same dynamic programming and acceptance as
  /// remove_edge). Why the result is valid: every new tet is positive (exact); in exact mode
  /// u, v, a, b lie exactly on their parent's plane, so the two new faces tile the two old ones
  /// (two triangulations of one planar quad) and the argument of remove_edge applies: the new
  /// tets fill the old ones' union exactly once. In rounded and projection modes the four points
  /// are within rounding of (or on the true surface over) the parent, not exactly coplanar: the
  /// boundary then changes by the thin tet (u, v, a, b), like a split's rounded point does, and
  /// the mesh stays valid against its own boundary (positive, conforming, closed).
  /// With `only_if_not_delaunay`, only when the angles at a and b facing (u, v) add up to more
  /// than 180 degrees (the edge is not locally Delaunay in its facet).
  /// The quality driver does not call it yet: in its flip pass (rounded mode, 6 CAD models at
  /// h = diagonal / 20) it raised the worst angle on some models and lowered it on others, with or
  /// without the Delaunay condition (docs/design/quality-stage.md).
  bool flip_boundary_edge(Index u, Index v, int max_ring = 7, const TetsAccept& accept = {},
                          bool only_if_not_delaunay = false);
  /// Inserts a new interior point p, Bowyer-Watson style. p is located by a visibility walk from
  /// tet `start` that never crosses a boundary face (kOutside when it would: p is outside the
  /// solid or on its boundary). The cavity is the tets whose circumsphere contains p (computed in
  /// doubles: this only SHAPES the cavity), connected to p's tet through interior faces, at most
  /// `max_cavity` tets; then, exactly, tets are dropped from it until p sees every face of the
  /// cavity's boundary strictly on its inner side (orient3d > 0), and every vertex of the cavity is
  /// on that boundary. The cavity is then replaced by the cone from p over its boundary.
  /// Why this is valid: the cone's tets are all positive, and their signed volumes add up to the
  /// cavity's (the cone over a closed oriented surface), so they cover every point of the cavity
  /// exactly once and nothing outside it (winding number 1 inside, 0 outside); no vertex is lost,
  /// the cavity's boundary faces (the solid's boundary faces among them) are kept as they are.
  /// kTooClose (nothing changed) when a vertex of the final cavity is closer than `clearance`.
  /// With `must_improve`, the insertion is applied only when the smallest min dihedral angle of
  /// the new tets exceeds that of the tets they replace (kNoImprovement otherwise).
  /// `accept` (optional) is asked last, with the new tets (the new point as index -1) and p;
  /// false refuses the insertion (kNoImprovement).
  /// `must_contain` (optional, a live tet): it is put in the cavity whatever its circumsphere, and
  /// the insertion fails (kNoStarCavity) when it cannot stay there. This is how a flat tet whose
  /// huge circumsphere lies on the far side of p (a cap on two nearly coplanar boundary faces)
  /// is replaced by tets from p.
  InsertOutcome insert_point(Index start, const Vec3& p, double clearance, Index* new_point = nullptr,
                             Index max_cavity = 512, bool must_improve = false,
                             const std::function<bool(const std::vector<std::array<Index, 4>>&, const Vec3&)>&
                                 accept = {},
                             Index must_contain = -1);
  /// Moves interior point v to p when every tet around it stays positive and the smallest min
  /// dihedral around it rises.
  bool relocate_point(Index v, const Vec3& p);
  /// Moves interior point v to p when every tet around it stays positive (exact) and `accept`
  /// returns true for the moved tets (corner coordinates, in the tets' order, v replaced by p).
  bool relocate_point_if(Index v, const Vec3& p,
                         const std::function<bool(const std::vector<std::array<Vec3, 4>>&)>& accept);

  /// Moves a sliding point v (slides(v)) to the hook's image of `target` on its face, when the
  /// hook answers a finite point, every tet around v stays positive (exact), no boundary
  /// triangle around v tilts by more than kSlideMaxTiltDeg or gets a smallest angle below
  /// min(the worst of them before, kSlideKeepTriangleDeg), and `accept` returns true for the
  /// moved tets (as relocate_point_if); the target itself must pass the same checks first, so
  /// the hook (a search on the CAD surface) runs only for a move likely to be taken. Validity is
  /// what it is for any point: positive tets, the boundary's combinatorics unchanged; the
  /// boundary stays on the true surface.
  bool slide_point_if(Index v, const Vec3& target,
                      const std::function<bool(const std::vector<std::array<Vec3, 4>>&)>& accept);
  /// The other corners of the boundary faces around point v (sorted, unique).
  std::vector<Index> boundary_neighbours(Index v);
  static constexpr double kSlideMaxTiltDeg = 20.0;
  static constexpr double kSlideKeepTriangleDeg = 25.0;

  // ---- Output ----------------------------------------------------------------------------------
  /// The live tets and the points they use: input points first, at their input indices order kept
  /// as in the mesh given to the constructor, then the others in creation order. `old_to_new`
  /// (optional) receives the renumbering (-1 for dropped points).
  TetMesh to_tet_mesh(std::vector<Index>* old_to_new = nullptr) const;
  /// The boundary faces as (face, parent input triangle), vertices as mesh indices, oriented
  /// outward, sorted.
  std::vector<std::pair<std::array<Index, 3>, Index>> boundary_faces();
  /// For every boundary edge (edge_key of its ends, renumbered through `renum` when given): the
  /// face tags of its two boundary faces' parents, the first met and the last (equal inside a face).
  EdgeMap<std::array<std::int32_t, 2>> boundary_edge_tags(const std::vector<Index>* renum = nullptr);

 private:
  using FaceKey = std::array<Index, 3>;
  struct FaceKeyHash {
    std::size_t operator()(const FaceKey& k) const;
  };
  static FaceKey face_key(Index a, Index b, Index c);
  /// edge_kind(u, v) == kInterior, for an edge whose tets (tets_around_edge) are `shell`: no
  /// boundary face holds it.
  bool is_interior_edge(Index u, Index v, const std::vector<Index>& shell) const;
  /// True when (a, b, c) is a boundary face. A face with an interior corner never is (supports
  /// are exact), which spares the hash lookup for most faces.
  bool is_boundary_face(Index a, Index b, Index c) const {
    if (support(a).kind == Support::kInterior || support(b).kind == Support::kInterior ||
        support(c).kind == Support::kInterior)
      return false;
    return boundary_.count(face_key(a, b, c)) != 0;
  }

  Index add_tet(const std::array<Index, 4>& t);
  void kill_tet(Index t);
  void touch(const std::array<Index, 4>& t);  ///< a change to tet t: its corners get a new stamp
  Index add_point(const Vec3& p, const PointSupport& s);
  /// Puts point v at p: `ball` its live tets, `moved` their corners with v at p (checked).
  void move_point(Index v, const Vec3& p, const std::vector<Index>& ball, const std::vector<std::array<Vec3, 4>>& moved);
  bool positive(const std::array<Index, 4>& t) const;
  bool positive_with(const std::array<Index, 4>& t, Index moved, const Vec3& p) const;
  double quality_of(const std::array<Index, 4>& t) const;
  /// Input triangles whose closed triangle contains point v (by support).
  bool support_allows_collapse(Index from, Index to) const;
  bool shell_links(Index u, Index v, const std::vector<Index>& shell, std::vector<std::pair<Index, Index>>& links) const;
  /// remove_edge and flip_boundary_edge after their checks: `ring` is the closed ring (open =
  /// false) or the open chain from a to b (open = true; `parent` the boundary faces' parent).
  bool retriangulate_shell(Index u, Index v, const std::vector<Index>& shell, const std::vector<Index>& ring,
                           bool open, Index parent, const TetsAccept& accept);
  /// The live tet other than t sharing t's face opposite its vertex k; -1 on the boundary.
  Index neighbour(Index t, int k);

  const SurfaceMesh& surface_;
  ProjectionHook hook_;
  std::vector<std::int32_t> fixed_tags_;  ///< sorted
  std::vector<std::int32_t> slide_tag_;   ///< per point: the face tag it slides on, else -1
  SurfacePoints surface_points_;
  std::vector<Vec3> xyz_;
  std::vector<PointSupport> support_;
  std::vector<char> point_alive_;
  std::vector<std::array<Index, 4>> tets_;
  std::vector<char> tet_alive_;
  std::vector<double> quality_;
  std::vector<std::vector<Index>> ball_;  ///< point -> its live tets, in increasing id order
  /// neighbour(t, k) cached at 4 t + k: kUnknownNeighbour, -1 (boundary) or a tet, valid while
  /// it is alive.
  static constexpr Index kUnknownNeighbour = -2;
  std::vector<Index> neighbour_;
  std::vector<std::uint64_t> stamp_;  ///< per point, see clock()
  std::uint64_t clock_ = 0;
  std::unordered_map<FaceKey, Index, FaceKeyHash> boundary_;  ///< sorted face -> parent triangle
  Index alive_tets_ = 0;
  Index first_added_point_ = 0;
  /// insert_point's cavity membership per tet slot: 2 g (in the cavity of call g), 2 g + 1 (taken
  /// in, then dropped), anything else (not in it); g counts the calls.
  std::vector<std::uint64_t> cavity_mark_;
  std::uint64_t cavity_generation_ = 0;
};

}  // namespace bsptet
