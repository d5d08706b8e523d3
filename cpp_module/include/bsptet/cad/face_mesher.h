// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet CAD layer: triangles of one CAD face at the size field, its boundary nodes fixed.
//
//   FaceMesh mesh_face(forward_face, loops, options, first_new_node)
//
// Method (in the face's parameter plane, lengths and shapes measured in 3D on the surface, as
// Gmsh's MeshAdapt does):
//  1. the boundary loops (the nodes of the face's edges, at their pcurve parameters) are
//     triangulated in (u, v) by ear cutting (uv_polygon.h), and that fan is flipped towards
//     better shapes: when a triangle is folded in 3D, first everywhere measured in the
//     surface's metric (the first fundamental form at each quad's (u, v) centroid: nodes close
//     in (u, v) may be far apart on the surface, and a fan of such triangles is needles a turn
//     long, folded in places), then in 3D;
//  2. rounds of local operations, each kept only when every triangle it makes is valid (below):
//     interior edges longer than 1.4 times the local size are split at their (u, v) midpoint
//     (the new node evaluated on the surface), edges shorter than 0.7 times it are collapsed onto
//     a neighbour (interior nodes only), edges are flipped when that raises the smaller quality
//     of their two triangles, and interior nodes move towards the mean of their neighbours when
//     that raises the worst quality around them;
//  3. triangles still facing against the surface are flipped away judged in 3D alone.
// Quality: 4 sqrt(3) area / (sum of squared edge lengths) in 3D (1 for an equilateral
// triangle) times the smallest cosine between the triangle's normal and the surface normal at
// its corners: a chord across a wide arc scores low however equilateral, and a triangle facing
// against the surface (a fold) scores negative. Valid: counter-clockwise in (u, v) (exact
// orient2d); a triangle with a corner on a pole is judged in 3D instead (quality > 0), since a
// pole's (u, v) copies are one point. The local size is the face's size, the local curvature
// size on non-analytic surfaces (size_field.h), and the boundary spacing grown by `grading`.
// Boundary nodes never move. Nodes of a degenerated edge (a cone apex, a sphere pole) share one
// node id: triangles with two such corners are zero-area in 3D and are dropped at the end. Two
// copies of one seam node (u = 0 and u = period) must never share a triangle: such edges are
// split or flipped away.
//
// Known limits: near a pole or a cone apex, and where a B-spline face creases within itself
// (its normal turning by more than 90 degrees over a few triangles), a few triangles may stay
// folded (FaceMesh::folds counts them); if they cross another triangle, the volume stage
// refuses the surface, naming the crossing triangles.
//
// Orientation: triangles turn counter-clockwise in (u, v) of the FORWARD face, so their right-hand
// normal is the surface's S_u x S_v; the caller reverses them for a face REVERSED in its solid.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include <TopoDS_Face.hxx>

#include "bsptet/cad/uv_polygon.h"
#include "bsptet/mesh/types.h"

namespace bsptet::cad {

/// A node on a face's boundary: its (u, v) on this face, its node id and 3D point.
struct BoundaryNode {
  Uv uv;
  Index node;
  Vec3 xyz;
};

struct FaceMeshOptions {
  double face_size = 1;    ///< the face's size (SizeField::face_size)
  /// The floor of the face's own sizes (face_size, curvature); sizes graded from boundary nodes
  /// closer than that (a short CAD edge) go down to the smallest boundary size. Edges shorter
  /// than twice the smaller of the two are never split.
  double min_size = 0;
  double grading = 0.3;    ///< growth of the size away from the boundary nodes, per unit length
  /// > 0: the size at a node is also at most the local curvature size there (size_field.h)
  double local_curvature_points_per_circle = 0;
  int max_rounds = 20;     ///< rounds of split / collapse / flip / smooth at most
  /// Sizes set from outside the face: points with their sizes, graded like the boundary nodes'
  /// (a face that cuts a solid takes the sizes the volume will have there: cad_split.h).
  std::vector<std::pair<Vec3, double>> size_sources;
};

struct FaceMesh {
  std::vector<std::array<Index, 3>> triangles;  ///< node ids, counter-clockwise in (u, v)
  std::vector<Vec3> new_xyz;                    ///< interior nodes: ids first_new_node + i
  std::vector<Uv> new_uv;
  int folds = 0;             ///< triangles left whose normal opposes the surface's
  double min_quality = 1;    ///< smallest shape quality (see above)
};

/// loops: the outer boundary first (counter-clockwise in (u, v): the face on its left), then the
/// holes (clockwise); no node repeated at a loop's end. Throws std::runtime_error when the
/// boundary is not a simple polygon in (u, v); the caller names the face.
FaceMesh mesh_face(const TopoDS_Face& forward_face, const std::vector<std::vector<BoundaryNode>>& loops,
                   const FaceMeshOptions& options, Index first_new_node);

}  // namespace bsptet::cad
