// SPDX-License-Identifier: LGPL-2.1-or-later
// Validity certificate of 10-node tets: Bezier coefficients of det J, enclosed in intervals, with
// adaptive subdivision (tet10.h states the method and the derivation of the coefficients).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <vector>

#include "bsptet/numerics/interval.h"
#include "bsptet/refine/tet10.h"

namespace bsptet {

namespace {

// Local corner pairs of the six mid-nodes, in types.h order: m12 m23 m31 m14 m24 m34.
constexpr int kEdge[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

// Node slot of the control point P_ij: the corner i when i == j, else the mid-node of edge ij.
constexpr int node_slot(int i, int j) {
  if (i == j) return i;
  for (int e = 0; e < 6; ++e)
    if ((kEdge[e][0] == i && kEdge[e][1] == j) || (kEdge[e][0] == j && kEdge[e][1] == i)) return 4 + e;
  return -1;
}

// Position in kCubicMultiIndex of the multi-index e_i + e_j + e_k.
constexpr int cubic_position(int i, int j, int k) {
  int a[4] = {0, 0, 0, 0};
  ++a[i], ++a[j], ++a[k];
  for (int p = 0; p < 20; ++p)
    if (kCubicMultiIndex[p][0] == a[0] && kCubicMultiIndex[p][1] == a[1] && kCubicMultiIndex[p][2] == a[2] &&
        kCubicMultiIndex[p][3] == a[3])
      return p;
  return -1;
}

// Positions of the corner values c_(3 e_i).
constexpr int kCornerPosition[4] = {0, 10, 16, 19};

// a0! a1! a2! a3! of each multi-index: 6 / (number of ordered triples (i, j, k) giving it).
constexpr double factorial_product(int p) {
  double f = 1;
  for (int i = 0; i < 4; ++i) f *= kCubicMultiIndex[p][i] == 3 ? 6 : (kCubicMultiIndex[p][i] == 2 ? 2 : 1);
  return f;
}

// Sums S_a over the ordered triples (i, j, k) with e_i + e_j + e_k = a of det(D_1[i], D_2[j],
// D_3[k]) (tet10.h), in the arithmetic of S (double or Interval). The Bezier coefficient is
// c_a = S_a * a! / 6.
template <class S>
void triple_sums(const double* x, S sums[20]) {
  // 2 P_ij, then D_a[b] = 2 P_ab - 2 P_0b.
  S p2[4][4][3];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int c = 0; c < 3; ++c) {
        const S xi(x[3 * i + c]), xj(x[3 * j + c]);
        p2[i][j][c] = i == j ? xi + xi : S(4 * x[3 * node_slot(i, j) + c]) - xi - xj;  // 4 m: exact
      }
  S d[3][4][3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 4; ++b)
      for (int c = 0; c < 3; ++c) d[a][b][c] = p2[a + 1][b][c] - p2[0][b][c];
  S cross[4][4][3];  // D_2[j] x D_3[k]
  for (int j = 0; j < 4; ++j)
    for (int k = 0; k < 4; ++k) {
      const S* u = d[1][j];
      const S* v = d[2][k];
      cross[j][k][0] = u[1] * v[2] - u[2] * v[1];
      cross[j][k][1] = u[2] * v[0] - u[0] * v[2];
      cross[j][k][2] = u[0] * v[1] - u[1] * v[0];
    }
  bool first[20];
  std::fill(first, first + 20, true);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) {
        const S* u = d[0][i];
        const S* w = cross[j][k];
        const S v = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
        const int p = cubic_position(i, j, k);
        sums[p] = first[p] ? v : sums[p] + v;
        first[p] = false;
      }
}

// A value computed in double precision together with the same computation on absolute values
// (every input replaced by its absolute value, every subtraction by an addition): the magnitude
// that bounds the rounding error of the value (certify_tet10's first test).
struct Magnitude {
  double v = 0, m = 0;
  Magnitude() = default;
  explicit Magnitude(double x) : v(x), m(std::fabs(x)) {}
  Magnitude(double value, double magnitude) : v(value), m(magnitude) {}
  friend Magnitude operator+(const Magnitude& a, const Magnitude& b) { return {a.v + b.v, a.m + b.m}; }
  friend Magnitude operator-(const Magnitude& a, const Magnitude& b) { return {a.v - b.v, a.m + b.m}; }
  friend Magnitude operator*(const Magnitude& a, const Magnitude& b) { return {a.v * b.v, a.m * b.m}; }
};

// Rounding error of the 6 c_a computed in double by triple_sums<Magnitude> and the factorial
// product: each c_a is a sum of terms (signed products of input coordinates), and each term goes
// through at most k = 20 roundings (2 P: 2, D: 1, so 3 per D entry and 9 for three of them; the
// cross product's product and difference 2; the dot product's product and two sums 3; up to 5
// additions over the ordered triples; the factorial 1). With u = 2^-53 and no underflow or
// overflow, |computed - exact| <= gamma_k * M, gamma_k = k u / (1 - k u), where M is the exact
// sum of the terms' absolute values; the magnitude computed alongside (the same operations on
// non-negative values, so the same k) is >= M (1 - gamma_k). Hence the error is at most
// gamma_20 / (1 - gamma_20) * computed magnitude < 2.2205e-15 * computed magnitude; kErrorFactor
// keeps a margin that also covers rounding the product kErrorFactor * magnitude.
constexpr double kErrorFactor = 2.5e-15;

// Inputs for which the bound above holds: each coordinate 0 or of magnitude in [2^-250, 2^250].
// Then every non-zero intermediate value is at least 2^-1010 in magnitude (inputs are multiples
// of 2^-302, D entries of 2^-354, cross products' entries of 2^-708, and so on, so nothing
// underflows) and at most about 2^780 (nothing overflows).
bool in_error_bound_range(const double* x, int n) {
  for (int i = 0; i < n; ++i) {
    const double a = std::fabs(x[i]);
    if (a != 0 && !(a >= 0x1p-250 && a <= 0x1p250)) return false;
  }
  return true;
}

// 6 c_a as intervals, in full symmetric tensor form t[i][j][k] = 6 c_(e_i + e_j + e_k), so that
// 6 det J(L) = sum_{i,j,k} t[i][j][k] L_i L_j L_k and, on a sub-tet with barycentric corners
// w_0..w_3 (in the element's L), the coefficient of multi-index a is the blossom
// sum t[i][j][k] u_i v_j z_k with (u, v, z) the corners w_b repeated a_b times.
struct JacobianTensor {
  Interval t[4][4][4];
  bool finite = true;
};

JacobianTensor jacobian_tensor(const double* x) {
  Interval sums[20];
  triple_sums(x, sums);
  Interval six_c[20];
  JacobianTensor jt;
  for (int p = 0; p < 20; ++p) {
    six_c[p] = sums[p] * Interval(factorial_product(p));
    jt.finite = jt.finite && std::isfinite(six_c[p].lo()) && std::isfinite(six_c[p].hi());
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) jt.t[i][j][k] = six_c[cubic_position(i, j, k)];
  return jt;
}

// A sub-tet of the element: its corners' barycentric coordinates (dyadic, so exact) and level.
struct Domain {
  double w[4][4];
  int depth = 0;
};

Domain whole_element() {
  Domain d;
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 4; ++i) d.w[a][i] = a == i ? 1 : 0;
  return d;
}

