// Filtered lookups where leaf depths change: a texture is deep only where it was painted, so a
// point on the surface can sit in a coarse leaf right beside fine painted ones. The filter must
// stay local there (the taps of a coarse level reach a whole coarse cell away, and a fine tap's
// sample is a point of the painted detail, not the cell's colour), and the GPU must do the same.
// A point a little off the painted surface, in a cell no paint reached, finds the paint beside it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "limn/paint/brush.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/texture.hpp"
#include "paint_oracle.hpp"

namespace limn {
namespace {

// One hard red dab of radius 0.3 at depth 9 in the middle of a sheet over [-1, 1]^2 at z = 0
// (leaves of 2.04 / 512 = 0.004 there); everywhere else the start tree's coarse leaves, opaque
// white. A patch at z = 2.04 / 32 moves the cube so that the sheet runs through the middle of
// level-5 cells: taps at the centres of the level-5 cells beside a coarse leaf then land on the
// sheet (a surface through cell boundaries, as at z = 0 of a centred cube, would hide them).
struct DabOnSheet {
  Mesh sheet = test::merge(
      {test::sheet(-1, 1, -1, 1, 0, 8, true), test::sheet(0.95, 1, 0.95, 1, 2.04 / 32, 1, true)});
  PaintSurface surface{sheet};
  OctreeTexture tex = OctreeTexture::create(surface, pack_rgba8(255, 255, 255, 255));
  float leaf = 0;
  DabOnSheet() {
    Brush b;
    b.depth = 9, b.radius = 0.3f, b.hardness = 1;
    b.color[0] = 1, b.color[1] = 0, b.color[2] = 0, b.color[3] = 1;
    StrokePainter p(tex, surface);
    p.begin(b);
    const float at[3] = {0, 0, 0};
    p.dab_world(at);
    p.end();
    leaf = tex.size() / 512.0f;
  }
};

// `count` dabs of random colour and hardness, radius r0 + r1 * (0-1), depth d0 + i % depths,
// at the point `at(i, u, v, p)` writes for two more random numbers u, v in [0, 1).
template <class At>
void random_dabs(OctreeTexture& t, const PaintSurface& surface, std::mt19937& rng, int count,
                 int d0, int depths, float r0, float r1, At at) {
  std::uniform_real_distribution<float> u01(0, 1);
  for (int i = 0; i < count; ++i) {
    Brush b;
    b.depth = d0 + i % depths;
    b.radius = r0 + r1 * u01(rng);
    b.hardness = u01(rng);
    for (float& c : b.color) c = u01(rng);
    StrokePainter p(t, surface);
    p.begin(b);
    float where[3];
    const float u = u01(rng), v = u01(rng);
    at(i, u, v, where);
    p.dab_world(where);
    p.end();
  }
}

TEST(PaintFilter, CoarseLeavesBesideFinePaintStayTheirOwnColour) {
  const DabOnSheet d;
  const double cells = (0.0 - d.tex.origin()[2]) / d.tex.size() * 32.0;
  ASSERT_NEAR(cells - std::floor(cells), 0.5, 0.01) << "the sheet should cross level-5 centres";
  OctreeSampler s(d.tex);
  const float up[3] = {0, 0, 1};
  // Points on the sheet in rings around the dab: beyond it by more than the filter's reach at
  // the dab's depth (one leaf, plus one for the dab's own edge) the colour is the white base.
  size_t coarse = 0, checked = 0;
  for (int i = 0; i < 4000; ++i) {
    const double a = 2 * M_PI * i / 4000.0, r = 0.3 + d.leaf * (2.5 + 40.0 * (i % 97) / 97.0);
    const float p[3] = {float(r * std::cos(a)), float(r * std::sin(a)), 0};
    Rgba8 c;
    int level = 0;
    ASSERT_TRUE(s.nearest(p, up, c, &level));
    ASSERT_EQ(c, pack_rgba8(255, 255, 255, 255)) << "the dab reached r = " << r;
    coarse += level < 9;

    float rgba[4];
    ASSERT_TRUE(s.filtered(p, up, 0.0f, rgba));
    for (int k = 0; k < 4; ++k)
      ASSERT_NEAR(rgba[k], 1.0f, 1e-6) << "r = " << r << " level " << level << " channel " << k;
    ++checked;
  }
  EXPECT_GT(coarse, checked / 2) << "the points should mostly lie in coarse leaves";
}

TEST(PaintFilter, ContinuousFromCoarseLeavesIntoFineOnes) {
  const DabOnSheet d;
  OctreeSampler s(d.tex);
  const float up[3] = {0, 0, 1};
  // Along rays from the dab's centre out into the coarse leaves, steps of 0.05 leaf: trilinear
  // at the dab's depth changes a channel by at most one per leaf (0.05 a step); a switch of level
  // would jump.
  for (int ray = 0; ray < 16; ++ray) {
    const double a = 2 * M_PI * (ray + 0.37) / 16.0;
    float last[4] = {1, 0, 0, 1};
    int levels_seen = 0, prev_level = -1;
    for (double r = 0.0; r < 0.3 + 30 * d.leaf; r += 0.05 * d.leaf) {
      const float p[3] = {float(r * std::cos(a)), float(r * std::sin(a)), 0};
      float rgba[4];
      ASSERT_TRUE(s.filtered(p, up, 0.0f, rgba));
      for (int k = 0; k < 4; ++k)
        ASSERT_LE(std::abs(rgba[k] - last[k]), 0.08f) << "ray " << ray << " r " << r << " " << k;
      std::copy(rgba, rgba + 4, last);
      Rgba8 c;
      int level = 0;
      s.nearest(p, up, c, &level);
      levels_seen += level != prev_level;
      prev_level = level;
    }
    EXPECT_GE(levels_seen, 2) << "the ray should cross from fine leaves into coarse ones";
  }
}

// A drawn surface lies a little off the one painted (a limit surface against its tessellation),
// and can cross into a cell the paint never touched, empty up to a coarse level. The filter there
// must go down to the painted leaves beside it, not read the coarse level's cell centres (which
// miss the sheet and gave the background: specks in painted bands). The sheet lies 0.3 leaf above
// the cube's middle plane, so points a fraction of a leaf below it are in the cube's empty lower
// half (an empty level-1 cell); two leaves and more away the filter still finds nothing.
TEST(PaintFilter, PointsJustOffThePaintKeepItsColour) {
  const float origin[3] = {-2, -2, -2};
  const float leaf = 4.0f / 512.0f;
  const float z0 = 0.3f * leaf;
  const Mesh m = test::sheet(-1, 1, -1, 1, z0, 8, true);
  const PaintSurface surface(m);
  OctreeTexture t = OctreeTexture::empty(origin, 4.0f, pack_rgba8(255, 255, 255, 255));
  {
    Brush b;
    b.depth = 9, b.radius = 0.2f, b.hardness = 1;
    b.color[0] = 1, b.color[1] = 0, b.color[2] = 0, b.color[3] = 1;
    StrokePainter p(t, surface);
    p.begin(b);
    const float at[3] = {0, 0, z0};
    p.dab_world(at);
    p.end();
  }
  OctreeSampler s(t);
  const float up[3] = {0, 0, 1};
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u01(0, 1);
  std::vector<float> pts, nrm;
  std::vector<uint8_t> want;
  size_t empty_cells = 0;
  for (int i = 0; i < 3000; ++i) {
    const float a = 2 * float(M_PI) * u01(rng), r = (0.2f - 3 * leaf) * std::sqrt(u01(rng));
    const bool near = i % 4 != 0;
    // Near: 0.75 leaf below to 0.95 above the sheet (below, within half a leaf of the painted
    // cells' centres, where trilinear taps reach them); far: 2.5 to 4 leaves below it.
    const float dz = near ? (1.7f * u01(rng) - 0.75f) * leaf : -(2.5f + 1.5f * u01(rng)) * leaf;
    const float p[3] = {r * std::cos(a), r * std::sin(a), z0 + dz};
    Rgba8 c;
    int level = 0;
    if (!s.nearest(p, up, c, &level)) empty_cells += near && level < 9;
    float rgba[4];
    ASSERT_EQ(s.filtered(p, up, 0.0f, rgba), near) << "dz " << dz / leaf << " leaf";
    for (int k = 0; k < 4 && near; ++k)
      ASSERT_NEAR(rgba[k], k == 0 || k == 3 ? 1.0f : 0.0f, 1e-6) << k;
    pts.insert(pts.end(), p, p + 3);
    nrm.insert(nrm.end(), up, up + 3);
    want.push_back(near);
  }
  EXPECT_GT(empty_cells, 300u) << "points below the sheet should lie in coarse empty cells";
  GlContext ctx;
  const GpuOctreeTexture gpu(t);
  const GpuOctreeTexture::Lookups l = gpu.lookup(pts, nrm, 0.0f);
  for (size_t i = 0; i < want.size(); ++i) {
    ASSERT_EQ(bool(l.filtered_found[i]), bool(want[i])) << i;
    for (int k = 0; k < 4 && want[i]; ++k)
      ASSERT_NEAR(l.filtered[4 * i + k], k == 0 || k == 3 ? 1.0f : 0.0f, 2e-3) << i;
  }
}

// A coherent path (rows of points a fraction of a leaf apart) is what the sampler's brick table
// serves: bricks are unpacked and their taps read from there, while a fresh sampler per point
// reads every tap from the pool. Both must give the same results to the bit, on two sheets a
// fraction of a leaf apart (two-sided cells, each side painted its own way), seen from both
// sides, over mixed depths; and both equal the brute-force map.
TEST(PaintFilter, CoherentPathsEqualFreshSamplersAndTheMap) {
  const double leaf = 2.04 / 256.0, gap = 0.3 * leaf;
  const Mesh m = test::merge({test::sheet(-1, 1, -1, 1, gap, 30, true),
                              test::sheet(-1, 1, -1, 1, 0.0, 30, false),
                              test::sheet(0.9, 1, 0.9, 1, 0.5, 1, true)});
  const PaintSurface surface(m);
  OctreeTexture t = OctreeTexture::create(surface, pack_rgba8(40, 80, 120, 255));
  std::mt19937 rng(11);
  random_dabs(t, surface, rng, 24, 7, 3, 0.08f, 0.12f, [&](int i, float u, float v, float at[3]) {
    at[0] = 0.6f * u - 0.3f, at[1] = 0.6f * v - 0.3f;
    at[2] = i % 2 == 0 ? float(gap) + 0.002f : -0.002f;  // A from above, B from below
  });
  ASSERT_GT(t.stats().double_cells, 1000u) << "the sheets should share cells";
  const test::CellMap map(t);
  const float up[3] = {0, 0, 1}, down[3] = {0, 0, -1};
  size_t found = 0, total = 0;
  for (int sheet = 0; sheet < 2; ++sheet)
    for (const float* n : {up, down}) {
      OctreeSampler path(t);
      const float z = sheet ? 0.0f : float(gap);
      const float step = float(0.37 * leaf);
      for (float y = -0.3f; y < 0.3f; y += 7 * step)
        for (float x = -0.3f; x < 0.3f; x += step) {
          const float p[3] = {x, y, z};
          float got[4], fresh[4], ref[4] = {0, 0, 0, 0};
          const bool hg = path.filtered(p, n, 0.0f, got);
          OctreeSampler one(t);
          ASSERT_EQ(one.filtered(p, n, 0.0f, fresh), hg) << x << "," << y << "," << z;
          for (int k = 0; k < 4; ++k) ASSERT_EQ(got[k], fresh[k]) << x << "," << y << " " << k;
          ASSERT_EQ(map.filtered(p, n, ref), hg) << x << "," << y << "," << z;
          for (int k = 0; k < 4 && hg; ++k) ASSERT_NEAR(got[k], ref[k], 2e-4) << k;
          found += hg, ++total;
        }
    }
  EXPECT_GT(found, total / 3);  // both sides seen, some from behind
}

// The brute-force map agrees on mixed depths (its filter resolves at the finest leaf its taps
// find, as the sampler's does), and so does the GPU.
TEST(PaintFilter, MixedDepthsEqualTheMapAndTheGpu) {
  const Mesh m = test::sheet(-1, 1, -1, 1, 0, 12, true);
  const PaintSurface surface(m);
  OctreeTexture t = OctreeTexture::create(surface, pack_rgba8(40, 80, 120, 255));
  std::mt19937 rng(7);
  random_dabs(t, surface, rng, 40, 5, 5, 0.05f, 0.15f, [](int, float u, float v, float at[3]) {
    at[0] = 2 * u - 1, at[1] = 2 * v - 1, at[2] = 0;
  });
  std::uniform_real_distribution<float> u01(0, 1);
  const test::CellMap map(t);
  OctreeSampler s(t);
  std::vector<float> pts, nrm;
  std::vector<float> want;
  std::vector<uint8_t> want_found;
  for (int i = 0; i < 6000; ++i) {
    const float p[3] = {2 * u01(rng) - 1, 2 * u01(rng) - 1, 0};
    const float n[3] = {0, 0, i % 3 == 0 ? -1.0f : 1.0f};
    float ref[4] = {0, 0, 0, 0}, got[4];
    const bool hr = map.filtered(p, n, ref);
    ASSERT_EQ(s.filtered(p, n, 0.0f, got), hr) << i;
    for (int k = 0; k < 4 && hr; ++k) ASSERT_NEAR(got[k], ref[k], 2e-4) << i << " " << k;
    pts.insert(pts.end(), p, p + 3);
    nrm.insert(nrm.end(), n, n + 3);
    want.insert(want.end(), got, got + 4);
    want_found.push_back(hr);
  }
  GlContext ctx;
  const GpuOctreeTexture gpu(t);
  const GpuOctreeTexture::Lookups l = gpu.lookup(pts, nrm, 0.0f);
  for (size_t i = 0; i < want_found.size(); ++i) {
    ASSERT_EQ(bool(l.filtered_found[i]), bool(want_found[i])) << i;
    for (int k = 0; k < 4; ++k) ASSERT_NEAR(l.filtered[4 * i + k], want[4 * i + k], 2e-3) << i;
  }
}

}  // namespace
}  // namespace limn
