// Brushes against geometry recomputed here: which cells a dab reaches (its ball, by clipping and
// closest points of the test's own), occlusion and facing against analytic sheets, the two-sheet
// no-bleed case, stroke opacity, blend formulas, fill, eyedropper and bad brushes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "limn/paint/brush.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "paint_oracle.hpp"

namespace limn {
namespace {

using test::P3;

// Exact RGBA8 of floats, as a brush at full strength writes them.
Rgba8 q8(const float c[4]) {
  uint32_t v[4];
  for (int k = 0; k < 4; ++k) v[k] = uint32_t(std::lround(double(c[k]) * 255.0));
  return pack_rgba8(v[0], v[1], v[2], v[3]);
}

// A sample's representative point as the brush defines it, recomputed: the point nearest the
// cell centre on the cell's triangles of the sample's side. `stable` is false when clipping with
// half or double the library's box slack disagrees on the triangles (a boundary case to skip).
struct SamplePoint {
  P3 q{};
  P3 n{};
  bool ok = false, stable = true;
};

SamplePoint sample_point(const OctreeTexture& t, const std::vector<test::Tri>& tris,
                         const OctreeSample& s) {
  const double cell = double(t.size()) / double(1u << s.level);
  const P3 lo = {t.origin()[0] + s.x * cell, t.origin()[1] + s.y * cell,
                 t.origin()[2] + s.z * cell};
  const P3 hi = {lo[0] + cell, lo[1] + cell, lo[2] + cell};
  const P3 c = {lo[0] + cell / 2, lo[1] + cell / 2, lo[2] + cell / 2};
  const double slack = double(t.size()) / double(1u << 22);
  SamplePoint sp;
  double best = INFINITY;
  for (const test::Tri& tri : tris) {
    if (tri.n == P3{0, 0, 0}) continue;
    bool apart = false;  // boxes apart: no need to clip
    for (size_t k = 0; k < 3; ++k)
      apart = apart || std::min({tri.a[k], tri.b[k], tri.c[k]}) > hi[k] + 4 * slack ||
              std::max({tri.a[k], tri.b[k], tri.c[k]}) < lo[k] - 4 * slack;
    if (apart) continue;
    const bool inner = test::tri_meets_box(tri, lo, hi, slack / 2);
    const bool outer = test::tri_meets_box(tri, lo, hi, slack * 2);
    if (inner != outer) sp.stable = false;
    if (!outer) continue;
    const float nf[3] = {float(tri.n[0]), float(tri.n[1]), float(tri.n[2])};
    if (test::side_of(s.tag, nf) != s.side) continue;
    const P3 q = test::closest_on_tri(c, tri);
    const double d = test::norm3(test::sub(q, c));
    if (d < best - 1e-9) best = d, sp.q = q, sp.n = tri.n, sp.ok = true;
  }
  return sp;
}

// Distance from p to the box of a sample's cell.
double box_distance(const OctreeTexture& t, const OctreeSample& s, P3 p) {
  const double cell = double(t.size()) / double(1u << s.level);
  const uint32_t xyz[3] = {s.x, s.y, s.z};
  double d2 = 0;
  for (size_t k = 0; k < 3; ++k) {
    const double lo = t.origin()[k] + xyz[k] * cell, hi = lo + cell;
    const double e = std::max({lo - p[k], 0.0, p[k] - hi});
    d2 += e * e;
  }
  return std::sqrt(d2);
}

// The surface point nearest p, by brute force.
P3 nearest_on(const std::vector<test::Tri>& tris, P3 p, P3* normal = nullptr) {
  double best = INFINITY;
  P3 out{};
  for (const test::Tri& t : tris) {
    if (t.n == P3{0, 0, 0}) continue;
    const P3 q = test::closest_on_tri(p, t);
    const double d = test::norm3(test::sub(q, p));
    if (d < best) {
      best = d, out = q;
      if (normal) *normal = t.n;
    }
  }
  return out;
}

TEST(PaintBrush, DabsWriteExactlyTheSurfaceCellsWithinTheirRadius) {
  const Mesh m = test::uv_sphere(1.0, 24, 48);
  const auto tris = test::triangles(m);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(0, 0, 0, 0));
  struct Dab {
    P3 centre;
    float color[4];
  };
  std::vector<Dab> dabs;
  const float radius = 0.15f;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 6; ++i) {
    P3 d = {u(rng), u(rng), u(rng)};
    const double l = test::norm3(d);
    const P3 p = {d[0] / l * 1.01, d[1] / l * 1.01, d[2] / l * 1.01};
    Dab dab{nearest_on(tris, p),
            {float(40 * i) / 255.0f, float(255 - 40 * i) / 255.0f, 128.0f / 255.0f, 1.0f}};
    dabs.push_back(dab);
    Brush b;
    b.radius = radius, b.hardness = 1, b.opacity = 1, b.depth = 8;
    std::copy_n(dab.color, 4, b.color);
    StrokePainter sp(t, s);
    sp.begin(b);
    const float pf[3] = {float(p[0]), float(p[1]), float(p[2])};
    ASSERT_TRUE(sp.dab_world(pf));
    sp.end();
  }
  ASSERT_EQ(t.check(), "");
  size_t painted = 0, checked = 0;
  t.for_each_sample([&](const OctreeSample& x) {
    bool near = false;  // a cell out of every ball keeps the background: no need for its point
    for (const Dab& d : dabs) near = near || box_distance(t, x, d.centre) <= radius + 1e-3;
    if (!near) {
      ASSERT_EQ(x.color, t.background());
      return;
    }
    const SamplePoint sp = sample_point(t, tris, x);
    if (!sp.ok || !sp.stable) return;
    Rgba8 want = t.background();
    bool ambiguous = false;
    for (const Dab& d : dabs) {
      const double dist = test::norm3(test::sub(sp.q, d.centre));
      if (std::fabs(dist - radius) < 1e-4) ambiguous = true;
      if (dist <= radius) want = q8(d.color);
    }
    if (ambiguous) return;
    ++checked;
    painted += want != t.background();
    ASSERT_EQ(x.color, want) << "level " << x.level << " cell " << x.x << "," << x.y << "," << x.z;
  });
  EXPECT_GT(painted, 2000u);
  EXPECT_GT(checked, painted);
}

