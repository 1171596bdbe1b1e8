// The walks of a CPU lookup: see octree_walk.hpp. Each is written once, as an always-inline
// template, and compiled into a plain and a fast variant; the sampler picks one per call.
#include "octree_walk.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#if LIMN_X86_SIMD
#include <immintrin.h>
#endif

namespace limn {
namespace {

using namespace detail;

struct TagTable {
  float d[octree::kTagCount + 1][3];
  TagTable() {
    for (int t = 0; t <= octree::kTagCount; ++t) {
      const auto v = octree::tag_direction(t);
      d[t][0] = v[0], d[t][1] = v[1], d[t][2] = v[2];
    }
  }
};
const TagTable kTags;

inline int side_of(uint32_t tag, const float* n) {
  if (!n || tag == 0) return 0;
  const float* d = kTags.d[tag];
  return d[0] * n[0] + d[1] * n[1] + d[2] * n[2] >= 0 ? 0 : 1;
}

// The instruction set of the walk's fast variant (see LIMN_WALK below).
#define LIMN_FAST_TARGET LIMN_TARGET("popcnt,sse4.1,sse4.2,bmi,bmi2,lzcnt,avx,avx2")

using F4 = float __attribute__((vector_size(16)));
using U4 = uint32_t __attribute__((vector_size(16)));
using I4 = int32_t __attribute__((vector_size(16)));

// The tag directions by axis, four tags to a vector (tags 15 and 0 are zero).
struct TagLanes {
  F4 d[3][4];
  TagLanes() {
    for (int t = 0; t < 16; ++t)
      for (int k = 0; k < 3; ++k) d[k][t / 4][t % 4] = t <= octree::kTagCount ? kTags.d[t][k] : 0;
  }
};
const TagLanes kTagLanes;

// Bit t set when side_of(t, n) is 1, for every tag at once: the taps of one lookup share n.
inline uint32_t back_tags(const float* n) {
  if (!n) return 0;
  uint32_t back = 0;
  for (int q = 0; q < 4; ++q) {
    // The sum in side_of's order, lane by lane.
    const F4 dot = kTagLanes.d[0][q] * n[0] + kTagLanes.d[1][q] * n[1] + kTagLanes.d[2][q] * n[2];
    const I4 m = !(dot >= 0);  // all ones where set
    for (int l = 0; l < 4; ++l) back |= (uint32_t(m[l]) & 1u) << (4 * q + l);
  }
  return back & ~1u;  // tag 0: no direction, seen from everywhere
}

#if LIMN_X86_SIMD
// back_tags with the 16 tags in two AVX vectors (the same float operations, lane by lane).
LIMN_FAST_TARGET inline uint32_t back_tags_avx(const float* n) {
  if (!n) return 0;
  uint32_t back = 0;
  for (int h = 0; h < 2; ++h) {
    const auto* d0 = reinterpret_cast<const float*>(&kTagLanes.d[0][2 * h]);
    const auto* d1 = reinterpret_cast<const float*>(&kTagLanes.d[1][2 * h]);
    const auto* d2 = reinterpret_cast<const float*>(&kTagLanes.d[2][2 * h]);
    const __m256 dot =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(d0), _mm256_set1_ps(n[0])),
                                    _mm256_mul_ps(_mm256_loadu_ps(d1), _mm256_set1_ps(n[1]))),
                      _mm256_mul_ps(_mm256_loadu_ps(d2), _mm256_set1_ps(n[2])));
    // !(dot >= 0): also for a NaN, as back_tags.
    back |= uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(dot, _mm256_setzero_ps(), _CMP_NGE_UQ)))
            << (8 * h);
  }
  return back & ~1u;
}
#endif

// The walk itself, written once and compiled twice: for CPUs with AVX2's integer set (popcnt,
// BMI1/2 shifts and bit tricks, SSE4.1 floor and byte widening: about a third fewer instructions
// per lookup than plain x86-64; without popcnt GCC calls a library routine for each of a dozen
// popcounts), and for any x86-64 otherwise. No FMA: sums round as on any machine.
#define LIMN_WALK __attribute__((always_inline)) inline

using Cache = OctreeSampler::Cache;

// Whether a leaf of the brick at `level` holds (x, y, z), without reading its sample. `cell`
// receives the level of the cell holding it that is a leaf or holds none: the brick's leaf
// level, or the whole level + 1 cell when its mask byte is empty (the brick's own cell when the
// mask is). A filtered lookup starts there.
LIMN_WALK bool mask_cell(uint64_t mask, int level, uint32_t x, uint32_t y, uint32_t z, int* cell) {
  const uint32_t c1 = octant(x, y, z, kD - 1 - level);
  const uint32_t byte = uint32_t(mask >> (8 * c1)) & 255u;
  *cell = byte ? level + 2 : mask ? level + 1 : level;
  return byte >> octant(x, y, z, kD - 2 - level) & 1u;
}
LIMN_WALK bool brick_cell(const uint32_t* pool, uint32_t word, int level, uint32_t x, uint32_t y,
                          uint32_t z, int* cell) {
  const uint32_t bp = word & ~kFlag;
  return mask_cell(uint64_t(pool[bp]) | uint64_t(pool[bp + 1]) << 32, level, x, y, z, cell);
}

