// What the paint benchmarks share: random surface points and a fixed set of painted strokes.
#pragma once

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "limn/paint/brush.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "paint/geometry.hpp"

namespace limn::bench {

struct Sample {
  float p[3], n[3];
};

// Area-weighted random surface points with their face normals.
inline std::vector<Sample> surface_points(const PaintSurface& s, size_t count, uint32_t seed) {
  std::vector<double> cdf;
  double total = 0;
  for (uint32_t t = 0; t < s.triangle_count(); ++t) {
    const paint_detail::V3 a = paint_detail::v3(s.corner(t, 0)),
                           b = paint_detail::v3(s.corner(t, 1)),
                           c = paint_detail::v3(s.corner(t, 2));
    total += 0.5 * double(length(cross(b - a, c - a)));
    cdf.push_back(total);
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Sample> out(count);
  for (Sample& x : out) {
    const uint32_t t =
        uint32_t(std::lower_bound(cdf.begin(), cdf.end(), u(rng) * total) - cdf.begin());
    double a = u(rng), b = u(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    for (int k = 0; k < 3; ++k) {
      x.p[k] = float(s.corner(t, 0)[k] + a * (s.corner(t, 1)[k] - s.corner(t, 0)[k]) +
                     b * (s.corner(t, 2)[k] - s.corner(t, 0)[k]));
      x.n[k] = s.normal(t)[k];
    }
  }
  return out;
}

// 12 strokes of 6 dabs wandering over the surface from `starts` (at least 12 points), radius
// 1/64 of the texture cube, leaves at `depth`.
inline void paint_strokes(OctreeTexture& t, const PaintSurface& s, int depth,
                          const std::vector<Sample>& starts) {
  std::mt19937 rng(17);
  std::normal_distribution<float> step(0, t.size() / 128.0f);
  for (size_t i = 0; i < 12; ++i) {
    Brush b;
    b.depth = depth, b.radius = t.size() / 64.0f, b.hardness = 0.6f;
    b.color[0] = float(i) / 12.0f, b.color[1] = 0.3f, b.color[2] = 0.8f, b.color[3] = 1;
    StrokePainter p(t, s);
    p.begin(b);
    float at[3] = {starts[i].p[0], starts[i].p[1], starts[i].p[2]};
    for (int d = 0; d < 6; ++d) {
      p.dab_world(at);
      SurfaceHit h;
      float next[3] = {at[0] + step(rng), at[1] + step(rng), at[2] + step(rng)};
      if (s.closest_point(next, t.size(), h)) std::copy_n(h.p, 3, at);
    }
    p.end();
  }
}

}  // namespace limn::bench
