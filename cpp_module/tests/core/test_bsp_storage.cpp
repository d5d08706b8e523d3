// SPDX-License-Identifier: LGPL-2.1-or-later
// The BSP complex's compact storage: the flat edge maps (edge_map.h) against std::unordered_map
// on random operations, the face lists' spill to the heap, and the float face boxes' enclosure.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <unordered_map>
#include <vector>

#include "bsptet/core/bsp_complex.h"
#include "bsptet/mesh/edge_map.h"

using namespace bsptet;


// Inserts, overwrites and erases (most of them in long probe runs: few vertices, so many keys
// share home slots after the table fills) must leave the same contents as std::unordered_map;
// a lookup after every erase catches a backward shift that strands an entry.
TEST(EdgeMap, AgreesWithUnorderedMapUnderRandomOperations) {
  for (int round = 0; round < 4; ++round) {
    std::mt19937 rng(1234 + round);
    const Index nv = round < 2 ? 40 : 3000;
    std::uniform_int_distribution<Index> vert(0, nv - 1);
    EdgeMap<std::array<Index, 2>> map;
    if (round % 2) map.reserve(500);
    std::unordered_map<std::uint64_t, std::array<Index, 2>> ref;
    for (int op = 0; op < 20000; ++op) {
      Index u = vert(rng), w = vert(rng);
      if (u == w) continue;
      const std::uint64_t k = edge_key(u, w);
      const int what = static_cast<int>(rng() % 3);
      if (what < 2) {
        map[k] = {u, op};
        ref[k] = {u, op};
      } else {
        map.erase(k);
        ref.erase(k);
        ASSERT_EQ(map.find(k), nullptr);
      }
      ASSERT_EQ(map.size(), ref.size());
    }
    for (const auto& [k, v] : ref) {
      const auto* got = map.find(k);
      ASSERT_NE(got, nullptr);
      EXPECT_EQ(*got, v);
    }
    std::size_t seen = 0;
    map.for_each([&](std::uint64_t k, const std::array<Index, 2>& v) {
      ++seen;
      auto it = ref.find(k);
      ASSERT_NE(it, ref.end());
      EXPECT_EQ(it->second, v);
    });
    EXPECT_EQ(seen, ref.size());
    // Absent keys are not found, whatever their home slot.
    for (Index u = 0; u < 50; ++u)
      for (Index w = u + 1; w < 50; ++w)
        EXPECT_EQ(map.find(edge_key(u, w)) != nullptr, ref.count(edge_key(u, w)) == 1);
    map.release();
    EXPECT_EQ(map.size(), 0u);
    EXPECT_EQ(map.find(edge_key(1, 2)), nullptr);
  }
}

// The order of iteration depends only on the operations (the mesher's output must not depend on
// addresses): two maps fed the same sequence iterate alike.
TEST(EdgeMap, IterationOrderIsDeterministic) {
  EdgeMap<Index> a, b;
  std::mt19937 rng(7);
  for (int i = 0; i < 5000; ++i) {
    const std::uint64_t k = edge_key(static_cast<Index>(rng() % 900), static_cast<Index>(900 + rng() % 900));
    a[k] = i;
    b[k] = i;
    if (i % 5 == 0) {
      a.erase(k ^ 1);
      b.erase(k ^ 1);
    }
  }
  std::vector<std::uint64_t> ka, kb;
  a.for_each([&](std::uint64_t k, Index) { ka.push_back(k); });
  b.for_each([&](std::uint64_t k, Index) { kb.push_back(k); });
  EXPECT_EQ(ka, kb);
  EXPECT_EQ(ka.size(), a.size());
}

