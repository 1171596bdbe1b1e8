// The octree texture: the start tree, lookups against a plain map of the cells, filtering against
// a reference trilinear sum, the pool's free lists, deep levels.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "limn/io/mesh_io.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "paint_oracle.hpp"

namespace limn {
namespace {

using test::P3;

const std::string kModels = LIMN_SHARED_MODELS;

// The level-l cells the oracle says the surface meets, with box slack `slack`.
std::set<std::tuple<uint32_t, uint32_t, uint32_t>> surface_cells(const OctreeTexture& t,
                                                                 const std::vector<test::Tri>& tris,
                                                                 int level, double slack) {
  std::set<std::tuple<uint32_t, uint32_t, uint32_t>> out;
  const double cell = double(t.size()) / double(1u << level);
  for (const test::Tri& tri : tris) {
    if (tri.n == P3{0, 0, 0}) continue;
    uint32_t lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      const double mn = std::min({tri.a[size_t(k)], tri.b[size_t(k)], tri.c[size_t(k)]});
      const double mx = std::max({tri.a[size_t(k)], tri.b[size_t(k)], tri.c[size_t(k)]});
      lo[k] = uint32_t(std::max(0.0, std::floor((mn - t.origin()[k] - 2 * slack) / cell)));
      hi[k] = uint32_t(
          std::min(double((1u << level) - 1), std::floor((mx - t.origin()[k] + 2 * slack) / cell)));
    }
    for (uint32_t x = lo[0]; x <= hi[0]; ++x)
      for (uint32_t y = lo[1]; y <= hi[1]; ++y)
        for (uint32_t z = lo[2]; z <= hi[2]; ++z) {
          const P3 blo = {t.origin()[0] + x * cell, t.origin()[1] + y * cell,
                          t.origin()[2] + z * cell};
          const P3 bhi = {blo[0] + cell, blo[1] + cell, blo[2] + cell};
          if (test::tri_meets_box(tri, blo, bhi, slack)) out.insert({x, y, z});
        }
  }
  return out;
}

TEST(PaintOctree, StartTreeHoldsExactlyTheCellsTheSurfaceMeets) {
  const Mesh m = test::uv_sphere(1.0, 10, 20);
  const OctreeTexture t = OctreeTexture::create(m, pack_rgba8(10, 20, 30, 40));
  EXPECT_EQ(t.check(), "");
  std::set<std::tuple<uint32_t, uint32_t, uint32_t>> got;
  size_t other_levels = 0;
  t.for_each_sample([&](const OctreeSample& s) {
    if (s.level != octree::kStartDepth) ++other_levels;
    if (s.side == 0) got.insert({s.x, s.y, s.z});
    EXPECT_EQ(s.color, pack_rgba8(10, 20, 30, 40));
  });
  EXPECT_EQ(other_levels, 0u);
  const auto tris = test::triangles(m);
  const double slack = double(t.size()) / double(1u << 22);
  const auto inner = surface_cells(t, tris, octree::kStartDepth, slack * 0.5);
  const auto outer = surface_cells(t, tris, octree::kStartDepth, slack * 2);
  for (const auto& c : inner) EXPECT_TRUE(got.count(c)) << "missing a surface cell";
  for (const auto& c : got) EXPECT_TRUE(outer.count(c)) << "a cell the surface does not meet";
  EXPECT_GT(got.size(), 50u);
  // The cube is the mesh's bounding cube.
  EXPECT_NEAR(t.size(), 2.0 * 1.02, 1e-5);
}

// Random dabs at mixed depths, colours, blends.
void paint_random(OctreeTexture& t, const PaintSurface& s, const Mesh& m, std::mt19937& rng,
                  int dabs, std::initializer_list<int> depths, float radius_frac) {
  const auto tris = test::triangles(m);
  std::uniform_real_distribution<double> u01(0, 1);
  const std::vector<int> ds(depths);
  for (int i = 0; i < dabs; ++i) {
    Brush b;
    b.depth = ds[size_t(i) % ds.size()];
    b.radius = float(t.size() * radius_frac * (0.5 + u01(rng)));
    for (float& c : b.color) c = float(u01(rng));
    b.hardness = float(u01(rng));
    b.opacity = float(0.3 + 0.7 * u01(rng));
    b.blend = BlendMode(i % 4);
    const test::Tri& tri = tris[size_t(u01(rng) * double(tris.size())) % tris.size()];
    const P3 p = test::point_in(tri, u01(rng), u01(rng));
    const float pf[3] = {float(p[0]), float(p[1]), float(p[2])};
    StrokePainter sp(t, s);
    sp.begin(b);
    sp.dab_world(pf);
    sp.end();
  }
}

struct Probe {
  float p[3];
  float n[3];
  bool has_n;
};

std::vector<Probe> probes(const OctreeTexture& t, const Mesh& m, std::mt19937& rng, size_t count) {
  const auto tris = test::triangles(m);
  std::uniform_real_distribution<double> u01(0, 1);
  std::vector<Probe> out;
  for (size_t i = 0; i < count; ++i) {
    Probe pr{};
    const int kind = int(i % 4);
    if (kind < 3) {
      const test::Tri& tri = tris[size_t(u01(rng) * double(tris.size())) % tris.size()];
      const P3 p = test::point_in(tri, u01(rng), u01(rng));
      for (int k = 0; k < 3; ++k) pr.p[k] = float(p[size_t(k)]);
      for (int k = 0; k < 3; ++k) pr.n[k] = float(kind == 1 ? -tri.n[size_t(k)] : tri.n[size_t(k)]);
      pr.has_n = kind != 2;
    } else {
      for (int k = 0; k < 3; ++k) {
        pr.p[k] = float(t.origin()[k] + t.size() * (1.1 * u01(rng) - 0.05));
        pr.n[k] = float(u01(rng) - 0.5);
      }
      pr.has_n = true;
    }
    out.push_back(pr);
  }
  return out;
}

void expect_lookups_match(const OctreeTexture& t, const Mesh& m, std::mt19937& rng) {
  const test::CellMap map(t);
  std::vector<Probe> pr = probes(t, m, rng, 12000);
  OctreeSampler random_order(t);
  size_t found = 0, compared_filtered = 0;
  for (const Probe& q : pr) {
    const float* n = q.has_n ? q.n : nullptr;
    Rgba8 want, got, fresh;
    const bool w = map.nearest(q.p, n, want);
    const bool g = random_order.nearest(q.p, n, got);
    const bool f = lookup_nearest(t, q.p, n, fresh);
    ASSERT_EQ(w, g);
    ASSERT_EQ(w, f);
    ASSERT_EQ(want, got);
    ASSERT_EQ(want, fresh);
    found += w;
    float rf[4], lf[4];
    const bool hr = map.filtered(q.p, n, rf);
    if (hr) {
      ASSERT_TRUE(random_order.filtered(q.p, n, 0.0f, lf));
      for (int k = 0; k < 4; ++k) ASSERT_NEAR(rf[k], lf[k], 2e-4) << k;
      ++compared_filtered;
    }
  }
  EXPECT_GT(found, pr.size() / 2);
  EXPECT_GT(compared_filtered, pr.size() / 2);
  // With a top-level index (any level), in batches, and after compaction: the same answers.
  std::vector<float> pts, nrm;
  for (const Probe& q : pr) {
    pts.insert(pts.end(), q.p, q.p + 3);
    nrm.insert(nrm.end(), q.n, q.n + 3);
  }
  const OctreeIndex idx4(t, 4), idx6(t, 6);
  OctreeTexture compacted = t;
  compacted.compact();
  ASSERT_EQ(compacted.check(), "");
  EXPECT_LE(compacted.words().size(), t.words().size());
  const OctreeIndex idxc(compacted, 5);
  for (int variant = 0; variant < 3; ++variant) {
    const OctreeTexture& tex = variant == 2 ? compacted : t;
    OctreeSampler smp(tex, variant == 0 ? &idx4 : variant == 1 ? &idx6 : &idxc);
    OctreeSampler batch(tex, variant == 1 ? &idx6 : nullptr);
    std::vector<Rgba8> got(pr.size());
    std::vector<uint8_t> got_found(pr.size());
    std::vector<float> got_f(4 * pr.size());
    batch.nearest_batch(pts.data(), nrm.data(), pr.size(), got.data(), got_found.data());
    batch.filtered_batch(pts.data(), nrm.data(), pr.size(), 0.0f, got_f.data());
    for (size_t i = 0; i < pr.size(); ++i) {
      const float* n = pr[i].has_n ? pr[i].n : nullptr;
      Rgba8 want, c;
      const bool w = map.nearest(pr[i].p, n, want);
      ASSERT_EQ(smp.nearest(pr[i].p, n, c), w) << variant;
      ASSERT_EQ(c, want) << variant;
      if (!pr[i].has_n) continue;  // the batch calls were given every normal
      ASSERT_EQ(bool(got_found[i]), w) << variant;
      ASSERT_EQ(got[i], want) << variant;
      float rf[4];
      if (map.filtered(pr[i].p, n, rf)) {
        for (int k = 0; k < 4; ++k) ASSERT_NEAR(got_f[4 * i + size_t(k)], rf[k], 2e-4) << variant;
      }
    }
  }
  // The same points in Morton order through one cached sampler.
  std::vector<std::pair<uint64_t, size_t>> order;
  for (size_t i = 0; i < pr.size(); ++i) {
    uint64_t key = 0;
    uint32_t c[3];
    for (int k = 0; k < 3; ++k) {
      const double u = std::clamp((double(pr[i].p[k]) - t.origin()[k]) / t.size(), 0.0, 0.999999);
      c[k] = uint32_t(u * 65536.0);
    }
    for (int b = 15; b >= 0; --b)
      for (int k = 0; k < 3; ++k) key = key << 1 | (c[k] >> b & 1u);
    order.push_back({key, i});
  }
  std::sort(order.begin(), order.end());
  OctreeSampler coherent(t);
  for (auto [key, i] : order) {
    const float* n = pr[i].has_n ? pr[i].n : nullptr;
    Rgba8 want, got;
    ASSERT_EQ(map.nearest(pr[i].p, n, want), coherent.nearest(pr[i].p, n, got));
    ASSERT_EQ(want, got);
  }
}

TEST(PaintOctree, LookupsEqualAMapOfTheCellsOnRandomPoints) {
  std::mt19937 rng(7);
  const Mesh m = test::uv_sphere(1.0, 24, 48);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(255, 255, 255, 0));
  paint_random(t, s, m, rng, 24, {5, 8, 10, 7, 11}, 0.03f);
  ASSERT_EQ(t.check(), "");
  const OctreeTextureStats st = t.stats();
  EXPECT_GE(st.max_depth, 11);
  EXPECT_GT(st.bricks, 10u);
  expect_lookups_match(t, m, rng);
}

