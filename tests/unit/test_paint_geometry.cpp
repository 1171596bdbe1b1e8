// The paint layer's fast box tests against its scalar triangle-box test: the 8-box test gives the
// scalar test's answer for every box (bit for bit, so refinement and painting keep the same
// cells), and the quick containment test never claims an overlap the scalar test denies; the
// BVH's box queries against testing every triangle, and a cell's leaf found from the BVH's
// candidates against the leaf of its exact list.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "limn/mesh/shapes.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "paint/cell_boxes.hpp"
#include "paint/geometry.hpp"
#include "paint/octree_blocks.hpp"
#include "paint/refine.hpp"
#include "paint_oracle.hpp"

namespace limn {
namespace {

using paint_detail::V3;

// The cell of `level` holding triangle tri's first corner.
void corner_cell(const OctreeTexture& t, const PaintSurface& s, uint32_t tri, int level,
                 uint32_t xyz[3]) {
  const uint32_t n = 1u << level;
  for (int k = 0; k < 3; ++k) {
    const float cell = std::floor((s.corner(tri, 0)[k] - t.origin()[k]) / t.size() * float(n));
    xyz[k] = uint32_t(std::clamp(cell, 0.0f, float(n - 1)));
  }
}

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

// The brick's leaf test (TriAxes from the brick's centre) against clipping the triangle to the
// box in double precision: a triangle meeting the box grown by the slack less the rounding of
// the float offsets is always found, and one missing the box grown by the slack plus that
// rounding never is. Boxes from 1/8 to 1/16384 of a unit cube, triangles from h/8 to 16 h
// around them, a quarter with a corner snapped onto a face (the cases rounding decides).
TEST(PaintGeometry, TriangleAxesTestIsTheBoxTestUpToRounding) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> u(-1, 1), pos(0, 1);
  const float slack = std::ldexp(1.0f, -22);
  size_t met = 0, total = 0, decided = 0;
  for (int iter = 0; iter < 200000; ++iter) {
    const float h = std::ldexp(1.0f, -3 - int(rng() % 12));
    const V3 o = {pos(rng), pos(rng), pos(rng)};  // the brick's centre
    // A leaf of the brick: offsets (i - 1.5) 2h.
    const float off[3] = {(float(rng() % 4) - 1.5f) * 2 * h, (float(rng() % 4) - 1.5f) * 2 * h,
                          (float(rng() % 4) - 1.5f) * 2 * h};
    const V3 c = {o.x + off[0], o.y + off[1], o.z + off[2]};
    const float size = h * std::ldexp(1.0f, int(rng() % 8) - 3);
    V3 p[3];
    for (V3& v : p) v = {c.x + size * u(rng) * 2, c.y + size * u(rng) * 2, c.z + size * u(rng) * 2};
    if (iter % 4 == 0) {
      const int axis = int(rng() % 3);
      const float face = (axis == 0 ? c.x : axis == 1 ? c.y : c.z) + (rng() % 2 ? h : -h);
      float* coord = axis == 0 ? &p[0].x : axis == 1 ? &p[0].y : &p[0].z;
      *coord = face + slack * u(rng);
    }
    paint_detail::TriAxes ta;
    paint_detail::tri_axes(o, h, slack, p[0], p[1], p[2], ta);
    const bool got = paint_detail::tri_axes_meet(ta, h, slack, off[0], off[1], off[2]);
    // The oracle, in double, on the box as the offsets place it.
    test::Tri t;
    t.a = {p[0].x, p[0].y, p[0].z}, t.b = {p[1].x, p[1].y, p[1].z}, t.c = {p[2].x, p[2].y, p[2].z};
    const test::P3 lo = {double(o.x) + off[0] - h, double(o.y) + off[1] - h,
                         double(o.z) + off[2] - h},
                   hi = {double(o.x) + off[0] + h, double(o.y) + off[1] + h,
                         double(o.z) + off[2] + h};
    double scale = 0;
    for (const V3& v : p)
      scale = std::max({scale, std::fabs(double(v.x) - o.x), std::fabs(double(v.y) - o.y),
                        std::fabs(double(v.z) - o.z)});
    scale = std::max({scale, double(std::fabs(off[0])) + h, double(std::fabs(off[1])) + h,
                      double(std::fabs(off[2])) + h});
    const double tol = std::ldexp(scale, -19);
    if (test::tri_meets_box(t, lo, hi, slack - tol)) {
      ASSERT_TRUE(got) << "iteration " << iter;
      ++decided;
    } else if (!test::tri_meets_box(t, lo, hi, slack + tol)) {
      ASSERT_FALSE(got) << "iteration " << iter;
      ++decided;
    }
    met += got, ++total;
  }
  EXPECT_GT(met, total / 10);
  EXPECT_LT(met, total * 9 / 10);
  EXPECT_GT(decided, total * 9 / 10);
}

// A brick's leaf masks (its two levels tested at once, 8 leaves per step) against testing each
// wanted leaf alone with the scalar form: the same bits, for bricks at every level of a sphere
// with two sheets through it, whole or with random wanted leaves.
TEST(PaintGeometry, LeafMasksEqualTestingEachLeaf) {
  const Mesh m =
      test::merge({test::uv_sphere(1.0, 30, 60), test::sheet(-1.2, -0.2, -0.6, 0.6, 0.0, 25, true),
                   test::sheet(-1.2, -0.2, -0.6, 0.6, 0.002, 25, false)});
  const PaintSurface s(m);
  OctreeTexture tex = OctreeTexture::create(s);
  const detail::CellBoxes r(tex, s);
  std::mt19937 rng(5);
  size_t bits = 0, tested = 0;
  std::vector<uint64_t> masks;
  for (int iter = 0; iter < 1500; ++iter) {
    const int level = 1 + int(rng() % 10);
    const uint32_t tri = uint32_t(rng() % s.triangle_count());
    uint32_t xyz[3];
    corner_cell(tex, s, tri, level, xyz);
    const detail::CellBox bb = r.box(level, xyz[0], xyz[1], xyz[2]);
    std::vector<uint32_t> list;
    const float c[3] = {bb.c.x, bb.c.y, bb.c.z};
    s.triangles_in_box(c, bb.h, r.slack(), list);
    const uint64_t want = iter % 2 ? ~uint64_t(0) : (uint64_t(rng()) << 32 | rng());
    r.leaf_masks(list, bb, want, masks);
    ASSERT_EQ(masks.size(), list.size());
    const detail::CellBoxes::BrickLeaves l = r.brick_leaves(bb);
    for (size_t i = 0; i < list.size(); ++i) {
      paint_detail::TriAxes ta;
      paint_detail::tri_axes(bb.c, l.h, r.slack(), paint_detail::v3(s.corner(list[i], 0)),
                             paint_detail::v3(s.corner(list[i], 1)),
                             paint_detail::v3(s.corner(list[i], 2)), ta);
      for (int leaf = 0; leaf < 64; ++leaf) {
        const detail::CellBox lb = detail::CellBoxes::leaf_box(l, leaf);
        ASSERT_EQ(lb.c.x, r.child(r.child(bb, leaf >> 3), leaf & 7).c.x);
        ASSERT_EQ(lb.c.y, r.child(r.child(bb, leaf >> 3), leaf & 7).c.y);
        ASSERT_EQ(lb.c.z, r.child(r.child(bb, leaf >> 3), leaf & 7).c.z);
        const bool expect =
            (want >> leaf & 1) && paint_detail::tri_axes_meet(ta, l.h, r.slack(), lb.c.x - bb.c.x,
                                                              lb.c.y - bb.c.y, lb.c.z - bb.c.z);
        ASSERT_EQ(bool(masks[i] >> leaf & 1), expect)
            << "iteration " << iter << " level " << level << " triangle " << list[i] << " leaf "
            << leaf;
        bits += expect, ++tested;
      }
    }
  }
  EXPECT_GT(bits, tested / 100);  // leaves met, and many not
  EXPECT_LT(bits, tested / 2);
}

// split() of a cell's list (the triangles meeting the cell, as filter() keeps them) against
// filter() on each child and clipping in double precision: no triangle meeting a child is
// lost, and every triangle a child gets meets its box grown by the slack, give or take the
// rounding of float coordinates (those whose bounds lie on the child's side go there
// untested). Cells from the root down to depth 12 on a sphere with two sheets through it.
TEST(PaintGeometry, SplitKeepsEveryTriangleMeetingAChildAndNothingFar) {
  const Mesh m =
      test::merge({test::uv_sphere(1.0, 30, 60), test::sheet(-1.2, -0.2, -0.6, 0.6, 0.0, 25, true),
                   test::sheet(-1.2, -0.2, -0.6, 0.6, 0.002, 25, false)});
  const PaintSurface s(m);
  const std::vector<test::Tri> tris = test::triangles(m);
  OctreeTexture tex = OctreeTexture::create(s);
  const detail::CellBoxes r(tex, s);
  std::mt19937 rng(13);
  size_t kept = 0, untested = 0;
  for (int iter = 0; iter < 1000; ++iter) {
    const int level = int(rng() % 12);
    const uint32_t tri = uint32_t(rng() % s.triangle_count());
    uint32_t xyz[3];
    corner_cell(tex, s, tri, level, xyz);
    const detail::CellBox cb = r.box(level, xyz[0], xyz[1], xyz[2]);
    std::vector<uint32_t> near, list;
    const float c[3] = {cb.c.x, cb.c.y, cb.c.z};
    s.triangles_near(c, cb.h * 1.7321f * 1.01f, near);
    r.filter(near, cb, list);
    detail::CellBox kids[8];
    r.children(cb, kids);
    const uint32_t want = iter % 3 ? 0xffu : uint32_t(rng() % 256);
    detail::Split out;
    r.split(list, cb, kids, out, want);
    for (int k = 0; k < 8; ++k) {
      std::vector<uint32_t> exact;
      if (want >> k & 1) r.filter(list, kids[k], exact);
      for (uint32_t t : exact)
        ASSERT_TRUE(std::binary_search(out[size_t(k)].begin(), out[size_t(k)].end(), t))
            << "iteration " << iter << " level " << level << " child " << k << " lost " << t;
      const detail::CellBox& kb = kids[k];
      const test::P3 lo = {double(kb.c.x) - kb.h, double(kb.c.y) - kb.h, double(kb.c.z) - kb.h},
                     hi = {double(kb.c.x) + kb.h, double(kb.c.y) + kb.h, double(kb.c.z) + kb.h};
      const double tol = std::ldexp(double(tex.size()), -20);
      for (uint32_t t : out[size_t(k)]) {
        ASSERT_TRUE(want >> k & 1);
        ASSERT_TRUE(test::tri_meets_box(tris[t], lo, hi, double(r.slack()) + tol))
            << "iteration " << iter << " level " << level << " child " << k << " far " << t;
        ++kept;
        untested += !std::binary_search(exact.begin(), exact.end(), t);
      }
    }
  }
  EXPECT_GT(kept, 10000u);
  EXPECT_LT(untested, kept / 1000 + 1);  // only the rounding cases differ from filter()
}

// The start cells' lists a dab splits instead of querying the BVH (kept with the surface per
// texture cube) against the BVH's box query on each start cell: the same triangles, for two
// textures of one surface with different cubes, asked in turn (the table follows the cube).
TEST(PaintGeometry, StartListsEqualTheBoxQueries) {
  const Mesh m =
      test::merge({test::uv_sphere(1.0, 30, 60), test::sheet(-1.2, -0.2, -0.6, 0.6, 0.0, 25, true),
                   test::sheet(-1.2, -0.2, -0.6, 0.6, 0.002, 25, false)});
  const PaintSurface s(m);
  OctreeTexture a = OctreeTexture::create(s, 0, 0.05f), b = OctreeTexture::create(s, 0, 0.3f);
  size_t found = 0;
  for (int round = 0; round < 2; ++round)
    for (OctreeTexture* t : {&a, &b}) {
      detail::Refiner r(*t, s);
      r.prepare_start_lists();
      const uint32_t n = 1u << octree::kStartDepth;
      for (uint32_t z = 0; z < n; ++z)
        for (uint32_t y = 0; y < n; ++y)
          for (uint32_t x = 0; x < n; ++x) {
            const detail::CellBox cb = r.boxes().box(octree::kStartDepth, x, y, z);
            const float c[3] = {cb.c.x, cb.c.y, cb.c.z};
            std::vector<uint32_t> want;
            s.triangles_in_box(c, cb.h, r.boxes().slack(), want);
            const std::span<const uint32_t> got = r.start_list(x, y, z);
            ASSERT_EQ(std::vector<uint32_t>(got.begin(), got.end()), want)
                << "cell " << x << " " << y << " " << z << " margin " << (t == &a ? 0.05 : 0.3);
            found += got.size();
          }
    }
  EXPECT_GT(found, 4 * s.triangle_count());  // every triangle in some cell, four times over
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

// A cell's leaf from the BVH's untested candidates (what refining a coarse leaf under a dab makes
// of the children off the dab) against make_leaf of the cell's exact list: the same tag, sides
// and colours, in any candidate order and with repeats, and no leaf where the list is empty. On
// a sphere with two sheets 0.002 apart through it, so that many cells have two sides.
TEST(PaintGeometry, LeafFromCandidatesEqualsTheLeafOfTheList) {
  const Mesh m =
      test::merge({test::uv_sphere(1.0, 30, 60), test::sheet(-1.2, -0.2, -0.6, 0.6, 0.0, 25, true),
                   test::sheet(-1.2, -0.2, -0.6, 0.6, 0.002, 25, false)});
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(10, 20, 30, 40));
  const detail::CellBoxes r(t, s);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  size_t leaves = 0, two_sided = 0, empty = 0;
  for (int iter = 0; iter < 4000; ++iter) {
    const int level = 1 + int(rng() % 11);
    // The cell holding a point of a triangle three times in four, else any cell.
    const uint32_t tri = uint32_t(rng() % s.triangle_count());
    const float a = u(rng), b = u(rng) * (1 - a);
    const uint32_t n = 1u << level;
    uint32_t xyz[3];
    for (int k = 0; k < 3; ++k) {
      const float p = iter % 4 ? s.corner(tri, 0)[k] * (1 - a - b) + s.corner(tri, 1)[k] * a +
                                     s.corner(tri, 2)[k] * b
                               : t.origin()[k] + t.size() * u(rng);
      const float cell = std::floor((p - t.origin()[k]) / t.size() * float(n));
      xyz[k] = uint32_t(std::clamp(cell, 0.0f, float(n - 1)));
    }
    const detail::CellBox cb = r.box(level, xyz[0], xyz[1], xyz[2]);
    const float c[3] = {cb.c.x, cb.c.y, cb.c.z};
    std::vector<uint32_t> list, candidates;
    s.triangles_in_box(c, cb.h, r.slack(), list);
    s.box_candidates(c, cb.h, r.slack(), candidates);
    for (uint32_t x : list)
      ASSERT_NE(std::find(candidates.begin(), candidates.end(), x), candidates.end());
    detail::LeafCell parent;
    parent.tag = uint8_t(1 + rng() % octree::kTagCount);
    parent.dbl = rng() % 2 != 0;
    parent.s[0] = pack_rgba8(1, 2, 3, 4), parent.s[1] = pack_rgba8(5, 6, 7, 8);
    const detail::LeafCell* from = iter % 5 ? &parent : nullptr;
    for (int order = 0; order < 2; ++order) {
      if (order == 1) {  // shuffled, with repeats
        const size_t k = candidates.size();
        for (size_t i = 0; i < k; i += 3) candidates.push_back(candidates[i]);
        std::shuffle(candidates.begin(), candidates.end(), rng);
      }
      detail::LeafCell got;
      ASSERT_EQ(r.leaf_from_candidates(candidates, cb, from, got), !list.empty()) << iter;
      if (list.empty()) continue;
      const detail::LeafCell want = r.make_leaf(list, from);
      ASSERT_EQ(got.tag, want.tag) << iter;
      ASSERT_EQ(got.dbl, want.dbl) << iter;
      ASSERT_EQ(got.s[0], want.s[0]) << iter;
      if (want.dbl) {
        ASSERT_EQ(got.s[1], want.s[1]) << iter;
      }
    }
    list.empty() ? ++empty : ++leaves;
    if (!list.empty() && r.make_leaf(list, from).dbl) ++two_sided;
  }
  // Both kinds of cells, and two-sided ones, were met.
  EXPECT_GT(leaves, 2000u);
  EXPECT_GT(empty, 200u);
  EXPECT_GT(two_sided, 20u);
}

// The split shortcut near the root (a list whose corners' bounds put every triangle in one
// child, inside its box, goes there whole, untested) against split() itself: the same lists
// whenever it claims so, for lists of triangles around points in cells of every level.
TEST(PaintGeometry, WholeListShortcutGivesTheSplitsLists) {
  const Mesh m = test::merge(
      {test::uv_sphere(1.0, 30, 60), test::sheet(-1.2, -0.2, -0.6, 0.6, 0.0, 25, true)});
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s);
  const detail::CellBoxes r(t, s);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(0, 1);
  size_t fired = 0, nowhere = 0, declined = 0;
  for (int iter = 0; iter < 3000; ++iter) {
    const int level = int(rng() % 4);  // cells far larger than the triangles
    const uint32_t tri = uint32_t(rng() % s.triangle_count());
    const float p[3] = {s.corner(tri, 0)[0], s.corner(tri, 0)[1], s.corner(tri, 0)[2]};
    uint32_t xyz[3];
    corner_cell(t, s, tri, level, xyz);
    const detail::CellBox cb = r.box(level, xyz[0], xyz[1], xyz[2]);
    std::vector<uint32_t> list;
    s.triangles_near(p, cb.h * std::ldexp(1.0f, -2 - int(rng() % 6)), list);
    detail::ListBox box = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    for (uint32_t x : list)
      for (int v = 0; v < 3; ++v)
        for (int a = 0; a < 3; ++a)
          box.lo[a] = std::min(box.lo[a], s.corner(x, v)[a]),
          box.hi[a] = std::max(box.hi[a], s.corner(x, v)[a]);
    detail::CellBox kids[8];
    r.children(cb, kids);
    const uint32_t want = iter % 3 ? 0xffu : uint32_t(rng() % 256);
    int only = -2;
    if (list.empty() || !r.whole_list_in_one(box, cb, want, only)) {
      ++declined;
      continue;
    }
    detail::Split out;
    r.split(list, cb, kids, out, want);
    for (int c = 0; c < 8; ++c)
      ASSERT_EQ(out[size_t(c)], c == only ? list : std::vector<uint32_t>{})
          << "iteration " << iter << " level " << level << " child " << c;
    only < 0 ? ++nowhere : ++fired;
  }
  // It took lists whole, dropped some (a child not wanted), and left others to the split.
  EXPECT_GT(fired, 140u);
  EXPECT_GT(nowhere, 80u);
  EXPECT_GT(declined, 1000u);
}

}  // namespace
}  // namespace limn
