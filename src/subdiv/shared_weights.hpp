// limn subdiv: stencil rows that share their weights (StencilTable::weight_offsets).
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

namespace limn::detail {

// Adds rows' weights to a table's weight pool, each distinct row once. Rows are equal when
// their floats are bit for bit equal, so sharing changes no point. A refined level has a few
// distinct rows (smooth face, edge and vertex rules per valence; creases add a few more), so
// the pool stays small and its hash slots stay in L1. O(row size) per row.
class SharedWeights {
 public:
  SharedWeights() : slots_(64) {}

  // Where row w[0, n) starts in `pool` (added if new). Every call passes the same pool.
  uint32_t add(std::vector<float>& pool, const float* w, uint32_t n) {
    // Rows come in runs of one rule (a level's face points, then its edge points, then its
    // vertex points): most equal the previous row, which costs one comparison.
    if (n == last_size_ && equal(pool.data() + last_at_, w, n)) return last_at_;
    return add_other(pool, w, n);
  }

 private:
  [[gnu::noinline]] uint32_t add_other(std::vector<float>& pool, const float* w, uint32_t n) {
    // Then a row seen lately with the same size and first weight (end caps cycle through a
    // few rows of each kind, which the last row alone misses).
    uint32_t first = 0;
    if (n) std::memcpy(&first, w, sizeof first);
    Recent& r = recent_[((first ^ n) * 0x9E3779B1u) >> (32 - kRecentBits)];
    if (r.size == n && equal(pool.data() + r.at, w, n)) return remember(r.at, n);
    const uint64_t h = hash(w, n);
    const uint32_t key = uint32_t(h >> 32) | 1u;  // 0 marks an empty slot
    const size_t mask = slots_.size() - 1;
    for (size_t s = size_t(h) & mask;; s = (s + 1) & mask) {
      Slot& slot = slots_[s];
      if (slot.key == 0) {
        slot = {key, n, uint32_t(pool.size())};
        pool.insert(pool.end(), w, w + n);
        if (2 * ++used_ > slots_.size()) grow(pool);
        r = {uint32_t(pool.size() - n), n};
        return remember(r.at, n);
      }
      if (slot.key == key && slot.size == n && equal(pool.data() + slot.at, w, n)) {
        r = {slot.at, n};
        return remember(slot.at, n);
      }
    }
  }

  struct Slot {
    uint32_t key = 0, size = 0, at = 0;
  };
  uint32_t remember(uint32_t at, uint32_t n) {
    last_at_ = at, last_size_ = n;
    return at;
  }
  // Bit for bit, so -0.0 and 0.0 differ (and rows with NaNs can still be shared).
  static bool equal(const float* a, const float* b, uint32_t n) {
    uint32_t i = 0;
    for (; i + 2 <= n; i += 2) {  // two floats a step
      uint64_t x, y;
      std::memcpy(&x, a + i, sizeof x);
      std::memcpy(&y, b + i, sizeof y);
      if (x != y) return false;
    }
    uint32_t x = 0, y = 0;
    if (i < n) std::memcpy(&x, a + i, sizeof x), std::memcpy(&y, b + i, sizeof y);
    return x == y;
  }
  static uint64_t hash(const float* w, uint32_t n) {
    uint64_t h = 0x9E3779B97F4A7C15ull * (n + 1);
    for (uint32_t i = 0; i < n; ++i) {
      uint32_t bits;
      std::memcpy(&bits, w + i, sizeof bits);
      h = (h ^ bits) * 0xff51afd7ed558ccdull;
    }
    return h ^ (h >> 29);
  }
  void grow(const std::vector<float>& pool) {
    std::vector<Slot> old(2 * slots_.size());
    old.swap(slots_);
    const size_t mask = slots_.size() - 1;
    for (const Slot& o : old) {
      if (o.key == 0) continue;
      size_t s = size_t(hash(pool.data() + o.at, o.size)) & mask;
      while (slots_[s].key != 0) s = (s + 1) & mask;
      slots_[s] = o;
    }
  }

  std::vector<Slot> slots_;
  size_t used_ = 0;
  uint32_t last_at_ = 0, last_size_ = UINT32_MAX;  // the previous row
  struct Recent {
    uint32_t at = 0, size = UINT32_MAX;
  };
  static constexpr int kRecentBits = 5;
  Recent recent_[1 << kRecentBits];  // by size and first weight: the latest such row
};

}  // namespace limn::detail
