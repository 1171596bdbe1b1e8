// The octree texture's pool: block codec, allocation with free lists, the journal hook, stats,
// the structural check and sample enumeration.
#include <sys/mman.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>

#include "limn/paint/texture.hpp"
#include "octree_blocks.hpp"

namespace limn {

using namespace detail;

namespace {

// float(i) / 255, as the division gives it.
constexpr std::array<float, 256> kByteToUnit = [] {
  std::array<float, 256> t{};
  for (int i = 0; i < 256; ++i) t[size_t(i)] = float(i) / 255.0f;
  return t;
}();

}  // namespace

namespace {

// Past kHugeBytes, 2 MiB-aligned storage advised as huge pages; smaller blocks from operator new.
// Throws std::bad_alloc.
uint32_t* pool_allocate(std::size_t words) {
  const std::size_t bytes = words * sizeof(uint32_t);
  if (bytes < octree::kHugeBytes) return static_cast<uint32_t*>(::operator new(bytes));
  const std::size_t size =
      (bytes + octree::kHugeBytes - 1) / octree::kHugeBytes * octree::kHugeBytes;
  void* p = std::aligned_alloc(octree::kHugeBytes, size);
  if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  madvise(p, size, MADV_HUGEPAGE);  // advice only: where refused, 4 KiB pages as before
#endif
  return static_cast<uint32_t*>(p);
}

void pool_deallocate(uint32_t* p, std::size_t words) noexcept {
  if (!p) return;
  if (words * sizeof(uint32_t) < octree::kHugeBytes)
    ::operator delete(p);
  else
    std::free(p);
}

}  // namespace

OctreeTexture::Words::Words() : data_(pool_allocate(2)), size_(2), capacity_(2) {
  data_[0] = data_[1] = 0;
}

// A copy keeps the original's room, so it grows (and costs) as the original would from here.
OctreeTexture::Words::Words(const Words& o)
    : data_(o.capacity_ ? pool_allocate(o.capacity_) : nullptr),
      size_(o.size_),
      capacity_(o.capacity_) {
  std::copy_n(o.data_, o.size_, data_);
}

OctreeTexture::Words::Words(Words&& o) noexcept
    : data_(std::exchange(o.data_, nullptr)),
      size_(std::exchange(o.size_, 0)),
      capacity_(std::exchange(o.capacity_, 0)) {}

OctreeTexture::Words& OctreeTexture::Words::operator=(const Words& o) {
  if (this != &o) *this = Words(o);
  return *this;
}

OctreeTexture::Words& OctreeTexture::Words::operator=(Words&& o) noexcept {
  if (this != &o) {
    pool_deallocate(data_, capacity_);
    data_ = std::exchange(o.data_, nullptr);
    size_ = std::exchange(o.size_, 0);
    capacity_ = std::exchange(o.capacity_, 0);
  }
  return *this;
}

OctreeTexture::Words::~Words() {
  pool_deallocate(data_, capacity_);
}

void OctreeTexture::Words::resize(size_t n, uint32_t v) {
  if (n > capacity_) {
    // Doubling, as std::vector grows.
    const size_t cap = std::max(2 * size_, n);
    uint32_t* p = pool_allocate(cap);
    std::copy_n(data_, size_, p);
    pool_deallocate(data_, capacity_);
    data_ = p, capacity_ = cap;
  }
  if (n > size_) std::fill(data_ + size_, data_ + n, v);
  size_ = n;
}

Rgba8 rgba8_from_float(const float rgba[4]) {
  return rgba8_from_floats(rgba[0], rgba[1], rgba[2], rgba[3]);
}

void rgba8_to_float(Rgba8 c, float rgba[4]) {
  for (int k = 0; k < 4; ++k) rgba[k] = kByteToUnit[channel(c, k)];
}

namespace octree {

namespace {
constexpr float kInvSqrt3 = 0.57735026918962576f;
}

std::array<float, 3> tag_direction(int tag) {
  if (tag >= 1 && tag <= 6) {
    std::array<float, 3> d{0, 0, 0};
    d[size_t((tag - 1) / 2)] = (tag - 1) % 2 ? -1.0f : 1.0f;
    return d;
  }
  if (tag >= 7 && tag <= 14) {
    const int i = tag - 7;  // bit 2: x negative, bit 1: y, bit 0: z
    return {i & 4 ? -kInvSqrt3 : kInvSqrt3, i & 2 ? -kInvSqrt3 : kInvSqrt3,
            i & 1 ? -kInvSqrt3 : kInvSqrt3};
  }
  return {0, 0, 0};
}

int tag_for_normal(const float n[3]) {
  if (!(std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]))) return 0;
  if (n[0] == 0 && n[1] == 0 && n[2] == 0) return 0;
  int best = 0;
  float best_dot = -INFINITY;
  const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int t = 1; t <= kTagCount; ++t) {
    const auto d = tag_direction(t);
    const float v = (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / len;
    if (v > best_dot) best_dot = v, best = t;
  }
  return best;
}

