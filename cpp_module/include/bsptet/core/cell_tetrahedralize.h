// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: tets from the convex leaf cells (paper Sec. 2.3), identical on both sides of
// every face.
//
// Every face is triangulated once, and both cells that share it use that triangulation: this is
// what makes the cells' tets conform without the paper's glue (Sec. 2.4) and crossed-edge fixing
// (Sec. 2.5). The triangulation keeps every vertex of the face, also the vertices a neighbour's
// split left in the middle of an edge (collinear), so it never creates a T-junction.
//
// Each inside cell is then filled in one of three ways:
//  * a cell that is already a tetrahedron is output as is;
//  * otherwise it is coned from an explicit point strictly inside it (checked exactly) to every face
//    triangle: valid for any convex cell;
//  * a cell too thin to hold a double-precision point is "pulled" from one of its vertices v: coned
//    from v to the triangles of every face whose plane does not contain v. The faces through v must
//    then be fans from v for both cells that share them, so v qualifies only if every face of the
//    cell on a plane through v has v as a corner (no collinear vertex next to v) and no other cell
//    has claimed a different fan vertex for it;
//  * failing that, it is coned from an implicit apex: the exact centroid of four of its
//    non-coplanar vertices.
// The interior Steiner points (apexes) are removed later where possible (steiner_removal.h).
//
// That is the CONE filler (CellFill::kCone, the behaviour before the per-cell Delaunay). The
// default, CellFill::kDelaunay (paper Sec. 2.3, cell_delaunay.h), triangulates every face by the
// perturbed 2D Delaunay rule (delaunay_face, once per face) and fills each inside cell with the
// perturbed 3D Delaunay tetrahedralization of its vertices (Bowyer-Watson), accepted only when its
// boundary is exactly the union of the cell's face triangulations (the consistency argument is in
// cell_delaunay.h). A cell whose Delaunay boundary does not match (a facet made of several BSP
// faces whose common edges the Delaunay crosses, e.g. a surface face split along an input edge)
// is repaired facet by facet (recover_cell_boundary: a cavity of Delaunay tets re-coned from one
// of its vertices, no new point); when that fails too, or a check fails, it falls back, with the same
// face triangulations, to: pulled from a vertex v when every face on a plane through v is already
// triangulated as triangles that all contain v (then the cone from v over the other faces tiles
// the cell); else coned from an explicit interior apex; else from the implicit centroid apex.
// Fallbacks are counted in CellTets::delaunay_fallback_cells.
#pragma once

#include <array>
#include <vector>

#include "bsptet/core/bsp_complex.h"
#include "bsptet/core/cell_classify.h"

namespace bsptet {

/// Triangles of face `face`, counter-clockwise around its plane normal, using all its vertices.
std::vector<std::array<Index, 3>> triangulate_face(ImplicitGeometry& geo, const BspFace& face);

/// How inside cells are filled (see the header comment).
enum class CellFill { kDelaunay, kCone };

struct CellTets {
  std::vector<std::array<Index, 4>> tets;      ///< positively oriented, geometry vertex ids
  std::vector<std::array<Index, 3>> boundary;  ///< faces between inside and outside, CCW seen from outside
  std::vector<Index> boundary_triangle;        ///< the input triangle that contains each boundary face
  std::int64_t inside_cells = 0, apex_cells = 0, pulled_cells = 0;
  std::int64_t delaunay_cells = 0;           ///< inside cells filled by their Delaunay tets (kDelaunay)
  std::int64_t recovered_cells = 0;          ///< of which boundary-recovered (recover_cell_boundary)
  std::int64_t delaunay_fallback_cells = 0;  ///< inside cells (> 4 vertices) whose Delaunay was not used
};

/// Tets filling the cells with winding number 1, and the boundary faces they expose. Every tet is
/// positively oriented (exact); two cells sharing a face use the same triangles on it.
CellTets tetrahedralize_cells(BspComplex& bsp, const CellLabels& labels, CellFill fill = CellFill::kDelaunay);

}  // namespace bsptet