// Ground (z = 0, up), a plate above its x > 0 half (z = 0.04, up) and a roof facing down over
// x < -0.3 (z = 0.08): the plate and the roof hide the ground under them; the roof faces away.
Mesh occluder_scene() {
  return test::merge({test::sheet(-1, 1, -1, 1, 0.0, 40, true),
                      test::sheet(0, 1, -1, 1, 0.04, 20, true),
                      test::sheet(-1, -0.3, -1, 1, 0.08, 14, false)});
}

// Does the segment q -> q + d * tmax cross a sheet of the scene other than q's own?
bool blocked(P3 q, P3 d, double tmax) {
  struct Rect {
    double x0, x1, z;
  };
  for (const Rect r : {Rect{0, 1, 0.04}, Rect{-1, -0.3, 0.08}, Rect{-1, 1, 0.0}}) {
    if (std::fabs(d[2]) < 1e-12 || std::fabs(q[2] - r.z) < 1e-6) continue;
    const double tt = (r.z - q[2]) / d[2];
    if (tt <= 1e-6 || tt >= tmax) continue;
    const double x = q[0] + tt * d[0], y = q[1] + tt * d[1];
    if (x >= r.x0 && x <= r.x1 && y >= -1 && y <= 1) return true;
  }
  return false;
}