int side_for_normal(int tag, const float* n) {
  if (tag == 0 || !n) return 0;
  const auto d = tag_direction(tag);
  return d[0] * n[0] + d[1] * n[1] + d[2] * n[2] >= 0 ? 0 : 1;
}

}  // namespace octree

namespace detail {

Rgba8 ColorMean::mean() const {
  if (n_ == 0 || a_ == 0) return 0;
  const double a = double(a_);
  return pack_rgba8(round_byte(double(r_) / a), round_byte(double(g_) / a),
                    round_byte(double(b_) / a), round_byte(a / double(n_)));
}

GeneralNode decode_general(std::span<const uint32_t> pool, uint32_t ptr, uint32_t info) {
  GeneralNode n;
  const uint32_t g = octree::generals(info), b = octree::bricks(info), l = octree::leaves(info),
                 d = octree::doubles(info);
  size_t pos = ptr;
  for (int c = 0; c < 8; ++c)
    if (g >> c & 1) {
      n.kind[c] = CellKind::general;
      n.ptr[c] = pool[pos], n.info[c] = pool[pos + 1];
      pos += 2;
    }
  for (int c = 0; c < 8; ++c)
    if (b >> c & 1) n.kind[c] = CellKind::brick, n.ptr[c] = pool[pos++];
  n.avg = pool[pos++];
  int k = 0;
  for (int c = 0; c < 8; ++c)
    if (l >> c & 1) {
      n.leaf[c].tag = uint8_t(pool[pos + size_t(k / 8)] >> (4 * (k % 8)) & 15u);
      ++k;
    }
  pos += size_t(k + 7) / 8;
  for (int c = 0; c < 8; ++c)
    if (l >> c & 1) {
      n.kind[c] = CellKind::leaf;
      n.leaf[c].s[0] = pool[pos++];
      n.leaf[c].dbl = d >> c & 1;
      if (n.leaf[c].dbl) n.leaf[c].s[1] = pool[pos++];
    }
  return n;
}

uint32_t encode_general(const GeneralNode& n, std::vector<uint32_t>& out) {
  uint32_t occ = 0, leaf = 0, brick = 0, dbl = 0;
  for (int c = 0; c < 8; ++c) {
    if (n.kind[c] == CellKind::empty) continue;
    occ |= 1u << c;
    if (n.kind[c] == CellKind::leaf) leaf |= 1u << c, dbl |= uint32_t(n.leaf[c].dbl) << c;
    if (n.kind[c] == CellKind::brick) brick |= 1u << c;
  }
  const uint32_t info = octree::make_info(occ, leaf, brick, dbl);
  out.clear();
  for (int c = 0; c < 8; ++c)
    if (n.kind[c] == CellKind::general) out.push_back(n.ptr[c]), out.push_back(n.info[c]);
  for (int c = 0; c < 8; ++c)
    if (n.kind[c] == CellKind::brick) out.push_back(n.ptr[c]);
  out.push_back(n.avg);
  const size_t tag0 = out.size();
  int k = 0;
  for (int c = 0; c < 8; ++c)
    if (n.kind[c] == CellKind::leaf) {
      if (k % 8 == 0) out.push_back(0);
      out[tag0 + size_t(k / 8)] |= uint32_t(n.leaf[c].tag & 15u) << (4 * (k % 8));
      ++k;
    }
  for (int c = 0; c < 8; ++c)
    if (n.kind[c] == CellKind::leaf) {
      out.push_back(n.leaf[c].s[0]);
      if (n.leaf[c].dbl) out.push_back(n.leaf[c].s[1]);
    }
  if (out.size() % 2) out.push_back(0);
  return info;
}

Brick decode_brick(std::span<const uint32_t> pool, uint32_t word) {
  Brick b;
  size_t pos = word & ~octree::kBrickDoubleFlag;
  b.mask = uint64_t(pool[pos]) | uint64_t(pool[pos + 1]) << 32;
  pos += 2;
  if (word & octree::kBrickDoubleFlag) {
    b.dbl = uint64_t(pool[pos]) | uint64_t(pool[pos + 1]) << 32;
    pos += 2;
  }
  b.avg = pool[pos++];
  // Occupied cells in order, by their bits.
  int k = 0;
  for (uint64_t bits = b.mask; bits; bits &= bits - 1, ++k)
    b.cell[std::countr_zero(bits)].tag = uint8_t(pool[pos + size_t(k / 8)] >> (4 * (k % 8)) & 15u);
  pos += size_t(k + 7) / 8;
  for (uint64_t bits = b.mask; bits; bits &= bits - 1) {
    const int m = std::countr_zero(bits);
    b.cell[m].s[0] = pool[pos++];
    b.cell[m].dbl = b.dbl >> m & 1;
    if (b.cell[m].dbl) b.cell[m].s[1] = pool[pos++];
  }
  return b;
}

uint32_t encode_brick(const Brick& b, std::vector<uint32_t>& out) {
  out.clear();
  uint64_t dbl = 0;
  for (uint64_t bits = b.mask; bits; bits &= bits - 1) {
    const int m = std::countr_zero(bits);
    if (b.cell[m].dbl) dbl |= uint64_t(1) << m;
  }
  out.push_back(uint32_t(b.mask));
  out.push_back(uint32_t(b.mask >> 32));
  if (dbl) out.push_back(uint32_t(dbl)), out.push_back(uint32_t(dbl >> 32));
  out.push_back(b.avg);
  const size_t tag0 = out.size();
  out.resize(tag0 + (size_t(std::popcount(b.mask)) + 7) / 8, 0);
  int k = 0;
  for (uint64_t bits = b.mask; bits; bits &= bits - 1, ++k)
    out[tag0 + size_t(k / 8)] |= uint32_t(b.cell[std::countr_zero(bits)].tag & 15u)
                                 << (4 * (k % 8));
  for (uint64_t bits = b.mask; bits; bits &= bits - 1) {
    const LeafCell& c = b.cell[std::countr_zero(bits)];
    out.push_back(c.s[0]);
    if (c.dbl) out.push_back(c.s[1]);
  }
  return dbl ? octree::kBrickDoubleFlag : 0;
}

void OctreeEditor::set(uint32_t i, uint32_t v) {
  uint32_t& w = t_.pool_[i];
  if (w == v) return;
  log(kSet, i, w, v);
  w = v;
}

uint32_t OctreeEditor::alloc(uint32_t n, bool brick) {
  const uint32_t cls = block_class(n, brick);
  if (cls < t_.free_.size() && !t_.free_[cls].empty()) {
    const uint32_t p = t_.free_[cls].back();
    t_.free_[cls].pop_back();
    log(kPop, cls, p, 0);
    return p;
  }
  size_t old = t_.pool_.size();
  if (old + n + 1 > octree::kMaxPoolWords)
    throw std::length_error("octree texture: the pool would exceed 2^31 words (8 GiB)");
  if (!brick && old % 2) {
    // A general node needs an even address: the odd word left over becomes a free one-word
    // block (no block is that small, so it stays free, but it is accounted for).
    log(kGrow, uint32_t(old), uint32_t(old + 1), 0);
    t_.pool_.resize(old + 1, 0);
    release(uint32_t(old), 1, true);
    ++old;
  }
  log(kGrow, uint32_t(old), uint32_t(old + n), 0);
  t_.pool_.resize(old + n, 0);
  return uint32_t(old);
}

void OctreeEditor::release(uint32_t ptr, uint32_t n, bool brick) {
  const uint32_t cls = block_class(n, brick);
  if (t_.free_.size() <= cls) t_.free_.resize(cls + 1);
  t_.free_[cls].push_back(ptr);
  log(kPush, cls, ptr, 0);
}

void OctreeEditor::write_block(uint32_t ptr, std::span<const uint32_t> words) {
  // set() word by word, written out: a dab's replay writes every block it made through here.
  uint32_t* w = t_.pool_.data() + ptr;
  if (!t_.recording_) {
    std::copy(words.begin(), words.end(), w);
    return;
  }
  for (size_t i = 0; i < words.size(); ++i)
    if (w[i] != words[i]) log(kSet, ptr + uint32_t(i), w[i], words[i]), w[i] = words[i];
}

uint32_t OctreeEditor::replace_block(uint32_t ptr, uint32_t old_n, std::span<const uint32_t> words,
                                     bool brick) {
  const uint32_t n = uint32_t(words.size());
  if (ptr != 0 && n == old_n) {
    write_block(ptr, words);
    return ptr;
  }
  const uint32_t p = alloc(n, brick);
  write_block(p, words);
  if (ptr != 0 && old_n) release(ptr, old_n, brick);
  return p;
}

void OctreeEditor::undo_ops(OctreeTexture& t, std::span<const OctreeTexture::JournalOp> ops) {
  for (size_t i = ops.size(); i-- > 0;) {
    const auto& o = ops[i];
    switch (o.kind) {
      case kSet:
        t.pool_[o.a] = o.b;
        break;
      case kGrow:
        t.pool_.resize(o.a);
        break;
      case kPush:
        t.free_[o.a].pop_back();
        break;
      case kPop:
        if (t.free_.size() <= o.a) t.free_.resize(o.a + 1);
        t.free_[o.a].push_back(o.b);
        break;
    }
  }
}

void OctreeEditor::redo_ops(OctreeTexture& t, std::span<const OctreeTexture::JournalOp> ops) {
  for (const auto& o : ops) {
    switch (o.kind) {
      case kSet:
        t.pool_[o.a] = o.c;
        break;
      case kGrow:
        t.pool_.resize(o.b, 0);
        break;
      case kPush:
        if (t.free_.size() <= o.a) t.free_.resize(o.a + 1);
        t.free_[o.a].push_back(o.b);
        break;
      case kPop:
        t.free_[o.a].pop_back();
        break;
    }
  }
}

}  // namespace detail

