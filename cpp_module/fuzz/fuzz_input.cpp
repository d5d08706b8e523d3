// SPDX-License-Identifier: LGPL-2.1-or-later
#include "fuzz_input.h"

#include <cmath>

namespace bsptet_fuzz {

double coordinate(Bytes& in) {
  const std::uint8_t b = in.byte();
  const double v = static_cast<double>(static_cast<int>(b & 7) - 3);  // -3 .. 4
  switch (b >> 5) {
    case 0:
    case 1:
    case 2:
    case 3:
      return v;
    case 4:
      return v / 2;
    case 5:
      return std::nextafter(v, (in.byte() & 1) ? 1e300 : -1e300);
    case 6:
      return v * std::ldexp(1.0, static_cast<int>(in.byte() % 64) - 32);
    default:
      return v + 1e6;  // far from the origin
  }
}

}  // namespace bsptet_fuzz
