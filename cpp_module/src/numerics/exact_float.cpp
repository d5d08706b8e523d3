// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/numerics/exact_float.h"

#include <cmath>
#include <limits>

namespace bsptet {

ExactFloat::ExactFloat(double d) {
  if (d == 0.0) {
    mant_ = 0;
    exp_ = 0;
    return;
  }
  int e = 0;
  const double frac = std::frexp(d, &e);  // d = frac * 2^e, 0.5 <= |frac| < 1
  // frac * 2^53 is an integer of at most 53 bits (exact for every finite double, subnormals too).
  const auto m = static_cast<std::int64_t>(std::ldexp(frac, 53));
  mant_ = static_cast<long>(m);  // long is 64-bit on the supported platforms
  exp_ = static_cast<std::int64_t>(e) - 53;
}

double ExactFloat::to_double() const {
  if (mant_ == 0) return 0.0;
  long exp2 = 0;
  const double d = mpz_get_d_2exp(&exp2, mant_.get_mpz_t());
  return std::ldexp(d, static_cast<int>(exp2 + exp_));
}

mpq_class ExactFloat::to_mpq() const {
  mpq_class q(mant_);
  if (exp_ > 0)
    mpz_mul_2exp(q.get_num_mpz_t(), q.get_num_mpz_t(), static_cast<mp_bitcnt_t>(exp_));
  else if (exp_ < 0)
    mpz_mul_2exp(q.get_den_mpz_t(), q.get_den_mpz_t(), static_cast<mp_bitcnt_t>(-exp_));
  q.canonicalize();
  return q;
}

double ExactFloat::truncated_quotient(const ExactFloat& den) const {
  mpq_t q;
  mpq_init(q);
  // (m1 2^e1) / (m2 2^e2): the power of two on the side that keeps both integers.
  const std::int64_t shift = exp_ - den.exp_;
  mpz_mul_2exp(mpq_numref(q), mant_.get_mpz_t(), static_cast<mp_bitcnt_t>(shift > 0 ? shift : 0));
  mpz_mul_2exp(mpq_denref(q), den.mant_.get_mpz_t(), static_cast<mp_bitcnt_t>(shift < 0 ? -shift : 0));
  if (mpz_sgn(mpq_denref(q)) < 0) {
    mpz_neg(mpq_numref(q), mpq_numref(q));
    mpz_neg(mpq_denref(q), mpq_denref(q));
  }
  const double d = mpq_get_d(q);  // truncates; needs no reduced fraction
  mpq_clear(q);
  return d;
}

// Sum or difference without temporaries: the operand with the larger exponent is shifted into the
// result's mantissa, then the other is added or subtracted in place (one allocation at most).
ExactFloat add_or_subtract(const ExactFloat& a, const ExactFloat& b, bool subtract) {
  ExactFloat r;
  mpz_ptr rm = r.mant_.get_mpz_t();
  mpz_srcptr am = a.mant_.get_mpz_t(), bm = b.mant_.get_mpz_t();
  if (a.exp_ == b.exp_) {
    subtract ? mpz_sub(rm, am, bm) : mpz_add(rm, am, bm);
    r.exp_ = a.exp_;
  } else if (a.exp_ > b.exp_) {
    mpz_mul_2exp(rm, am, static_cast<mp_bitcnt_t>(a.exp_ - b.exp_));
    subtract ? mpz_sub(rm, rm, bm) : mpz_add(rm, rm, bm);
    r.exp_ = b.exp_;
  } else {
    mpz_mul_2exp(rm, bm, static_cast<mp_bitcnt_t>(b.exp_ - a.exp_));
    subtract ? mpz_sub(rm, am, rm) : mpz_add(rm, am, rm);
    r.exp_ = a.exp_;
  }
  return r;
}

ExactFloat operator+(const ExactFloat& a, const ExactFloat& b) {
  if (a.mant_ == 0) return b;
  if (b.mant_ == 0) return a;
  return add_or_subtract(a, b, false);
}

ExactFloat operator-(const ExactFloat& a, const ExactFloat& b) {
  if (b.mant_ == 0) return a;
  if (a.mant_ == 0) return -b;
  return add_or_subtract(a, b, true);
}

ExactFloat operator*(const ExactFloat& a, const ExactFloat& b) {
  ExactFloat r;
  if (a.mant_ == 0 || b.mant_ == 0) return r;
  mpz_mul(r.mant_.get_mpz_t(), a.mant_.get_mpz_t(), b.mant_.get_mpz_t());
  r.exp_ = a.exp_ + b.exp_;
  return r;
}

}  // namespace bsptet