LIMN_WALK bool brick_leaf(const uint32_t* pool, uint32_t word, int level, uint32_t x, uint32_t y,
                          uint32_t z, const float* n, Rgba8& out, int* leaf_level) {
  const uint32_t bp = word & ~kFlag;
  const uint64_t mask = uint64_t(pool[bp]) | uint64_t(pool[bp + 1]) << 32;
  const int m = int(octant(x, y, z, kD - 1 - level) * 8 + octant(x, y, z, kD - 2 - level));
  if (leaf_level) *leaf_level = level + 2;
  if (!(mask >> m & 1)) {
    if (leaf_level) brick_cell(pool, word, level, x, y, z, leaf_level);
    return false;
  }
  const uint64_t below = (uint64_t(1) << m) - 1;
  uint64_t dbl = 0;
  uint32_t base = bp + 3;
  if (word & kFlag) dbl = uint64_t(pool[bp + 2]) | uint64_t(pool[bp + 3]) << 32, base = bp + 5;
  // Tags first, then samples: the mask, the tag and most samples share a cache line.
  const uint32_t r = uint32_t(std::popcount(mask & below));
  const uint32_t si = r + uint32_t(std::popcount(dbl & below));
  const uint32_t tag = pool[base + r / 8] >> (4 * (r % 8)) & 15u;
  const int side = side_of(tag, n);
  if (side && !(dbl >> m & 1)) return false;
  out = pool[base + (uint32_t(std::popcount(mask)) + 7) / 8 + si + uint32_t(side)];
  return true;
}

// Makes `s` the most recent slot.
LIMN_WALK void remember(Cache& cache, const OctreeSampler::CacheSlot& s) {
  cache.slot[3] = cache.slot[2], cache.slot[2] = cache.slot[1], cache.slot[1] = cache.slot[0];
  cache.slot[0] = s;
}

// kSample false: only the level the walk ends at (a filtered lookup's leaf level) and whether a
// leaf holds the point (whatever its sides); the sample is not read.
template <bool kSample = true>
LIMN_WALK bool walk_nearest(const uint32_t* pool, const OctreeIndex* index, Cache& cache,
                            uint32_t x, uint32_t y, uint32_t z, const float* n, Rgba8& out,
                            int* level) {
  uint32_t ptr, info;
  int l;
  int hit = -1;
  for (int k = 0; k < 4; ++k) {
    const OctreeSampler::CacheSlot& s = cache.slot[k];
    if (s.level >= 0 && (x >> (kD - s.level)) == s.x && (y >> (kD - s.level)) == s.y &&
        (z >> (kD - s.level)) == s.z) {
      hit = k;
      break;
    }
  }
  if (hit >= 0) {
    if (hit > 0) std::swap(cache.slot[0], cache.slot[hit]);
    const OctreeSampler::CacheSlot& s = cache.slot[0];
    if (s.brick) {
      if constexpr (!kSample) return brick_cell(pool, s.ptr, s.level, x, y, z, level);
      return brick_leaf(pool, s.ptr, s.level, x, y, z, n, out, level);
    }
    ptr = s.ptr, info = s.info, l = s.level;
  } else if (const OctreeSampler::CacheSlot& s = cache.parent;
             s.level >= 0 && (x >> (kD - s.level)) == s.x && (y >> (kD - s.level)) == s.y &&
             (z >> (kD - s.level)) == s.z) {
    ptr = s.ptr, info = s.info, l = s.level;
  } else if (index) {
    const int il = index->level();
    const OctreeIndex::Entry& e = index->at(x >> (kD - il), y >> (kD - il), z >> (kD - il));
    if (e.brick) {
      remember(cache, {e.level, true, e.ptr, 0, x >> (kD - e.level), y >> (kD - e.level),
                       z >> (kD - e.level)});
      if constexpr (!kSample) return brick_cell(pool, e.ptr, e.level, x, y, z, level);
      return brick_leaf(pool, e.ptr, e.level, x, y, z, n, out, level);
    }
    ptr = e.ptr, info = e.info, l = e.level;
  } else {
    ptr = pool[0], info = pool[1], l = 0;
  }
  const int start_level = l;
  for (;;) {
    const uint32_t bit = 1u << octant(x, y, z, kD - 1 - l);
    if (level) *level = l + 1;
    if (!(info & bit)) return false;
    const uint32_t below = bit - 1;
    const uint32_t gen = octree::generals(info);
    if (gen & bit) {
      const uint32_t i = ptr + 2 * uint32_t(std::popcount(gen & below));
      ptr = pool[i], info = pool[i + 1], ++l;
      continue;
    }
    const uint32_t br = octree::bricks(info);
    const uint32_t after_gen = ptr + 2 * uint32_t(std::popcount(gen));
    if (br & bit) {
      const uint32_t w = pool[after_gen + uint32_t(std::popcount(br & below))];
      remember(cache, {l + 1, true, w, 0, x >> (kD - l - 1), y >> (kD - l - 1), z >> (kD - l - 1)});
      cache.parent = {l, false, ptr, info, x >> (kD - l), y >> (kD - l), z >> (kD - l)};
      if constexpr (!kSample) return brick_cell(pool, w, l + 1, x, y, z, level);
      return brick_leaf(pool, w, l + 1, x, y, z, n, out, level);
    }
    // A leaf of this general node: remember the node (unless it is the cached one we began at).
    if (hit < 0 || l != start_level)
      remember(cache, {l, false, ptr, info, x >> (kD - l), y >> (kD - l), z >> (kD - l)});
    if constexpr (!kSample) return true;
    const uint32_t lf = octree::leaves(info), dbl = octree::doubles(info);
    const uint32_t base = after_gen + uint32_t(std::popcount(br)) + 1;
    const uint32_t r = uint32_t(std::popcount(lf & below));
    const uint32_t si = r + uint32_t(std::popcount(dbl & below));
    const uint32_t tag = pool[base + r / 8] >> (4 * (r % 8)) & 15u;
    const int side = side_of(tag, n);
    if (side && !(dbl & bit)) return false;
    out = pool[base + (uint32_t(std::popcount(lf)) + 7) / 8 + si + uint32_t(side)];
    return true;
  }
}

