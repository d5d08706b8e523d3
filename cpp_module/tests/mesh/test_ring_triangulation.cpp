// SPDX-License-Identifier: LGPL-2.1-or-later
// RingTriangulation (mesh/ring_triangulation.h) against brute force: every triangulation of
// polygons of 3 to 9 vertices enumerated, random triangle scores (some not allowed), random
// forbidden diagonals.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "bsptet/mesh/ring_triangulation.h"

using namespace bsptet;

namespace {

using Triangles = std::vector<std::tuple<int, int, int>>;

// Every triangulation of the sub-polygon (i, j), in apex order, recursively.
std::vector<Triangles> all_triangulations(int i, int j) {
  if (j - i < 2) return {Triangles{}};
  std::vector<Triangles> out;
  for (int k = i + 1; k < j; ++k)
    for (const Triangles& left : all_triangulations(i, k))
      for (const Triangles& right : all_triangulations(k, j)) {
        Triangles t{{i, k, j}};
        t.insert(t.end(), left.begin(), left.end());
        t.insert(t.end(), right.begin(), right.end());
        out.push_back(t);
      }
  return out;
}

}  // namespace

TEST(RingTriangulation, BestIsTheBruteForceBottleneckOptimum) {
  std::mt19937 rng(7);
  for (int n = 3; n <= 9; ++n) {
    const std::vector<Triangles> every = all_triangulations(0, n - 1);
    for (int trial = 0; trial < 40; ++trial) {
      std::map<std::tuple<int, int, int>, double> score;
      for (int i = 0; i < n; ++i)
        for (int k = i + 1; k < n; ++k)
          for (int j = k + 1; j < n; ++j)
            score[{i, k, j}] = rng() % 5 == 0 ? -1.0 : static_cast<double>(rng() % 8);  // ties on purpose
      std::set<std::pair<int, int>> forbidden;
      for (int i = 0; i < n; ++i)
        for (int j = i + 2; j < n; ++j)
          if (!(i == 0 && j == n - 1) && rng() % 6 == 0) forbidden.insert({i, j});
      const double floor = trial % 3 == 0 ? 2.0 : -1.0;

      // Brute force: the best bottleneck above floor among triangulations whose triangles are
      // allowed and whose diagonals are not forbidden.
      double expected = -1;
      for (const Triangles& t : every) {
        double q = std::numeric_limits<double>::infinity();
        bool ok = true;
        for (const auto& [i, k, j] : t) {
          if (score[{i, k, j}] < 0) ok = false;
          q = std::min(q, score[{i, k, j}]);
          for (const auto& d : {std::pair{i, k}, std::pair{k, j}})
            if (forbidden.count(d)) ok = false;
        }
        if (ok && q > floor) expected = std::max(expected, q);
      }

      std::map<std::tuple<int, int, int>, int> calls;
      auto ring = make_ring_triangulation(
          n, floor, std::numeric_limits<double>::infinity(),
          [&](int i, int k, int j, double) {
            ++calls[{i, k, j}];
            return score[{i, k, j}];
          },
          [&](int i, int j) {
            EXPECT_FALSE(i == 0 && j == n - 1);
            return !forbidden.count({i, j});
          });
      const double best = ring.best(0, n - 1);
      ASSERT_EQ(best, expected) << "n " << n << " trial " << trial;
      for (const auto& [key, count] : calls) EXPECT_EQ(count, 1);
      if (best < 0) continue;
      // The triangulation it gives has that score and n - 2 triangles; each apex is the lowest
      // that reaches its sub-polygon's best.
      int triangles = 0;
      double q = std::numeric_limits<double>::infinity();
      ring.for_each_triangle(0, n - 1, [&](int i, int k, int j) {
        ++triangles;
        q = std::min(q, score[{i, k, j}]);
        for (int lower = i + 1; lower < k; ++lower) {
          const double b = ring.best(i, j);
          const bool as_good = ring.best(i, lower) >= b && ring.best(lower, j) >= b && score[{i, lower, j}] >= b;
          EXPECT_FALSE(as_good) << "a lower apex was as good";
        }
      });
      EXPECT_EQ(triangles, n - 2);
      EXPECT_EQ(q, best);
    }
  }
}

TEST(RingTriangulation, FirstAllowedTriangulationStopsAtTheFirstApex) {
  // All triangles allowed: with enough = 1 the fan from vertex 0's side is found by trying apex
  // i + 1 first everywhere, and no sub-polygon is measured twice.
  const int n = 7;
  int calls = 0;
  auto ring = make_ring_triangulation(
      n, 0.0, 1.0,
      [&](int, int, int, double) {
        ++calls;
        return 1.0;
      },
      [](int, int) { return true; });
  ASSERT_EQ(ring.best(0, n - 1), 1.0);
  EXPECT_EQ(calls, n - 2);
  std::vector<int> apexes, right_first_apexes;
  ring.for_each_triangle(0, n - 1, [&](int, int k, int) { apexes.push_back(k); });
  ring.for_each_triangle(0, n - 1, [&](int, int k, int) { right_first_apexes.push_back(k); }, true);
  EXPECT_EQ(apexes, (std::vector<int>{1, 2, 3, 4, 5}));
  EXPECT_EQ(right_first_apexes, apexes);  // a chain: one sub-polygon at each step
  // Nothing allowed: no triangulation.
  auto none = make_ring_triangulation(
      4, 0.0, 1.0, [](int, int, int, double) { return -1.0; }, [](int, int) { return true; });
  EXPECT_LT(none.best(0, 3), 0);
}
