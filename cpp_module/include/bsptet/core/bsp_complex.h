// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the BSP as a conforming convex cell complex (paper Sec. 2.1-2.2: BSP tree and
// convex decomposition; Sec. 2.2.1: BSP points).
//
// The complex starts as one cell, a box around the input, and is split recursively by the planes
// of the input triangles (an auto-partition: coplanar triangles share one plane). Each cell keeps a
// conflict list: the input triangles that may cross its interior (a conservative superset). A cell
// whose list is empty is a leaf: every input triangle meeting it lies on its boundary.
//
// Conformity: a split cuts the crossing edges of the cell once, for every face that uses them, and
// splits each crossing face for both cells that share it. So the complex never has a T-junction
// hidden inside a face or an edge: the paper's "glue" and "crossed-edge fixing" problems cannot
// arise (the crossing points p, q, r, s of its Fig. 9 are the vertices a face split creates).
//
// Orientation (stated once): a face's vertex cycle is counter-clockwise around its plane's normal n
// (implicit_geometry.h). cell[0] lies on the positive side (n points into it), cell[1] on the
// negative side; -1 means outside the bounding box.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "bsptet/mesh/edge_map.h"
#include "bsptet/numerics/implicit_geometry.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

/// Side of one splitting plane per vertex (-1, 0, +1; 0 for a vertex not set since reset()):
/// a flat array over vertex ids with a generation stamp, so a reset costs nothing.
class VertexSigns {
 public:
  void reset() {
    if (++stamp_ == 0) {
      std::fill(set_.begin(), set_.end(), 0u);
      stamp_ = 1;
    }
  }
  bool count(Index v) const { return static_cast<std::size_t>(v) < set_.size() && set_[v] == stamp_; }
  int& operator[](Index v) {
    if (static_cast<std::size_t>(v) >= set_.size()) {
      const std::size_t n = std::max<std::size_t>(static_cast<std::size_t>(v) + 1, 2 * set_.size());
      set_.resize(n, 0u);
      value_.resize(n, 0);
    }
    if (set_[v] != stamp_) {
      set_[v] = stamp_;
      value_[v] = 0;
    }
    return value_[v];
  }

 private:
  std::vector<std::uint32_t> set_;
  std::vector<int> value_;
  std::uint32_t stamp_ = 1;
};

/// A box enclosing a face's vertices, in floats rounded outward (lo down, hi up: still an
/// enclosure, a third of the memory of double intervals; a box made wider than the face's own only
/// sends a split to the exact per-vertex test more often). ok() is false when a vertex had no
/// interval box. Cells keep a copy beside their face ids, so that a split scans its cell's boxes
/// in order instead of visiting every face record.
struct FaceBox {
  std::array<float, 3> lo{{1.f, 1.f, 1.f}}, hi{{0.f, 0.f, 0.f}};  ///< empty (lo > hi) when not ok
  bool ok() const { return lo[0] <= hi[0]; }
  /// The smallest float box enclosing [lo, hi] (double bounds, lo <= hi); not ok when a bound is
  /// beyond the floats' range.
  static FaceBox enclosing(const std::array<double, 3>& lo, const std::array<double, 3>& hi);
  /// The box as double intervals (exact: every float is a double).
  std::array<Interval, 3> intervals() const {
    return {Interval(lo[0], hi[0]), Interval(lo[1], hi[1]), Interval(lo[2], hi[2])};
  }
};

struct BspFace {
  Index plane = -1;
  std::vector<Index> verts;     ///< cyclic, CCW around the plane normal
  Index cell[2] = {-1, -1};     ///< [0] positive side, [1] negative side, -1 outside the box
  std::vector<Index> coplanar;  ///< input triangles on this plane that may overlap the face
  bool alive = true;
};

struct BspCell {
  std::vector<Index> faces;
  std::vector<FaceBox> boxes;   ///< parallel to faces (rebuilt by split_cell if out of step)
  std::vector<Index> conflict;  ///< input triangles that may cross the interior
  bool alive = true;
};