OctreeTexture OctreeTexture::empty(const float origin[3], float size, Rgba8 background) {
  OctreeTexture t;
  OctreeEditor::set_cube(t, origin, size, background);
  return t;
}

std::vector<std::pair<uint32_t, uint32_t>> OctreeTexture::free_blocks() const {
  std::vector<std::pair<uint32_t, uint32_t>> v;
  for (size_t k = 0; k < free_.size(); ++k)
    for (uint32_t p : free_[k]) v.push_back({uint32_t(k), p});
  std::sort(v.begin(), v.end());
  return v;
}

void OctreeTexture::to_unit(const float p[3], double u[3]) const {
  const double scale = 65536.0 / double(size_);
  for (int k = 0; k < 3; ++k) u[k] = (double(p[k]) - double(origin_[k])) * scale / 65536.0;
}

bool OctreeTexture::operator==(const OctreeTexture& o) const {
  auto trimmed = [](const std::vector<std::vector<uint32_t>>& f) {
    size_t n = f.size();
    while (n && f[n - 1].empty()) --n;
    return std::vector<std::vector<uint32_t>>(f.begin(), f.begin() + std::ptrdiff_t(n));
  };
  return std::equal(origin_, origin_ + 3, o.origin_) && size_ == o.size_ &&
         background_ == o.background_ && std::ranges::equal(words(), o.words()) &&
         trimmed(free_) == trimmed(o.free_);
}

