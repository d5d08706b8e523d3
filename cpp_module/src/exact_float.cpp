#include "bsptet/exact_float.h"

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

namespace {
// Aligns two numbers to the smaller exponent: returns mantissas scaled so that both share `e`.
void align(const mpz_class& am, std::int64_t ae, const mpz_class& bm, std::int64_t be, mpz_class& ra,
           mpz_class& rb, std::int64_t& e) {
  if (ae == be) {
    ra = am;
    rb = bm;
    e = ae;
  } else if (ae > be) {
    mpz_mul_2exp(ra.get_mpz_t(), am.get_mpz_t(), static_cast<mp_bitcnt_t>(ae - be));
    rb = bm;
    e = be;
  } else {
    ra = am;
    mpz_mul_2exp(rb.get_mpz_t(), bm.get_mpz_t(), static_cast<mp_bitcnt_t>(be - ae));
    e = ae;
  }
}
}  // namespace

ExactFloat operator+(const ExactFloat& a, const ExactFloat& b) {
  if (a.mant_ == 0) return b;
  if (b.mant_ == 0) return a;
  ExactFloat r;
  mpz_class x, y;
  align(a.mant_, a.exp_, b.mant_, b.exp_, x, y, r.exp_);
  r.mant_ = x + y;
  return r;
}

ExactFloat operator-(const ExactFloat& a, const ExactFloat& b) { return a + (-b); }

ExactFloat operator*(const ExactFloat& a, const ExactFloat& b) {
  ExactFloat r;
  r.mant_ = a.mant_ * b.mant_;
  r.exp_ = (r.mant_ == 0) ? 0 : a.exp_ + b.exp_;
  return r;
}

}  // namespace bsptet
