// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the mesh checker. Decides, exactly on the output doubles, whether a tet mesh is a
// valid constrained tetrahedralization of a closed input surface. Used by the tests on every mesh
// they make, by the mesher itself (`valid` in the stats) and by `fembsptet check`.
//
// A mesh is VALID when all of these hold (each one decided exactly, see predicates.h):
//  1. indices are in range and coordinates finite; no two points share coordinates; every point is
//     used by some tet;
//  2. every tet is positively oriented (orient3d > 0, see types.h);
//  3. every triangle face is shared by at most two tets, and two tets sharing it see it with opposite
//     orientations;
//  4. every boundary face (a face of exactly one tet), oriented outward, lies on an input triangle
//     (coplanar and inside it, closed) with the same orientation as that triangle; the boundary
//     faces on each input triangle cover exactly its area (exact sum of projected areas) and every
//     directed boundary edge is matched by its reverse: the boundary tiles the input surface;
//  5. the total tet volume equals the volume enclosed by the input surface (exact sums);
//  6. for 10-node tets, every edge has one mid-node, the same in every tet that uses the edge.
// Conditions 2-4 together imply that the tets cover the enclosed solid exactly once (a degree
// argument), so no overlap, gap or hanging node can hide; 5 is checked anyway as a cross-check.
//
// Quality figures (double precision, informative): dihedral angles and radius-edge ratios.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bsptet/mesh/types.h"

namespace bsptet {

struct QualityStats {
  std::int64_t tets = 0;
  double min_dihedral_deg = 0;
  double max_dihedral_deg = 0;
  double p1_dihedral_deg = 0;       ///< 1st percentile of all 6 #K dihedral angles
  double median_dihedral_deg = 0;
  double median_tet_min_dihedral_deg = 0;  ///< median over tets of each tet's smallest angle
  double max_radius_edge_ratio = 0;  ///< circumradius / shortest edge (regular tet: 0.612)
  double median_radius_edge_ratio = 0;
  std::vector<std::int64_t> dihedral_histogram;  ///< 180 bins of one degree: [k, k + 1)
};

/// Dihedral angles and radius-edge ratios of the linear tets (first four nodes of each tet).
QualityStats tet_quality(const TetMesh& mesh);

struct MeshCheckOptions {
  int max_messages = 20;          ///< messages kept (counts are always complete)
  bool compute_quality = true;
};

struct MeshCheckReport {
  bool valid = false;
  std::int64_t points = 0, tets = 0, boundary_faces = 0, interior_faces = 0;
  // Defect counts: all zero in a valid mesh.
  std::int64_t bad_indices = 0, nonfinite_points = 0, duplicate_points = 0, unreferenced_points = 0;
  std::int64_t inverted_tets = 0, flat_tets = 0;
  std::int64_t overshared_faces = 0, same_orientation_faces = 0;
  std::int64_t boundary_faces_off_surface = 0, boundary_faces_inward = 0;
  std::int64_t unpaired_boundary_edges = 0, miscovered_triangles = 0;
  std::int64_t inconsistent_midnodes = 0;
  bool volume_equal = false;
  double tet_volume = 0, surface_volume = 0;  ///< rounded from the exact sums
  // Points of the tet mesh that are not input vertices.
  std::int64_t steiner_points = 0, boundary_steiner_points = 0;
  std::vector<std::string> messages;  ///< the first max_messages problems, with indices
  QualityStats quality;
};

/// Checks `mesh` against the closed input surface `surface`. Never throws on bad data: everything
/// wrong is reported. Cost: O(#K log #K) plus exact arithmetic on faces that are not input
/// triangles themselves.
MeshCheckReport check_mesh(const SurfaceMesh& surface, const TetMesh& mesh,
                           const MeshCheckOptions& options = {});

/// The boundary of a tet mesh (its first four nodes per tet) as a surface: the faces of exactly
/// one tet, oriented outward (types.h), in the order of their sorted vertex triples; the points
/// are the mesh's. What a mesh whose surface points are off the input (rounded mode, a projection
/// hook) is checked against.
SurfaceMesh boundary_surface(const TetMesh& mesh);

}  // namespace bsptet
