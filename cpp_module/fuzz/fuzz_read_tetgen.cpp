// SPDX-License-Identifier: LGPL-2.1-or-later
// Fuzz target: the C++ TetGen reader (mesh_io.h parse_tetgen). The input is the .node text, a NUL
// byte, then the .ele text. Only InputError may come out; a returned mesh has indices in range.
#include <cmath>
#include <string>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_io.h"
#include "fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string all(reinterpret_cast<const char*>(data), size);
  const std::size_t cut = all.find('\0');
  const std::string node = all.substr(0, cut), ele = cut == std::string::npos ? std::string() : all.substr(cut + 1);
  try {
    const bsptet::TetMesh m = bsptet::parse_tetgen(node, ele, "fuzz.node", "fuzz.ele");
    fuzz_require(m.nodes_per_tet == 4 || m.nodes_per_tet == 10);
    fuzz_require(m.tet.size() % m.nodes_per_tet == 0);
    for (double v : m.xyz) fuzz_require(std::isfinite(v));
    for (bsptet::Index v : m.tet) fuzz_require(v >= 0 && v < m.num_points());
  } catch (const bsptet::InputError& e) {
    const std::string what = e.what();
    fuzz_require(what.rfind("fuzz.node:", 0) == 0 || what.rfind("fuzz.ele:", 0) == 0);
  }
  return 0;
}
