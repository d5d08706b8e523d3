// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: minimal file I/O for C++ tests, fuzz targets and debug dumps. The user-facing
// readers and writers (every format, precise messages) are in the Python package; these follow the
// same conventions (types.h) and throw InputError naming the file and line.
#pragma once

#include <string>

#include "bsptet/mesh/types.h"

namespace bsptet {

/// Reads an ASCII OFF file of triangles ("OFF" header, "#" comments). Throws InputError.
SurfaceMesh read_off(const std::string& path);
/// Parses OFF text (`name` is used in messages). Throws InputError.
SurfaceMesh parse_off(const std::string& text, const std::string& name);
/// Writes an ASCII OFF file with round-trip precision.
void write_off(const std::string& path, const SurfaceMesh& surface);

/// Reads TetGen's `stem.node` + `stem.ele` (index base 0 or 1, as the .node file says).
TetMesh read_tetgen(const std::string& stem);
/// Parses the texts of a `.node` and an `.ele` file (names used in messages). Throws InputError.
TetMesh parse_tetgen(const std::string& node_text, const std::string& ele_text, const std::string& node_name,
                     const std::string& ele_name);
/// Writes `stem.node` + `stem.ele` (1-based), round-trip precision.
void write_tetgen(const std::string& stem, const TetMesh& mesh);

}  // namespace bsptet
