// SPDX-License-Identifier: LGPL-2.1-or-later
#include "bsptet/input/self_intersection.h"

#include <algorithm>

#include "bsptet/input/triangle_intersection.h"

namespace bsptet {

namespace {

struct Box {
  double lo[3], hi[3];
};

Box box_of(const SurfaceMesh& s, Index t) {
  Box b;
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = b.hi[k] = s.xyz[3 * s.tri[3 * t] + k];
    for (int c = 1; c < 3; ++c) {
      const double v = s.xyz[3 * s.tri[3 * t + c] + k];
      b.lo[k] = std::min(b.lo[k], v);
      b.hi[k] = std::max(b.hi[k], v);
    }
  }
  return b;
}

IndexedTriangle indexed(const SurfaceMesh& s, Index t) {
  IndexedTriangle r;
  for (int c = 0; c < 3; ++c) {
    r.id[c] = s.tri[3 * t + c];
    r.p[c] = s.point(r.id[c]);
  }
  return r;
}

}  // namespace

namespace {

// A bounding-volume hierarchy over the triangles' boxes: median splits of the centroids along the
// longest axis, leaves of at most kLeafSize triangles. Ties are broken by triangle index.
constexpr std::size_t kLeafSize = 8;

struct Node {
  Box box;
  std::size_t begin, end;  // range in `order`
  int left = -1, right = -1;
};

class PairFinder {
 public:
  PairFinder(const SurfaceMesh& s, std::int64_t max_pairs) : s_(s), max_pairs_(max_pairs) {
    const Index nt = s.num_triangles();
    boxes_.resize(nt);
    order_.resize(nt);
    for (Index t = 0; t < nt; ++t) {
      boxes_[t] = box_of(s, t);
      order_[t] = t;
    }
    build(0, order_.size());
  }

  bool run(std::vector<std::array<Index, 2>>& pairs) {
    pairs_ = &pairs;
    visit(0, 0);
    return !full();
  }

 private:
  bool full() const { return static_cast<std::int64_t>(pairs_->size()) >= max_pairs_; }

  int build(std::size_t begin, std::size_t end) {
    Node n;
    n.begin = begin;
    n.end = end;
    n.box = boxes_[order_[begin]];
    for (std::size_t i = begin + 1; i < end; ++i)
      for (int k = 0; k < 3; ++k) {
        n.box.lo[k] = std::min(n.box.lo[k], boxes_[order_[i]].lo[k]);
        n.box.hi[k] = std::max(n.box.hi[k], boxes_[order_[i]].hi[k]);
      }
    const int id = static_cast<int>(nodes_.size());
    nodes_.push_back(n);
    if (end - begin <= kLeafSize) return id;
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (n.box.hi[k] - n.box.lo[k] > n.box.hi[axis] - n.box.lo[axis]) axis = k;
    const std::size_t mid = begin + (end - begin) / 2;
    // Centroid along `axis` (times 2, no division needed for the ordering), then index.
    auto key = [&](Index t) { return boxes_[t].lo[axis] + boxes_[t].hi[axis]; };
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](Index a, Index b) {
      const double ka = key(a), kb = key(b);
      return ka < kb || (ka == kb && a < b);
    });
    const int l = build(begin, mid), r = build(mid, end);
    nodes_[id].left = l;
    nodes_[id].right = r;
    return id;
  }

  static bool overlap(const Box& a, const Box& b) {
    for (int k = 0; k < 3; ++k)
      if (a.hi[k] < b.lo[k] || b.hi[k] < a.lo[k]) return false;
    return true;
  }

  void test(Index a, Index b) {
    if (full() || !overlap(boxes_[a], boxes_[b])) return;
    if (triangles_intersect(indexed(s_, a), indexed(s_, b))) pairs_->push_back({std::min(a, b), std::max(a, b)});
  }

  void visit(int a, int b) {
    if (full()) return;
    const Node &na = nodes_[a], &nb = nodes_[b];
    if (a == b) {
      if (na.left < 0) {
        for (std::size_t i = na.begin; i < na.end; ++i)
          for (std::size_t j = i + 1; j < na.end; ++j) test(order_[i], order_[j]);
        return;
      }
      visit(na.left, na.left);
      visit(na.right, na.right);
      visit(na.left, na.right);
      return;
    }
    if (!overlap(na.box, nb.box)) return;
    if (na.left < 0 && nb.left < 0) {
      for (std::size_t i = na.begin; i < na.end; ++i)
        for (std::size_t j = nb.begin; j < nb.end; ++j) test(order_[i], order_[j]);
      return;
    }
    // Descend into the node with more triangles (a leaf is never split).
    if (nb.left < 0 || (na.left >= 0 && na.end - na.begin >= nb.end - nb.begin)) {
      visit(na.left, b);
      visit(na.right, b);
    } else {
      visit(a, nb.left);
      visit(a, nb.right);
    }
  }

  const SurfaceMesh& s_;
  std::int64_t max_pairs_;
  std::vector<Box> boxes_;
  std::vector<Index> order_;
  std::vector<Node> nodes_;
  std::vector<std::array<Index, 2>>* pairs_ = nullptr;
};

}  // namespace

std::vector<std::array<Index, 2>> find_self_intersections(const SurfaceMesh& s, std::int64_t max_pairs,
                                                          bool* complete) {
  std::vector<std::array<Index, 2>> pairs;
  if (complete) *complete = true;
  if (s.num_triangles() < 2) return pairs;
  PairFinder finder(s, std::max<std::int64_t>(1, max_pairs));
  const bool all = finder.run(pairs);
  if (complete) *complete = all;
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace bsptet