/// Seed tets kept out of the cell complex (BspSeed::kDelaunay, bsp_seed.cpp). A seed tet becomes a
/// cell of the complex only when a split or a face refinement can reach it: when it shares an edge
/// with a seed tet that an input triangle crosses, or with a seed face on an input plane that is
/// not exactly one input triangle (refine_covered_faces would split it). Splits stay inside the
/// closure of the crossed tets and refinements inside the closure of those faces, so they only
/// cut edges that every tet around is in the complex for: an untouched tet stays a tet, and its
/// faces shared with complex cells stay single triangles. Most seed tets of a fine surface are
/// untouched; they skip the complex's faces, edge maps and per-cell passes.
/// Adjacency of untouched tet t across the face opposite corner i (the face
/// (tets[t][kTetOppositeFace[i][0..2]]), whose normal in that order points into t):
///   adj >= 0: that untouched tet; adj == -1: outside the box; adj <= -2: complex face -2 - adj.
/// step: the winding number across that face, neighbour's minus t's: 0 when no input triangle lies
/// on the face; +1 when the input triangle on it has its outward normal pointing into t (t is
/// outside there), -1 when pointing away (t inside). cover: that input triangle, or -1.
struct UntouchedSeedTets {
  std::vector<std::array<Index, 4>> tets;  ///< positive, vertex ids (input points and box corners)
  std::vector<std::array<Index, 4>> adj;
  std::vector<std::array<signed char, 4>> step;
  std::vector<std::array<Index, 4>> cover;
  /// Complex cells made from seed tets before this one (cells are numbered in seed order, split
  /// products after them): an untouched tet goes out just before cell before_cell[u] (or after
  /// the last seed cell), so the output keeps the seed's order whatever was left out.
  std::vector<Index> before_cell;
};

/// What the complex starts from: one box cell (the paper: every input plane may cut it), or the
/// tets of the Delaunay tetrahedralization of the input points and the box corners (bsp_seed.cpp:
/// only the cells an input triangle actually crosses are split).
enum class BspSeed { kBox, kDelaunay };

struct BspStats {
  std::int64_t seed_tets = 0;       ///< cells the complex started from beside the box (BspSeed::kDelaunay)
  std::int64_t untouched_tets = 0;  ///< of the seed tets, those kept out of the complex (UntouchedSeedTets)
  std::int64_t seed_conflicts = 0;  ///< (seed tet, input triangle crossing it) pairs after seeding
  std::int64_t seed_faces_relabelled = 0;  ///< seed faces found on an input plane only by the walk
  std::int64_t seed_missing_edges = 0;    ///< input edges not in the Delaunay seed
  std::int64_t seed_recovered_edges = 0;  ///< of those, made seed edges by flips
  std::int64_t seed_missing_faces = 0;    ///< input triangles with their edges but not a face of the seed
  std::int64_t seed_recovered_faces = 0;  ///< of those, made seed faces by 3-2 flips
  std::int64_t seed_flips = 0;            ///< 2-3, 3-2 and 4-4 flips made for them
  std::int64_t seed_face_triangles = 0;   ///< input triangles that are faces of the seed (no walk)
  /// The seed's conflict lists passed max_seed_conflicts and were abandoned: the complex is
  /// unusable (the caller starts from the box instead).
  bool seed_abandoned = false;
  /// Seconds of the seed's steps: "seed_delaunay" (the points' Delaunay), "seed_flips" (edge and
  /// face recovery), "seed_faces" (the complex's faces and planes), "seed_walk" (conflict lists),
  /// "seed_lines" (edge lines). Measurement only: nothing depends on them.
  std::map<std::string, double> seed_seconds;
  std::int64_t splits = 0;          ///< internal BSP nodes
  std::int64_t leaves = 0;          ///< convex cells
  std::int64_t bsp_points = 0;      ///< vertices created by splits (TPI points)
  std::int64_t planes = 0;          ///< distinct input planes
};

class BspComplex {
 public:
  /// The 8 corners of the bounding box, in bit order x + 2y + 4z; the caller appends them to the
  /// explicit points after the input points.
  static std::vector<Vec3> box_corners(const SurfaceMesh& surface);

  /// `geo` holds the input points as explicit points 0..#P-1 with vertices of the same ids, and
  /// the planes; `tri_plane[t]` is the plane of input triangle t.
  /// `seed`: see BspSeed (kDelaunay also needs the box corners as the last 8 explicit points).
  /// `max_seed_conflicts` (kDelaunay; -1: no bound): when the (seed tet, crossing triangle) pairs
  /// pass it, the walks stop and stats().seed_abandoned is set (long triangles across many seed
  /// tets: the walks alone would cost more than the box's partition).
  BspComplex(ImplicitGeometry& geo, const SurfaceMesh& surface, std::vector<Index> tri_plane,
             BspSeed seed = BspSeed::kBox, std::int64_t max_seed_conflicts = -1);
  /// Which sampled candidates choose_plane scores: the i-th is the conflict list's entry
  /// (i * n / ncand + candidate_shift) mod n. 0 (the default) is the paper's sampling; another
  /// value gives another, equally valid partition (the mesher's last retry).
  void set_candidate_shift(std::size_t shift) { candidate_shift_ = shift; }