// A sum of interval products with point weights (the weights are >= 0; zero terms are skipped).
void add_scaled(Interval& acc, bool& started, const Interval& v, double weight) {
  if (weight == 0) return;
  const Interval term = weight == 1 ? v : v * Interval(weight);
  acc = started ? acc + term : term;
  started = true;
}

// The 20 coefficients (times 6) of det J on sub-tet `d`, as intervals enclosing the exact ones.
void domain_coefficients(const JacobianTensor& jt, const Domain& d, Interval out[20]) {
  // a[b][j][k] = sum_i t[i][j][k] w_b[i]; then the pairs, then the triples.
  Interval a[4][4][4];
  for (int b = 0; b < 4; ++b)
    for (int j = 0; j < 4; ++j)
      for (int k = j; k < 4; ++k) {  // symmetric in (j, k)
        Interval acc;
        bool started = false;
        for (int i = 0; i < 4; ++i) add_scaled(acc, started, jt.t[i][j][k], d.w[b][i]);
        a[b][j][k] = a[b][k][j] = acc;
      }
  Interval pair[4][4][4];
  for (int b = 0; b < 4; ++b)
    for (int c = b; c < 4; ++c)
      for (int k = 0; k < 4; ++k) {
        Interval acc;
        bool started = false;
        for (int j = 0; j < 4; ++j) add_scaled(acc, started, a[b][j][k], d.w[c][j]);
        pair[b][c][k] = acc;
      }
  for (int b = 0; b < 4; ++b)
    for (int c = b; c < 4; ++c)
      for (int e = c; e < 4; ++e) {
        Interval acc;
        bool started = false;
        for (int k = 0; k < 4; ++k) add_scaled(acc, started, pair[b][c][k], d.w[e][k]);
        out[cubic_position(b, c, e)] = acc;
      }
}

