// Small geometric kernels the paint layer shares: box-triangle overlap, closest point on a
// triangle; Morton codes from limn/mesh/morton.hpp. Internal header.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/closest_point.hpp"
#include "core/vec3.hpp"
#include "limn/mesh/morton.hpp"

namespace limn::paint_detail {

using V3 = Vec3f;
inline V3 v3(const float* p) {
  return load3<float>(p);
}

// Separating-axis test of a triangle against an axis-aligned box given by its centre and half
// size (Akenine-Moller, "Fast 3D triangle-box overlap testing", 2001: the 3 box axes, the
// triangle normal and the 9 edge cross products). Touching counts as overlapping, and the box is
// grown by `slack` so a surface lying exactly on a cell face belongs to both cells: a point on the
// surface then always finds a cell holding it, whichever way floor() rounds.
inline bool tri_box_overlap(V3 c, float h, V3 a, V3 b, V3 d, float slack) {
  const float e = h + slack;
  const V3 v0 = a - c, v1 = b - c, v2 = d - c;
  // Box axes: the triangle's extent against the box's.
  if (std::min({v0.x, v1.x, v2.x}) > e || std::max({v0.x, v1.x, v2.x}) < -e) return false;
  if (std::min({v0.y, v1.y, v2.y}) > e || std::max({v0.y, v1.y, v2.y}) < -e) return false;
  if (std::min({v0.z, v1.z, v2.z}) > e || std::max({v0.z, v1.z, v2.z}) < -e) return false;
  const V3 e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
  // Triangle normal: the plane's distance to the box centre against the box's projected radius.
  const V3 n = cross(e0, e1);
  const float rn = e * (std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z));
  const float dn = dot(n, v0);
  if (dn > rn || dn < -rn) return false;
  // Edge x box-axis cross products.
  const V3 edges[3] = {e0, e1, e2};
  const V3 verts[3] = {v0, v1, v2};
  for (const V3& f : edges) {
    const V3 axes[3] = {{0, -f.z, f.y}, {f.z, 0, -f.x}, {-f.y, f.x, 0}};
    for (const V3& ax : axes) {
      const float p0 = dot(ax, verts[0]), p1 = dot(ax, verts[1]), p2 = dot(ax, verts[2]);
      const float r = e * (std::fabs(ax.x) + std::fabs(ax.y) + std::fabs(ax.z));
      if (std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r) return false;
    }
  }
  return true;
}

// A quick sufficient test for tri_box_overlap: true only when tri_box_overlap(c, h, a, b, d, slack)
// is true, found from the vertices alone (it does not decide the other cases). With e = h + slack
// and v = vertex - c as tri_box_overlap computes them, every |v_k| <= e (1 - 2^-10) makes each of
// its projections |sum ax_k v_k| <= (1 - 2^-10) e sum |ax_k| plus a few units of rounding, below
// the radius e sum |ax_k| it compares against (less a few units): no axis separates. (e > 1e-12
// keeps the products far from underflow.)
// tri_inside_box's bound on each corner's offset from the centre (m); false where the box is
// too small for it. Shared with the refiner's list-wide form of the test, which must use the
// same float operations.
inline bool inside_margin(float h, float slack, float& m) {
  const float e = h + slack;
  if (!(e > 1e-12f)) return false;
  m = e * (1.0f - 1.0f / 1024.0f);
  return true;
}

inline bool tri_inside_box(V3 c, float h, V3 a, V3 b, V3 d, float slack) {
  float m;
  if (!inside_margin(h, slack, m)) return false;
  const V3 v0 = a - c, v1 = b - c, v2 = d - c;
  return std::fabs(v0.x) <= m && std::fabs(v0.y) <= m && std::fabs(v0.z) <= m &&
         std::fabs(v1.x) <= m && std::fabs(v1.y) <= m && std::fabs(v1.z) <= m &&
         std::fabs(v2.x) <= m && std::fabs(v2.y) <= m && std::fabs(v2.z) <= m;
}

// Whether a triangle meets a box as the paint layer decides it everywhere (cell lists, box
// queries, splits): the quick containment test, else the separating-axis test.
inline bool tri_meets_box(V3 c, float h, V3 a, V3 b, V3 d, float slack) {
  return tri_inside_box(c, h, a, b, d, slack) || tri_box_overlap(c, h, a, b, d, slack);
}

