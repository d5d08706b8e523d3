// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet fuzz targets: shared helpers. Each target defines LLVMFuzzerTestOneInput; it is built
// twice: with libFuzzer (-DFEMBSPTET_FUZZ=ON, scripts/fuzz.sh) and, linked with replay_main.cpp, as
// a plain program that replays the pinned findings in regressions/<target>/ (a CTest, label unit).
//
// A target "finds" something by crashing: a sanitizer report, an exception other than the typed
// InputError (or MeshingError where the core may fail), or a broken invariant (fuzz_require).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#define fuzz_require(cond)                                                                 \
  do {                                                                                     \
    if (!(cond)) {                                                                         \
      std::fprintf(stderr, "fuzz invariant broken: %s (%s:%d)\n", #cond, __FILE__, __LINE__); \
      std::abort();                                                                        \
    }                                                                                      \
  } while (0)

namespace bsptet_fuzz {

/// Reads the fuzz input as a stream of small values; past the end it yields zeros.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  std::size_t left() const { return pos_ < size_ ? size_ - pos_ : 0; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// A coordinate from one or two bytes: mostly small integers (many ties, collinear and coplanar
/// points), sometimes halves, tiny or huge magnitudes, or values one ulp off an integer.
double coordinate(Bytes& in);

}  // namespace bsptet_fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