// float(i) / 255: the alpha of a tap, looked up rather than divided.
struct UnitTable {
  float v[256];
  UnitTable() {
    for (int i = 0; i < 256; ++i) v[i] = float(i) / 255.0f;
  }
};
const UnitTable kUnit;

// Where brick cell bits (v & 3 along axis k) land in the brick's Morton index: bit 1 picks the
// cell at the brick's level + 1 (mask byte), bit 0 the cell inside it.
constexpr uint32_t brick_bits(uint32_t v, int k) {
  return (v >> 1 & 1u) << (3 + k) | (v & 1u) << k;
}
// brick_bits(v, k) by [k][v].
struct BrickBits {
  uint32_t v[3][4];
  constexpr BrickBits() : v{} {
    for (int k = 0; k < 3; ++k)
      for (uint32_t i = 0; i < 4; ++i) v[k][i] = brick_bits(i, k);
  }
};
constexpr BrickBits kBrickBits;

// The brick table's key of a brick cell: 16 bits per coordinate (a brick's level is at most
// kMaxDepth - 2), the level above them and bit 63, so no key is the empty slot's 0.
inline uint64_t brick_key(int64_t level, int64_t x, int64_t y, int64_t z) {
  return uint64_t(1) << 63 | uint64_t(level) << 48 | uint64_t(x) << 32 | uint64_t(y) << 16 |
         uint64_t(z);
}

constexpr int kSlotBits = Cache::kSlotBits;
constexpr int64_t kSlotMask = (1 << kSlotBits) - 1;
// The brick table slot of a brick cell.
inline uint32_t brick_slot(int64_t x, int64_t y, int64_t z) {
  return uint32_t((x & kSlotMask) | (y & kSlotMask) << kSlotBits |
                  (z & kSlotMask) << (2 * kSlotBits));
}

constexpr uint64_t kUnpacked = uint64_t(1) << 62;

// Puts a brick in a slot of the brick table, packed (see Cache::brick_key).
LIMN_WALK void remember_brick(const uint32_t* pool, uint32_t word, Cache& cache, uint32_t slot,
                              uint64_t key) {
  const uint32_t bp = word & ~kFlag;
  cache.brick_key[slot] = key, cache.brick_word[slot] = word;
  cache.brick_mask[slot] = uint64_t(pool[bp]) | uint64_t(pool[bp + 1]) << 32;
}

// Unpacks the brick in a slot of the brick table. Samples of cells without one keep what the
// slot held: never counted (their cell byte says so).
LIMN_WALK void unpack_brick(const uint32_t* pool, Cache& cache, uint32_t slot) {
  const uint32_t word = cache.brick_word[slot], bp = word & ~kFlag;
  const uint64_t mask = cache.brick_mask[slot];
  uint64_t dbl = 0;
  uint32_t base = bp + 3;
  if (word & kFlag) dbl = uint64_t(pool[bp + 2]) | uint64_t(pool[bp + 3]) << 32, base = bp + 5;
  cache.brick_key[slot] |= kUnpacked;
  uint8_t* cell = cache.brick_cell + 64 * slot;
  Rgba8* color = cache.brick_color + 128 * slot;
  std::fill_n(cell, 64, uint8_t(0));
  const uint32_t* samples = pool + base + (uint32_t(std::popcount(mask)) + 7) / 8;
  const uint32_t* tags = pool + base;
  uint32_t r = 0, tag = 0;
  for (uint64_t left = mask; left; left &= left - 1, ++r, tag >>= 4) {
    const uint32_t next = tags[r / 8];
    tag = r % 8 ? tag : next;  // eight nibbles a word (a select: a branch mispredicted often)
    const int m = std::countr_zero(left);
    const uint32_t two = uint32_t(dbl >> m & 1);
    cell[m] = uint8_t((tag & 15u) | 16u | two << 5);
    color[2 * m] = samples[0];
    color[2 * m + 1] = samples[two];  // the front sample again when there is no back one
    samples += 1 + two;
  }
}

// Resolves the taps in `set` (corner bits) from a packed brick whose leaves are at the taps'
// level (a brick's first use): the mask and offsets are read once, each tap costs its popcounts.
// mb: the Morton bits of each axis's two tap cells. Returns the corners that have a sample facing
// n.
LIMN_WALK uint32_t pool_taps(const uint32_t* pool, uint32_t word, const uint32_t mb[3][2],
                             uint32_t set, uint32_t back, Rgba8 col[8]) {
  const uint32_t bp = word & ~kFlag;
  const uint64_t mask = uint64_t(pool[bp]) | uint64_t(pool[bp + 1]) << 32;
  uint64_t dbl = 0;
  uint32_t base = bp + 3;
  if (word & kFlag) dbl = uint64_t(pool[bp + 2]) | uint64_t(pool[bp + 3]) << 32, base = bp + 5;
  const uint32_t samples = base + (uint32_t(std::popcount(mask)) + 7) / 8;
  if (!mask) return 0;
  uint32_t found = 0;
  // Branch-free: whether a tap's cell is occupied is as good as random on a surface. A missing
  // cell's rank is at most the cell count, so its tag word still lies in the block.
  for (; set; set &= set - 1) {
    const int corner = std::countr_zero(set);
    const uint32_t m = mb[0][corner & 1] | mb[1][corner >> 1 & 1] | mb[2][corner >> 2];
    const uint64_t below = (uint64_t(1) << m) - 1;
    const uint32_t r = uint32_t(std::popcount(mask & below));
    const uint32_t si = r + uint32_t(std::popcount(dbl & below));
    const uint32_t tag = pool[base + r / 8] >> (4 * (r % 8)) & 15u;
    const uint32_t side = back >> tag & 1u;
    const uint32_t ok = uint32_t(mask >> m) & (~side | uint32_t(dbl >> m)) & 1u;
    col[corner] = pool[bp + ((samples + si + side - bp) & (0u - ok))];
    found |= ok << corner;
  }
  return found;
}