// tri_box_overlap against 8 boxes of one half size h at once (centres cx[k], cy[k], cz[k]): bit k
// set when tri_box_overlap(box k) is true. Lane by lane the same float operations in the same
// order, so the same answers; the edge axes' zero components are left out (each adds a signed
// zero to a product, which changes no comparison). Written with GCC vector types so that a
// caller compiled for AVX does 8 lanes at a time and any other does two halves; always inlined
// into such a caller (no vector crosses a call, so no ABI question).
using F8 = float __attribute__((vector_size(32)));
using I8 = int32_t __attribute__((vector_size(32)));

// Bit k set where lane k of a comparison result is true: or-reduced in three shuffles (a
// lane-by-lane loop was 4 instructions a lane). By reference and always inlined: no vector
// crosses a call.
__attribute__((always_inline)) inline uint32_t lane_bits(const I8& ok) {
  const I8 lane_bit = {1, 2, 4, 8, 16, 32, 64, 128};
  I8 m = ok & lane_bit;
#if defined(__clang__)
  m |= __builtin_shufflevector(m, m, 4, 5, 6, 7, 0, 1, 2, 3);
  m |= __builtin_shufflevector(m, m, 2, 3, 0, 1, 6, 7, 4, 5);
  m |= __builtin_shufflevector(m, m, 1, 0, 3, 2, 5, 4, 7, 6);
#else
  const I8 halves = {4, 5, 6, 7, 0, 1, 2, 3}, pairs = {2, 3, 0, 1, 6, 7, 4, 5},
           ones = {1, 0, 3, 2, 5, 4, 7, 6};
  m |= __builtin_shuffle(m, halves);
  m |= __builtin_shuffle(m, pairs);
  m |= __builtin_shuffle(m, ones);
#endif
  return uint32_t(m[0]);
}

__attribute__((always_inline)) inline uint32_t tri_box_overlap8(const float* cx, const float* cy,
                                                                const float* cz, float h, V3 a,
                                                                V3 b, V3 d, float slack) {
  const float e = h + slack;
  F8 x, y, z;
  __builtin_memcpy(&x, cx, sizeof x);
  __builtin_memcpy(&y, cy, sizeof y);
  __builtin_memcpy(&z, cz, sizeof z);
  const F8 v0x = a.x - x, v0y = a.y - y, v0z = a.z - z;
  const F8 v1x = b.x - x, v1y = b.y - y, v1z = b.z - z;
  const F8 v2x = d.x - x, v2y = d.y - y, v2z = d.z - z;
#define LIMN_MIN3(p, q, r) ((p) < (q) ? ((p) < (r) ? (p) : (r)) : ((q) < (r) ? (q) : (r)))
#define LIMN_MAX3(p, q, r) ((p) > (q) ? ((p) > (r) ? (p) : (r)) : ((q) > (r) ? (q) : (r)))
#define LIMN_ABS(v) ((F8)((I8)(v)&0x7fffffff))
  // Box axes.
  I8 ok = ~(LIMN_MIN3(v0x, v1x, v2x) > e) & ~(LIMN_MAX3(v0x, v1x, v2x) < -e);
  ok &= ~(LIMN_MIN3(v0y, v1y, v2y) > e) & ~(LIMN_MAX3(v0y, v1y, v2y) < -e);
  ok &= ~(LIMN_MIN3(v0z, v1z, v2z) > e) & ~(LIMN_MAX3(v0z, v1z, v2z) < -e);
  const F8 e0x = v1x - v0x, e0y = v1y - v0y, e0z = v1z - v0z;
  const F8 e1x = v2x - v1x, e1y = v2y - v1y, e1z = v2z - v1z;
  const F8 e2x = v0x - v2x, e2y = v0y - v2y, e2z = v0z - v2z;
  // Triangle normal.
  {
    const F8 nx = e0y * e1z - e0z * e1y, ny = e0z * e1x - e0x * e1z, nz = e0x * e1y - e0y * e1x;
    const F8 rn = e * (LIMN_ABS(nx) + LIMN_ABS(ny) + LIMN_ABS(nz));
    const F8 dn = nx * v0x + ny * v0y + nz * v0z;
    ok &= ~(dn > rn) & ~(dn < -rn);
  }
  // Edge x box-axis: (0, -f.z, f.y), (f.z, 0, -f.x), (-f.y, f.x, 0) for each edge f.
  // (A macro, not a lambda: no vector crosses a call.)
#define LIMN_EDGE(fx, fy, fz)                                                                   \
  {                                                                                             \
    const F8 ax = LIMN_ABS(fx), ay = LIMN_ABS(fy), az = LIMN_ABS(fz);                           \
    {                                                                                           \
      const F8 p0 = -fz * v0y + fy * v0z, p1 = -fz * v1y + fy * v1z, p2 = -fz * v2y + fy * v2z; \
      const F8 r = e * (az + ay);                                                               \
      ok &= ~(LIMN_MIN3(p0, p1, p2) > r) & ~(LIMN_MAX3(p0, p1, p2) < -r);                       \
    }                                                                                           \
    {                                                                                           \
      const F8 p0 = fz * v0x + -fx * v0z, p1 = fz * v1x + -fx * v1z, p2 = fz * v2x + -fx * v2z; \
      const F8 r = e * (az + ax);                                                               \
      ok &= ~(LIMN_MIN3(p0, p1, p2) > r) & ~(LIMN_MAX3(p0, p1, p2) < -r);                       \
    }                                                                                           \
    {                                                                                           \
      const F8 p0 = -fy * v0x + fx * v0y, p1 = -fy * v1x + fx * v1y, p2 = -fy * v2x + fx * v2y; \
      const F8 r = e * (ay + ax);                                                               \
      ok &= ~(LIMN_MIN3(p0, p1, p2) > r) & ~(LIMN_MAX3(p0, p1, p2) < -r);                       \
    }                                                                                           \
  }
  LIMN_EDGE(e0x, e0y, e0z)
  LIMN_EDGE(e1x, e1y, e1z)
  LIMN_EDGE(e2x, e2y, e2z)
#undef LIMN_EDGE
#undef LIMN_MIN3
#undef LIMN_MAX3
#undef LIMN_ABS
  return lane_bits(ok);
}

