// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/numerics/errors.h"

namespace bsptet {

const char* error_code_name(ErrorCode code) {
  switch (code) {
    case ErrorCode::kBadArgument: return "bad_argument";
    case ErrorCode::kNonFiniteCoordinate: return "non_finite_coordinate";
    case ErrorCode::kDegenerateTriangle: return "degenerate_triangle";
    case ErrorCode::kDuplicateTriangle: return "duplicate_triangle";
    case ErrorCode::kOpenBoundary: return "open_boundary";
    case ErrorCode::kNonManifold: return "non_manifold";
    case ErrorCode::kInconsistentOrientation: return "inconsistent_orientation";
    case ErrorCode::kInwardFacing: return "inward_facing";
    case ErrorCode::kSelfIntersection: return "self_intersection";
    case ErrorCode::kCancelled: return "cancelled";
    case ErrorCode::kInternal: return "internal";
  }
  return "unknown";
}

}  // namespace bsptet
