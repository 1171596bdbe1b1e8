// Small geometric kernels the paint layer shares: box-triangle overlap, closest point on a
// triangle, Morton codes. Internal header.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace limn::paint_detail {

struct V3 {
  float x = 0, y = 0, z = 0;
};
inline V3 v3(const float* p) {
  return {p[0], p[1], p[2]};
}
inline V3 operator-(V3 a, V3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline V3 operator+(V3 a, V3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline V3 operator*(float s, V3 a) {
  return {s * a.x, s * a.y, s * a.z};
}
inline float dot(V3 a, V3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline V3 cross(V3 a, V3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(V3 a) {
  return std::sqrt(dot(a, a));
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

// Closest point to p on triangle abc, by which Voronoi region of the triangle p projects into
// (vertex, edge or face; Ericson, Real-Time Collision Detection, 5.1.5).
inline V3 closest_on_triangle(V3 p, V3 a, V3 b, V3 c) {
  const V3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const V3 bp = p - b;
  const float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const V3 cp = p - c;
  const float d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const float den = va + vb + vc;
  if (!(den > 0)) return a;
  return a + (vb / den) * ab + (vc / den) * ac;
}

// Spreads the low 16 bits of x to every third bit.
inline uint64_t spread3(uint32_t x) {
  uint64_t v = x & 0xffffu;
  v = (v | v << 16) & 0x0000ff0000ffull;
  v = (v | v << 8) & 0x00f00f00f00full;
  v = (v | v << 4) & 0x0c30c30c30c3ull;
  v = (v | v << 2) & 0x249249249249ull;
  return v;
}
inline uint64_t morton3(uint32_t x, uint32_t y, uint32_t z) {
  return spread3(x) | spread3(y) << 1 | spread3(z) << 2;
}

}  // namespace limn::paint_detail
