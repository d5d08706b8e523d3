// FemBspTet core: fewer Steiner points, none on the surface, and every point a double (beyond the
// paper: its Sec. 4.2 counts the BSP points but keeps them all).
//
// Input: the cells' tets over geometry vertices (explicit or implicit TPI points), valid exactly,
// and the boundary faces with the input triangle containing each. Three local operations, each
// decided by exact predicates on the current (possibly implicit) points:
//
//  * COLLAPSE v -> u along an edge (v a Steiner point, u a neighbour): every tet of v that does not
//    contain u gets u instead of v. Allowed when every such tet stays positively oriented and u
//    lies where v's surface lies (the support rule: a point inside input triangle t may go to any
//    point of the closed triangle t; a point on an input edge only to a point of that edge; an
//    interior point anywhere). Why this is valid: the new tets are the cone from u over the faces
//    of v's link that do not contain u; the cone from u over the whole boundary of v's star has
//    coverage equal to the winding number (1 inside the star, 0 outside), and the cones over faces
//    through u, or over v's surface faces (coplanar with u by the support rule), are flat; so if
//    all the others are positive they tile the star exactly. The same argument in the plane shows
//    the surface faces (u, x, y) tile what v's surface faces tiled, inside the same input triangle.
//
//  * RELOCATE a surface Steiner point v inward: v's surface faces (one planar polygon per input
//    triangle around v: a cycle inside a triangle, or two paths on an input edge) are
//    re-triangulated without v by ear clipping (exact orient2d), and a double point w just inside
//    both input planes is coned to the new surface triangles and to v's link. Such a w exists: v
//    sees every link face strictly, and the intersection of the inner half-spaces of at most two
//    input planes near v is a non-empty wedge. Each candidate is checked exactly.
//
//    Candidates are tried fat first (clear of every face by 1e-3 of the star's size), then deep
//    ones (centroids of v's tets and of its cavity) with cavity growth: every face w does not see
//    takes the tet beyond it (never across the surface) into the cavity, until w sees all.
//
//  * CONE an interior Steiner point v from a vertex u over a grown cavity (v's star plus tets
//    beyond the faces u does not see): the cone over the cavity's boundary faces that do not
//    contain u tiles it when every cone tet is positive (the COLLAPSE argument). Vertices strictly
//    inside the cavity must be interior Steiner points; they vanish with v.
//
//  * EDGE REMOVAL (n-to-2(n-2) flip, n <= 7) of an interior edge (v, x): the n tets around it are
//    replaced by the cones from v and x over a triangulation of their ring polygon, when all are
//    positive; the outer faces are kept, so the complex stays conforming. Used to lower the degree
//    of an interior Steiner point until it collapses.
//
//  * ROUND an implicit interior point: the nearest doubles, else points pulled towards the centroid
//    of its neighbours, taken only if every tet around it stays positive.
//
// Order: collapse passes over all Steiner points until none applies; relocate the surface ones that
// remain (unless boundary Steiner points are allowed and are exactly doubles); collapse passes
// again; merge interior points with their interior Steiner neighbours; cones from neighbours over
// grown cavities; edge removals then collapses; cones from the 48 nearest vertices; round what is
// left. Input points never move. Deterministic: vertices in id order,
// neighbours input points first, then by id.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "bsptet/cell_tetrahedralize.h"
#include "bsptet/implicit_geometry.h"
#include "bsptet/types.h"

namespace bsptet {

struct SteinerRemovalOptions {
  bool allow_boundary_steiner = false;
  std::function<bool()> cancelled;          ///< polled now and then; true stops (MeshingError kCancelled)
  std::function<void(double)> progress;     ///< fraction in [0, 1]
};

struct SteinerRemovalStats {
  std::int64_t steiner_before = 0, boundary_steiner_before = 0;
  std::int64_t collapsed = 0, relocated = 0, rounded = 0, rounded_moved = 0;
  std::int64_t boundary_steiner_after = 0;
};

/// Removes and relocates Steiner points as described above. `tri_plane[t]` is the plane of input
/// triangle t; vertex ids below `surface.num_points()` are the input points. Returns the tets (all
/// vertices explicit). Throws MeshingError if a surface point cannot be moved off the surface or
/// an implicit point has no double position that keeps its tets positive.
std::vector<std::array<Index, 4>> remove_steiner_points(ImplicitGeometry& geo, const SurfaceMesh& surface,
                                                        const std::vector<Index>& tri_plane, const CellTets& cells,
                                                        const SteinerRemovalOptions& options,
                                                        SteinerRemovalStats* stats);

}  // namespace bsptet
