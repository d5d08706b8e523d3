// SPDX-License-Identifier: LGPL-2.1-or-later
// Small real inputs for the quality stage's pieces (tests/refine): a box meshed by the core, as
// RefineMesh takes it, and the invariants the pieces keep (exact volume, worst angle).
#pragma once

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "bsptet/core/mesher.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/mesh/mesh_io.h"
#include "bsptet/mesh/types.h"
#include "bsptet/refine/refine_mesh.h"
#include "support/test_shapes.h"

namespace bsptet_test {

/// The box [0, side]^3 (12 triangles; with `tag_bottom`, the two triangles of z = 0 get tag 1 and
/// the others tag 0) and its core mesh.
struct BoxInput {
  bsptet::SurfaceMesh surface;
  bsptet::TetMesh mesh;
  explicit BoxInput(double side = 1.0, bool tag_bottom = false) {
    add_box(surface, 0.0, side);
    if (tag_bottom) {
      surface.tag.assign(12, 0);
      surface.tag[0] = surface.tag[1] = 1;  // add_box: triangles 0 and 1 are the face z = 0
    }
    mesh = bsptet::tetrahedralize(surface);
  }
};

/// A surface of tests/data (FEMBSPTET_DATA_DIR) and its core mesh.
struct FileInput {
  bsptet::SurfaceMesh surface;
  bsptet::TetMesh mesh;
  explicit FileInput(const std::string& rel) {
    surface = bsptet::read_off(std::string(FEMBSPTET_DATA_DIR) + "/" + rel);
    mesh = bsptet::tetrahedralize(surface);
  }
  /// The diagonal of the surface's bounding box.
  double diagonal() const {
    const auto [lo, hi] = box();
    return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                     (hi[2] - lo[2]) * (hi[2] - lo[2]));
  }
  /// The centre of the surface's bounding box.
  bsptet::Vec3 centre() const {
    const auto [lo, hi] = box();
    return {(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
  }

 private:
  std::pair<std::array<double, 3>, std::array<double, 3>> box() const {
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (std::size_t i = 0; i < surface.xyz.size(); ++i) {
      lo[i % 3] = std::min(lo[i % 3], surface.xyz[i]);
      hi[i % 3] = std::max(hi[i % 3], surface.xyz[i]);
    }
    return {lo, hi};
  }
};

/// Six times the volume of the live tets of m, exactly (each tet's determinant of its double
/// corners as a rational).
inline mpq_class exact_volume6(const bsptet::RefineMesh& m) {
  mpq_class sum = 0;
  for (bsptet::Index t = 0; t < m.num_tet_slots(); ++t) {
    if (!m.tet_alive(t)) continue;
    const auto& q = m.tet(t);
    const bsptet::Vec3 &a = m.point(q[0]), &b = m.point(q[1]), &c = m.point(q[2]), &d = m.point(q[3]);
    const mpq_class bx = mpq_class(b.x) - a.x, by = mpq_class(b.y) - a.y, bz = mpq_class(b.z) - a.z;
    const mpq_class cx = mpq_class(c.x) - a.x, cy = mpq_class(c.y) - a.y, cz = mpq_class(c.z) - a.z;
    const mpq_class dx = mpq_class(d.x) - a.x, dy = mpq_class(d.y) - a.y, dz = mpq_class(d.z) - a.z;
    sum += bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx);
  }
  return sum;
}

/// The smallest min dihedral angle of the live tets (degrees; 180 without tets).
inline double worst_angle(const bsptet::RefineMesh& m) {
  double w = 180;
  for (bsptet::Index t = 0; t < m.num_tet_slots(); ++t)
    if (m.tet_alive(t)) w = std::min(w, m.tet_quality(t));
  return w;
}

/// True when the mesh is valid for `surface` by the exact checker (mesh_check.h).
inline bool valid(const bsptet::SurfaceMesh& surface, const bsptet::RefineMesh& m) {
  return bsptet::check_mesh(surface, m.to_tet_mesh()).valid;
}

}  // namespace bsptet_test
