// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: SplitMix64, the small deterministic generator behind every randomized order
// of the core (insertion orders, walk directions). The state is the caller's: no global state,
// the same seed gives the same sequence on every machine.
#pragma once

#include <cstdint>

namespace bsptet {

/// Advances `state` and returns the next 64-bit value (Steele, Lea and Flood's SplitMix64).
inline std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace bsptet