TEST(PaintOctree, LookupsEqualAMapOfTheCellsOnSpot) {
  std::mt19937 rng(11);
  const Mesh m = read_mesh(kModels + "/tri/spot.obj");
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  paint_random(t, s, m, rng, 20, {10, 9, 6}, 0.02f);
  ASSERT_EQ(t.check(), "");
  expect_lookups_match(t, m, rng);
}

// The mip average of a cell, recomputed from the map: a leaf's value (both sides averaged), or
// the mean of its occupied children's averages, premultiplied by alpha and rounded to RGBA8 at
// every level, as the header documents.
using CellKey = std::tuple<int, uint32_t, uint32_t, uint32_t>;

// Every cell above a leaf of the map (where averages live).
std::set<CellKey> ancestors(const test::CellMap& map) {
  std::set<CellKey> out;
  for (const auto& [key, cell] : map.cells) {
    auto [l, x, y, z] = key;
    while (l > 0) --l, x >>= 1, y >>= 1, z >>= 1, out.insert({l, x, y, z});
  }
  return out;
}

Rgba8 reference_average(const test::CellMap& map, const std::set<CellKey>& above, int level,
                        uint32_t x, uint32_t y, uint32_t z, bool& any) {
  auto it = map.cells.find({level, x, y, z});
  auto mean = [](const std::vector<Rgba8>& v) -> Rgba8 {
    double r = 0, g = 0, b = 0, a = 0;
    for (Rgba8 c : v) {
      const double al = channel(c, 3);
      r += channel(c, 0) * al, g += channel(c, 1) * al, b += channel(c, 2) * al, a += al;
    }
    if (v.empty() || a <= 0) return 0;
    auto q = [](double d) { return uint32_t(std::clamp(std::lround(d), 0l, 255l)); };
    return pack_rgba8(q(r / a), q(g / a), q(b / a), q(a / double(v.size())));
  };
  if (it != map.cells.end()) {
    any = true;
    return it->second.dbl ? mean({it->second.s[0], it->second.s[1]}) : it->second.s[0];
  }
  if (!above.count({level, x, y, z})) {
    any = false;
    return 0;
  }
  std::vector<Rgba8> kids;
  for (uint32_t c = 0; c < 8; ++c) {
    bool k = false;
    const Rgba8 v = reference_average(map, above, level + 1, 2 * x + (c & 1), 2 * y + (c >> 1 & 1),
                                      2 * z + (c >> 2), k);
    if (k) kids.push_back(v);
  }
  any = !kids.empty();
  return mean(kids);
}