// A triangle's separating axes for testing it against many boxes of one half size h (grown by
// slack): its corners' offsets from a point o (their bounds: the box axes), and per other axis
// (its normal, then the 9 edge x box-axis cross products) the interval [lo, hi] a box centre's
// offset from o must project into for that axis not to separate them. Built once, it tests each
// box with one projection per axis (tri_boxes_meet8) where tri_box_overlap recomputes the
// triangle per box: a brick's 64 leaves from one build. Offsets are taken from o (a brick's
// centre, near the boxes), so rounding stays on the scale of the triangle's and the boxes'
// distances from o, as tri_box_overlap's does on their distances from each box's centre: far
// below the slack. Not the same float operations as tri_box_overlap: the two can disagree on a
// triangle within a few units of rounding of a box's grown face.
struct TriAxes {
  float mn[3], mx[3];  // bounds of the corners' offsets from o
  // Axis k (0: the normal; 1 + 3 i + j: edge i x box axis j) is (ax[0][k], ax[1][k], ax[2][k]).
  float ax[3][16], lo[16], hi[16];
};

// tri_axes in two steps, the bounds first: a caller that finds no box within them skips the rest.
inline void tri_axes_bounds(V3 o, V3 a, V3 b, V3 d, V3 v[3], TriAxes& t) {
  v[0] = a - o, v[1] = b - o, v[2] = d - o;
  t.mn[0] = std::min({v[0].x, v[1].x, v[2].x}), t.mx[0] = std::max({v[0].x, v[1].x, v[2].x});
  t.mn[1] = std::min({v[0].y, v[1].y, v[2].y}), t.mx[1] = std::max({v[0].y, v[1].y, v[2].y});
  t.mn[2] = std::min({v[0].z, v[1].z, v[2].z}), t.mx[2] = std::max({v[0].z, v[1].z, v[2].z});
}