TEST(PaintBrush, OnlyVisibleFrontFacingSurfaceIsPaintedWorldDab) {
  const Mesh m = occluder_scene();
  const auto tris = test::triangles(m);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  Brush b;
  b.radius = 0.3f, b.hardness = 1, b.depth = 8;
  StrokePainter sp(t, s);
  sp.begin(b);
  const float p[3] = {-0.1f, 0.0f, -0.01f};  // nearest surface: the ground at (-0.1, 0, 0)
  ASSERT_TRUE(sp.dab_world(p));
  sp.end();
  const P3 c = {-0.1, 0, 0};
  size_t painted = 0, hidden = 0, away = 0;
  t.for_each_sample([&](const OctreeSample& x) {
    if (box_distance(t, x, c) > b.radius + 1e-3) {
      ASSERT_EQ(x.color, t.background());
      return;
    }
    const SamplePoint q = sample_point(t, tris, x);
    if (!q.ok || !q.stable) return;
    const double dist = test::norm3(test::sub(q.q, c));
    if (std::fabs(dist - b.radius) < 1e-4) return;
    // Near the edges of the plate and the roof the ray grazes them: skip.
    if (std::fabs(q.q[0]) < 1e-3 || std::fabs(q.q[0] + 0.3) < 1e-3) return;
    const bool facing = q.n[2] > 0;
    const bool visible = !blocked(q.q, {0, 0, 1}, 2 * b.radius);
    const bool want = dist <= b.radius && facing && visible;
    if (dist <= b.radius && !facing) ++away;
    if (dist <= b.radius && facing && !visible) ++hidden;
    ASSERT_EQ(x.color != t.background(), want)
        << "q " << q.q[0] << "," << q.q[1] << "," << q.q[2] << " n.z " << q.n[2];
    painted += want;
  });
  EXPECT_GT(painted, 1000u);
  EXPECT_GT(hidden, 300u);  // the ground under the plate and the roof was in reach
  EXPECT_GT(away, 50u);     // so was the roof, facing away
}

// The test's own pinhole projection (x right, y down, pixel centres at +0.5).
bool project(const PaintCamera& c, P3 p, double& px, double& py) {
  const P3 eye = {c.eye[0], c.eye[1], c.eye[2]};
  P3 f = test::sub({c.target[0], c.target[1], c.target[2]}, eye);
  f = {f[0] / test::norm3(f), f[1] / test::norm3(f), f[2] / test::norm3(f)};
  P3 r = test::cross3(f, {c.up[0], c.up[1], c.up[2]});
  r = {r[0] / test::norm3(r), r[1] / test::norm3(r), r[2] / test::norm3(r)};
  const P3 up = test::cross3(r, f);
  const P3 d = test::sub(p, eye);
  const double z = test::dot3(d, f);
  if (z <= 0) return false;
  const double th = std::tan(c.fovy_deg * 3.14159265358979323846 / 360.0);
  const double aspect = double(c.width) / c.height;
  px = (test::dot3(d, r) / z / (th * aspect) + 1) * 0.5 * c.width;
  py = (1 - test::dot3(d, up) / z / th) * 0.5 * c.height;
  return true;
}

TEST(PaintBrush, OnlyVisibleFrontFacingSurfaceIsPaintedScreenDab) {
  const Mesh m = occluder_scene();
  const auto tris = test::triangles(m);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  PaintCamera cam;
  cam.eye[0] = -0.1f, cam.eye[1] = 0.2f, cam.eye[2] = 1.5f;
  cam.target[0] = -0.1f, cam.target[1] = 0.0f, cam.target[2] = 0.0f;
  cam.fovy_deg = 40, cam.width = 400, cam.height = 300;
  Brush b;
  b.radius = 90, b.hardness = 1, b.depth = 8;
  StrokePainter sp(t, s);
  sp.begin(b, &cam);
  double cx, cy;
  ASSERT_TRUE(project(cam, {-0.1, 0, 0}, cx, cy));
  ASSERT_TRUE(sp.dab_screen(cx, cy));
  sp.end();
  const P3 eye = {cam.eye[0], cam.eye[1], cam.eye[2]};
  size_t painted = 0, hidden = 0, away = 0;
  t.for_each_sample([&](const OctreeSample& x) {
    if (box_distance(t, x, {-0.1, 0, 0}) > 0.7) {  // the 90 px disc spans ~0.33 here
      ASSERT_EQ(x.color, t.background());
      return;
    }
    const SamplePoint q = sample_point(t, tris, x);
    if (!q.ok || !q.stable) return;
    double px, py;
    if (!project(cam, q.q, px, py)) return;
    const double dpx = std::hypot(px - cx, py - cy);
    if (std::fabs(dpx - b.radius) < 0.05) return;
    P3 d = test::sub(eye, q.q);
    const double len = test::norm3(d);
    d = {d[0] / len, d[1] / len, d[2] / len};
    // Skip rays that graze an edge of the plate or the roof.
    for (const double z : {0.04, 0.08}) {
      const double tt = (z - q.q[2]) / d[2];
      if (tt > 0) {
        const double xx = q.q[0] + tt * d[0];
        if (std::fabs(xx) < 2e-3 || std::fabs(xx + 0.3) < 2e-3) return;
      }
    }
    const bool facing = test::dot3(q.n, d) > 0;
    const bool visible = !blocked(q.q, d, len);
    const bool want = dpx <= b.radius && facing && visible;
    if (dpx <= b.radius && !facing) ++away;
    if (dpx <= b.radius && facing && !visible) ++hidden;
    ASSERT_EQ(x.color != t.background(), want) << "q " << q.q[0] << "," << q.q[1] << "," << q.q[2];
    painted += want;
  });
  EXPECT_GT(painted, 1000u);
  EXPECT_GT(hidden, 100u);
  EXPECT_GT(away, 20u);
}