namespace {

struct SampleWalker {
  std::span<const uint32_t> pool;
  void* ctx;
  void (*f)(void*, const OctreeSample&);

  void leaf(int level, uint32_t x, uint32_t y, uint32_t z, const LeafCell& c, size_t word) {
    OctreeSample s;
    s.level = level, s.x = x, s.y = y, s.z = z, s.tag = c.tag;
    s.side = 0, s.color = c.s[0], s.word = word;
    f(ctx, s);
    if (c.dbl) {
      s.side = 1, s.color = c.s[1], s.word = word + 1;
      f(ctx, s);
    }
  }

  void brick(uint32_t word, int level, uint32_t x, uint32_t y, uint32_t z) {
    const Brick b = decode_brick(pool, word);
    size_t pos = (word & ~octree::kBrickDoubleFlag) + 2 + (b.dbl ? 2 : 0) + 1 +
                 (size_t(popc64(b.mask)) + 7) / 8;
    for (int m = 0; m < 64; ++m) {
      if (!(b.mask >> m & 1)) continue;
      const int c1 = m >> 3, c2 = m & 7;
      const uint32_t cx = (x << 2) | uint32_t(c1 & 1) << 1 | uint32_t(c2 & 1);
      const uint32_t cy = (y << 2) | uint32_t(c1 >> 1 & 1) << 1 | uint32_t(c2 >> 1 & 1);
      const uint32_t cz = (z << 2) | uint32_t(c1 >> 2 & 1) << 1 | uint32_t(c2 >> 2 & 1);
      leaf(level + 2, cx, cy, cz, b.cell[m], pos);
      pos += b.cell[m].dbl ? 2 : 1;
    }
  }

