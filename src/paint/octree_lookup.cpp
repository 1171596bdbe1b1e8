// CPU lookups over the pool, the same walk a shader does, plus a last-node cache (the role an
// OpenVDB ValueAccessor plays) so coherent lookups skip the descent.
#include "limn/paint/lookup.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace limn {

namespace {

constexpr int kD = octree::kMaxDepth;
constexpr uint32_t kFlag = octree::kBrickDoubleFlag;

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

inline uint32_t octant(uint32_t x, uint32_t y, uint32_t z, int shift) {
  return (x >> shift & 1u) | (y >> shift & 1u) << 1 | (z >> shift & 1u) << 2;
}

// World point -> integer coordinates at kMaxDepth; false outside the cube.
inline bool to_int(const OctreeTexture& t, const float p[3], uint32_t xyz[3]) {
  for (int k = 0; k < 3; ++k) {
    const double u = (double(p[k]) - double(t.origin()[k])) / double(t.size());
    if (!(u >= 0.0 && u < 1.0)) return false;
    xyz[k] = std::min(uint32_t(u * double(1u << kD)), (1u << kD) - 1);
  }
  return true;
}

Rgba8 premul_mean(const uint32_t* s, size_t count) {
  double r = 0, g = 0, b = 0, a = 0;
  for (size_t i = 0; i < count; ++i) {
    const double al = channel(s[i], 3);
    r += channel(s[i], 0) * al, g += channel(s[i], 1) * al, b += channel(s[i], 2) * al, a += al;
  }
  if (a <= 0) return 0;
  auto q = [](double v) { return uint32_t(std::clamp(std::lround(v), 0l, 255l)); };
  return pack_rgba8(q(r / a), q(g / a), q(b / a), q(a / double(count)));
}

}  // namespace

bool OctreeSampler::brick_leaf(uint32_t word, int level, uint32_t x, uint32_t y, uint32_t z,
                               const float* n, Rgba8& out, int* leaf_level) const {
  const uint32_t* pool = t_->words().data();
  const uint32_t bp = word & ~kFlag;
  const uint64_t mask = uint64_t(pool[bp]) | uint64_t(pool[bp + 1]) << 32;
  const int m = int(octant(x, y, z, kD - 1 - level) * 8 + octant(x, y, z, kD - 2 - level));
  if (leaf_level) *leaf_level = level + 2;
  if (!(mask >> m & 1)) return false;
  const uint64_t below = (uint64_t(1) << m) - 1;
  uint64_t dbl = 0;
  uint32_t base = bp + 3;
  if (word & kFlag) dbl = uint64_t(pool[bp + 2]) | uint64_t(pool[bp + 3]) << 32, base = bp + 5;
  const uint32_t r = uint32_t(std::popcount(mask & below));
  const uint32_t si = r + uint32_t(std::popcount(dbl & below));
  const uint32_t tags = base + uint32_t(std::popcount(mask)) + uint32_t(std::popcount(dbl));
  const uint32_t tag = pool[tags + r / 8] >> (4 * (r % 8)) & 15u;
  const int side = side_of(tag, n);
  if (side && !(dbl >> m & 1)) return false;
  out = pool[base + si + uint32_t(side)];
  return true;
}

bool OctreeSampler::nearest_at(uint32_t x, uint32_t y, uint32_t z, const float* n, Rgba8& out,
                               int* level) {
  const uint32_t* pool = t_->words().data();
  out = t_->background();
  uint32_t ptr, info;
  int l;
  if (cache_level_ >= 0 && (x >> (kD - cache_level_)) == cache_x_ &&
      (y >> (kD - cache_level_)) == cache_y_ && (z >> (kD - cache_level_)) == cache_z_) {
    if (cache_brick_) return brick_leaf(cache_ptr_, cache_level_, x, y, z, n, out, level);
    ptr = cache_ptr_, info = cache_info_, l = cache_level_;
  } else {
    ptr = pool[0], info = pool[1], l = 0;
  }
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
      cache_level_ = l + 1, cache_brick_ = true, cache_ptr_ = w;
      cache_x_ = x >> (kD - l - 1), cache_y_ = y >> (kD - l - 1), cache_z_ = z >> (kD - l - 1);
      return brick_leaf(w, l + 1, x, y, z, n, out, level);
    }
    // A leaf of this general node: remember the node for the next lookup.
    cache_level_ = l, cache_brick_ = false, cache_ptr_ = ptr, cache_info_ = info;
    cache_x_ = l ? x >> (kD - l) : 0, cache_y_ = l ? y >> (kD - l) : 0;
    cache_z_ = l ? z >> (kD - l) : 0;
    const uint32_t lf = octree::leaves(info), dbl = octree::doubles(info);
    const uint32_t base = after_gen + uint32_t(std::popcount(br)) + 1;
    const uint32_t r = uint32_t(std::popcount(lf & below));
    const uint32_t si = r + uint32_t(std::popcount(dbl & below));
    const uint32_t tags = base + uint32_t(std::popcount(lf)) + uint32_t(std::popcount(dbl));
    const uint32_t tag = pool[tags + r / 8] >> (4 * (r % 8)) & 15u;
    const int side = side_of(tag, n);
    if (side && !(dbl & bit)) return false;
    out = pool[base + si + uint32_t(side)];
    return true;
  }
}

