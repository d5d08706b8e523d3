// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: typed errors. The core never prints and never exits; it throws these.
// The Python binding maps InputError -> ValueError (bad input, CLI exit 2) and
// MeshingError -> RuntimeError (internal failure, CLI exit 1).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace bsptet {

enum class ErrorCode {
  kBadArgument,         ///< malformed arrays (shape, index range)
  kNonFiniteCoordinate,  ///< NaN or infinite coordinate
  kDegenerateTriangle,   ///< zero-area triangle
  kDuplicateTriangle,    ///< the same triangle twice
  kOpenBoundary,         ///< an edge used by one triangle
  kNonManifold,          ///< an edge used by more than two triangles, or a pinched vertex
  kInconsistentOrientation,
  kInwardFacing,
  kSelfIntersection,
  kCancelled,
  kInternal,
};

/// Returns a stable snake_case name for a code ("open_boundary", ...).
const char* error_code_name(ErrorCode code);

/// Base of all core errors. `index` is the element the message is about (triangle, vertex, tet),
/// or -1 when there is none.
class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, std::string stage, std::int64_t index, const std::string& message)
      : std::runtime_error(message), code_(code), stage_(std::move(stage)), index_(index) {}
  ErrorCode code() const { return code_; }
  const std::string& stage() const { return stage_; }
  std::int64_t index() const { return index_; }

 private:
  ErrorCode code_;
  std::string stage_;
  std::int64_t index_;
};

/// The input is invalid: the user can fix it.
class InputError : public Error {
 public:
  using Error::Error;
};

/// The core failed although the input was valid: a bug, please report it.
class MeshingError : public Error {
 public:
  using Error::Error;
};

}  // namespace bsptet