  void general(uint32_t ptr, uint32_t info, int level, uint32_t x, uint32_t y, uint32_t z) {
    if (octree::occupied(info) == 0) return;
    const GeneralNode n = decode_general(pool, ptr, info);
    size_t sample = ptr + 2 * size_t(popc(octree::generals(info))) +
                    size_t(popc(octree::bricks(info))) + 1 +
                    (size_t(popc(octree::leaves(info))) + 7) / 8;
    for (int c = 0; c < 8; ++c) {
      const uint32_t cx = 2 * x + uint32_t(c & 1), cy = 2 * y + uint32_t(c >> 1 & 1),
                     cz = 2 * z + uint32_t(c >> 2 & 1);
      switch (n.kind[c]) {
        case CellKind::general:
          general(n.ptr[c], n.info[c], level + 1, cx, cy, cz);
          break;
        case CellKind::brick:
          brick(n.ptr[c], level + 1, cx, cy, cz);
          break;
        case CellKind::leaf:
          leaf(level + 1, cx, cy, cz, n.leaf[c], sample);
          sample += n.leaf[c].dbl ? 2 : 1;
          break;
        case CellKind::empty:
          break;
      }
    }
  }
};

}  // namespace

void OctreeTexture::visit_samples(void* ctx, void (*f)(void*, const OctreeSample&)) const {
  SampleWalker w{pool_, ctx, f};
  w.general(pool_[0], pool_[1], 0, 0, 0, 0);
}

OctreeTextureStats OctreeTexture::stats() const {
  OctreeTextureStats s;
  struct Walk {
    std::span<const uint32_t> pool;
    OctreeTextureStats& s;
    void brick(uint32_t word) {
      ++s.bricks;
      const Brick b = decode_brick(pool, word);
      s.nodes += 1;
      for (int k = 0; k < 8; ++k) s.nodes += (b.mask >> (8 * k) & 255u) ? 1 : 0;
    }
    void general(uint32_t ptr, uint32_t info) {
      if (octree::occupied(info) == 0) return;
      ++s.general_nodes, ++s.nodes;
      const GeneralNode n = decode_general(pool, ptr, info);
      for (int c = 0; c < 8; ++c) {
        if (n.kind[c] == CellKind::general) general(n.ptr[c], n.info[c]);
        if (n.kind[c] == CellKind::brick) brick(n.ptr[c]);
      }
    }
  } walk{pool_, s};
  walk.general(pool_[0], pool_[1]);
  if (octree::occupied(pool_[1]) == 0) s.nodes = 1, s.general_nodes = 1;
  for_each_sample([&](const OctreeSample& x) {
    if (x.side == 0) {
      ++s.leaf_cells;
      if (x.level > s.max_depth) s.max_depth = x.level, s.leaves_at_depth = 0;
      if (x.level == s.max_depth) ++s.leaves_at_depth;
    } else {
      ++s.double_cells;
    }
    ++s.samples;
    if (x.color != background_) ++s.painted_samples;
  });
  s.pool_words = pool_.size();
  for (size_t k = 0; k < free_.size(); ++k) s.free_words += k / 2 * free_[k].size();
  s.bytes = 4 * s.pool_words;
  s.bytes_per_painted_texel = s.painted_samples ? double(s.bytes) / double(s.painted_samples) : 0;
  return s;
}

