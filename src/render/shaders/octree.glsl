// octree: `vec3 oct_paint(base, pos, nrm)`, the octree texture lookup (a no-op unless a
// GpuOctreeTexture is bound to the program), shared by the drawers and the lookup shader. Line for
// line the walks of src/paint/octree_walk.cpp and lookup.cpp (nearest, cell_value, filtered);
// 64-bit brick masks as two words. Coordinates in double, as there, so both pick the same cells.
layout(std430, binding = 5) readonly buffer OctreePool { uint pool[]; };
uniform dvec3 oct_origin;
uniform double oct_scale;  // 65536 / size
uniform float oct_size;
uniform uint oct_background;
uniform int oct_mode;  // 0: no texture, 1: nearest, 2: filtered
uniform vec3 oct_tags[15];

const int kD = 16;
const uint kFlag = 0x80000000u;

uint oct_octant(uvec3 c, int shift) {
  return ((c.x >> shift) & 1u) | ((c.y >> shift) & 1u) << 1 | ((c.z >> shift) & 1u) << 2;
}
int oct_side(uint tag, vec3 n) {
  if (tag == 0u) return 0;
  vec3 d = oct_tags[tag];
  return d.x * n.x + d.y * n.y + d.z * n.z >= 0.0 ? 0 : 1;
}
bool oct_bit64(uvec2 m, int k) {
  return k < 32 ? ((m.x >> k) & 1u) != 0u : ((m.y >> (k - 32)) & 1u) != 0u;
}
// Byte k (0-7) of a 64-bit mask: the 8 cells of a brick's level + 1 cell k.
uint oct_byte64(uvec2 m, int k) {
  return k < 4 ? (m.x >> (8 * k)) & 255u : (m.y >> (8 * (k - 4))) & 255u;
}
uint oct_below64(uvec2 m, int k) {
  if (k < 32) return uint(bitCount(m.x & ((1u << k) - 1u)));
  return uint(bitCount(m.x)) + uint(bitCount(m.y & ((1u << (k - 32)) - 1u)));
}
vec4 oct_unpack(uint c) {
  return vec4(float(c & 255u), float((c >> 8) & 255u), float((c >> 16) & 255u),
              float(c >> 24)) / 255.0;
}

// ended: the level of the leaf, or of the coarsest cell holding no leaf (the brick's level + 1
// cell when its mask byte is empty).
bool oct_brick_leaf(uint word, int level, uvec3 c, vec3 n, out uint col, out int ended) {
  col = oct_background;
  uint bp = word & ~kFlag;
  uvec2 mask = uvec2(pool[bp], pool[bp + 1u]);
  int m = int(oct_octant(c, kD - 1 - level) * 8u + oct_octant(c, kD - 2 - level));
  ended = level + 2;
  if (!oct_bit64(mask, m)) {
    if (oct_byte64(mask, m >> 3) == 0u) ended = (mask.x | mask.y) != 0u ? level + 1 : level;
    return false;
  }
  uvec2 dbl = uvec2(0u);
  uint base = bp + 3u;
  if ((word & kFlag) != 0u) {
    dbl = uvec2(pool[bp + 2u], pool[bp + 3u]);
    base = bp + 5u;
  }
  uint r = oct_below64(mask, m);
  uint si = r + oct_below64(dbl, m);
  uint tag = (pool[base + r / 8u] >> (4u * (r % 8u))) & 15u;
  int side = oct_side(tag, n);
  if (side != 0 && !oct_bit64(dbl, m)) return false;
  uint count = uint(bitCount(mask.x)) + uint(bitCount(mask.y));
  col = pool[base + (count + 7u) / 8u + si + uint(side)];
  return true;
}

// The sample facing n of leaf cell `bit` of a general node with the given info, whose tags start
// at `base` (after its descriptors, brick words and average).
bool oct_general_leaf(uint base, uint info, uint bit, vec3 n, out uint col) {
  col = oct_background;
  uint lf = (info >> 8) & 255u, dbl = info >> 24, below = bit - 1u;
  uint r = uint(bitCount(lf & below));
  uint si = r + uint(bitCount(dbl & below));
  uint tag = (pool[base + r / 8u] >> (4u * (r % 8u))) & 15u;
  int side = oct_side(tag, n);
  if (side != 0 && (dbl & bit) == 0u) return false;
  col = pool[base + (uint(bitCount(lf)) + 7u) / 8u + si + uint(side)];
  return true;
}

