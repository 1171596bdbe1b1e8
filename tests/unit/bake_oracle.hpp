// Checking a bake against the octree: random points on a mesh's surface with their UVs, and
// bilinear samples of a baked image at a UV, as a renderer takes them.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limn/mesh/mesh.hpp"

namespace limn::test {

struct SurfacePoint {
  float p[3], n[3];  // n: the triangle's (unnormalised) normal
  double uv[2];
  int tile() const { return int(std::floor(uv[0])) + 10 * int(std::floor(uv[1])); }
};

/// `count` points spread over the surface by area (faces fanned), with their UVs.
inline std::vector<SurfacePoint> random_surface_points(const Mesh& m, int count, uint32_t seed) {
  std::vector<double> cdf;
  std::vector<std::array<uint32_t, 3>> tris;
  double total = 0;
  for (uint32_t f = 0; f < m.face_count(); ++f)
    for (uint32_t k = 1; k + 1 < m.face_size(f); ++k) {
      const uint32_t o = m.face_offsets[f];
      tris.push_back({o, o + k, o + k + 1});
      const float* a = &m.positions[3 * size_t(m.face_vertices[o])];
      const float* b = &m.positions[3 * size_t(m.face_vertices[o + k])];
      const float* c = &m.positions[3 * size_t(m.face_vertices[o + k + 1])];
      const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                           e1[0] * e2[1] - e1[1] * e2[0]};
      total += std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      cdf.push_back(total);
    }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0, 1);
  std::vector<SurfacePoint> out;
  for (int i = 0; i < count; ++i) {
    const size_t ti =
        size_t(std::lower_bound(cdf.begin(), cdf.end(), u01(rng) * total) - cdf.begin());
    const auto& tri = tris[std::min(ti, tris.size() - 1)];
    double r1 = u01(rng), r2 = u01(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    const double w[3] = {1 - r1 - r2, r1, r2};
    SurfacePoint s{{0, 0, 0}, {0, 0, 0}, {0, 0}};
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k)
        s.p[k] += float(w[j]) * m.positions[3 * size_t(m.face_vertices[tri[j]]) + size_t(k)];
      for (int k = 0; k < 2; ++k)
        s.uv[k] += w[j] * m.uvs[2 * size_t(m.uv_indices[tri[j]]) + size_t(k)];
    }
    const float* a = &m.positions[3 * size_t(m.face_vertices[tri[0]])];
    const float* b = &m.positions[3 * size_t(m.face_vertices[tri[1]])];
    const float* c = &m.positions[3 * size_t(m.face_vertices[tri[2]])];
    const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
                e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    s.n[0] = e1[1] * e2[2] - e1[2] * e2[1], s.n[1] = e1[2] * e2[0] - e1[0] * e2[2],
    s.n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    out.push_back(s);
  }
  return out;
}

/// Bilinear sample (texel centres at +0.5, edges clamped) of an image of `channels` values per
/// texel, rows top to bottom, UDIM tile `tile`, at (u, v), v up.
template <class T>
void sample_bilinear(const T* data, int channels, int width, int height, int tile, double u,
                     double v, double* out) {
  const double x = (u - tile % 10) * width - 0.5, y = (1 - (v - tile / 10)) * height - 0.5;
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  for (int k = 0; k < channels; ++k) out[k] = 0;
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const int xx = std::clamp(x0 + dx, 0, width - 1), yy = std::clamp(y0 + dy, 0, height - 1);
      const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy);
      for (int k = 0; k < channels; ++k)
        out[k] +=
            w *
            double(data[size_t(channels) * (size_t(yy) * size_t(width) + size_t(xx)) + size_t(k)]);
    }
}

/// The q-quantile of `v` (sorted in place).
inline double quantile(std::vector<double>& v, double q) {
  std::sort(v.begin(), v.end());
  return v[size_t(q * double(v.size() - 1))];
}

/// Records the median, 99th percentile and largest of per-sample errors (8-bit steps) as the
/// test's properties and checks each against its bound.
inline void expect_steps_within(std::vector<double>& steps, double median, double q99,
                                double worst) {
  const double m = quantile(steps, 0.5), q = quantile(steps, 0.99), w = quantile(steps, 1.0);
  ::testing::Test::RecordProperty("median_steps", std::to_string(m));
  ::testing::Test::RecordProperty("q99_steps", std::to_string(q));
  ::testing::Test::RecordProperty("max_steps", std::to_string(w));
  EXPECT_LE(m, median);
  EXPECT_LE(q, q99);
  EXPECT_LE(w, worst);
}

}  // namespace limn::test