  /// Splits until every cell is a leaf. `cancelled` is polled between splits.
  void build(const std::function<bool()>& cancelled, const std::function<void(double)>& progress);

  /// After build(): replaces every TPI vertex that coincides with an input point by that input
  /// point's vertex (splits through input vertices create them: the input vertices are not
  /// vertices of the complex until then). Exact: a rounded-coordinate lookup proposes, the three
  /// defining planes confirm.
  /// Only vertices with ids >= `first` are looked at (those created since an earlier call).
  void identify_input_vertices(Index first = 0);

  /// After build(): splits every face that lies on an input plane until each one is inside a single
  /// input triangle (or overlaps none). The covering triangle is then face.coplanar[0]. Two steps:
  ///  1. Where the plane's part of the surface ends inside a face (an edge of a covering triangle
  ///     whose other triangle is on another plane meets the face's interior), the face is split
  ///     along that edge's line, for every face that uses the crossed edges. Then each face is
  ///     either covered entirely by the plane's triangles or not at all.
  ///  2. A covered face that overlaps several triangles is replaced by the convex pieces f ∩ t,
  ///     one per triangle: the points where the triangles' edges meet the face's edges become
  ///     vertices (of every face using those edges). Unlike splitting along whole edge lines (an
  ///     arrangement of lines: O(k^2) points for k triangles in a face), this adds only where
  ///     input edges actually cross the face's boundary.
  void refine_covered_faces();
  /// The earlier refinement, kept as the fallback of tetrahedralize (mesher.h): every covered face
  /// split along the line of an edge of its covering triangle until it lies in one triangle (an
  /// arrangement of lines: many more points on planes with many triangles, but a different
  /// complex when the Steiner removal gets stuck on the first one).
  void refine_covered_faces_along_lines();

  const std::vector<BspFace>& faces() const { return faces_; }
  /// Seed tets kept out of the complex (empty unless seeded by BspSeed::kDelaunay).
  const UntouchedSeedTets& untouched() const { return untouched_; }
  /// The untouched seed tet on the side of complex face f whose cell is -1, or -1 (outside the
  /// box, or no such side).
  Index face_untouched(Index f) const {
    return static_cast<std::size_t>(f) < face_untouched_.size() ? face_untouched_[f] : -1;
  }
  const std::vector<BspCell>& cells() const { return cells_; }
  const BspStats& stats() const { return stats_; }
  /// After the last build, refinement and identify_input_vertices: frees what only splitting
  /// needs (the face boxes, each cell's boxes and conflict list, the edge maps), so that the cells'
  /// tetrahedralization does not hold them (they were a fifth of the peak memory). The faces,
  /// cells, vertices and untouched seed tets stay. Splitting or refining afterwards throws.
  void release_split_data();
  ImplicitGeometry& geometry() { return geo_; }
  /// The plane of each input triangle.
  const std::vector<Index>& triangle_planes() const { return tri_plane_; }
  /// Vertex k of input triangle t (input point ids are vertex ids).
  Index triangle_vertex(Index t, int k) const { return surface_.tri[3 * t + k]; }

  /// Debug check of the combinatorics: every face's cells list it, every edge is used by faces
  /// consistently, cells are closed. Throws MeshingError on a violation.
  void check_consistency() const;
  /// Run check_consistency() after every split (slow; for tests).
  void set_debug_checks(bool on) { debug_checks_ = on; }

