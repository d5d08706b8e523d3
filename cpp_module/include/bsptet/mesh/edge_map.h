// SPDX-License-Identifier: LGPL-2.1-or-later
// Flat hash maps keyed by an edge (two vertex ids packed into 64 bits), for the BSP complex's edge
// records: one array of slots (open addressing, linear probing, deletion by backward shift), so an
// entry costs no allocation of its own. std::unordered_map spent a node (48 bytes) and a bucket
// pointer per edge, plus a heap array per face list: about a sixth of the BSP's peak memory.
//
// Contract: keys are any 64-bit value but kEmptyKey (edge_key below packs two 32-bit ids, lower
// first, and an edge's ends differ, so ~0 never occurs). Pointers into the map are invalidated by any
// insertion or erasure. Iteration (for_each) visits the slots in array order: the same sequence
// of operations gives the same order (deterministic output).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "bsptet/mesh/types.h"

namespace bsptet {

/// The key of the undirected edge (u, w), u != w: the lower id in the high 32 bits.
inline std::uint64_t edge_key(Index u, Index w) {
  if (u > w) std::swap(u, w);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(u)) << 32) | static_cast<std::uint32_t>(w);
}

template <class V>
class EdgeMap {
 public:
  static constexpr std::uint64_t kEmptyKey = ~std::uint64_t{0};

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  /// Room for n entries without growing (the table grows by doubling at 3/4 load).
  void reserve(std::size_t n) {
    std::size_t cap = 16;
    while (cap * 3 < n * 4) cap *= 2;
    if (cap > slots_.size()) rehash(cap);
  }

  V* find(std::uint64_t key) {
    const std::size_t i = slot_of(key);
    return i == kNone ? nullptr : &slots_[i].value;
  }
  const V* find(std::uint64_t key) const {
    const std::size_t i = slot_of(key);
    return i == kNone ? nullptr : &slots_[i].value;
  }
  bool contains(std::uint64_t key) const { return slot_of(key) != kNone; }

  /// The value of key, inserted as V{} when absent.
  V& operator[](std::uint64_t key) {
    if ((size_ + 1) * 4 > slots_.size() * 3) rehash(slots_.empty() ? 16 : 2 * slots_.size());
    std::size_t i = home(key);
    for (; slots_[i].key != kEmptyKey; i = (i + 1) & mask_)
      if (slots_[i].key == key) return slots_[i].value;
    slots_[i].key = key;
    slots_[i].value = V{};
    ++size_;
    return slots_[i].value;
  }

  /// Removes key (if present): the entries after it in its probe run move back, so no tombstone
  /// is left and lookups stay short.
  void erase(std::uint64_t key) {
    std::size_t i = slot_of(key);
    if (i == kNone) return;
    for (std::size_t j = (i + 1) & mask_;; j = (j + 1) & mask_) {
      if (slots_[j].key == kEmptyKey) break;
      // Slot j may move to the hole i unless its home lies cyclically in (i, j].
      const std::size_t h = home(slots_[j].key);
      const bool stays = i <= j ? (i < h && h <= j) : (i < h || h <= j);
      if (stays) continue;
      slots_[i] = std::move(slots_[j]);
      i = j;
    }
    slots_[i].key = kEmptyKey;
    slots_[i].value = V{};
    --size_;
  }

  /// f(key, value) for every entry, in slot order.
  template <class F>
  void for_each(F&& f) const {
    for (const Slot& s : slots_)
      if (s.key != kEmptyKey) f(s.key, s.value);
  }

  /// Empties the map and gives its memory back.
  void release() {
    std::vector<Slot>().swap(slots_);
    size_ = 0;
    mask_ = 0;
  }

 private:
  struct Slot {
    std::uint64_t key = kEmptyKey;
    V value{};
  };
  static constexpr std::size_t kNone = ~std::size_t{0};
  /// The slot holding key, or kNone.
  std::size_t slot_of(std::uint64_t key) const {
    if (slots_.empty()) return kNone;
    for (std::size_t i = home(key);; i = (i + 1) & mask_) {
      if (slots_[i].key == key) return i;
      if (slots_[i].key == kEmptyKey) return kNone;
    }
  }
  std::size_t home(std::uint64_t key) const {
    // Fibonacci hashing: the high bits of key * 2^64 / phi spread consecutive ids.
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_) & mask_;
  }
  void rehash(std::size_t cap) {
    std::vector<Slot> old(cap);
    old.swap(slots_);
    mask_ = cap - 1;
    shift_ = 64;
    for (std::size_t c = cap; c > 1; c >>= 1) --shift_;
    size_ = 0;
    for (Slot& s : old)
      if (s.key != kEmptyKey) {
        std::size_t i = home(s.key);
        while (slots_[i].key != kEmptyKey) i = (i + 1) & mask_;
        slots_[i] = std::move(s);
        ++size_;
      }
  }

  std::vector<Slot> slots_;
  std::size_t size_ = 0;
  std::size_t mask_ = 0;
  int shift_ = 64;
};

/// The faces using one edge of the complex, in registration order: up to kInline ids in place,
/// more spill into a heap array (an edge of a split complex has 2 to about 8 faces).
class EdgeFaceList {
 public:
  static constexpr std::size_t kInline = 5;
  std::size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  Index operator[](std::size_t i) const { return n_ <= kInline ? in_[i] : (*more_)[i]; }
  void push_back(Index f) {
    if (n_ < kInline) {
      in_[n_++] = f;
      return;
    }
    if (n_ == kInline) more_ = std::make_unique<std::vector<Index>>(in_, in_ + kInline);
    more_->push_back(f);
    ++n_;
  }
  /// Removes every occurrence of f, keeping the others' order.
  void remove(Index f) {
    if (n_ <= kInline) {
      n_ = static_cast<std::uint32_t>(std::remove(in_, in_ + n_, f) - in_);
      return;
    }
    more_->erase(std::remove(more_->begin(), more_->end(), f), more_->end());
    n_ = static_cast<std::uint32_t>(more_->size());
    if (n_ <= kInline) {
      std::copy(more_->begin(), more_->end(), in_);
      more_.reset();
    }
  }
  std::vector<Index> to_vector() const {
    std::vector<Index> v(n_);
    for (std::size_t i = 0; i < n_; ++i) v[i] = (*this)[i];
    return v;
  }

 private:
  std::uint32_t n_ = 0;
  Index in_[kInline] = {};
  std::unique_ptr<std::vector<Index>> more_;  ///< all n_ ids when n_ > kInline
};

}  // namespace bsptet
