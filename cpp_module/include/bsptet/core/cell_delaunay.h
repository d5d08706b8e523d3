// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the paper's per-cell Delaunay tetrahedralization (Sec. 2.3), exact, and the face
// triangulations that make the cells' tets conform.
//
// One global rule decides every tie: the perturbed lifting of ImplicitGeometry::lifted_det3/2,
// H(v) = |v|^2 + eps^k(v) with k strictly decreasing in the global vertex id. Under it, every
// finite point set has exactly one regular ("perturbed Delaunay") triangulation, in 2D and in 3D,
// using every point as a vertex (the lifted points are in strictly convex position: a strictly
// convex paraboloid, perturbed infinitesimally).
//
// Why both cells of a shared face triangulate it identically (the argument, also for cocircular
// points and for T-junction vertices collinear on a face's edges):
//  1. delaunay_face() gives the perturbed 2D regular triangulation of the face's own vertices (in
//     the face's plane, lifted by the same H). It depends only on those vertices and their ids,
//     so it is the same whichever cell asks; it is computed once per face anyway.
//  2. For a cell, the hull triangles of the 3D perturbed regular triangulation on one facet plane
//     F of the cell are the 2D perturbed regular triangulation of the cell's points on F with the
//     same heights (the lower faces of the lifted hull above the face F of the convex hull are the
//     lower faces of the lifted points above F; an affine parameterization of F's plane keeps
//     "below"). When F carries one BSP face, that is exactly the face's triangulation of 1.
//  3. When F carries several BSP faces (a neighbour was split, this cell was not; or a surface face
//     was split along an input edge), the 3D hull may cross their common edges. So the caller
//     compares, per cell, the boundary of its tets (recomputed from the tets as a chain) with the
//     union of its faces' triangulations (1.), as oriented triangles. Only an exact match is
//     accepted; the tets then meet every neighbour on the shared face's one triangulation. A
//     mismatch is repaired by recover_cell_boundary (below), whose result is compared the same
//     way; if that fails too, the cell goes to the cone fillers (cell_tetrahedralize.h), which use
//     the same face triangulations.
// Validity of the tets: the Delaunay triangulation of the cell's vertices tiles their convex hull,
// which is the (convex) cell; Bowyer-Watson never makes a flat tet under the perturbation (a
// coplanar point on a hull face is in conflict with the outside of that face exactly when it is
// in conflict with the tet inside, since the circumsphere meets the plane in the circumcircle);
// and every output tet is also re-checked to be strictly positive (exact orient3d), else the cell
// falls back as in 3. Independently of the algorithm's correctness, what is accepted is proved by
// the checks: tets all strictly positive whose boundary chain is exactly the cell's boundary cycle
// cover every point of the cell with winding number 1, hence tile it once. No epsilon anywhere:
// every decision is an exact sign.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "bsptet/core/bsp_complex.h"
#include "bsptet/numerics/implicit_geometry.h"

namespace bsptet {

/// The perturbed 2D Delaunay (regular) triangulation of convex face `face` (all its vertices, also
/// collinear ones), counter-clockwise around the plane normal: ear clipping, then Lawson flips
/// under lifted_det2. Throws MeshingError (kInternal) if the face is degenerate.
std::vector<std::array<Index, 3>> delaunay_face(ImplicitGeometry& geo, const BspFace& face);

struct CellDelaunay {
  std::vector<std::array<Index, 4>> tets;  ///< positively oriented (exact), global vertex ids
  std::vector<std::array<Index, 3>> hull;  ///< boundary triangles, counter-clockwise seen from outside
};

/// Randomized incremental Bowyer-Watson of `points` (distinct global vertex ids, not all coplanar),
/// with ghost tets for the outside: the perturbed Delaunay tetrahedralization of the points.
/// `seed` fixes the insertion order (a local generator: no global state; the result itself does
/// not depend on the order, the perturbed triangulation being unique). Returns false (output
/// unspecified) if an internal consistency check fails (a non-manifold cavity, a walk that does
/// not end, a non-positive tet): the caller then uses another filler.
/// `planes`: planes known to carry points of the set (the cell's face planes; may be empty): with
/// ImplicitGeometry::known_on_plane they decide coplanar cases without arithmetic (speed only).
bool delaunay_cell(ImplicitGeometry& geo, std::vector<Index> points, const std::vector<Index>& planes,
                   std::uint64_t seed, CellDelaunay& out);

/// Boundary recovery for a cell whose Delaunay boundary differs from its faces' triangulations on
/// some facet planes (a facet made of several BSP faces). `tets` (positive, tiling the cell) is
/// modified in place; `want` holds the required boundary triangles, outward (counter-clockwise seen
/// from outside), each with its plane. For each plane P whose triangles differ, Sloan's edge
/// insertion in P's 2D triangulation: every missing edge (c, d) of the wanted triangulation is
/// made by flipping edges (a, b) that cross it (strictly convex quadrilaterals; the wanted edges
/// never cross each other, so none is flipped away). Each 2D flip is done in 3D by re-filling a
/// cavity C (the tets around the edge (a, b), grown tet by tet across the faces the apex does not
/// see, at most `max_growth` rounds, never across the cell boundary) with the cone from one of its
/// vertices v over C's boundary with the two triangles swapped for the flipped pair. If a flip
/// fails, the whole facet is swapped in one cavity the same way.
/// Valid by the chain argument of steiner_removal.h: the new boundary Z of C is a closed cycle (the
/// swapped triangles cover the same region with the same boundary edges), the cone v * Z has
/// boundary Z (cones over faces through v are flat, zero chains), so when every other cone tet is
/// strictly positive (checked exactly) they tile C once and keep Z. No new point, no epsilon.
/// Work is limited (about 20000 + 60 x #tets orientation tests and tets visited): past it, false.
/// Returns true when every tet is positive and the boundary of the resulting tets equals `want`
/// exactly (recomputed from the tets); false otherwise (tets then unspecified).
bool recover_cell_boundary(ImplicitGeometry& geo, std::vector<std::array<Index, 4>>& tets,
                           const std::vector<std::pair<std::array<Index, 3>, Index>>& want, int max_growth);

}  // namespace bsptet
