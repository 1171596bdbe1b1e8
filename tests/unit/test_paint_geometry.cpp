// The paint layer's fast box tests against its scalar triangle-box test: the 8-box test gives the
// scalar test's answer for every box (bit for bit, so refinement and painting keep the same
// cells), and the quick containment test never claims an overlap the scalar test denies.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../../src/paint/geometry.hpp"

namespace limn {
namespace {

using paint_detail::V3;

// Random triangles around 8 child boxes of a random cell, at scales from far larger to far
// smaller than the cell, many of them grazing a box face within the slack.
TEST(PaintGeometry, EightBoxTestEqualsTheScalarTest) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1, 1);
  size_t overlaps = 0, total = 0, inside = 0;
  for (int iter = 0; iter < 200000; ++iter) {
    const float scale = std::ldexp(1.0f, int(rng() % 12));  // cells of 1 .. 1/2048
    const float h = 0.5f / scale;                           // child half size
    const V3 c = {0.3f + u(rng), -0.2f + u(rng), 0.7f + u(rng)};
    const float slack = std::ldexp(1.0f, -22);
    float kx[8], ky[8], kz[8];
    for (int k = 0; k < 8; ++k) {
      kx[k] = c.x + (k & 1 ? h : -h), ky[k] = c.y + (k & 2 ? h : -h),
      kz[k] = c.z + (k & 4 ? h : -h);
    }
    const float size = h * std::ldexp(1.0f, int(rng() % 8) - 3);  // triangles of h/8 .. 16 h
    // Around the parent's centre (across children) or, every other time, a child's.
    const int at = int(rng() % 16);
    const V3 o = at < 8 ? V3{kx[at], ky[at], kz[at]} : c;
    V3 p[3];
    for (V3& v : p) v = {o.x + size * u(rng) * 2, o.y + size * u(rng) * 2, o.z + size * u(rng) * 2};
    if (iter % 4 == 0) {
      // Snap a vertex onto a child's face (within a few ulps): the cases rounding decides.
      const int k = int(rng() % 8), axis = int(rng() % 3);
      const float face[3] = {kx[k] + (k & 1 ? h : -h), ky[k] + (k & 2 ? h : -h),
                             kz[k] + (k & 4 ? h : -h)};
      float* coord = axis == 0 ? &p[0].x : axis == 1 ? &p[0].y : &p[0].z;
      *coord = std::nextafter(face[axis] + slack * u(rng), float(rng() % 2 ? 10 : -10));
    }
    const uint32_t bits = paint_detail::tri_box_overlap8(kx, ky, kz, h, p[0], p[1], p[2], slack);
    for (int k = 0; k < 8; ++k) {
      const V3 kc = {kx[k], ky[k], kz[k]};
      const bool scalar = paint_detail::tri_box_overlap(kc, h, p[0], p[1], p[2], slack);
      ASSERT_EQ(bool(bits >> k & 1), scalar) << "iteration " << iter << " box " << k;
      const bool in = paint_detail::tri_inside_box(kc, h, p[0], p[1], p[2], slack);
      if (in) {
        ASSERT_TRUE(scalar) << "iteration " << iter << " box " << k;
      }
      overlaps += scalar, inside += in, ++total;
    }
  }
  // Both answers occur often enough for the comparison to mean something.
  EXPECT_GT(overlaps, total / 10);
  EXPECT_LT(overlaps, total * 9 / 10);
  EXPECT_GT(inside, total / 100);
}

}  // namespace
}  // namespace limn