// OctreeSampler::nearest_at: the leaf holding c (level-16 coordinates), its sample facing n.
bool oct_nearest_at(uvec3 c, vec3 n, out uint col, out int level) {
  col = oct_background;
  level = 0;
  uint ptr = pool[0], info = pool[1];
  for (int l = 0; l < kD; ++l) {
    uint bit = 1u << oct_octant(c, kD - 1 - l);
    level = l + 1;
    if ((info & bit) == 0u) return false;
    uint below = bit - 1u;
    uint lf = (info >> 8) & 255u, br = (info >> 16) & 255u;
    uint gen = info & 255u & ~lf & ~br;
    if ((gen & bit) != 0u) {
      uint i = ptr + 2u * uint(bitCount(gen & below));
      ptr = pool[i];
      info = pool[i + 1u];
      continue;
    }
    uint after_gen = ptr + 2u * uint(bitCount(gen));
    if ((br & bit) != 0u) {
      uint w = pool[after_gen + uint(bitCount(br & below))];
      return oct_brick_leaf(w, l + 1, c, n, col, level);
    }
    return oct_general_leaf(after_gen + uint(bitCount(br)) + 1u, info, bit, n, col);
  }
  return false;
}

// Premultiplied mean of a short run of samples, rounded as the CPU does.
uint oct_premul_mean(uint v[8], uint k) {
  double r = 0.0, g = 0.0, b = 0.0, a = 0.0;
  for (uint i = 0u; i < k; ++i) {
    uint s = v[i];
    double al = double(s >> 24);
    r += double(s & 255u) * al;
    g += double((s >> 8) & 255u) * al;
    b += double((s >> 16) & 255u) * al;
    a += al;
  }
  if (a <= 0.0) return 0u;
  uint qr = uint(clamp(floor(r / a + 0.5), 0.0, 255.0));
  uint qg = uint(clamp(floor(g / a + 0.5), 0.0, 255.0));
  uint qb = uint(clamp(floor(b / a + 0.5), 0.0, 255.0));
  uint qa = uint(clamp(floor(a / double(k) + 0.5), 0.0, 255.0));
  return qr | qg << 8 | qb << 16 | qa << 24;
}
uint oct_mean2(uint s0, uint s1) {
  uint v[8];
  v[0] = s0;
  v[1] = s1;
  return oct_premul_mean(v, 2u);
}

