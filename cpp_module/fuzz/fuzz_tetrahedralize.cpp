// SPDX-License-Identifier: LGPL-2.1-or-later
// Fuzz target: the whole core on small closed surfaces. The first byte picks a closed
// triangulation (tetrahedron, octahedron, triangular prism, cube, hexagonal bipyramid); the
// following bytes place its vertices on a small grid (coplanar faces, collinear edges, ties) or
// off it by an ulp. The surface check runs first (re-orienting). A surface it accepts must be
// meshed validly: tetrahedralize may throw MeshingError (an internal limit, reported as such), but
// a mesh it returns must pass the exact checker (mesh_check.h), and it must not call an accepted
// surface bad input.
#include <cstdio>
#include <vector>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/core/mesher.h"
#include "bsptet/input/surface_check.h"
#include "fuzz_input.h"

using namespace bsptet;

namespace {

struct Shape {
  int points;
  std::vector<Index> tri;
};

const Shape& shape(int k) {
  static const Shape shapes[5] = {
      {4, {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2}},
      {6, {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5}},
      {6, {0, 2, 1, 3, 4, 5, 0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 2, 0, 3, 2, 3, 5}},
      {8, {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5}},
      {8, {0, 1, 6, 1, 2, 6, 2, 3, 6, 3, 4, 6, 4, 5, 6, 5, 0, 6, 1, 0, 7, 2, 1, 7, 3, 2, 7, 4, 3, 7, 5, 4, 7, 0, 5, 7}},
  };
  return shapes[k % 5];
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bsptet_fuzz::Bytes in(data, size);
  const Shape& sh = shape(in.byte());
  SurfaceMesh s;
  s.tri = sh.tri;
  for (int i = 0; i < 3 * sh.points; ++i) s.xyz.push_back(bsptet_fuzz::coordinate(in));
  try {
    SurfaceCheckOptions o;
    o.reorient = true;
    s.tri = check_surface(s, o).tri;
  } catch (const InputError&) {
    return 0;
  }
  MeshOptions mo;
  mo.allow_boundary_steiner = in.byte() & 1;
  TetMesh m;
  try {
    m = tetrahedralize(s, mo);
  } catch (const InputError& e) {
    std::fprintf(stderr, "the core refused a surface the input check accepted: %s\n", e.what());
    fuzz_require(false);
  } catch (const MeshingError&) {
    return 0;  // an internal limit of the core, typed and reported; not a crash
  }
  const MeshCheckReport r = check_mesh(s, m);
  if (!r.valid)
    for (const auto& msg : r.messages) std::fprintf(stderr, "  %s\n", msg.c_str());
  fuzz_require(r.valid);
  return 0;
}
