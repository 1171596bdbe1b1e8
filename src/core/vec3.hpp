// A 3-vector for the geometric kernels of every layer: arithmetic on a few points at a time
// (meshes and tables keep their points in flat arrays). Internal header.
#pragma once

#include <cmath>
#include <cstddef>
#include <type_traits>

namespace limn {

template <class T>
struct Vec3 {
  T x = 0, y = 0, z = 0;
};
using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

/// The point at p[0], p[1], p[2], converted to T.
template <class T, class S>
inline Vec3<T> load3(const S* p) {
  return {T(p[0]), T(p[1]), T(p[2])};
}
template <class T>
inline Vec3<T> operator-(Vec3<T> a, Vec3<T> b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class T>
inline Vec3<T> operator+(Vec3<T> a, Vec3<T> b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class T>
inline Vec3<T> operator*(std::type_identity_t<T> s, Vec3<T> a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class T>
inline T dot(Vec3<T> a, Vec3<T> b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
inline Vec3<T> cross(Vec3<T> a, Vec3<T> b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
inline T length(Vec3<T> a) {
  return std::sqrt(dot(a, a));
}

/// Twice the vector area of the polygon `face` over xyz `positions` (Newell's method), in double
/// and relative to its first corner, so large coordinates lose no precision to cancellation.
template <class Index>
inline void newell_double(const float* positions, const Index* face, size_t n, double out[3]) {
  const float* o = positions + 3 * size_t(face[0]);
  out[0] = out[1] = out[2] = 0;
  for (size_t i = 1; i + 1 < n; ++i) {
    const float* a = positions + 3 * size_t(face[i]);
    const float* b = positions + 3 * size_t(face[i + 1]);
    const double ax = double(a[0]) - o[0], ay = double(a[1]) - o[1], az = double(a[2]) - o[2];
    const double bx = double(b[0]) - o[0], by = double(b[1]) - o[1], bz = double(b[2]) - o[2];
    out[0] += ay * bz - az * by;
    out[1] += az * bx - ax * bz;
    out[2] += ax * by - ay * bx;
  }
}

}  // namespace limn