// OctreeSampler::cell_value: the leaf at or above `level` holding c, or the node average there.
bool oct_cell_value(uvec3 c, int level, vec3 n, out uint col) {
  col = oct_background;
  uint ptr = pool[0], info = pool[1];
  if (level == 0) {
    if ((info & 255u) == 0u) return false;
    uint gen0 = info & 255u & ~((info >> 8) & 255u) & ~((info >> 16) & 255u);
    col = pool[ptr + 2u * uint(bitCount(gen0)) + uint(bitCount((info >> 16) & 255u))];
    return true;
  }
  for (int l = 0; l < kD; ++l) {
    uint bit = 1u << oct_octant(c, kD - 1 - l);
    if ((info & bit) == 0u) return false;
    uint below = bit - 1u;
    uint lf = (info >> 8) & 255u, br = (info >> 16) & 255u;
    uint gen = info & 255u & ~lf & ~br;
    uint after_gen = ptr + 2u * uint(bitCount(gen));
    if ((gen & bit) != 0u) {
      uint i = ptr + 2u * uint(bitCount(gen & below));
      ptr = pool[i];
      info = pool[i + 1u];
      if (l + 1 == level) {
        uint g2 = info & 255u & ~((info >> 8) & 255u) & ~((info >> 16) & 255u);
        col = pool[ptr + 2u * uint(bitCount(g2)) + uint(bitCount((info >> 16) & 255u))];
        return true;
      }
      continue;
    }
    if ((br & bit) != 0u) {
      uint w = pool[after_gen + uint(bitCount(br & below))];
      uint bp = w & ~kFlag, hdr = (w & kFlag) != 0u ? 4u : 2u;
      if (l + 1 == level) {
        col = pool[bp + hdr];
        return true;
      }
      if (l + 2 == level) {
        uvec2 mask = uvec2(pool[bp], pool[bp + 1u]);
        uvec2 dm = (w & kFlag) != 0u ? uvec2(pool[bp + 2u], pool[bp + 3u]) : uvec2(0u);
        int c1 = int(oct_octant(c, kD - 2 - l));
        if (oct_byte64(mask, c1) == 0u) return false;
        uint count = uint(bitCount(mask.x)) + uint(bitCount(mask.y));
        uint at = bp + hdr + 1u + (count + 7u) / 8u + oct_below64(mask, 8 * c1) +
                  oct_below64(dm, 8 * c1);
        uint cells[8];
        uint k = 0u;
        for (int c2 = 0; c2 < 8; ++c2) {
          int m = 8 * c1 + c2;
          if (!oct_bit64(mask, m)) continue;
          bool two = oct_bit64(dm, m);
          cells[k++] = two ? oct_mean2(pool[at], pool[at + 1u]) : pool[at];
          at += two ? 2u : 1u;
        }
        col = oct_premul_mean(cells, k);
        return true;
      }
      int ended;
      return oct_brick_leaf(w, l + 1, c, n, col, ended);
    }
    return oct_general_leaf(after_gen + uint(bitCount(br)) + 1u, info, bit, n, col);
  }
  return false;
}

// The 8 taps around u at `level`: acc = premultiplied rgb, alpha; weight in acc_w.
// deepest: rises to the level of a finer leaf whose sample a tap read, reach: to the deepest
// level a tap's walk ended at (leaf taps only).
bool oct_trilinear(dvec3 u, int level, vec3 n, bool averages, inout vec4 acc, inout float acc_w,
                   inout int deepest, inout int reach) {
  double cells = double(1u << level);
  dvec3 g = u * cells - 0.5;
  dvec3 f = floor(g);
  ivec3 i0 = ivec3(f);
  dvec3 t = g - f;
  int hi = 1 << level;
  int shift = kD - level;
  uint half_cell = shift > 0 ? 1u << (shift - 1) : 0u;
  bool hit = false;
  for (int corner = 0; corner < 8; ++corner) {
    ivec3 ic;
    double w = 1.0;
    for (int k = 0; k < 3; ++k) {
      int d = (corner >> k) & 1;
      ic[k] = i0[k] + d;
      w *= d != 0 ? t[k] : 1.0 - t[k];
    }
    if (w <= 0.0) continue;
    if (any(lessThan(ic, ivec3(0))) || any(greaterThanEqual(ic, ivec3(hi)))) continue;
    uvec3 x = (uvec3(ic) << uint(shift)) + half_cell;
    uint c;
    int lv;
    lv = level;
    bool found = averages ? oct_cell_value(x, level, n, c) : oct_nearest_at(x, n, c, lv);
    reach = max(reach, lv);
    if (!found) continue;
    if (!averages) deepest = max(deepest, lv);
    float a = float(c >> 24) / 255.0, fw = float(w);
    acc.r += fw * a * float(c & 255u) / 255.0;
    acc.g += fw * a * float((c >> 8) & 255u) / 255.0;
    acc.b += fw * a * float((c >> 16) & 255u) / 255.0;
    acc.a += fw * a;
    acc_w += fw;
    hit = true;
  }
  return hit;
}

bool oct_cell(vec3 p, out uvec3 c, out dvec3 u) {
  dvec3 s = (dvec3(p) - oct_origin) * oct_scale;
  u = s / 65536.0;
  c = uvec3(0u);
  if (!(all(greaterThanEqual(s, dvec3(0.0))) && all(lessThan(s, dvec3(65536.0))))) return false;
  c = uvec3(s);
  return true;
}