// The eight children of `d` by red refinement with Bey's ordering (the interior octahedron split
// along its diagonal between the midpoints of edges 02 and 13).
void red_children(const Domain& d, Domain kids[8]) {
  double m[4][4][4];  // m[a][b]: midpoint of corners a, b (m[a][a] = corner a)
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      for (int i = 0; i < 4; ++i) m[a][b][i] = 0.5 * (d.w[a][i] + d.w[b][i]);  // dyadic: exact
  static constexpr int kChild[8][4][2] = {
      {{0, 0}, {0, 1}, {0, 2}, {0, 3}}, {{0, 1}, {1, 1}, {1, 2}, {1, 3}},
      {{0, 2}, {1, 2}, {2, 2}, {2, 3}}, {{0, 3}, {1, 3}, {2, 3}, {3, 3}},
      {{0, 1}, {0, 2}, {0, 3}, {1, 3}}, {{0, 1}, {0, 2}, {1, 2}, {1, 3}},
      {{0, 2}, {0, 3}, {1, 3}, {2, 3}}, {{0, 2}, {1, 2}, {1, 3}, {2, 3}}};
  for (int c = 0; c < 8; ++c) {
    for (int v = 0; v < 4; ++v)
      for (int i = 0; i < 4; ++i) kids[c].w[v][i] = m[kChild[c][v][0]][kChild[c][v][1]][i];
    kids[c].depth = d.depth + 1;
  }
}

bool all_finite(const double* x, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(x[i])) return false;
  return true;
}

// The quotient by 6, rounded and then stepped one ulp down (a lower bound of the exact quotient)
// or up (an upper bound); 0 stays 0.
double sixth_down(double v) { return v == 0 ? v : std::nextafter(v / 6, -std::numeric_limits<double>::infinity()); }
double sixth_up(double v) { return v == 0 ? v : std::nextafter(v / 6, std::numeric_limits<double>::infinity()); }

}  // namespace

void tet10_jacobian_bezier(const double* xyz30, double* out20) {
  double sums[20];
  triple_sums(xyz30, sums);
  for (int p = 0; p < 20; ++p) out20[p] = sums[p] * factorial_product(p) / 6;
}

