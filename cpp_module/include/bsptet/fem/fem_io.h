// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet FEM pipeline: writing a FemMesh for viewers (ParaView) and debugging. The user-facing
// writers (CalculiX .inp, FreeCAD FemMesh) are in the Python package.
#pragma once

#include <string>

#include "bsptet/fem/fem_mesh.h"

namespace bsptet::fem {

/// Writes a VTK XML unstructured grid (ASCII .vtu, round-trip precision): the tets (VTK_TETRA or
/// VTK_QUADRATIC_TETRA) then the CAD face triangles (VTK_TRIANGLE or VTK_QUADRATIC_TRIANGLE),
/// with cell data "solid" (the tet's solid, -1 on triangles) and "face" (the triangle's CAD face,
/// -1 on tets). Node orders are VTK's, the same as types.h. Throws InputError naming the file
/// when it cannot be written.
void write_vtu(const std::string& path, const FemMesh& mesh);

}  // namespace bsptet::fem
