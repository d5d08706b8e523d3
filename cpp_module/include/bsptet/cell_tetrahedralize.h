// FemBspTet core: tets from the convex leaf cells (paper Sec. 2.3), identical on both sides of
// every face.
//
// Every face is triangulated once (face_triangulation), and both cells that share it use that
// triangulation: this is what makes the cells' tets conform without the paper's glue (Sec. 2.4)
// and crossed-edge fixing (Sec. 2.5). The triangulation keeps every vertex of the face, also the
// vertices a neighbour's split left in the middle of an edge (collinear), so it never creates a
// T-junction. Then each inside cell is coned from an explicit point strictly inside it (checked
// exactly) to every face triangle: valid for any convex cell. (Coning from a cell vertex would fan
// the faces at that vertex from it, disagreeing with the neighbour's triangulation of those faces
// and skipping collinear vertices.) A cell that is already a tetrahedron is output as is. The
// interior Steiner points are to be removed later where possible.
#pragma once

#include <array>
#include <vector>

#include "bsptet/bsp_complex.h"
#include "bsptet/cell_classify.h"

namespace bsptet {

/// Triangles of face `face`, counter-clockwise around its plane normal, using all its vertices.
std::vector<std::array<Index, 3>> triangulate_face(ImplicitGeometry& geo, const BspFace& face);

/// Positively oriented tets (vertex ids of the geometry) filling the cells with winding number 1.
std::vector<std::array<Index, 4>> tetrahedralize_cells(BspComplex& bsp, const CellLabels& labels,
                                                       std::int64_t* inside_cells = nullptr);

}  // namespace bsptet
