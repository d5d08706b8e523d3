// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: flat mesh containers.
//
// Conventions, stated once for the whole core:
//  * Points are doubles, `xyz` holds #P by 3 coordinates, row-major.
//  * Input triangles are oriented counter-clockwise seen from outside (outward right-hand normals).
//  * A tetrahedron (a, b, c, d) is POSITIVELY ORIENTED when det[b - a, c - a, d - a] > 0, i.e. d lies
//    on the side into which the right-hand normal of (a, b, c) points (see predicates.h: orient3d).
//    Its four outward faces are then (a, c, b), (a, b, d), (a, d, c), (b, c, d).
//  * Indices are 0-based 32-bit.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "bsptet/numerics/vec3.h"  // Index, Vec3

namespace bsptet {

/// The face of a tet opposite its vertex k, ordered so that vertex k lies on its positive side
/// (orient3d > 0 for a positive tet; the outward faces above, reversed).
inline constexpr int kTetOppositeFace[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};

/// A closed triangle surface: #P points, #T triangles (outward CCW), optional tag per triangle.
struct SurfaceMesh {
  std::vector<double> xyz;        ///< #P by 3
  std::vector<Index> tri;         ///< #T by 3, indices into points
  std::vector<std::int32_t> tag;  ///< empty or #T: CAD face index per triangle

  Index num_points() const { return static_cast<Index>(xyz.size() / 3); }
  Index num_triangles() const { return static_cast<Index>(tri.size() / 3); }
  Vec3 point(Index i) const { return {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}; }
};

/// A tetrahedral mesh: #P points and #K tets of 4 (linear) or 10 (quadratic) nodes each.
/// Quadratic node order: n1 n2 n3 n4 m12 m23 m31 m14 m24 m34 (SMESH / CalculiX C3D10 / VTK).
struct TetMesh {
  std::vector<double> xyz;  ///< #P by 3
  std::vector<Index> tet;   ///< #K by nodes_per_tet
  int nodes_per_tet = 4;

  Index num_points() const { return static_cast<Index>(xyz.size() / 3); }
  Index num_tets() const { return static_cast<Index>(tet.size() / nodes_per_tet); }
  Vec3 point(Index i) const { return {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}; }
};

}  // namespace bsptet
