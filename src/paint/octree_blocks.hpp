// The pool's block codec and the one place that writes the pool (allocation, free lists and the
// undo journal). Internal header of the paint layer; the layout is documented in
// include/limn/paint/texture.hpp.
#pragma once

#include <bit>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "limn/paint/texture.hpp"

namespace limn::octree {

// The pool's words, as the layout in include/limn/paint/texture.hpp describes them.
/// Cell kinds inside a general node.
enum class CellKind : uint8_t { empty, leaf, general, brick };

/// Bits of a general node's info word.
inline constexpr uint32_t occupied(uint32_t info) {
  return info & 255u;
}
inline constexpr uint32_t leaves(uint32_t info) {
  return (info >> 8) & 255u;
}
inline constexpr uint32_t bricks(uint32_t info) {
  return (info >> 16) & 255u;
}
inline constexpr uint32_t doubles(uint32_t info) {
  return (info >> 24) & 255u;
}
inline constexpr uint32_t generals(uint32_t info) {
  return occupied(info) & ~leaves(info) & ~bricks(info);
}
inline constexpr uint32_t make_info(uint32_t occ, uint32_t leaf, uint32_t brick, uint32_t dbl) {
  return (occ & 255u) | (leaf & 255u) << 8 | (brick & 255u) << 16 | (dbl & 255u) << 24;
}
inline constexpr uint32_t kBrickDoubleFlag = 0x80000000u;
inline constexpr uint32_t kMaxPoolWords = 0x7ffffffeu;  ///< brick words keep 31 bits of address
/// Pools of at least this many bytes are 2 MiB-aligned and advised as huge pages.
inline constexpr std::size_t kHugeBytes = std::size_t(2) << 20;

}  // namespace limn::octree

namespace limn::detail {

using octree::CellKind;

inline int popc(uint32_t x) {
  return std::popcount(x);
}
inline int popc64(uint64_t x) {
  return std::popcount(x);
}

/// rgba8_from_float of (r, g, b, a), inline for the callers that make one per texel (a dab's
/// blends): the channels built in registers instead of read back from just-stored floats.
inline Rgba8 rgba8_from_floats(float r, float g, float b, float a) {
  // The four channels at once: each clamped to [0, 1] (non-finite values give 0), then
  // std::lround(255 v) without the library call: u - trunc(u) is exact for u in [0, 255], so
  // ties go up, away from zero, as lround's do.
  using F4 = float __attribute__((vector_size(16)));
  using I4 = int32_t __attribute__((vector_size(16)));
  const F4 v = {r, g, b, a};
  const F4 zero = {0, 0, 0, 0}, one = {1, 1, 1, 1}, half = {0.5f, 0.5f, 0.5f, 0.5f};
  const float mx = std::numeric_limits<float>::max();
  const F4 big = {mx, mx, mx, mx};
  const I4 finite = (F4)((I4)v & 0x7fffffff) <= big;  // false for infinities and NaNs
  F4 c = v > zero ? v : zero;                         // NaN lanes are masked below
  c = c < one ? c : one;
  c = (F4)((I4)c & finite);
  const F4 u = c * 255.0f;
  const I4 q = __builtin_convertvector(u, I4);
  const I4 k = q - ((u - __builtin_convertvector(q, F4)) >= half);  // true lanes are -1
  return pack_rgba8(uint32_t(k[0]), uint32_t(k[1]), uint32_t(k[2]), uint32_t(k[3]));
}

/// A leaf cell's content: tag, one or two samples.
struct LeafCell {
  uint8_t tag = 0;
  bool dbl = false;
  Rgba8 s[2] = {0, 0};
};

/// A general node, decoded.
struct GeneralNode {
  CellKind kind[8] = {};
  uint32_t ptr[8] = {};   ///< general: child block; brick: brick word
  uint32_t info[8] = {};  ///< general: child info
  LeafCell leaf[8];
  Rgba8 avg = 0;
};

/// A brick, decoded into dense per-cell arrays (cell m = 8 c1 + c2).
struct Brick {
  uint64_t mask = 0, dbl = 0;
  Rgba8 avg = 0;
  LeafCell cell[64];
};

/// Words of a general node's block (even).
inline uint32_t general_block_words(uint32_t info) {
  const uint32_t g = octree::generals(info), l = octree::leaves(info);
  const uint32_t n = 2 * uint32_t(popc(g)) + uint32_t(popc(octree::bricks(info))) + 1 +
                     uint32_t(popc(l)) + uint32_t(popc(octree::doubles(info))) +
                     (uint32_t(popc(l)) + 7) / 8;
  return (n + 1) & ~1u;
}

/// Words of a brick's block (any parity: bricks need no alignment, so they carry no pad).
inline uint32_t brick_block_words(uint64_t mask, uint64_t dbl) {
  const uint32_t cells = uint32_t(popc64(mask));
  return 2 + (dbl ? 2 : 0) + 1 + cells + uint32_t(popc64(dbl)) + (cells + 7) / 8;
}

/// Free-list class of a block: general blocks (even size, even address) and bricks (any) are
/// kept apart, so a general node is never given an odd address.
inline uint32_t block_class(uint32_t words, bool brick) {
  return 2 * words + (brick ? 1 : 0);
}

/// Decodes the general node (ptr, info). Precondition: the block is inside `pool`.
GeneralNode decode_general(std::span<const uint32_t> pool, uint32_t ptr, uint32_t info);
/// Encodes a general node; returns the info word and fills `out` with the block.
uint32_t encode_general(const GeneralNode& n, std::vector<uint32_t>& out);
/// Decodes the brick named by brick word `word`.
Brick decode_brick(std::span<const uint32_t> pool, uint32_t word);
/// Encodes a brick into `out`; returns the double flag to or into the brick word.
uint32_t encode_brick(const Brick& b, std::vector<uint32_t>& out);

/// std::clamp(std::lround(v), 0, 255) for v >= 0 (not NaN), without the library call (means are
/// taken per brick and per node on every dab): v - r is exact below 2^52, so ties go up, away
/// from zero, as lround's do.
inline uint32_t round_byte(double v) {
  if (!(v < 255.0)) return 255;
  const uint32_t r = uint32_t(v);
  return r + uint32_t(v - double(r) >= 0.5);
}

/// Premultiplied mean of colours (equal weights), back to straight RGBA8. 0 for none.
class ColorMean {
 public:
  // Integer sums (exact, as the double sums they replace were: every term is an integer below
  // 2^16), turned to doubles only in mean().
  void add(Rgba8 c) {
    const uint32_t a = channel(c, 3);
    r_ += channel(c, 0) * a, g_ += channel(c, 1) * a, b_ += channel(c, 2) * a, a_ += a;
    ++n_;
  }
  Rgba8 mean() const;