// Cache::table_hits: a moving average over about 8 lookups of whether all their taps' bricks
// were in the table, 0-256; above half the lookups follow a coherent path.
LIMN_WALK void count_table_hit(Cache& cache, bool hit) {
  cache.table_hits = cache.table_hits - (cache.table_hits >> 3) + (hit ? 32u : 0u);
}
LIMN_WALK bool coherent(const Cache& cache) {
  return cache.table_hits > 128;
}

// Resolves one tap from entry e of the brick table: its sample facing the lookup's normal
// (`back`: see back_tags) into `col`; returns 1 when there is one. Branch-free: whether a
// tap's cell is occupied is as good as random on a surface.
LIMN_WALK uint32_t entry_tap(const Cache& cache, uint32_t e, uint32_t back, Rgba8& col) {
  const uint32_t c = cache.brick_cell[e];
  const uint32_t side = back >> (c & 15u) & 1u;
  col = cache.brick_color[2 * e + side];
  return c >> (4 + side) & 1u;
}

// The taps in `set` (corner bits) from the brick in table slot `slot`, whose leaves are at the
// taps' level. mb: the Morton bits of each axis's two tap cells. Returns the corners that have
// a sample facing n.
LIMN_WALK uint32_t slot_taps(const Cache& cache, uint32_t slot, const uint32_t mb[3][2],
                             uint32_t set, uint32_t back, Rgba8 col[8]) {
  uint32_t found = 0;
  for (; set; set &= set - 1) {
    const int corner = std::countr_zero(set);
    const uint32_t m = mb[0][corner & 1] | mb[1][corner >> 1 & 1] | mb[2][corner >> 2];
    found |= entry_tap(cache, slot << 6 | m, back, col[corner]) << corner;
  }
  return found;
}

// The accumulation of walk_trilinear (below): the taps in `found` (corner bits) with their
// trilinear weights, premultiplied into acc (rgb, alpha, weight) in corner order. Returns
// whether any tap had a sample.
LIMN_WALK bool accumulate8(const double wt[3][2], uint32_t found, const Rgba8 col[8],
                           float acc[5]) {
  F4 sum = {acc[0], acc[1], acc[2], acc[3]};
  float weight = acc[4];
  bool any = false;
  const F4 norm = {255.0f, 255.0f, 255.0f, 1.0f};
  // Taps without a sample weigh 0: adding exact zeros leaves the sums as they were, and the
  // branch on `found` would be as good as random.
  const U4 shifts = {0, 8, 16, 24};
#pragma GCC unroll 8
  for (int corner = 0; corner < 8; ++corner) {
    const double w = wt[0][corner & 1] * wt[1][corner >> 1 & 1] * wt[2][corner >> 2];
    const bool tap = (found >> corner & 1) & (w > 0);
    const Rgba8 c = col[corner];
    // w >= 0, so this is float(w) or +0 (a select here was a branch, mispredicted often).
    const float fw = float(w) * float(tap), wa = fw * kUnit.v[channel(c, 3)];
    // The channels as floats, exactly (one shift, mask and conversion of a vector).
    F4 ch = __builtin_convertvector(I4((U4{c, c, c, c} >> shifts) & 255u), F4);
    ch[3] = 1.0f;
    // Lane by lane what one tap did before: fw * a * channel / 255 (and fw * a for alpha).
    sum += (F4{wa, wa, wa, wa} * ch) / norm;
    weight += fw;
    any |= tap;
  }
  for (int k = 0; k < 4; ++k) acc[k] = sum[k];
  acc[4] = weight;
  return any;
}