TEST(PaintOctree, MipAveragesAreTheMeansOfTheirCells) {
  std::mt19937 rng(21);
  const Mesh m = test::uv_sphere(1.0, 16, 32);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(255, 255, 255, 128));
  paint_random(t, s, m, rng, 10, {6, 8}, 0.1f);
  const test::CellMap map(t);
  const std::set<CellKey> above = ancestors(map);
  OctreeSampler smp(t);
  size_t compared = 0;
  std::uniform_int_distribution<uint32_t> coord(0, 65535);
  for (int i = 0; i < 3000; ++i) {
    const uint32_t x = coord(rng), y = coord(rng), z = coord(rng);
    const int level = int(rng() % 8);
    // Only cells whose subtree holds no leaf coarser than them (those read as the leaf).
    int leaf_level = 0;
    if (map.leaf(x, y, z, &leaf_level) && leaf_level <= level) continue;
    bool any = false;
    const Rgba8 want = reference_average(map, above, level, x >> (16 - level), y >> (16 - level),
                                         z >> (16 - level), any);
    Rgba8 got;
    const bool found = smp.cell_value(x, y, z, level, nullptr, got);
    ASSERT_EQ(found, any) << level;
    if (!any) continue;
    for (int k = 0; k < 4; ++k)
      ASSERT_NEAR(double(channel(got, k)), double(channel(want, k)), 1.0) << level << " " << k;
    ++compared;
  }
  EXPECT_GT(compared, 300u);
  // A wide footprint reads the averages: at a red/blue boundary it mixes, a point lookup does not.
  const Mesh sh = test::sheet(-1, 1, -1, 1, 0, 8, true);
  const PaintSurface ss(sh);
  OctreeTexture u = OctreeTexture::create(ss);
  for (const auto& [x, r, b] : {std::tuple{-0.5f, 1.0f, 0.0f}, std::tuple{0.5f, 0.0f, 1.0f}}) {
    Brush br;
    br.depth = 8, br.radius = 0.52f, br.hardness = 1;
    br.color[0] = r, br.color[1] = 0, br.color[2] = b, br.color[3] = 1;
    StrokePainter p(u, ss);
    p.begin(br);
    const float at[3] = {x, 0, 0};
    p.dab_world(at);
    p.end();
  }
  const float up[3] = {0, 0, 1}, at[3] = {-0.06f, 0.0f, 0.0f};
  float sharp[4], wide[4];
  OctreeSampler su(u);
  ASSERT_TRUE(su.filtered(at, up, 0.0f, sharp));
  ASSERT_TRUE(su.filtered(at, up, 0.3f, wide));
  EXPECT_GT(sharp[0], 0.9f);
  EXPECT_LT(sharp[2], 0.1f);
  EXPECT_GT(wide[0], 0.2f);
  EXPECT_GT(wide[2], 0.2f);
}