TEST(PaintBrush, TwoSheetsAFractionOfALeafApartNeverBleed) {
  // Leaves at depth 8 over a cube of side 2.04 are 0.008 wide; the sheets are 0.3 of that apart.
  // A small patch at z = 0.5 moves the cube's centre (a cell boundary at every level) off the
  // sheets, so they share leaf cells.
  const double leaf = 2.04 / 256.0, gap = 0.3 * leaf;
  const Mesh m = test::merge({test::sheet(-1, 1, -1, 1, gap, 30, true),   // A, up
                              test::sheet(-1, 1, -1, 1, 0.0, 30, false),  // B, down
                              test::sheet(0.9, 1, 0.9, 1, 0.5, 1, true)});
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  ASSERT_NEAR(t.size(), 2.04, 1e-4);
  const float up[3] = {0, 0, 1}, down[3] = {0, 0, -1};
  const Rgba8 red = pack_rgba8(255, 0, 0, 255), blue = pack_rgba8(0, 0, 255, 255);
  auto dab = [&](float z, float r, float g, float bl) {
    Brush b;
    b.radius = 0.4f, b.hardness = 1, b.depth = 8;
    b.color[0] = r, b.color[1] = g, b.color[2] = bl, b.color[3] = 1;
    StrokePainter sp(t, s);
    sp.begin(b);
    const float p[3] = {0, 0, z};
    ASSERT_TRUE(sp.dab_world(p));
    sp.end();
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.27f, 0.27f);  // inside the 0.4 disc, off its rim
  auto check = [&](float z, const float* n, Rgba8 want_nearest, const float want[4]) {
    OctreeSampler smp(t);
    for (int i = 0; i < 3000; ++i) {
      const float p[3] = {u(rng), u(rng), z};
      Rgba8 c;
      smp.nearest(p, n, c);
      ASSERT_EQ(c, want_nearest) << p[0] << "," << p[1] << "," << p[2];
      float f[4];
      smp.filtered(p, n, 0.0f, f);
      for (int k = 0; k < 4; ++k) ASSERT_NEAR(f[k], want[k], 1e-5) << k;
    }
  };
  dab(float(gap) + 0.005f, 1, 0, 0);  // paint A from above
  EXPECT_GT(t.stats().double_cells, 1000u) << "the sheets should share cells";
  const float red_f[4] = {1, 0, 0, 1}, blue_f[4] = {0, 0, 1, 1}, none[4] = {0, 0, 0, 0};
  check(float(gap), up, red, red_f);
  check(0.0f, down, t.background(), none);  // B sees nothing of A's red
  dab(-0.005f, 0, 0, 1);                    // paint B from below
  check(float(gap), up, red, red_f);
  check(0.0f, down, blue, blue_f);
  ASSERT_EQ(t.check(), "");
}