 private:
  uint64_t r_ = 0, g_ = 0, b_ = 0, a_ = 0, n_ = 0;
};

/// The mip average of a leaf cell (both sides of a double cell).
inline void add_leaf(ColorMean& m, const LeafCell& c) {
  if (!c.dbl) {
    m.add(c.s[0]);
    return;
  }
  ColorMean two;
  two.add(c.s[0]);
  two.add(c.s[1]);
  m.add(two.mean());
}

/// A brick's average: the mean of its inner nodes' averages, each the mean of its leaf cells,
/// the same rule a general node follows (occupied cells weighted equally at every level), so
/// a mip value does not depend on whether a region is stored as a brick or as general nodes.
inline Rgba8 brick_average(const Brick& b) {
  ColorMean outer;
  for (int c1 = 0; c1 < 8; ++c1) {
    if (!(b.mask >> (8 * c1) & 255u)) continue;
    ColorMean inner;
    for (int c2 = 0; c2 < 8; ++c2)
      if (b.mask >> (8 * c1 + c2) & 1) add_leaf(inner, b.cell[8 * c1 + c2]);
    outer.add(inner.mean());
  }
  return outer.mean();
}

/// Every write to a texture's pool goes through here, so the journal sees it.
class OctreeEditor {
 public:
  explicit OctreeEditor(OctreeTexture& t) : t_(t) {}

  std::span<const uint32_t> pool() const { return t_.words(); }
  uint32_t word(size_t i) const { return t_.pool_[i]; }
  Rgba8 background() const { return t_.background_; }
  const OctreeTexture& texture() const { return t_; }

  /// Writes one word (journaled when it changes).
  void set(uint32_t i, uint32_t v);
  /// A block of `n` words for a brick (any address) or a general node (n even, even address),
  /// from the free list of its class or the end of the pool. Throws std::length_error past
  /// kMaxPoolWords.
  uint32_t alloc(uint32_t n, bool brick);
  /// Returns a block to its free list.
  void release(uint32_t ptr, uint32_t n, bool brick);
  /// Writes `words` into a block of the same size: only the words that differ.
  void write_block(uint32_t ptr, std::span<const uint32_t> words);
  /// Replaces the block (ptr, old_n) by `words`: in place when the size is the same, else a new
  /// block (the old one is released). Returns the block's address.
  uint32_t replace_block(uint32_t ptr, uint32_t old_n, std::span<const uint32_t> words, bool brick);

  // Journal replay (undo.cpp).
  static void undo_ops(OctreeTexture& t, std::span<const OctreeTexture::JournalOp> ops);
  static void redo_ops(OctreeTexture& t, std::span<const OctreeTexture::JournalOp> ops);
  static bool& recording(OctreeTexture& t) { return t.recording_; }
  static std::vector<OctreeTexture::JournalOp>& journal(OctreeTexture& t) { return t.journal_; }
  /// The pool's storage, for a reader that fills it whole (file.cpp).
  static OctreeTexture::Words& pool(OctreeTexture& t) { return t.pool_; }
  static std::vector<std::vector<uint32_t>>& free_lists(OctreeTexture& t) { return t.free_; }
  static const std::vector<std::vector<uint32_t>>& free_lists(const OctreeTexture& t) {
    return t.free_;
  }
  static void set_cube(OctreeTexture& t, const float origin[3], float size, Rgba8 background) {
    for (int k = 0; k < 3; ++k) t.origin_[k] = origin[k];
    t.size_ = size;
    t.background_ = background;
  }

  enum Op : uint32_t { kSet = 0, kGrow = 1, kPush = 2, kPop = 3 };

 private:
  void log(uint32_t kind, uint32_t a, uint32_t b, uint32_t c) {
    if (t_.recording_) t_.journal_.push_back({kind, a, b, c});
  }
  OctreeTexture& t_;
};

}  // namespace limn::detail