__attribute__((always_inline)) inline void tri_axes_rest(float h, float slack, const V3 v[3],
                                                         TriAxes& t) {
  const float e = h + slack;
  const V3 f[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  auto put = [&](int k, float x, float y, float z) {
    t.ax[0][k] = x, t.ax[1][k] = y, t.ax[2][k] = z;
  };
  const V3 n = cross(f[0], f[1]);
  put(0, n.x, n.y, n.z);
  // Edge f x box axis: (0, -f.z, f.y), (f.z, 0, -f.x), (-f.y, f.x, 0).
  for (int i = 0; i < 3; ++i) {
    put(1 + 3 * i, 0, -f[i].z, f[i].y);
    put(2 + 3 * i, f[i].z, 0, -f[i].x);
    put(3 + 3 * i, -f[i].y, f[i].x, 0);
  }
  // Axes 1-8 eight at a time: the projections of the corners and the box's radius. A zero
  // component adds a signed zero to a product, which changes no comparison.
  {
    F8 A, B, C;
    __builtin_memcpy(&A, &t.ax[0][1], sizeof A);
    __builtin_memcpy(&B, &t.ax[1][1], sizeof B);
    __builtin_memcpy(&C, &t.ax[2][1], sizeof C);
    const F8 p0 = A * v[0].x + B * v[0].y + C * v[0].z;
    const F8 p1 = A * v[1].x + B * v[1].y + C * v[1].z;
    const F8 p2 = A * v[2].x + B * v[2].y + C * v[2].z;
    const F8 r =
        e * ((F8)((I8)A & 0x7fffffff) + (F8)((I8)B & 0x7fffffff) + (F8)((I8)C & 0x7fffffff));
    const F8 mn01 = p0 < p1 ? p0 : p1, mx01 = p0 > p1 ? p0 : p1;
    const F8 lo = (mn01 < p2 ? mn01 : p2) - r, hi = (mx01 > p2 ? mx01 : p2) + r;
    __builtin_memcpy(&t.lo[1], &lo, sizeof lo);
    __builtin_memcpy(&t.hi[1], &hi, sizeof hi);
  }
  // The normal and axis 9, one at a time.
  for (int k : {0, 9}) {
    const float x = t.ax[0][k], y = t.ax[1][k], z = t.ax[2][k];
    const float p0 = x * v[0].x + y * v[0].y + z * v[0].z;
    const float p1 = x * v[1].x + y * v[1].y + z * v[1].z;
    const float p2 = x * v[2].x + y * v[2].y + z * v[2].z;
    const float r = e * (std::fabs(x) + std::fabs(y) + std::fabs(z));
    t.lo[k] = std::min({p0, p1, p2}) - r, t.hi[k] = std::max({p0, p1, p2}) + r;
  }
}

inline void tri_axes(V3 o, float h, float slack, V3 a, V3 b, V3 d, TriAxes& t) {
  V3 v[3];
  tri_axes_bounds(o, a, b, d, v, t);
  tri_axes_rest(h, slack, v, t);
}

// Whether the box centred at o + (x, y, z) meets the triangle of t: the scalar form of what
// tri_boxes_meet8 and the box-axis tests of its callers decide.
inline bool tri_axes_meet(const TriAxes& t, float h, float slack, float x, float y, float z) {
  const float e = h + slack;
  const float c[3] = {x, y, z};
  for (int a = 0; a < 3; ++a)
    if (t.mn[a] - c[a] > e || t.mx[a] - c[a] < -e) return false;
  for (int k = 0; k < 10; ++k) {
    const float q = t.ax[0][k] * x + t.ax[1][k] * y + t.ax[2][k] * z;
    if (!(q >= t.lo[k] && q <= t.hi[k])) return false;
  }
  return true;
}

// tri_axes_meet's 10 non-box axes on 8 boxes at once (centres o + (x[k], y[k], z[k])): bit k set
// when none separates box k. The same float operations lane by lane as tri_axes_meet (the edge
// axes' zero components left out: each adds a signed zero, which changes no comparison). The box
// axes are the caller's (the same expressions per axis). Always inlined, as tri_box_overlap8.
__attribute__((always_inline)) inline uint32_t tri_boxes_meet8(const TriAxes& t, const float* x,
                                                               const float* y, const float* z) {
  F8 X, Y, Z;
  __builtin_memcpy(&X, x, sizeof X);
  __builtin_memcpy(&Y, y, sizeof Y);
  __builtin_memcpy(&Z, z, sizeof Z);
  I8 ok;
  {
    const F8 q = t.ax[0][0] * X + t.ax[1][0] * Y + t.ax[2][0] * Z;
    ok = (q >= t.lo[0]) & (q <= t.hi[0]);
  }
  for (int i = 0; i < 3; ++i) {
    const int k = 1 + 3 * i;
    const F8 q0 = t.ax[1][k] * Y + t.ax[2][k] * Z;
    const F8 q1 = t.ax[0][k + 1] * X + t.ax[2][k + 1] * Z;
    const F8 q2 = t.ax[0][k + 2] * X + t.ax[1][k + 2] * Y;
    ok &= (q0 >= t.lo[k]) & (q0 <= t.hi[k]) & (q1 >= t.lo[k + 1]) & (q1 <= t.hi[k + 1]) &
          (q2 >= t.lo[k + 2]) & (q2 <= t.hi[k + 2]);
  }
  return lane_bits(ok);
}

using limn::morton3;

}  // namespace limn::paint_detail