TEST(PaintBrush, StrokeOpacityIsACeilingNotABuildUp) {
  const Mesh m = test::sheet(-1, 1, -1, 1, 0.0, 20, true);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(255, 255, 255, 255));
  Brush b;
  b.radius = 0.2f, b.hardness = 1, b.opacity = 0.5f, b.depth = 7, b.spacing = 0.05f;
  b.color[0] = 0, b.color[1] = 0, b.color[2] = 1, b.color[3] = 1;
  const std::vector<float> line = {-0.5f, 0, 0, 0.5f, 0, 0, 0.5f, 0.3f, 0};
  for (int stroke = 0; stroke < 2; ++stroke) {
    StrokePainter sp(t, s);
    sp.begin(b);
    sp.stroke_world(line);
    const StrokeStats st = sp.end();
    EXPECT_GT(st.dabs, 100u);  // heavy overlap
    // One stroke: mix at strength 0.5 of blue over white = (0.5, 0.5, 1); two: (0.25, 0.25, 1).
    const Rgba8 want = stroke == 0 ? pack_rgba8(128, 128, 255, 255) : pack_rgba8(64, 64, 255, 255);
    size_t n = 0;
    t.for_each_sample([&](const OctreeSample& x) {
      if (x.color == t.background()) return;
      ASSERT_EQ(x.color, want);
      ++n;
    });
    EXPECT_GT(n, 1000u);
  }
}

// The blend formulas, restated (straight alpha, strength w).
std::array<double, 4> blend_ref(const std::array<double, 4>& d, const float* s, BlendMode mode,
                                double w) {
  std::array<double, 4> o{};
  const double a = w * s[3];
  switch (mode) {
    case BlendMode::mix:
      o[3] = a + d[3] * (1 - a);
      for (int k = 0; k < 3; ++k) o[size_t(k)] = (s[k] * a + d[size_t(k)] * d[3] * (1 - a)) / o[3];
      break;
    case BlendMode::add:
      o[3] = a + d[3] * (1 - a);
      for (int k = 0; k < 3; ++k) o[size_t(k)] = std::min(1.0, d[size_t(k)] + s[k] * a);
      break;
    case BlendMode::multiply:
      for (int k = 0; k < 3; ++k) o[size_t(k)] = d[size_t(k)] * (1 - a + a * s[k]);
      o[3] = d[3];
      break;
    case BlendMode::erase:
      o = d;
      o[3] = d[3] * (1 - w);
      break;
  }
  return o;
}

TEST(PaintBrush, BlendModesFollowTheirFormulas) {
  const Mesh m = test::sheet(-1, 1, -1, 1, 0.0, 10, true);
  const PaintSurface s(m);
  const Rgba8 bg = pack_rgba8(51, 102, 153, 204);
  const std::array<double, 4> d = {51 / 255.0, 102 / 255.0, 153 / 255.0, 204 / 255.0};
  for (BlendMode mode : {BlendMode::mix, BlendMode::add, BlendMode::multiply, BlendMode::erase}) {
    OctreeTexture t = OctreeTexture::create(s, bg);
    Brush b;
    b.radius = 0.3f, b.hardness = 1, b.opacity = 0.6f, b.depth = 7, b.blend = mode;
    const float col[4] = {0.9f, 0.5f, 0.1f, 0.7f};
    std::copy_n(col, 4, b.color);
    StrokePainter sp(t, s);
    sp.begin(b);
    const float p[3] = {0, 0, 0};
    ASSERT_TRUE(sp.dab_world(p));
    sp.end();
    const auto o = blend_ref(d, col, mode, 0.6);
    const Rgba8 want =
        pack_rgba8(uint32_t(std::lround(o[0] * 255)), uint32_t(std::lround(o[1] * 255)),
                   uint32_t(std::lround(o[2] * 255)), uint32_t(std::lround(o[3] * 255)));
    ASSERT_NE(want, bg);
    size_t n = 0;
    t.for_each_sample([&](const OctreeSample& x) {
      if (x.color == bg) return;
      for (int k = 0; k < 4; ++k)
        ASSERT_NEAR(double(channel(x.color, k)), double(channel(want, k)), 1.0) << int(mode) << k;
      ++n;
    });
    EXPECT_GT(n, 500u) << int(mode);
  }
}