TEST(PaintOctree, FreedBlocksAreRecycledAndEveryWordIsAccountedFor) {
  const Mesh m = test::uv_sphere(1.0, 16, 32);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  const float here[3] = {0, 0, 1}, there[3] = {0, 1, 0};
  Brush b;
  b.radius = 0.3f;
  b.depth = 6;
  for (int depth : {6, 9}) {  // deeper over the same place: bricks explode, blocks are freed
    b.depth = depth;
    StrokePainter p(t, s);
    p.begin(b);
    p.dab_world(here);
    p.end();
    ASSERT_EQ(t.check(), "");
  }
  const auto freed = t.free_blocks();
  ASSERT_FALSE(freed.empty());
  b.depth = 9;
  StrokePainter p(t, s);
  p.begin(b);
  p.dab_world(there);
  p.end();
  ASSERT_EQ(t.check(), "");  // no overlaps, no leaks: every word is in a live or a free block
  const auto still = t.free_blocks();
  size_t reused = 0;
  for (const auto& f : freed)
    if (!std::binary_search(still.begin(), still.end(), f)) ++reused;
  EXPECT_GT(reused, 0u) << "freed blocks were not handed out again";
}

TEST(PaintOctree, DepthTwelveAndSixteenAreReachable) {
  const Mesh m = test::uv_sphere(1.0, 16, 32);
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  const float a[3] = {0.6f, 0.0f, 0.8f}, c[3] = {-0.6f, 0.0f, -0.8f};
  for (auto [depth, radius, near] : {std::tuple{12, 0.004f, a}, std::tuple{16, 0.0003f, c}}) {
    SurfaceHit on;
    ASSERT_TRUE(s.closest_point(near, 1, on));
    const float* where = on.p;
    Brush b;
    b.depth = depth, b.radius = radius, b.hardness = 1;
    b.color[0] = 0, b.color[1] = 1, b.color[2] = 0, b.color[3] = 1;
    StrokePainter p(t, s);
    p.begin(b);
    ASSERT_TRUE(p.dab_world(where));
    p.end();
    SurfaceHit h;
    ASSERT_TRUE(s.closest_point(where, 1, h));
    Rgba8 col;
    int level = 0;
    OctreeSampler smp(t);
    ASSERT_TRUE(smp.nearest(h.p, h.n, col, &level));
    EXPECT_EQ(col, pack_rgba8(0, 255, 0, 255));
    EXPECT_EQ(level, depth);
  }
  ASSERT_EQ(t.check(), "");
  const OctreeTextureStats st = t.stats();
  EXPECT_EQ(st.max_depth, 16);
  // Adaptive: two small deep spots cost kilobytes, not the 65536^3 grid.
  EXPECT_LT(st.bytes, 400000u);
}

}  // namespace
}  // namespace limn
