// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: an exact binary floating-point number, value = mantissa * 2^exponent with an
// arbitrary-precision integer mantissa (GMP). Every double converts exactly; +, -, * are exact.
// Used as the exact fallback of the filtered predicates and for exact area/volume sums. There is no
// division: predicates are written in homogeneous form.
#pragma once

#include <gmpxx.h>

#include <cstdint>

namespace bsptet {

class ExactFloat {
 public:
  ExactFloat() : mant_(0), exp_(0) {}
  /// Exact conversion. Precondition: d is finite.
  explicit ExactFloat(double d);

  int sign() const { return sgn(mant_); }
  /// Nearest double (for reporting only; never used to decide).
  double to_double() const;
  /// The exact value as a GMP rational.
  mpq_class to_mpq() const;
  /// *this / den truncated towards zero to a double (den nonzero): a function of the two exact
  /// values alone, computed without reducing the fraction (for canonical keys, never to decide).
  double truncated_quotient(const ExactFloat& den) const;

  friend ExactFloat operator+(const ExactFloat& a, const ExactFloat& b);
  friend ExactFloat operator-(const ExactFloat& a, const ExactFloat& b);
  friend ExactFloat operator*(const ExactFloat& a, const ExactFloat& b);
  ExactFloat operator-() const {
    ExactFloat r(*this);
    r.mant_ = -r.mant_;
    return r;
  }
  ExactFloat& operator+=(const ExactFloat& b) { return *this = *this + b; }
  friend bool operator==(const ExactFloat& a, const ExactFloat& b) { return (a - b).sign() == 0; }
  friend bool operator!=(const ExactFloat& a, const ExactFloat& b) { return !(a == b); }

 private:
  friend ExactFloat add_or_subtract(const ExactFloat& a, const ExactFloat& b, bool subtract);
  mpz_class mant_;
  std::int64_t exp_;
};

}  // namespace bsptet