#if LIMN_X86_SIMD
// accumulate8 with the 8 taps in the lanes of AVX vectors: each
// lane does one tap's float operations in the same order (w in double, then float(w), its
// alpha as float(a) / 255, fw * a * channel / 255), and the sums run in corner order, so the
// results are those of the scalar loop to the bit.
LIMN_FAST_TARGET inline bool accumulate8_avx(const double wt[3][2], uint32_t found, __m256i c,
                                             float acc[5]) {
  const __m256d w01 = _mm256_mul_pd(_mm256_setr_pd(wt[0][0], wt[0][1], wt[0][0], wt[0][1]),
                                    _mm256_setr_pd(wt[1][0], wt[1][0], wt[1][1], wt[1][1]));
  const __m256d w_lo = _mm256_mul_pd(w01, _mm256_set1_pd(wt[2][0]));
  const __m256d w_hi = _mm256_mul_pd(w01, _mm256_set1_pd(wt[2][1]));
  const __m256d zero = _mm256_setzero_pd();
  const uint32_t positive = uint32_t(_mm256_movemask_pd(_mm256_cmp_pd(w_lo, zero, _CMP_GT_OQ))) |
                            uint32_t(_mm256_movemask_pd(_mm256_cmp_pd(w_hi, zero, _CMP_GT_OQ)))
                                << 4;
  const uint32_t taps = found & positive;
  const __m256i bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256i on = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(int(taps)), bit), bit);
  // float(w) where the tap counts, +0 elsewhere (w >= 0).
  const __m256 fw = _mm256_and_ps(_mm256_set_m128(_mm256_cvtpd_ps(w_hi), _mm256_cvtpd_ps(w_lo)),
                                  _mm256_castsi256_ps(on));
  const __m256i byte = _mm256_set1_epi32(255);
  const __m256 k255 = _mm256_set1_ps(255.0f);
  const __m256 wa =
      _mm256_mul_ps(fw, _mm256_div_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(c, 24)), k255));
  __m256 t[3];
  for (int k = 0; k < 3; ++k) {
    const __m256i v = _mm256_and_si256(_mm256_srlv_epi32(c, _mm256_set1_epi32(8 * k)), byte);
    t[k] = _mm256_div_ps(_mm256_mul_ps(wa, _mm256_cvtepi32_ps(v)), k255);
  }
  // Transposed to one (r, g, b, a) vector per corner (alpha's term is (wa * 1) / 1 = wa), the
  // two halves holding corners 0-3 and 4-7, then summed in corner order.
  const __m256 rg_lo = _mm256_unpacklo_ps(t[0], t[1]), rg_hi = _mm256_unpackhi_ps(t[0], t[1]);
  const __m256 ba_lo = _mm256_unpacklo_ps(t[2], wa), ba_hi = _mm256_unpackhi_ps(t[2], wa);
  const __m256 c04 = _mm256_shuffle_ps(rg_lo, ba_lo, 0x44),
               c15 = _mm256_shuffle_ps(rg_lo, ba_lo, 0xee);
  const __m256 c26 = _mm256_shuffle_ps(rg_hi, ba_hi, 0x44),
               c37 = _mm256_shuffle_ps(rg_hi, ba_hi, 0xee);
  __m128 sum = _mm_loadu_ps(acc);
  sum = _mm_add_ps(sum, _mm256_castps256_ps128(c04));
  sum = _mm_add_ps(sum, _mm256_castps256_ps128(c15));
  sum = _mm_add_ps(sum, _mm256_castps256_ps128(c26));
  sum = _mm_add_ps(sum, _mm256_castps256_ps128(c37));
  sum = _mm_add_ps(sum, _mm256_extractf128_ps(c04, 1));
  sum = _mm_add_ps(sum, _mm256_extractf128_ps(c15, 1));
  sum = _mm_add_ps(sum, _mm256_extractf128_ps(c26, 1));
  sum = _mm_add_ps(sum, _mm256_extractf128_ps(c37, 1));
  _mm_storeu_ps(acc, sum);
  alignas(32) float w[8];
  _mm256_store_ps(w, fw);
  float weight = acc[4];
  for (int corner = 0; corner < 8; ++corner) weight += w[corner];
  acc[4] = weight;
  return taps != 0;
}

LIMN_FAST_TARGET inline bool accumulate8_avx(const double wt[3][2], uint32_t found,
                                             const Rgba8 col[8], float acc[5]) {
  return accumulate8_avx(wt, found, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(col)), acc);
}

// The fast path of walk_trilinear (below) in AVX2 lanes, a corner a lane: when every tap's
// brick is unpacked in the brick table (one gather of the 8 slots' keys), the taps are two
// gathers (cell bytes, then samples) and are accumulated as accumulate8_avx does. entry, keys:
// per axis and tap cell, the entry bits and key bits of walk_trilinear; lk: the level's key
// bits with kUnpacked. Returns -1 (nothing done) when a brick is not there, else whether any
// tap has a sample.
LIMN_FAST_TARGET inline int table_trilinear_avx(const Cache& cache, const uint32_t entry[3][2],
                                                const uint64_t keys[3][2], uint64_t lk,
                                                uint32_t back, const double wt[3][2],
                                                float acc[5]) {
  // Corner c = x | y << 1 | z << 2 in lane c: x picks odd lanes, y lanes 2-3 and 6-7, z 4-7.
  const __m256i x0 = _mm256_set1_epi32(int(entry[0][0])), x1 = _mm256_set1_epi32(int(entry[0][1]));
  const __m256i y0 = _mm256_set1_epi32(int(entry[1][0])), y1 = _mm256_set1_epi32(int(entry[1][1]));
  const __m256i z0 = _mm256_set1_epi32(int(entry[2][0])), z1 = _mm256_set1_epi32(int(entry[2][1]));
  const __m256i e = _mm256_or_si256(
      _mm256_or_si256(_mm256_blend_epi32(x0, x1, 0xaa), _mm256_blend_epi32(y0, y1, 0xcc)),
      _mm256_blend_epi32(z0, z1, 0xf0));
  // The keys of corners 0-3 and 4-7, a 64-bit lane each.
  const __m256i kxy =
      _mm256_or_si256(_mm256_blend_epi32(_mm256_set1_epi64x(int64_t(keys[0][0])),
                                         _mm256_set1_epi64x(int64_t(keys[0][1])), 0xcc),
                      _mm256_blend_epi32(_mm256_set1_epi64x(int64_t(keys[1][0])),
                                         _mm256_set1_epi64x(int64_t(keys[1][1])), 0xf0));
  const __m256i want_lo = _mm256_or_si256(kxy, _mm256_set1_epi64x(int64_t(lk | keys[2][0])));
  const __m256i want_hi = _mm256_or_si256(kxy, _mm256_set1_epi64x(int64_t(lk | keys[2][1])));
  const __m256i slot = _mm256_srli_epi32(e, 6);
  const auto* key = reinterpret_cast<const long long*>(cache.brick_key);
  const __m256i have_lo = _mm256_i32gather_epi64(key, _mm256_castsi256_si128(slot), 8);
  const __m256i have_hi = _mm256_i32gather_epi64(key, _mm256_extracti128_si256(slot, 1), 8);
  const __m256i same =
      _mm256_and_si256(_mm256_cmpeq_epi64(have_lo, want_lo), _mm256_cmpeq_epi64(have_hi, want_hi));
  if (_mm256_movemask_epi8(same) != -1) return -1;
  const __m256i one = _mm256_set1_epi32(1);
  const __m256i cell =
      _mm256_and_si256(_mm256_i32gather_epi32(reinterpret_cast<const int*>(cache.brick_cell), e, 1),
                       _mm256_set1_epi32(255));
  const __m256i side =
      _mm256_and_si256(_mm256_srlv_epi32(_mm256_set1_epi32(int(back)),
                                         _mm256_and_si256(cell, _mm256_set1_epi32(15))),
                       one);
  const __m256i col = _mm256_i32gather_epi32(reinterpret_cast<const int*>(cache.brick_color),
                                             _mm256_add_epi32(_mm256_add_epi32(e, e), side), 4);
  const __m256i has = _mm256_srlv_epi32(cell, _mm256_add_epi32(side, _mm256_set1_epi32(4)));
  const uint32_t found =
      uint32_t(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_slli_epi32(has, 31))));
  return accumulate8_avx(wt, found, col, acc);
}
#endif  // LIMN_X86_SIMD

