// CPU lookups over the pool, the same walk a shader does (octree_walk.cpp), plus a last-node cache
// (the role an OpenVDB ValueAccessor plays) so coherent lookups skip the descent.
#include "limn/paint/lookup.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>

#include "octree_blocks.hpp"
#include "octree_walk.hpp"

namespace limn {

using namespace detail;

namespace {

// The mip means' premultiplied mean (the same sums and rounding as the refiner's averages).
Rgba8 premul_mean(const uint32_t* s, size_t count) {
  ColorMean m;
  for (size_t i = 0; i < count; ++i) m.add(s[i]);
  return m.mean();
}

}  // namespace

OctreeIndex::OctreeIndex(const OctreeTexture& t, int level) : level_(std::clamp(level, 1, 7)) {
  entries_.resize(size_t(1) << (3 * level_));
  const auto pool = t.words();
  // Fills the entries of the cell (l, x, y, z) with e.
  auto fill = [&](int l, uint32_t x, uint32_t y, uint32_t z, const Entry& e) {
    const int sh = level_ - l;
    for (uint32_t k = z << sh; k < (z + 1) << sh; ++k)
      for (uint32_t j = y << sh; j < (y + 1) << sh; ++j)
        for (uint32_t i = x << sh; i < (x + 1) << sh; ++i)
          entries_[(size_t(k) << (2 * level_)) | (size_t(j) << level_) | i] = e;
  };
  struct Frame {
    uint32_t ptr, info;
    int level;
    uint32_t x, y, z;
  };
  std::vector<Frame> stack = {{pool[0], pool[1], 0, 0, 0, 0}};
  while (!stack.empty()) {
    const Frame f = stack.back();
    stack.pop_back();
    const Entry here{f.ptr, f.info, int8_t(f.level), 0};
    if (f.level == level_ || octree::occupied(f.info) == 0) {
      fill(f.level, f.x, f.y, f.z, here);
      continue;
    }
    const uint32_t gen = octree::generals(f.info), br = octree::bricks(f.info);
    uint32_t gi = f.ptr, bi = f.ptr + 2 * uint32_t(std::popcount(gen));
    for (uint32_t c = 0; c < 8; ++c) {
      const uint32_t cx = 2 * f.x + (c & 1), cy = 2 * f.y + (c >> 1 & 1), cz = 2 * f.z + (c >> 2);
      if (gen >> c & 1) {
        stack.push_back({pool[gi], pool[gi + 1], f.level + 1, cx, cy, cz});
        gi += 2;
      } else if (br >> c & 1) {
        fill(f.level + 1, cx, cy, cz, Entry{pool[bi++], 0, int8_t(f.level + 1), 1});
      } else {
        fill(f.level + 1, cx, cy, cz, here);  // a leaf or nothing: resolved at this node
      }
    }
  }
}

OctreeSampler::OctreeSampler(const OctreeTexture& t, const OctreeIndex* index)
    : t_(&t), index_(index), cache_(std::make_unique<Cache>()) {
  for (int k = 0; k < 3; ++k) origin_[k] = t.origin()[k];
  scale_ = double(1u << kD) / double(t.size());
}

OctreeSampler::~OctreeSampler() = default;
OctreeSampler::OctreeSampler(OctreeSampler&&) noexcept = default;
OctreeSampler& OctreeSampler::operator=(OctreeSampler&&) noexcept = default;

void OctreeSampler::reset() {
  *cache_ = Cache{};
}

bool OctreeSampler::nearest_at(uint32_t x, uint32_t y, uint32_t z, const float* n, Rgba8& out,
                               int* level) {
  out = t_->background();
  const uint32_t* pool = t_->words().data();
  return fast_walk() ? walk_nearest_fast(pool, index_, *cache_, x, y, z, n, out, level)
                     : walk_nearest_generic(pool, index_, *cache_, x, y, z, n, out, level);
}

bool OctreeSampler::nearest(const float p[3], const float* n, Rgba8& out, int* level) {
  uint32_t c[3];
  for (int k = 0; k < 3; ++k) {
    // Divided, not multiplied by a reciprocal: the cell a point falls in must be the one
    // u = (p - origin) / size names, to the last bit.
    const double u = (double(p[k]) - origin_[k]) * scale_;
    if (!(u >= 0.0 && u < double(1u << kD))) {
      out = t_->background();
      if (level) *level = 0;
      return false;
    }
    c[k] = uint32_t(u);
  }
  return nearest_at(c[0], c[1], c[2], n, out, level);
}

bool OctreeSampler::cell_value(uint32_t x, uint32_t y, uint32_t z, int level, const float* n,
                               Rgba8& out) {
  const uint32_t* pool = t_->words().data();
  out = t_->background();
  uint32_t ptr = pool[0], info = pool[1];
  if (level == 0) {
    if (!octree::occupied(info)) return false;
    out = pool[ptr + 2 * uint32_t(std::popcount(octree::generals(info))) +
               uint32_t(std::popcount(octree::bricks(info)))];
    return true;
  }
  for (int l = 0;; ++l) {
    const uint32_t bit = 1u << octant(x, y, z, kD - 1 - l);
    if (!(info & bit)) return false;
    const uint32_t below = bit - 1, gen = octree::generals(info), br = octree::bricks(info);
    const uint32_t after_gen = ptr + 2 * uint32_t(std::popcount(gen));
    if (gen & bit) {
      const uint32_t i = ptr + 2 * uint32_t(std::popcount(gen & below));
      ptr = pool[i], info = pool[i + 1];
      if (l + 1 == level) {
        out = pool[ptr + 2 * uint32_t(std::popcount(octree::generals(info))) +
                   uint32_t(std::popcount(octree::bricks(info)))];
        return true;
      }
      continue;
    }
    if (br & bit) {
      const uint32_t w = pool[after_gen + uint32_t(std::popcount(br & below))];
      const uint32_t bp = w & ~kFlag, hdr = (w & kFlag) ? 4 : 2;
      if (l + 1 == level) {
        out = pool[bp + hdr];
        return true;
      }
      if (l + 2 == level) {
        // A brick's inner node: its cells are contiguous in Morton order, so its average is
        // one short run of samples (a two-sided cell counts once, the mean of its sides).
        const uint64_t mask = uint64_t(pool[bp]) | uint64_t(pool[bp + 1]) << 32;
        const uint64_t dbl =
            (w & kFlag) ? uint64_t(pool[bp + 2]) | uint64_t(pool[bp + 3]) << 32 : 0;
        const uint32_t c1 = octant(x, y, z, kD - 2 - l);
        if (!(mask >> (8 * c1) & 255u)) return false;
        const uint64_t lo = (uint64_t(1) << (8 * c1)) - 1;
        uint32_t at = bp + hdr + 1 + uint32_t(std::popcount(mask) + 7) / 8 +
                      uint32_t(std::popcount(mask & lo) + std::popcount(dbl & lo));
        Rgba8 cells[8];
        size_t count = 0;
        for (int c2 = 0; c2 < 8; ++c2) {
          const int m = 8 * int(c1) + c2;
          if (!(mask >> m & 1)) continue;
          cells[count++] = (dbl >> m & 1) ? premul_mean(pool + at, 2) : pool[at];
          at += (dbl >> m & 1) ? 2 : 1;
        }
        out = premul_mean(cells, count);
        return true;
      }
      return brick_leaf_sample(pool, w, l + 1, x, y, z, n, out);
    }
    const uint32_t lf = octree::leaves(info), dbl = octree::doubles(info);
    const uint32_t base = after_gen + uint32_t(std::popcount(br)) + 1;
    const uint32_t r = uint32_t(std::popcount(lf & below));
    const uint32_t si = r + uint32_t(std::popcount(dbl & below));
    const uint32_t tag = pool[base + r / 8] >> (4 * (r % 8)) & 15u;
    const int side = leaf_side(tag, n);
    if (side && !(dbl & bit)) return false;
    out = pool[base + (uint32_t(std::popcount(lf)) + 7) / 8 + si + uint32_t(side)];
    return true;
  }
}

// Accumulates the 8 taps around u at `level`: acc = premultiplied rgb, alpha, weight.
bool OctreeSampler::trilinear(const double u[3], int level, const float* n, bool averages,
                              float acc[5]) {
  const uint32_t* pool = t_->words().data();
  if (!averages) {
    int deepest = level, reach = level;
    return fast_walk()
               ? walk_trilinear_fast(pool, index_, *cache_, u, level, n, acc, deepest, reach)
               : walk_trilinear_generic(pool, index_, *cache_, u, level, n, acc, deepest, reach);
  }
  // Mip levels (node averages): not the hot path.
  const double cells = double(1u << level);
  int64_t i0[3];
  double t[3];
  for (int k = 0; k < 3; ++k) {
    const double g = u[k] * cells - 0.5;
    const double f = std::floor(g);
    i0[k] = int64_t(f), t[k] = g - f;
  }
  const int64_t hi = int64_t(1) << level;
  const int shift = kD - level;
  const uint32_t half = shift > 0 ? 1u << (shift - 1) : 0;
  bool any = false;
  for (int corner = 0; corner < 8; ++corner) {
    int64_t ic[3];
    double w = 1;
    for (int k = 0; k < 3; ++k) {
      const int d = corner >> k & 1;
      ic[k] = i0[k] + d;
      w *= d ? t[k] : 1 - t[k];
    }
    if (w <= 0) continue;
    if (ic[0] < 0 || ic[1] < 0 || ic[2] < 0 || ic[0] >= hi || ic[1] >= hi || ic[2] >= hi) continue;
    const uint32_t x = (uint32_t(ic[0]) << shift) + half, y = (uint32_t(ic[1]) << shift) + half,
                   z = (uint32_t(ic[2]) << shift) + half;
    Rgba8 c;
    if (!cell_value(x, y, z, level, n, c)) continue;
    const float a = float(channel(c, 3)) / 255.0f, fw = float(w);
    acc[0] += fw * a * float(channel(c, 0)) / 255.0f;
    acc[1] += fw * a * float(channel(c, 1)) / 255.0f;
    acc[2] += fw * a * float(channel(c, 2)) / 255.0f;
    acc[3] += fw * a;
    acc[4] += fw;
    any = true;
  }
  return any;
}

bool OctreeSampler::filtered(const float p[3], const float* n, float footprint, float rgba[4]) {
  rgba[0] = rgba[1] = rgba[2] = rgba[3] = 0;
  double u[3];
  uint32_t c[3];
  for (int k = 0; k < 3; ++k) {
    // The cell nearest() would find: u scaled back by a power of two, exactly.
    const double v = (double(p[k]) - origin_[k]) * scale_;
    u[k] = v / double(1u << kD);
    if (!(u[k] >= 0 && u[k] < 1)) return false;
    c[k] = uint32_t(v);
  }
  int leaf_level = 0;
  float acc[5] = {0, 0, 0, 0, 0};
  const uint32_t* pool = t_->words().data();
  const double size = double(t_->size());
  int at_leaf =
      fast_walk()
          ? walk_filtered_fast(pool, index_, *cache_, c, u, n, footprint, size, leaf_level, acc)
          : walk_filtered_generic(pool, index_, *cache_, c, u, n, footprint, size, leaf_level, acc);
  bool any = at_leaf > 0;
  if (at_leaf < 0) {
    const double lf =
        std::clamp(std::log2(double(t_->size()) / double(footprint)), 0.0, double(leaf_level));
    const int l0 = int(std::floor(lf));
    const double frac = lf - l0;
    float a0[5] = {0, 0, 0, 0, 0}, a1[5] = {0, 0, 0, 0, 0};
    const bool h0 = trilinear(u, l0, n, true, a0);
    const bool h1 =
        frac > 0 && l0 + 1 <= leaf_level && trilinear(u, l0 + 1, n, l0 + 1 < leaf_level, a1);
    any = h0 || h1;
    // Each level renormalised on its own, then blended.
    for (int k = 0; k < 4; ++k) {
      const float v0 = a0[4] > 0 ? a0[k] / a0[4] : 0, v1 = a1[4] > 0 ? a1[k] / a1[4] : 0;
      const float w0 = h0 ? float(1 - frac) : 0, w1 = h1 ? float(frac) : 0;
      acc[k] = w0 * v0 + w1 * v1;
    }
    acc[4] = (h0 ? float(1 - frac) : 0) + (h1 ? float(frac) : 0);
  }
  if (!any || !(acc[4] > 0)) return false;
  const float alpha = acc[3] / acc[4];
  if (acc[3] > 0)
    for (int k = 0; k < 3; ++k) rgba[k] = std::clamp(acc[k] / acc[3], 0.0f, 1.0f);
  rgba[3] = std::clamp(alpha, 0.0f, 1.0f);
  return true;
}

bool OctreeSampler::prefetch_group(const float* p, size_t count, bool prefetch) {
  uint32_t xyz[3 * 16] = {};
  size_t m = 0, near = 0;
  uint32_t last[3] = {0, 0, 0};
  for (size_t i = 0; i < count; ++i) {
    bool inside = true;
    uint32_t c[3];
    for (int k = 0; k < 3; ++k) {
      const double u = (double(p[3 * i + size_t(k)]) - origin_[k]) * scale_;
      inside = inside && u >= 0.0 && u < double(1u << kD);
      c[k] = inside ? uint32_t(u) : 0;
    }
    if (!inside) continue;
    // Neighbours: in the same level-8 cell as the point before.
    near += m > 0 && ((c[0] ^ last[0]) | (c[1] ^ last[1]) | (c[2] ^ last[2])) >> (kD - 8) == 0;
    for (int k = 0; k < 3; ++k) xyz[3 * m + size_t(k)] = last[k] = c[k];
    ++m;
  }
  if (prefetch) prefetch_coords(xyz, m);
  return m > 1 && 4 * near >= 3 * (m - 1);
}

void OctreeSampler::prefetch_coords(const uint32_t* xyz, size_t count) {
  // Walk state per point: the node to read next (a general node, or a brick).
  struct Walk {
    uint32_t ptr, info;
    int level;
    bool brick, live, pending;
  };
  constexpr size_t kGroup = 32;
  const uint32_t* pool = t_->words().data();
  for (size_t g = 0; g < count; g += kGroup) {
    const size_t m = std::min(kGroup, count - g);
    const uint32_t* c = xyz + 3 * g;
    Walk w[kGroup];
    for (size_t i = 0; i < m; ++i) {
      Walk& s = w[i];
      s.live = true, s.brick = false, s.pending = false;
      if (index_) {
        const int il = index_->level();
        __builtin_prefetch(&index_->at(c[3 * i] >> (kD - il), c[3 * i + 1] >> (kD - il),
                                       c[3 * i + 2] >> (kD - il)));
        s.pending = true;  // the entry is read next round, once it has arrived
      } else {
        s.ptr = pool[0], s.info = pool[1], s.level = 0;
      }
    }
    for (int round = 0; round <= kD + 1; ++round) {
      bool any = false;
      for (size_t i = 0; i < m; ++i) {
        Walk& s = w[i];
        if (!s.live) continue;
        const uint32_t x = c[3 * i], y = c[3 * i + 1], z = c[3 * i + 2];
        if (s.pending) {
          const int il = index_->level();
          const OctreeIndex::Entry& e = index_->at(x >> (kD - il), y >> (kD - il), z >> (kD - il));
          s.ptr = e.ptr, s.info = e.info, s.level = e.level, s.brick = e.brick, s.pending = false;
        } else if (s.brick) {
          s.live = false;  // its block was fetched last round
          continue;
        } else {
          const uint32_t bit = 1u << octant(x, y, z, kD - 1 - s.level);
          const uint32_t gen = octree::generals(s.info), br = octree::bricks(s.info);
          if (gen & bit) {
            const uint32_t at = s.ptr + 2 * uint32_t(std::popcount(gen & (bit - 1)));
            s.ptr = pool[at], s.info = pool[at + 1], ++s.level;
          } else if (br & bit) {
            s.ptr = pool[s.ptr + 2 * uint32_t(std::popcount(gen)) +
                         uint32_t(std::popcount(br & (bit - 1)))];
            s.brick = true, ++s.level;
          } else {
            s.live = false;  // a leaf or nothing: in the block already fetched
            continue;
          }
        }
        const uint32_t at = s.brick ? (s.ptr & ~kFlag) : s.ptr;
        __builtin_prefetch(pool + at);
        if (s.brick) __builtin_prefetch(pool + at + 16);  // mask, tags, samples: two lines
        any = true;
      }
      if (!any) break;
    }
  }
}

void OctreeSampler::nearest_batch(const float* p, const float* n, size_t count, Rgba8* out,
                                  uint8_t* found) {
  // Points that follow a path hit the cache: prefetching their walks only costs the walks.
  bool coherent = false;
  for (size_t g = 0; g < count; g += 16) {
    const size_t m = std::min<size_t>(16, count - g);
    coherent = prefetch_group(p + 3 * g, m, !coherent);
    for (size_t i = g; i < g + m; ++i) {
      const bool f = nearest(p + 3 * i, n ? n + 3 * i : nullptr, out[i]);
      if (found) found[i] = f;
    }
  }
}

void OctreeSampler::filtered_batch(const float* p, const float* n, size_t count, float footprint,
                                   float* rgba, uint8_t* found) {
  // Points that follow a path hit the cache: prefetching their walks only costs the walks.
  bool coherent = false;
  for (size_t g = 0; g < count; g += 16) {
    const size_t m = std::min<size_t>(16, count - g);
    coherent = prefetch_group(p + 3 * g, m, !coherent);
    for (size_t i = g; i < g + m; ++i) {
      const bool f = filtered(p + 3 * i, n ? n + 3 * i : nullptr, footprint, rgba + 4 * i);
      if (found) found[i] = f;
    }
  }
}

bool lookup_nearest(const OctreeTexture& t, const float p[3], const float* n, Rgba8& out) {
  OctreeSampler s(t);
  return s.nearest(p, n, out);
}

bool lookup_filtered(const OctreeTexture& t, const float p[3], const float* n, float footprint,
                     float rgba[4]) {
  OctreeSampler s(t);
  return s.filtered(p, n, footprint, rgba);
}

}  // namespace limn
