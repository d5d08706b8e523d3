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
#pragma once

#include <array>
#include <vector>

#include "bsptet/bsp_complex.h"
#include "bsptet/cell_classify.h"

namespace bsptet {

/// Triangles of face `face`, counter-clockwise around its plane normal, using all its vertices.
std::vector<std::array<Index, 3>> triangulate_face(ImplicitGeometry& geo, const BspFace& face);

struct CellTets {
  std::vector<std::array<Index, 4>> tets;      ///< positively oriented, geometry vertex ids
  std::vector<std::array<Index, 3>> boundary;  ///< faces between inside and outside, CCW seen from outside
  std::vector<Index> boundary_triangle;        ///< the input triangle that contains each boundary face
  std::int64_t inside_cells = 0, apex_cells = 0, pulled_cells = 0;
};

/// Tets filling the cells with winding number 1, and the boundary faces they expose.
CellTets tetrahedralize_cells(BspComplex& bsp, const CellLabels& labels);

}  // namespace bsptet