// The 8 leaf-level taps of a filtered lookup, accumulated premultiplied (acc: rgb, alpha,
// weight). `deepest` rises to the level of a finer leaf whose sample a tap read, `reach` to the
// deepest level any tap's walk ended at (a leaf or an empty cell). The taps are resolved first,
// then accumulated in corner order with the float operations of one tap at a time, so the sums do
// not depend on how a tap was found. Taps sharing a brick (at most 8 blocks of them, one when the
// 2x2x2 block does not cross a brick boundary) are read from it together once the cache holds it;
// the others are nearest walks sharing the cache.
template <bool kAvx>
LIMN_WALK bool walk_trilinear(const uint32_t* pool, const OctreeIndex* index, Cache& cache,
                              const double u[3], int level, const float* n, float acc[5],
                              int& deepest, int& reach) {
  const double cells = double(1u << level);
  int64_t i0[3];
  double wt[3][2];
  for (int k = 0; k < 3; ++k) {
    const double g = u[k] * cells - 0.5;
    const double f = std::floor(g);
    i0[k] = int64_t(f), wt[k][1] = g - f, wt[k][0] = 1 - wt[k][1];
  }
  const int64_t hi = int64_t(1) << level;
  const int shift = kD - level;
  const uint32_t half = shift > 0 ? 1u << (shift - 1) : 0;
  Rgba8 col[8] = {};
  uint32_t found = 0;
  // One tap by a nearest walk. Returns the level the walk ended at, -1 when the tap is out of
  // the cube or weighs nothing (not walked).
  auto walk_tap = [&](int corner) __attribute__((always_inline)) {
    int64_t ic[3];
    for (int k = 0; k < 3; ++k) ic[k] = i0[k] + (corner >> k & 1);
    if (wt[0][corner & 1] * wt[1][corner >> 1 & 1] * wt[2][corner >> 2] <= 0) return -1;
    if (ic[0] < 0 || ic[1] < 0 || ic[2] < 0 || ic[0] >= hi || ic[1] >= hi || ic[2] >= hi) return -1;
    // The tap's centre at kMaxDepth resolution.
    const uint32_t x = (uint32_t(ic[0]) << shift) + half, y = (uint32_t(ic[1]) << shift) + half,
                   z = (uint32_t(ic[2]) << shift) + half;
    int ended = 0;
    if (walk_nearest(pool, index, cache, x, y, z, n, col[corner], &ended)) {
      found |= 1u << corner;
      deepest = std::max(deepest, ended);  // a finer leaf's sample (bricks' are at `level`)
    }
    reach = std::max(reach, ended);
    return ended;
  };
  if (level < 2) {
    for (int corner = 0; corner < 8; ++corner) walk_tap(corner);
  } else {
    uint32_t back;
#if LIMN_X86_SIMD
    if constexpr (kAvx)
      back = back_tags_avx(n);
    else
#endif
      back = back_tags(n);
    // Per axis, each tap cell's Morton bits in its brick, its brick cell's key bits, and its
    // slot's bits in a brick table entry with the cell's own Morton bits.
    uint32_t mb[3][2], entry[3][2];
    uint64_t keys[3][2];
    bool inside = true;
    for (int k = 0; k < 3; ++k) {
      for (int d = 0; d < 2; ++d) {
        const int64_t i = i0[k] + d, b = i >> 2;
        mb[k][d] = kBrickBits.v[k][i & 3];
        keys[k][d] = uint64_t(b) << (32 - 16 * k);
        entry[k][d] = uint32_t(b & kSlotMask) << (6 + kSlotBits * k) | mb[k][d];
      }
      inside &= i0[k] >= 0 && i0[k] + 1 < hi;
    }
    // A coherent path mostly finds every tap's brick in the table: then the taps are read
    // there in corner order, with no walk and no loop over blocks.
    bool all = inside;
    if (inside) {
      const uint64_t lk = brick_key(level - 2, 0, 0, 0) | kUnpacked;
#if LIMN_X86_SIMD
      if constexpr (kAvx) {
        const int r = table_trilinear_avx(cache, entry, keys, lk, back, wt, acc);
        all = r >= 0;
        count_table_hit(cache, all);
        if (all) return r;
      } else
#endif
      {
        uint32_t e[8];
#pragma GCC unroll 8
        for (int corner = 0; corner < 8; ++corner) {
          const int cx = corner & 1, cy = corner >> 1 & 1, cz = corner >> 2;
          e[corner] = entry[0][cx] | entry[1][cy] | entry[2][cz];
          all &= cache.brick_key[e[corner] >> 6] == (lk | keys[0][cx] | keys[1][cy] | keys[2][cz]);
        }
        count_table_hit(cache, all);
        if (all) {
#pragma GCC unroll 8
          for (int corner = 0; corner < 8; ++corner)
            found |= entry_tap(cache, e[corner], back, col[corner]) << corner;
        }
      }
    }
    // Per axis, the corners on each side of a brick boundary (all 8 on one side when the two
    // tap cells share the brick's 4 cells along it).
    static constexpr uint32_t kSide[3][2] = {{0x55, 0xaa}, {0x33, 0xcc}, {0x0f, 0xf0}};
    uint32_t sets[3][2];
    int parts[3];
    for (int k = 0; k < 3; ++k) {
      const bool split = (i0[k] & 3) == 3;
      parts[k] = split ? 2 : 1;
      sets[k][0] = split ? kSide[k][0] : 0xffu, sets[k][1] = kSide[k][1];
    }
    for (int ez = 0; ez < (all ? 0 : parts[2]); ++ez)
      for (int ey = 0; ey < parts[1]; ++ey)
        for (int ex = 0; ex < parts[0]; ++ex) {
          uint32_t set = sets[0][ex] & sets[1][ey] & sets[2][ez];
          // The block's brick cell; out of the cube, all its taps are.
          const int64_t bx = (i0[0] + ex) >> 2, by = (i0[1] + ey) >> 2, bz = (i0[2] + ez) >> 2;
          if (bx < 0 || by < 0 || bz < 0 || bx >= hi >> 2 || by >= hi >> 2 || bz >= hi >> 2)
            continue;
          const uint32_t slot = brick_slot(bx, by, bz);
          const uint64_t key = brick_key(level - 2, bx, by, bz);
          if (const uint64_t have = cache.brick_key[slot]; (have & ~kUnpacked) == key) {
            if (!(have & kUnpacked)) unpack_brick(pool, cache, slot);  // its second use
            found |= slot_taps(cache, slot, mb, set, back, col);
            continue;
          }
          // The block's node, by a walk that reads no sample: its brick, if it is one, then
          // serves every tap.
          {
            Rgba8 unused;
            int ended = 0;
            walk_nearest<false>(pool, index, cache, uint32_t(bx << (shift + 2)),
                                uint32_t(by << (shift + 2)), uint32_t(bz << (shift + 2)), n, unused,
                                &ended);
            const OctreeSampler::CacheSlot& s0 = cache.slot[0];
            if (s0.brick && s0.level == level - 2 && int64_t(s0.x) == bx && int64_t(s0.y) == by &&
                int64_t(s0.z) == bz) {
              remember_brick(pool, s0.ptr, cache, slot, key);
              cache.brick_level = s0.level;
              if (coherent(cache)) {  // the next lookups will read it too
                unpack_brick(pool, cache, slot);
                found |= slot_taps(cache, slot, mb, set, back, col);
              } else {
                found |= pool_taps(pool, s0.ptr, mb, set, back, col);
              }
              continue;
            }
          }
          while (set) {
            const int corner = std::countr_zero(set);
            set &= set - 1;
            const int ended = walk_tap(corner);
            if (ended >= 0 && ended <= level - 2) {
              // A leaf or empty cell holding the whole brick cell: the same answer for all.
              const uint32_t same = (found >> corner & 1) ? set : 0;
              for (; set; set &= set - 1) col[std::countr_zero(set)] = col[corner];
              found |= same;
            }
          }
        }
  }
#if LIMN_X86_SIMD
  if constexpr (kAvx) return accumulate8_avx(wt, found, col, acc);
#endif
  return accumulate8(wt, found, col, acc);
}