void OctreeTexture::compact() {
  if (recording_) throw std::logic_error("OctreeTexture::compact while a stroke is recorded");
  Words out;
  std::vector<std::vector<uint32_t>> gaps;
  std::vector<uint32_t> words;
  // Reserves a block; general blocks start at even words (a one-word gap becomes a free block).
  auto reserve = [&](size_t n, bool brick) {
    if (!brick && out.size() % 2) {
      if (gaps.size() <= block_class(1, true)) gaps.resize(block_class(1, true) + 1);
      gaps[block_class(1, true)].push_back(uint32_t(out.size()));
      out.resize(out.size() + 1, 0);
    }
    const size_t at = out.size();
    out.resize(at + n, 0);
    return uint32_t(at);
  };
  auto copy_brick = [&](uint32_t word) {
    const Brick b = decode_brick(pool_, word);
    const uint32_t n = brick_block_words(b.mask, b.dbl), from = word & ~octree::kBrickDoubleFlag;
    const uint32_t at = reserve(n, true);
    std::copy_n(pool_.data() + from, n, out.data() + at);
    return at | (word & octree::kBrickDoubleFlag);
  };
  // Returns the node's new address.
  auto copy_general = [&](auto&& self, uint32_t ptr, uint32_t info) -> uint32_t {
    GeneralNode n = decode_general(pool_, ptr, info);
    const uint32_t at = reserve(general_block_words(info), false);
    for (int c = 0; c < 8; ++c)
      if (n.kind[c] == CellKind::general) n.ptr[c] = self(self, n.ptr[c], n.info[c]);
    for (int c = 0; c < 8; ++c)
      if (n.kind[c] == CellKind::brick) n.ptr[c] = copy_brick(n.ptr[c]);
    encode_general(n, words);
    std::copy(words.begin(), words.end(), out.data() + at);
    return at;
  };
  if (octree::occupied(pool_[1])) {
    out[0] = copy_general(copy_general, pool_[0], pool_[1]);
    out[1] = pool_[1];
  }
  pool_ = std::move(out);
  free_ = std::move(gaps);
}