// Face lists keep registration order across the spill from the inline ids to the heap and back.
TEST(EdgeFaceList, KeepsOrderAcrossTheSpill) {
  EdgeMap<EdgeFaceList> map;
  const std::uint64_t k = edge_key(3, 9);
  std::vector<Index> ref;
  for (Index f = 0; f < 12; ++f) {
    map[k].push_back(f * 10);
    ref.push_back(f * 10);
    ASSERT_EQ(map[k].to_vector(), ref);
  }
  // Rehashes move the lists (inline and spilled) intact.
  for (Index u = 10; u < 2000; ++u) map[edge_key(u, u + 1)].push_back(u);
  EXPECT_EQ(map.find(k)->to_vector(), ref);
  for (Index f : {110, 0, 50, 70, 20, 30, 40, 60}) {
    map[k].remove(f);
    ref.erase(std::remove(ref.begin(), ref.end(), f), ref.end());
    ASSERT_EQ(map[k].to_vector(), ref);
    ASSERT_EQ(map[k].size(), ref.size());
  }
  EXPECT_EQ(map[k].size(), 4u);  // back inline
  for (Index f : {10, 80, 90, 100}) map[k].remove(f);
  EXPECT_TRUE(map[k].empty());
  for (Index u = 10; u < 2000; ++u) EXPECT_EQ(map.find(edge_key(u, u + 1))->to_vector(), std::vector<Index>{u});
}

// The float box encloses the double bounds (it may only be wider), at every scale; bounds past
// the floats' range give no box (a split then decides every vertex exactly).
TEST(FaceBox, FloatBoxEnclosesTheDoubleBounds) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> mant(-1.0, 1.0);
  std::uniform_int_distribution<int> expo(-140, 120);
  for (int i = 0; i < 200000; ++i) {
    std::array<double, 3> lo, hi;
    for (int k = 0; k < 3; ++k) {
      const double a = std::ldexp(mant(rng), expo(rng)), b = a + std::ldexp(std::fabs(mant(rng)), expo(rng));
      lo[k] = a;
      hi[k] = b;
    }
    const FaceBox box = FaceBox::enclosing(lo, hi);
    ASSERT_TRUE(box.ok());
    const auto iv = box.intervals();
    for (int k = 0; k < 3; ++k) {
      ASSERT_LE(iv[k].lo(), lo[k]);
      ASSERT_GE(iv[k].hi(), hi[k]);
      // Tight: the next float inward is no longer an enclosure.
      ASSERT_GT(static_cast<double>(std::nextafter(box.lo[k], std::numeric_limits<float>::infinity())), lo[k]);
      ASSERT_LT(static_cast<double>(std::nextafter(box.hi[k], -std::numeric_limits<float>::infinity())), hi[k]);
    }
  }
  // Exactly representable bounds stay exact; 0.1 does not, and is rounded outward.
  const FaceBox exact = FaceBox::enclosing({{0.5, -2.0, 0.0}}, {{1.0, 3.0, 0.25}});
  EXPECT_EQ(exact.lo[0], 0.5f);
  EXPECT_EQ(exact.hi[2], 0.25f);
  const FaceBox tenth = FaceBox::enclosing({{0.1, 0.1, 0.1}}, {{0.1, 0.1, 0.1}});
  EXPECT_LT(static_cast<double>(tenth.lo[0]), 0.1);
  EXPECT_GT(static_cast<double>(tenth.hi[0]), 0.1);
  EXPECT_FALSE(FaceBox::enclosing({{0, 0, 0}}, {{1e39, 1, 1}}).ok());
  EXPECT_FALSE(FaceBox::enclosing({{-1e300, 0, 0}}, {{1, 1, 1}}).ok());
  EXPECT_FALSE(FaceBox{}.ok());
  // Subnormal and tiny bounds: still enclosed (the float rounds to 0 or a subnormal, then steps).
  const FaceBox tiny = FaceBox::enclosing({{1e-60, -1e-60, 1e-45}}, {{2e-60, 1e-60, 2e-45}});
  ASSERT_TRUE(tiny.ok());
  EXPECT_LE(static_cast<double>(tiny.lo[0]), 1e-60);
  EXPECT_GE(static_cast<double>(tiny.hi[0]), 2e-60);
  EXPECT_LE(static_cast<double>(tiny.lo[1]), -1e-60);
  EXPECT_GE(static_cast<double>(tiny.hi[1]), 1e-60);
  EXPECT_LE(static_cast<double>(tiny.lo[2]), 1e-45);
  EXPECT_GE(static_cast<double>(tiny.hi[2]), 2e-45);
}
