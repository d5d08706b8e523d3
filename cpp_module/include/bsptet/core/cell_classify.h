// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: inside/outside of the leaf cells (paper Sec. 2.2: "convex subpolyhedra in the
// polyhedron"). A leaf face on an input plane is either wholly covered by coplanar input triangles
// or not at all (no input triangle crosses a leaf). Its coverage (+1 when the covering triangles'
// outward normal is the plane normal n, -1 when it is -n, 0 when uncovered) is decided exactly by
// a separating-axis test in the plane. The winding number of a cell is then propagated from the
// cells touching the bounding box (winding 0) across faces:
//     winding(cell[1]) = winding(cell[0]) + coverage(face).
// Seed tets kept out of the complex (UntouchedSeedTets, bsp_complex.h) take part in the same
// propagation, across their faces (their steps) and across the complex faces they share.
// A contradiction, or a winding number other than 0 or 1, means the surface does not bound a
// solid (open, inconsistently oriented, inward-facing, overlapping or self-intersecting): an
// InputError names an input triangle there.
#pragma once

#include <vector>

#include "bsptet/core/bsp_complex.h"

namespace bsptet {

struct CellLabels {
  std::vector<int> winding;   ///< per cell (dead cells: 0)
  std::vector<int> coverage;  ///< per face: -1, 0 or +1
  std::vector<int> untouched_winding;  ///< per untouched seed tet (BspComplex::untouched())
  /// The winding number on side s (0: positive, 1: negative) of complex face `face` (id f): its
  /// cell's, else the untouched seed tet's there, else 0 (outside the box).
  int side_winding(const BspComplex& bsp, Index f, int s) const {
    const Index c = bsp.faces()[f].cell[s];
    if (c >= 0) return winding[c];
    const Index u = bsp.face_untouched(f);
    return u >= 0 ? untouched_winding[u] : 0;
  }
};

CellLabels classify_cells(BspComplex& bsp);

}  // namespace bsptet
