// SPDX-License-Identifier: LGPL-2.1-or-later
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
//  * PUSH an interior Steiner point z deeper: z is replaced by w, the Chebyshev centre of the kernel
//    of its star (the point that maximizes the smallest distance to the planes of z's link faces,
//    found by a 4-variable LP in doubles, then rounded), when every tet (f, w) over a link face f is
//    positive (decided exactly). Valid by the COLLAPSE argument: the cones from w over the link
//    tile the star when they are all positive (z has no surface faces, nothing else changes). It
//    exists and helps: z sees its link strictly, so the kernel is an open convex set containing z
//    and its Chebyshev radius is at least z's clearance; it is taken only when it at least doubles
//    that clearance (estimated in doubles).
//    Why it is needed (bottle.brep as the FreeCAD mesher tessellates it, surface Steiner point on
//    the reflex cylinder edge 352-539, interior dihedral 193.8 deg): earlier relocations had left
//    interior points 4.6e-10 inside input triangle 973 and 3e-11 beyond its plane's extension.
//    A RELOCATE target w must see v's link faces and lie inside both input planes at v; a link
//    face (a, b, z) with a, b on plane P through v and z at distance delta from P admits only
//    points in a wedge of angle ~delta/|ab| between it and P, and two such faces on either side
//    of P (here (352, 54630, 540) and (540, 32022, 539)) left a kernel of clearance <= 0 (LP:
//    -2e-13 for v's star, and <= 0 for every union of v's star with its neighbours' stars, so no
//    candidate and no cavity growth could succeed). Pushing the two points (to clearances 0.0998
//    and 2.3e-3) opened v's kernel to a clearance of 1.4e-5. So when RELOCATE fails, the interior
//    Steiner neighbours of v are pushed and RELOCATE is tried once more.
//
//  * RETETRAHEDRALIZE a cavity without an interior Steiner point v: the cavity C is v's star grown
//    by k layers (the tets across its boundary faces, k = 0..5, at most 120 tets); its boundary
//    vertices B must include every vertex of C but interior Steiner points (those vanish). New
//    tets over B are
//    chosen by a depth-first search: the front starts as C's outward boundary faces; a step takes
//    the front face f = (a, b, c) with the fewest apexes p in B that make t = (a, c, b, p)
//    positive (exact), and fills t: each face of t that is on the front leaves it, the reverse of
//    each other face joins it (t is refused if the reverse of one of its faces is on the front:
//    that side is already filled). The search ends when the front is empty (or after a bounded
//    number of steps: then nothing changes). The k = 0..5 searches of one v share 1000 steps:
//    each success seen on tests/data took at most 400 steps with the searches before it, while a
//    search that fails usually runs out of steps, and six of them made most of the time of small
//    meshes (tinytorus: 12 of its 14 ms).
//    Why the result tiles C: as oriented 2-chains the front is always dC minus the boundaries of
//    the tets chosen, so an empty front means sum_t dt = dC. The winding number is linear in the
//    chain and equals a tet's indicator (a.e.) for a positive tet, so sum_t 1_t = 1_C almost
//    everywhere: the positive tets cover C and their interiors are disjoint. Their faces on dC are
//    exactly C's boundary faces (what the front started with), so the tets outside C still meet
//    them face to face; inside C every face is shared by two new tets (its two orientations
//    cancelled on the front). A vertex of B cannot lie inside a new tet, face or edge: the tets at
//    that vertex would overlap the ones around that simplex. Needed for box_with_hole (paper):
//    its last interior Steiner point has no cone from any vertex and no edge removal; its star and
//    the cavities 1 to 3 layers out have no fill over their boundary vertices (searched to the
//    end), the cavity 4 layers out (24 of the 29 tets, 16 vertices) is re-filled with 19 tets: 24
//    tets and no Steiner point in all, as tetgen -pY. Bounded work: 5000 search steps per cavity.
//
//  * ROUND an implicit interior point: the nearest doubles, else points pulled towards the centroid
//    of its neighbours, taken only if every tet around it stays positive.
//
// Order: collapse passes over all Steiner points until none applies; relocate the surface ones that
// remain (unless boundary Steiner points are allowed and are exactly doubles; a point that cannot
// move gets its interior Steiner neighbours pushed and is tried again); collapse passes
// again; merge interior points with their interior Steiner neighbours; cones from neighbours over
// grown cavities; edge removals then collapses; cones from the 48 nearest vertices; re-tetrahedralized
// cavities; round what is left. Input points never move. Deterministic: vertices in id order,
// neighbours input points first, then by id.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bsptet/core/cell_tetrahedralize.h"
#include "bsptet/numerics/implicit_geometry.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

struct SteinerRemovalOptions {
  bool allow_boundary_steiner = false;
  /// The effort the optional phases (merge, cone_neighbours, edge_removal, cone_nearest,
  /// retetrahedralize) may spend on one interior Steiner point, in work units (exact orientation
  /// tests, and the faces and tets a cavity growth handles); a point still there when its budget is
  /// spent stays (interior Steiner points are valid).
  /// 0: unlimited.
  std::int64_t interior_work_per_point = 0;
  std::function<bool()> cancelled;          ///< polled now and then; true stops (MeshingError kCancelled)
  std::function<void(double)> progress;     ///< fraction in [0, 1]
};

struct SteinerRemovalStats {
  std::int64_t steiner_before = 0, boundary_steiner_before = 0;
  std::int64_t collapsed = 0, relocated = 0, rounded = 0, rounded_moved = 0, pushed = 0;
  std::int64_t boundary_steiner_after = 0;
  /// Per phase of the order above ("collapse", "relocate", "merge", "cone_neighbours",
  /// "edge_removal", "cone_nearest", "retetrahedralize", "round"): seconds spent, and how many
  /// Steiner points were gone at its end (collapse passes run inside other phases count there).
  std::map<std::string, double> seconds_by_phase;
  std::map<std::string, std::int64_t> removed_by_phase;
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