TEST(PaintBrush, FillAndEyedropper) {
  const Mesh m = test::uv_sphere(1.0, 16, 32);
  const auto tris = test::triangles(m);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  const float green[4] = {0, 1, 0, 1};
  EXPECT_GT(fill(t, s, green, BlendMode::mix, 1.0f, 6), 1000u);
  ASSERT_EQ(t.check(), "");
  const OctreeTextureStats st = t.stats();
  EXPECT_EQ(st.max_depth, 6);
  EXPECT_EQ(st.painted_samples, st.samples);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 300; ++i) {
    const test::Tri& tri = tris[size_t(u(rng) * double(tris.size())) % tris.size()];
    const P3 p = test::point_in(tri, u(rng), u(rng));
    const float pf[3] = {float(p[0] * 1.05), float(p[1] * 1.05), float(p[2] * 1.05)};
    float rgba[4];
    ASSERT_TRUE(pick_world(t, s, pf, 1.0f, rgba));
    EXPECT_EQ(rgba[1], 1.0f);
    EXPECT_EQ(rgba[0], 0.0f);
  }
  // Erase everything at the current resolution.
  EXPECT_EQ(fill(t, s, green, BlendMode::erase, 1.0f), st.samples);
  EXPECT_EQ(t.stats().max_depth, 6);
  const float pf[3] = {0, 0, 1.2f};
  float rgba[4];
  ASSERT_TRUE(pick_world(t, s, pf, 1.0f, rgba));
  EXPECT_EQ(rgba[3], 0.0f);
  // Nothing within reach: the background, and false.
  const float far[3] = {5, 5, 5};
  EXPECT_FALSE(pick_world(t, s, far, 1.0f, rgba));
  // The mip average of the root after the erase: transparent.
  Rgba8 root;
  OctreeSampler smp(t);
  ASSERT_TRUE(smp.cell_value(0, 0, 0, 0, nullptr, root));
  EXPECT_EQ(channel(root, 3), 0u);
}

TEST(PaintBrush, MissedDabsAndBadBrushes) {
  const Mesh m = test::sheet(-1, 1, -1, 1, 0.0, 4, true);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  const OctreeTexture before = t;
  Brush b;
  b.radius = 0.125f;
  {
    StrokePainter sp(t, s);
    sp.begin(b);
    const std::vector<float> above = {0, 0, 0.5f, 0.5f, 0, 0.5f};  // 0.5 over the sheet
    sp.stroke_world(above);
    const StrokeStats st = sp.end();
    EXPECT_EQ(st.dabs, 0u);
    EXPECT_EQ(st.dabs_missed, 17u);  // 0.5 / (0.25 * 0.125) + 1
  }
  EXPECT_TRUE(t == before);
  auto bad = [&](auto edit) {
    Brush x = b;
    edit(x);
    StrokePainter sp(t, s);
    EXPECT_THROW(sp.begin(x), InputError);
  };
  bad([](Brush& x) { x.radius = 0; });
  bad([](Brush& x) { x.radius = NAN; });
  bad([](Brush& x) { x.color[1] = NAN; });
  bad([](Brush& x) { x.color[3] = 1.5f; });
  bad([](Brush& x) { x.opacity = -0.1f; });
  bad([](Brush& x) { x.hardness = INFINITY; });
  bad([](Brush& x) { x.spacing = 0; });
  bad([](Brush& x) { x.depth = 17; });
  bad([](Brush& x) { x.depth = 0; });
  bad([](Brush& x) { x.falloff_angle_deg = 91; });
  StrokePainter sp(t, s);
  sp.begin(b);
  EXPECT_THROW(sp.dab_screen(1, 1), InputError);  // no camera
  const float nan_point[3] = {0, NAN, 0};
  EXPECT_THROW(sp.dab_world(nan_point), InputError);
  const std::vector<float> long_line = {0, 0, 0, 1e6f, 0, 0};
  EXPECT_THROW(sp.stroke_world(long_line), InputError);  // 40 billion dabs
  sp.end();
  PaintCamera cam;
  cam.target[0] = cam.eye[0], cam.target[1] = cam.eye[1], cam.target[2] = cam.eye[2];
  StrokePainter sp2(t, s);
  EXPECT_THROW(sp2.begin(b, &cam), InputError);
  EXPECT_TRUE(t == before);
}

}  // namespace
}  // namespace limn
