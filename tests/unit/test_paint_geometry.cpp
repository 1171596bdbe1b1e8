// The paint layer's fast box tests against its scalar triangle-box test: the 8-box test gives the
// scalar test's answer for every box (bit for bit, so refinement and painting keep the same
// cells), and the quick containment test never claims an overlap the scalar test denies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "../../src/paint/geometry.hpp"
#include "../../src/paint/octree_blocks.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"

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

// The paint layer rounds colours to bytes without calling lround (dabs and means round
// thousands of values): every float of [0, 1] in steps of 2^-20, every tie (k + 0.5) / 255 and
// its neighbours, and doubles in [0, 255] must round as clamp(lround(255 v)) and clamp(lround(v))
// do.
TEST(PaintGeometry, ByteRoundingEqualsLround) {
  auto ref = [](float v) {
    return std::isfinite(v) ? uint32_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)) : 0u;
  };
  auto check = [&](float v) {
    const float in[4] = {v, v, v, v};
    const Rgba8 c = rgba8_from_float(in);
    for (int k = 0; k < 4; ++k) ASSERT_EQ(channel(c, k), ref(v)) << v << " channel " << k;
  };
  for (uint32_t i = 0; i <= (1u << 20); ++i) check(float(i) / float(1u << 20));
  for (int k = 0; k < 255; ++k) {
    const float tie = (float(k) + 0.5f) / 255.0f;
    check(tie), check(std::nextafter(tie, 0.0f)), check(std::nextafter(tie, 1.0f));
  }
  check(-1.0f), check(2.0f), check(NAN), check(INFINITY), check(-INFINITY), check(-0.0f);
  check(std::numeric_limits<float>::max()), check(-std::numeric_limits<float>::max());
  check(std::numeric_limits<float>::denorm_min()), check(std::nextafter(1.0f, 2.0f));
  std::mt19937_64 rng(3);
  for (int i = 0; i < 1000000; ++i) {  // any float bits: every sign, exponent and NaN
    const uint32_t bits = uint32_t(rng());
    float v;
    std::memcpy(&v, &bits, sizeof v);
    check(v);
  }
  std::uniform_real_distribution<float> near_unit(-0.5f, 1.5f);
  for (int i = 0; i < 100000; ++i) {  // different values in the four channels
    const float in[4] = {near_unit(rng), near_unit(rng), near_unit(rng), near_unit(rng)};
    const Rgba8 c = rgba8_from_float(in);
    for (int k = 0; k < 4; ++k) ASSERT_EQ(channel(c, k), ref(in[k])) << in[k];
  }
  std::uniform_real_distribution<double> u(0, 255);
  for (int i = 0; i < 1000000; ++i) {
    const double v = i < 256 ? double(i) + 0.5 : u(rng);
    ASSERT_EQ(detail::round_byte(v), uint32_t(std::min(std::lround(v), 255l))) << v;
  }
  EXPECT_EQ(detail::round_byte(255.0), 255u);
}

// The BVH's box query against testing every triangle: the same triangles (the paint layer's box
// test decides both), sorted, for boxes from larger than the shape down to depth-12 cells, many
// of them on the surface.
TEST(PaintGeometry, BoxQueryEqualsTestingEveryTriangle) {
  const Mesh m = make_shape("torus");
  const PaintSurface s(m);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  const Box& b = s.bounds();
  size_t found = 0;
  for (int iter = 0; iter < 400; ++iter) {
    const float h = std::ldexp(b.diagonal(), -int(rng() % 13));
    // On a vertex of the mesh every other time (cells the surface crosses), else anywhere.
    float c[3];
    const uint32_t t0 = uint32_t(rng() % s.triangle_count());
    for (int k = 0; k < 3; ++k)
      c[k] = iter % 2 ? s.corner(t0, 0)[k] + h * (u(rng) - 0.5f)
                      : b.min[k] + (b.max[k] - b.min[k]) * u(rng);
    const float slack = std::ldexp(h, -20);
    std::vector<uint32_t> got, want;
    s.triangles_in_box(c, h, slack, got);
    const V3 cc = {c[0], c[1], c[2]};
    for (uint32_t t = 0; t < s.triangle_count(); ++t) {
      const float* n = s.normal(t);
      if (n[0] == 0 && n[1] == 0 && n[2] == 0) continue;
      const V3 p0 = paint_detail::v3(s.corner(t, 0)), p1 = paint_detail::v3(s.corner(t, 1)),
               p2 = paint_detail::v3(s.corner(t, 2));
      if (paint_detail::tri_meets_box(cc, h, p0, p1, p2, slack)) want.push_back(t);
    }
    ASSERT_EQ(got, want) << "box " << iter << " half size " << h;
    found += got.size();
  }
  EXPECT_GT(found, 400u);  // the boxes did meet the surface
}

}  // namespace
}  // namespace limn