bool OctreeSampler::nearest(const float p[3], const float* n, Rgba8& out, int* level) {
  uint32_t c[3];
  if (!to_int(*t_, p, c)) {
    out = t_->background();
    if (level) *level = 0;
    return false;
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
        // one short run of samples.
        const uint64_t mask = uint64_t(pool[bp]) | uint64_t(pool[bp + 1]) << 32;
        const uint64_t dbl =
            (w & kFlag) ? uint64_t(pool[bp + 2]) | uint64_t(pool[bp + 3]) << 32 : 0;
        const uint32_t c1 = octant(x, y, z, kD - 2 - l);
        if (!(mask >> (8 * c1) & 255u)) return false;
        const uint64_t lo = (uint64_t(1) << (8 * c1)) - 1;
        const uint64_t hi = c1 == 7 ? ~uint64_t(0) : (uint64_t(1) << (8 * c1 + 8)) - 1;
        const uint32_t first = uint32_t(std::popcount(mask & lo) + std::popcount(dbl & lo));
        const uint32_t last = uint32_t(std::popcount(mask & hi) + std::popcount(dbl & hi));
        out = premul_mean(pool + bp + hdr + 1 + first, last - first);
        return true;
      }
      return brick_leaf(w, l + 1, x, y, z, n, out, nullptr);
    }
    const uint32_t lf = octree::leaves(info), dbl = octree::doubles(info);
    const uint32_t base = after_gen + uint32_t(std::popcount(br)) + 1;
    const uint32_t r = uint32_t(std::popcount(lf & below));
    const uint32_t si = r + uint32_t(std::popcount(dbl & below));
    const uint32_t tags = base + uint32_t(std::popcount(lf)) + uint32_t(std::popcount(dbl));
    const uint32_t tag = pool[tags + r / 8] >> (4 * (r % 8)) & 15u;
    const int side = side_of(tag, n);
    if (side && !(dbl & bit)) return false;
    out = pool[base + si + uint32_t(side)];
    return true;
  }
}

// Accumulates the 8 taps around u at `level`: acc = premultiplied rgb, alpha, weight.
bool OctreeSampler::trilinear(const double u[3], int level, const float* n, bool averages,
                              float acc[5]) {
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
    // The tap's centre at kMaxDepth resolution.
    const uint32_t half = shift > 0 ? 1u << (shift - 1) : 0;
    const uint32_t x = (uint32_t(ic[0]) << shift) + half, y = (uint32_t(ic[1]) << shift) + half,
                   z = (uint32_t(ic[2]) << shift) + half;
    Rgba8 c;
    const bool ok =
        averages ? cell_value(x, y, z, level, n, c) : nearest_at(x, y, z, n, c, nullptr);
    if (!ok) continue;
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
  t_->to_unit(p, u);
  if (!(u[0] >= 0 && u[0] < 1 && u[1] >= 0 && u[1] < 1 && u[2] >= 0 && u[2] < 1)) return false;
  Rgba8 c;
  int leaf_level = 0;
  nearest(p, n, c, &leaf_level);
  float acc[5] = {0, 0, 0, 0, 0};
  bool any;
  const double leaf_size = double(t_->size()) / double(1u << leaf_level);
  if (!(footprint > leaf_size) || !std::isfinite(footprint)) {
    any = trilinear(u, leaf_level, n, false, acc);
  } else {
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