Tet10Validity certify_tet10(const double* xyz30, int max_depth, double* min_bound) {
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (min_bound) *min_bound = kNaN;
  if (!all_finite(xyz30, 30)) return Tet10Validity::kUndecided;
  if (in_error_bound_range(xyz30, 30)) {
    // First the element's own coefficients in double with the error bound (most elements are
    // decided here, at a tenth of the interval evaluation's cost).
    Magnitude sums[20];
    triple_sums(xyz30, sums);
    double lowest = std::numeric_limits<double>::infinity();
    for (int p = 0; p < 20; ++p) {
      const double f = factorial_product(p);
      const double v = sums[p].v * f, err = kErrorFactor * (sums[p].m * f);
      lowest = std::min(lowest, v - err);
    }
    if (lowest > 0) {
      if (min_bound) *min_bound = sixth_down(lowest);
      return Tet10Validity::kCertified;
    }
    for (int p : kCornerPosition) {
      const double f = factorial_product(p);
      const double high = sums[p].v * f + kErrorFactor * (sums[p].m * f);
      if (high <= 0) {
        if (min_bound) *min_bound = sixth_up(high);
        return Tet10Validity::kInvalid;
      }
    }
  }
  const JacobianTensor jt = jacobian_tensor(xyz30);
  if (!jt.finite) return Tet10Validity::kUndecided;  // overflow: no subdivision narrows it
  double lowest = std::numeric_limits<double>::infinity();  // of the leaves' 6 c_a lower bounds
  bool undecided = false;
  std::vector<Domain> stack{whole_element()};
  Interval c[20];
  Domain kids[8];
  while (!stack.empty()) {
    const Domain d = stack.back();
    stack.pop_back();
    domain_coefficients(jt, d, c);
    bool corner_undecided = false;
    for (int p : kCornerPosition) {
      if (c[p].hi() <= 0) {
        if (min_bound) *min_bound = sixth_up(c[p].hi());
        return Tet10Validity::kInvalid;
      }
      corner_undecided = corner_undecided || c[p].lo() <= 0;
    }
    double lo = c[0].lo();
    for (int p = 1; p < 20; ++p) lo = std::min(lo, c[p].lo());
    if (lo > 0 || d.depth >= max_depth || corner_undecided) {
      undecided = undecided || lo <= 0;
      lowest = std::min(lowest, lo);
      continue;
    }
    red_children(d, kids);
    stack.insert(stack.end(), kids, kids + 8);
  }
  if (min_bound) *min_bound = sixth_down(lowest);
  return undecided ? Tet10Validity::kUndecided : Tet10Validity::kCertified;
}

double tet10_min_scaled_jacobian(const double* xyz30, double tolerance, int max_depth) {
  if (!all_finite(xyz30, 30)) return std::numeric_limits<double>::quiet_NaN();
  const double* n = xyz30;
  const double e[3][3] = {{n[3] - n[0], n[4] - n[1], n[5] - n[2]},
                          {n[6] - n[0], n[7] - n[1], n[8] - n[2]},
                          {n[9] - n[0], n[10] - n[1], n[11] - n[2]}};
  const double j0 = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                    e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
  if (!(j0 > 0)) return -std::numeric_limits<double>::infinity();
  const JacobianTensor jt = jacobian_tensor(xyz30);
  if (!jt.finite) return std::numeric_limits<double>::quiet_NaN();
  // Best first: the sub-tet with the lowest bound is split until that bound is within tolerance
  // of the lowest sampled value (the sub-tets' corner values).
  struct Entry {
    double lo;
    Domain d;
    bool operator<(const Entry& o) const { return lo > o.lo; }  // smallest bound on top
  };
  std::priority_queue<Entry> queue;
  double sampled = std::numeric_limits<double>::infinity();
  Interval c[20];
  auto push = [&](const Domain& d) {
    domain_coefficients(jt, d, c);
    double lo = c[0].lo();
    for (int p = 1; p < 20; ++p) lo = std::min(lo, c[p].lo());
    for (int p : kCornerPosition) sampled = std::min(sampled, 0.5 * (c[p].lo() + c[p].hi()));
    queue.push({lo, d});
  };
  push(whole_element());
  const double slack = tolerance * 6 * j0;  // the coefficients are 6 c_a
  Domain kids[8];
  for (;;) {
    const Entry top = queue.top();
    if (top.lo >= sampled - slack || top.d.depth >= max_depth) return top.lo / 6 / j0;
    queue.pop();
    red_children(top.d, kids);
    for (const Domain& k : kids) push(k);
  }
}

}  // namespace bsptet