 private:
  void make_box();
  /// bsp_seed.cpp: the cells are the Delaunay tets of the used input points and the box corners;
  /// conflict lists by a walk and a separating-axis test per input triangle.
  void seed_delaunay(std::int64_t max_conflicts);
  Index new_face(BspFace f);
  void register_edges(Index f);
  void unregister_edges(Index f);
  Index choose_plane(Index c);
  std::size_t candidate_shift_ = 0;
  /// Splits cell c by plane p; returns the id of the cell on p's negative side (the other one has
  /// the other id: the side with more faces keeps c, so fewer faces are relabelled), or -1 when p
  /// does not cut c's interior.
  Index split_cell(Index c, Index p);
  const FaceBox& face_box(Index f) const { return face_boxes_[f]; }
  /// Throws MeshingError (kInternal) when release_split_data has been called.
  void require_split_data(const char* what) const;
  /// Cuts the edges of face f whose ends are strictly on opposite sides of plane q (`sign`),
  /// inserting the new vertex into every face that uses the edge.
  void cut_crossing_edges(Index f, Index q, VertexSigns& sign);
  /// Splits face f by plane q (`sign`: side of each of f's vertices, crossing edges already cut).
  std::array<Index, 2> split_face(Index f, Index q, VertexSigns& sign);
  void split_edge(Index u, Index w, Index x);
  /// The two distinct planes whose intersection is the line of edge (u, w).
  std::array<Index, 2> edge_line(Index u, Index w) const;
  void classify_triangle(Index t, Index p, int& mn, int& mx);
  /// Exact: does the interior of face f overlap the interior of coplanar input triangle t?
  bool face_overlaps_triangle(Index f, Index t, int axis, int face_orientation);
  Index edge_plane(Index a, Index b, Index face_plane);
  /// Exact: does closed input segment (a, b), in f's plane, meet the interior of face f?
  bool segment_crosses_face(Index f, Index a, Index b, int axis, int face_orientation);
  /// Splits face f (on an input plane) by plane q through a line of that plane, which crosses its
  /// interior: the crossed edges are cut for every face using them, and both cells of f get the
  /// two halves. Returns {positive half, negative half}.
  std::array<Index, 2> split_face_in_plane(Index f, Index q);
  /// Live faces that may overlap input triangles of their plane, as a work stack (lowest id on top).
  std::vector<Index> faces_on_input_planes() const;
  /// The loop of both refinements of the covered faces: visits every face of
  /// faces_on_input_planes(), and both halves of every split, as visit(f, axis, face_orientation)
  /// (f's projection axis and the sign of its plane's normal along it). A visit returns the plane to
  /// split f along (split_face_in_plane; the halves are visited next), or -1 when f is done.
  void visit_faces_on_input_planes(const std::function<Index(Index, int, int)>& visit);
  /// In the face lists of f's cells (but `skip_cell`), f becomes ids[0] and ids[1..] are appended.
  void substitute_face(Index f, const std::vector<Index>& ids, Index skip_cell = -1);
  /// Replaces face f by `pieces` (same plane and cells) in both of its cells.
  void replace_face(Index f, std::vector<BspFace> pieces);
  /// f lies in the union of the coplanar input triangles `over` (each overlapping it): makes every
  /// crossing of their edges with f's edges a vertex (conformity), then replaces f by the convex
  /// pieces f ∩ t, one per triangle.
  void overlay_covered_face(Index f, const std::vector<Index>& over, int axis, int face_orientation);
  std::unordered_map<std::uint64_t, Index> edge_planes_;
  VertexSigns signs_;  ///< scratch for split_cell and refine_covered_faces (reset by each)
  std::vector<signed char> face_side_;  ///< scratch for split_cell

  ImplicitGeometry& geo_;
  const SurfaceMesh& surface_;
  std::vector<Index> tri_plane_;
  std::vector<std::array<Interval, 3>> tri_box_;  ///< each input triangle's (exact) bounding box
  std::vector<BspFace> faces_;
  /// Parallel to faces_: intervals enclosing every vertex of the face (set by new_face; still
  /// valid when a vertex is inserted on an edge or replaced by one at the same place), so that a
  /// split can skip a face far from its plane without deciding each vertex.
  std::vector<FaceBox> face_boxes_;
  bool split_data_released_ = false;
  std::vector<BspCell> cells_;
  EdgeMap<EdgeFaceList> edge_faces_;  ///< the live faces using each edge
  /// The two planes whose line carries each edge (entries stay after the edge is split).
  EdgeMap<std::array<Index, 2>> edge_line_;
  BspStats stats_;
  UntouchedSeedTets untouched_;
  std::vector<Index> face_untouched_;  ///< per seed face of the complex (see face_untouched)
  bool debug_checks_ = false;
  Index corner0_ = -1;  ///< vertex id of the first box corner
};

}  // namespace bsptet