std::string OctreeTexture::check() const {
  const size_t n = pool_.size();
  if (n < 2) return "the pool must hold at least the root's two words";
  if (n > octree::kMaxPoolWords + 2) return "the pool is larger than 2^31 words";
  if (!(size_ > 0) || !std::isfinite(size_) || !std::isfinite(origin_[0]) ||
      !std::isfinite(origin_[1]) || !std::isfinite(origin_[2]))
    return "the texture cube is not a finite cube of positive size";
  std::vector<uint8_t> used(n, 0);
  used[0] = used[1] = 1;
  std::string err;
  auto claim = [&](size_t ptr, size_t words, bool aligned, const char* what) {
    if ((aligned && ptr % 2) || ptr < 2 || ptr > n || words > n - ptr) {
      err = std::string(what) + " block at word " + std::to_string(ptr) + " lies outside the pool";
      return false;
    }
    for (size_t i = ptr; i < ptr + words; ++i) {
      if (used[i]) {
        err =
            std::string(what) + " block at word " + std::to_string(ptr) + " overlaps another block";
        return false;
      }
      used[i] = 1;
    }
    return true;
  };
  auto check_tags = [&](size_t pos, size_t cells, const char* what) {
    for (size_t k = 0; k < cells; ++k) {
      const uint32_t t = pool_[pos + k / 8] >> (4 * (k % 8)) & 15u;
      if (t > uint32_t(octree::kTagCount)) {
        err = std::string(what) + " at word " + std::to_string(pos) + " has an invalid tag";
        return false;
      }
    }
    // The unused nibbles of the last tag word must be zero (one encoding per texture).
    if (cells % 8 && (pool_[pos + cells / 8] >> (4 * (cells % 8))) != 0) {
      err = std::string(what) + " at word " + std::to_string(pos) + " has stray tag bits";
      return false;
    }
    return true;
  };
  // Double cells need a direction to tell their sides apart.
  auto check_double_tags = [&](const LeafCell& c, size_t ptr, const char* what) {
    if (c.dbl && c.tag == 0) {
      err = std::string(what) + " at word " + std::to_string(ptr) +
            " has a two-sided cell without a direction";
      return false;
    }
    return true;
  };
  struct Frame {
    uint32_t ptr, info;
    int level;
  };
  std::vector<Frame> stack;
  if (octree::occupied(pool_[1]) == 0) {
    if (pool_[0] != 0 || pool_[1] != 0) return "the empty root must be (0, 0)";
  } else {
    stack.push_back({pool_[0], pool_[1], 0});
  }
  while (!stack.empty()) {
    const Frame f = stack.back();
    stack.pop_back();
    const uint32_t occ = octree::occupied(f.info), l = octree::leaves(f.info),
                   b = octree::bricks(f.info), d = octree::doubles(f.info);
    if (occ == 0) return "a general node at word " + std::to_string(f.ptr) + " is empty";
    if ((l & b) || ((l | b) & ~occ) || (d & ~l))
      return "a general node at word " + std::to_string(f.ptr) + " has inconsistent masks";
    if (f.level >= octree::kMaxDepth)
      return "the tree is deeper than " + std::to_string(octree::kMaxDepth) + " levels";
    const size_t words = general_block_words(f.info);
    if (!claim(f.ptr, words, true, "a general node's")) return err;
    const GeneralNode node = decode_general(pool_, f.ptr, f.info);
    const size_t tags = f.ptr + 2 * size_t(popc(octree::generals(f.info))) + size_t(popc(b)) + 1;
    if (!check_tags(tags, size_t(popc(l)), "a general node")) return err;
    if (words > tags - f.ptr + (size_t(popc(l)) + 7) / 8 + size_t(popc(l)) + size_t(popc(d)) &&
        pool_[f.ptr + words - 1] != 0)
      return "a general node at word " + std::to_string(f.ptr) + " has a non-zero pad word";
    for (int c = 0; c < 8; ++c) {
      if (node.kind[c] == CellKind::leaf && !check_double_tags(node.leaf[c], f.ptr, "a node"))
        return err;
      if (node.kind[c] == CellKind::general)
        stack.push_back({node.ptr[c], node.info[c], f.level + 1});
      if (node.kind[c] != CellKind::brick) continue;
      if (f.level + 3 > octree::kMaxDepth)
        return "a brick at level " + std::to_string(f.level + 1) + " is deeper than allowed";
      const uint32_t w = node.ptr[c], bp = w & ~octree::kBrickDoubleFlag;
      if (bp < 2 || size_t(bp) + 4 > n)
        return "a brick at word " + std::to_string(bp) + " lies outside the pool";
      const uint64_t mask = uint64_t(pool_[bp]) | uint64_t(pool_[bp + 1]) << 32;
      const uint64_t dbl = (w & octree::kBrickDoubleFlag)
                               ? uint64_t(pool_[bp + 2]) | uint64_t(pool_[bp + 3]) << 32
                               : 0;
      if (mask == 0) return "a brick at word " + std::to_string(bp) + " is empty";
      if ((w & octree::kBrickDoubleFlag) && (dbl == 0 || (dbl & ~mask)))
        return "a brick at word " + std::to_string(bp) + " has an inconsistent double mask";
      const size_t bw = brick_block_words(mask, dbl);
      if (!claim(bp, bw, false, "a brick's")) return err;
      const size_t cells = size_t(popc64(mask));
      const size_t btags = bp + 2 + (dbl ? 2 : 0) + 1;
      if (!check_tags(btags, cells, "a brick")) return err;
      const Brick br = decode_brick(pool_, w);
      for (int m = 0; m < 64; ++m)
        if ((mask >> m & 1) && !check_double_tags(br.cell[m], bp, "a brick")) return err;
    }
  }
  for (size_t k = 0; k < free_.size(); ++k)
    for (uint32_t p : free_[k]) {
      const bool brick = k % 2;
      if (k / 2 == 0 || (!brick && (k / 2) % 2)) return "a free block of a bad size class";
      if (!claim(p, k / 2, !brick, "a free")) return err;
    }
  for (size_t i = 0; i < n; ++i)
    if (!used[i]) return "word " + std::to_string(i) + " belongs to no block (a leak)";
  return {};
}

}  // namespace limn