// OctreeSampler::nearest.
bool oct_nearest(vec3 p, vec3 n, out uint col, out int level) {
  uvec3 c;
  dvec3 u;
  col = oct_background;
  level = 0;
  if (!oct_cell(p, c, u)) return false;
  return oct_nearest_at(c, n, col, level);
}

// OctreeSampler::filtered: straight rgba.
bool oct_filtered(vec3 p, vec3 n, float footprint, out vec4 rgba) {
  rgba = vec4(0.0);
  uvec3 c;
  dvec3 u;
  if (!oct_cell(p, c, u)) return false;
  uint col;
  int leaf_level;
  // Whatever its sides (a zero normal reads the front sample every leaf has).
  bool at_leaf = oct_nearest_at(c, vec3(0.0), col, leaf_level);
  vec4 acc = vec4(0.0);
  float acc_w = 0.0;
  bool hit;
  // OctreeSampler::filtered: a tap reading a finer leaf's sample moves the filter to that level;
  // p where no leaf is (off the painted surface): one finer while a tap's cell holds finer leaves.
  bool mip = false;
  for (;;) {
    double leaf_size = double(oct_size) / double(1u << leaf_level);
    if (double(footprint) > leaf_size && !isinf(footprint) && !isnan(footprint)) {
      mip = true;
      break;
    }
    acc = vec4(0.0);
    acc_w = 0.0;
    int deepest = leaf_level, reach = leaf_level;
    hit = oct_trilinear(u, leaf_level, n, false, acc, acc_w, deepest, reach);
    if (deepest > leaf_level)
      leaf_level = deepest;
    else if (!at_leaf && reach > leaf_level && leaf_level < kD)
      ++leaf_level;
    else
      break;
  }
  if (mip) {
    int unused = 0, unused_reach = 0;
    float lf = clamp(log2(oct_size / footprint), 0.0, float(leaf_level));
    int l0 = int(floor(lf));
    float frac = lf - float(l0);
    vec4 a0 = vec4(0.0), a1 = vec4(0.0);
    float w0s = 0.0, w1s = 0.0;
    bool h0 = oct_trilinear(u, l0, n, true, a0, w0s, unused, unused_reach);
    bool h1 = frac > 0.0 && l0 + 1 <= leaf_level &&
              oct_trilinear(u, l0 + 1, n, l0 + 1 < leaf_level, a1, w1s, unused, unused_reach);
    hit = h0 || h1;
    vec4 v0 = w0s > 0.0 ? a0 / w0s : vec4(0.0), v1 = w1s > 0.0 ? a1 / w1s : vec4(0.0);
    float w0 = h0 ? 1.0 - frac : 0.0, w1 = h1 ? frac : 0.0;
    acc = w0 * v0 + w1 * v1;
    acc_w = w0 + w1;
  }
  if (!hit || !(acc_w > 0.0)) return false;
  float alpha = acc.a / acc_w;
  if (acc.a > 0.0) rgba.rgb = clamp(acc.rgb / acc.a, 0.0, 1.0);
  rgba.a = clamp(alpha, 0.0, 1.0);
  return true;
}

#ifndef OCT_LOOKUP_ONLY
// A fragment's colour: the texture at its position and normal over `base`, a one-pixel footprint.
vec3 oct_paint(vec3 base, vec3 pos, vec3 nrm) {
  if (oct_mode == 0) return base;
  float footprint = max(length(dFdx(pos)), length(dFdy(pos)));
  vec4 c = oct_unpack(oct_background);
  // A surface drawn from patches lies a little off the triangles it was painted on, and may
  // cross into a cell they never touched: a nearest miss falls back to the filtered lookup,
  // whose taps reach the neighbouring cells.
  uint col;
  int lv;
  vec4 f;
  if (oct_mode == 1 && oct_nearest(pos, nrm, col, lv))
    c = oct_unpack(col);
  else if (oct_filtered(pos, nrm, footprint, f))
    c = f;
  return mix(base, c.rgb, c.a);
}
#endif
