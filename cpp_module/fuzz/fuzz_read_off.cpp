// SPDX-License-Identifier: LGPL-2.1-or-later
// Fuzz target: the C++ OFF reader (mesh_io.h parse_off) on arbitrary bytes. Only InputError may
// come out; what it returns must have indices in range and finite coordinates.
#include <cmath>
#include <string>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_io.h"
#include "fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const bsptet::SurfaceMesh s = bsptet::parse_off(text, "fuzz.off");
    fuzz_require(s.xyz.size() % 3 == 0 && s.tri.size() % 3 == 0);
    for (double v : s.xyz) fuzz_require(std::isfinite(v));
    for (bsptet::Index v : s.tri) fuzz_require(v >= 0 && v < s.num_points());
  } catch (const bsptet::InputError& e) {
    fuzz_require(std::string(e.what()).rfind("fuzz.off:", 0) == 0);  // the message names the place
  }
  return 0;
}