// A filtered lookup at p's leaf level: finds the level (a walk that reads no sample, leaving p's
// node first in the cache for the taps), then, unless the footprint is wider than a leaf,
// accumulates the taps. Returns -1 when the footprint asks for mip levels instead.
template <bool kAvx>
LIMN_WALK int walk_filtered(const uint32_t* pool, const OctreeIndex* index, Cache& cache,
                            const uint32_t c[3], const double u[3], const float* n, float footprint,
                            double size, int& leaf_level, float acc[5]) {
  // p's brick is usually one the last lookup's taps read: then its leaves are p's level.
  bool at_leaf;
  const int b = cache.brick_level;
  const uint32_t bx = c[0] >> (kD - b), by = c[1] >> (kD - b), bz = c[2] >> (kD - b);
  const uint32_t slot = brick_slot(bx, by, bz);
  if (b >= 0 && (cache.brick_key[slot] & ~kUnpacked) == brick_key(b, bx, by, bz)) {
    at_leaf = mask_cell(cache.brick_mask[slot], b, c[0], c[1], c[2], &leaf_level);
  } else {
    Rgba8 unused;
    at_leaf = walk_nearest<false>(pool, index, cache, c[0], c[1], c[2], n, unused, &leaf_level);
  }
  // Where a tap reads the sample of a finer leaf, p sits in a coarse leaf beside finer ones
  // (the texture is deep only where it was painted): the taps of p's level would reach a whole
  // coarse cell away and read points of that detail. Filter at the finer level instead, until
  // no tap finds a finer leaf: the filter stays local and continuous into the finer leaves.
  // p in a cell no leaf holds (a drawn surface a little off the painted one, in a cell the paint
  // never touched): while a tap's cell holds finer leaves, one level finer, so the filter reads
  // the leaves beside p rather than coarse cell centres that miss them (or coarse leaves a whole
  // cell away). It stops where every tap's walk ends in a leaf or empty cell no finer than the
  // taps; those cells hold every finer level's taps, so nothing finer lies within reach.
  for (;;) {
    const double leaf_size = size / double(1u << leaf_level);
    if (footprint > leaf_size && std::isfinite(footprint)) return -1;
    int deepest = leaf_level, reach = leaf_level;
    const bool any =
        walk_trilinear<kAvx>(pool, index, cache, u, leaf_level, n, acc, deepest, reach);
    if (deepest > leaf_level) {
      leaf_level = deepest;
    } else if (!at_leaf && reach > leaf_level && leaf_level < kD) {
      ++leaf_level;
    } else {
      return any;
    }
    std::fill(acc, acc + 5, 0.0f);
  }
}

