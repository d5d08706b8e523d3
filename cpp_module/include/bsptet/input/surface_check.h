// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the input surface check, before any meshing. Decides exactly whether a triangle
// surface bounds a solid the mesher can fill, and names the first problem precisely.
//
//   SurfaceCheckResult r = check_surface(surface, options);   // throws InputError, or returns
//
// Checks, in this order (the first failing one throws; its message names the triangle, edge or
// vertex, and the total count of that kind of problem):
//   1. arrays of 3 columns, at least one triangle          ErrorCode::kBadArgument
//   2. finite coordinates                                   kNonFiniteCoordinate (vertex index)
//   3. vertex indices in range (no negative ones)           kBadArgument (triangle index)
//   -- points with identical coordinates are one vertex from here on (no tolerance) --
//   4. no zero-area triangle (exact collinearity)           kDegenerateTriangle
//   5. no two triangles on the same three vertices          kDuplicateTriangle
//   6. every edge in exactly two triangles                  kOpenBoundary (1) / kNonManifold (> 2)
//   7. the two triangles of each edge use it in opposite directions   kInconsistentOrientation
//      (options.reorient: flip triangles instead, shell by shell; a non-orientable shell still throws)
//   8. the triangles around each vertex form one fan        kNonManifold (vertex index)
//   9. no two triangles intersect (exact; triangle pairs)   kSelfIntersection (SelfIntersectionError)
//  10. shells face the right way: a shell inside an even number of other shells bounds the solid
//      (outward, positive signed volume), inside an odd number it bounds a cavity (inward)
//                                                           kInwardFacing (options.reorient: flip)
// Exact throughout: orientations and signed-volume signs are exact (predicates.h, ExactFloat);
// nesting is decided by exact ray parity with a ray that meets no edge or vertex.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/types.h"

namespace bsptet {

struct SurfaceCheckOptions {
  /// Make each shell consistently oriented and facing the right way (see 7 and 10 above) by
  /// flipping triangles, instead of refusing the surface.
  bool reorient = false;
  /// Look for self-intersecting triangle pairs (step 9).
  bool self_intersections = true;
  /// The most intersecting pairs collected for SelfIntersectionError (>= 1).
  std::int64_t max_reported_pairs = 1000;
};

struct SurfaceCheckResult {
  /// The triangles (#T by 3, the input's vertex indices), with the flipped ones reversed (their
  /// second and third corners swapped). Equal to the input unless options.reorient flipped some.
  std::vector<Index> tri;
  std::int64_t flipped_triangles = 0;
  /// Connected components through edges (closed shells).
  std::int64_t shells = 0;
  /// Input points whose coordinates repeat an earlier point's (they are one vertex).
  std::int64_t merged_points = 0;
};

/// The surface crosses or touches itself. `pairs()` holds intersecting triangle pairs (s < t),
/// sorted; `complete()` is false when there were more than the options allowed to collect.
class SelfIntersectionError : public InputError {
 public:
  SelfIntersectionError(std::int64_t index, const std::string& message, std::vector<std::array<Index, 2>> pairs,
                        bool complete)
      : InputError(ErrorCode::kSelfIntersection, "input", index, message),
        pairs_(std::move(pairs)),
        complete_(complete) {}
  const std::vector<std::array<Index, 2>>& pairs() const { return pairs_; }
  bool complete() const { return complete_; }

 private:
  std::vector<std::array<Index, 2>> pairs_;
  bool complete_;
};

/// Checks `surface` (see the list above). Throws InputError (SelfIntersectionError for step 9).
SurfaceCheckResult check_surface(const SurfaceMesh& surface, const SurfaceCheckOptions& options = {});

/// Step 9 alone: throws SelfIntersectionError (pairs as check_surface reports them) when two
/// triangles of `surface` meet beyond their shared vertices. Precondition: steps 1 to 8 pass
/// (check_surface with options.self_intersections = false returned). Reads `surface` only, so it
/// may run on another thread while the core meshes the same surface (mesher.h
/// check_and_tetrahedralize).
void check_self_intersections(const SurfaceMesh& surface, const SurfaceCheckOptions& options = {});

/// `surface` with the points of identical coordinates made one vertex: each triangle corner
/// replaced by the smallest index of a point with its coordinates (-0.0 equals 0.0; no tolerance).
/// `merged` (optional) receives how many points repeat an earlier one's coordinates.
SurfaceMesh merge_coincident_points(const SurfaceMesh& surface, std::int64_t* merged = nullptr);

}  // namespace bsptet
