// The closest point on a triangle, for paint's brush and surface queries (float) and simplify's
// distance report (double). Internal header.
#pragma once

#include "core/vec3.hpp"

namespace limn {

/// The point of triangle abc closest to p, by the Voronoi region of the triangle p projects into
/// (vertex, edge or face; Ericson, Real-Time Collision Detection, sec. 5.1.5). A degenerate
/// triangle (no face region): the nearest of its corners. O(1).
template <class T>
Vec3<T> closest_on_triangle(Vec3<T> p, Vec3<T> a, Vec3<T> b, Vec3<T> c) {
  const Vec3<T> ab = b - a, ac = c - a, ap = p - a;
  const T d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3<T> bp = p - b;
  const T d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const Vec3<T> cp = p - c;
  const T d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const T va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const T den = va + vb + vc;
  if (!(den > 0)) {
    const T da = dot(ap, ap), db = dot(bp, bp), dc = dot(cp, cp);
    return da <= db && da <= dc ? a : db <= dc ? b : c;
  }
  return a + (vb / den) * ab + (vc / den) * ac;
}

}  // namespace limn