// Whether lookups take the fast walks (LIMN_NO_SIMD=1 in the environment: the plain ones).

}  // namespace

namespace detail {

bool walk_trilinear_generic(const uint32_t* pool, const OctreeIndex* index, Cache& cache,
                            const double u[3], int level, const float* n, float acc[5],
                            int& deepest, int& reach) {
  return walk_trilinear<false>(pool, index, cache, u, level, n, acc, deepest, reach);
}

int walk_filtered_generic(const uint32_t* pool, const OctreeIndex* index, Cache& cache,
                          const uint32_t c[3], const double u[3], const float* n, float footprint,
                          double size, int& leaf_level, float acc[5]) {
  return walk_filtered<false>(pool, index, cache, c, u, n, footprint, size, leaf_level, acc);
}

bool walk_nearest_generic(const uint32_t* pool, const OctreeIndex* index, Cache& cache, uint32_t x,
                          uint32_t y, uint32_t z, const float* n, Rgba8& out, int* level) {
  return walk_nearest(pool, index, cache, x, y, z, n, out, level);
}

// The walks compiled for the fast variant's instruction set (LIMN_FAST_TARGET), taken where
// cpu::features() says the processor has it; without the x86 kernels, the plain walks.
#if LIMN_X86_SIMD
LIMN_FAST_TARGET bool walk_trilinear_fast(const uint32_t* pool, const OctreeIndex* index,
                                          Cache& cache, const double u[3], int level,
                                          const float* n, float acc[5], int& deepest, int& reach) {
  return walk_trilinear<true>(pool, index, cache, u, level, n, acc, deepest, reach);
}

LIMN_FAST_TARGET int walk_filtered_fast(const uint32_t* pool, const OctreeIndex* index,
                                        Cache& cache, const uint32_t c[3], const double u[3],
                                        const float* n, float footprint, double size,
                                        int& leaf_level, float acc[5]) {
  return walk_filtered<true>(pool, index, cache, c, u, n, footprint, size, leaf_level, acc);
}

LIMN_FAST_TARGET bool walk_nearest_fast(const uint32_t* pool, const OctreeIndex* index,
                                        Cache& cache, uint32_t x, uint32_t y, uint32_t z,
                                        const float* n, Rgba8& out, int* level) {
  return walk_nearest(pool, index, cache, x, y, z, n, out, level);
}
#else
bool walk_trilinear_fast(const uint32_t* pool, const OctreeIndex* index, Cache& cache,
                         const double u[3], int level, const float* n, float acc[5], int& deepest,
                         int& reach) {
  return walk_trilinear_generic(pool, index, cache, u, level, n, acc, deepest, reach);
}

int walk_filtered_fast(const uint32_t* pool, const OctreeIndex* index, Cache& cache,
                       const uint32_t c[3], const double u[3], const float* n, float footprint,
                       double size, int& leaf_level, float acc[5]) {
  return walk_filtered_generic(pool, index, cache, c, u, n, footprint, size, leaf_level, acc);
}

bool walk_nearest_fast(const uint32_t* pool, const OctreeIndex* index, Cache& cache, uint32_t x,
                       uint32_t y, uint32_t z, const float* n, Rgba8& out, int* level) {
  return walk_nearest_generic(pool, index, cache, x, y, z, n, out, level);
}
#endif

int leaf_side(uint32_t tag, const float* n) {
  return side_of(tag, n);
}

bool brick_leaf_sample(const uint32_t* pool, uint32_t word, int level, uint32_t x, uint32_t y,
                       uint32_t z, const float* n, Rgba8& out) {
  return brick_leaf(pool, word, level, x, y, z, n, out, nullptr);
}

}  // namespace detail
}  // namespace limn
