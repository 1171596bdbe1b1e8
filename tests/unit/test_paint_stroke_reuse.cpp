// Reuse across the dabs of a stroke (StrokePainter::set_reuse): what a stroke keeps from one dab
// to the next (each brick's leaf triangle lists, each texel's nearest surface point) must never
// change a result. The reference is the same strokes painted with reuse off, on a texture of its
// own: every pool word, every stroke's counts, and undo/redo back to the exact bytes. The same
// holds for threads: a dab's task cells painted on many threads against the same strokes on one.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "limn/paint/brush.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "limn/paint/undo.hpp"
#include "paint_oracle.hpp"

namespace limn {
namespace {

std::vector<uint32_t> words(const OctreeTexture& t) {
  return {t.words().begin(), t.words().end()};
}

// A stroke: world polyline or screen polyline (with the camera), and its brush.
struct Stroke {
  Brush brush;
  std::vector<float> xyz;
  std::vector<double> xy;  // screen points (camera strokes)
};

// A circle of `n` points of radius r around (cx, cy) at height z: on a sphere of radius 1
// centred at 0 when z = sqrt(1 - r^2), a closed loop that comes back over its own paint.
std::vector<float> circle(float cx, float cy, float z, float r, int n, float turns = 1.0f) {
  std::vector<float> v;
  for (int i = 0; i <= n; ++i) {
    const float a = 6.2831853f * turns * float(i) / float(n);
    v.insert(v.end(), {cx + r * std::cos(a), cy + r * std::sin(a), z});
  }
  return v;
}

struct Counts {
  size_t dabs, changed, rays, leaves, nodes;
  bool operator==(const Counts&) const = default;
};

StrokeStats paint_stroke(OctreeTexture& t, const PaintSurface& s, const Stroke& st, bool reuse,
                         const PaintCamera* cam, PaintHistory* h) {
  StrokePainter p(t, s, h);
  p.set_reuse(reuse);
  p.begin(st.brush, st.xy.empty() ? nullptr : cam);
  if (st.xy.empty())
    p.stroke_world(st.xyz);
  else
    p.stroke_screen(st.xy);
  return p.end();
}

Counts paint(OctreeTexture& t, const PaintSurface& s, const Stroke& st, bool reuse,
             const PaintCamera* cam, PaintHistory* h) {
  const StrokeStats r = paint_stroke(t, s, st, reuse, cam, h);
  return {r.dabs, r.samples_changed, r.rays, r.leaves_created, r.nodes_created};
}

// Strokes on a sphere with two close sheets through it (cells with two sides): loops that
// overlap themselves and earlier strokes, cross many bricks, change radius, depth and blend mode,
// and screen strokes whose world radius changes from dab to dab.
std::vector<Stroke> strokes() {
  std::vector<Stroke> v;
  Stroke a;
  a.brush.radius = 0.12f, a.brush.depth = 8, a.brush.hardness = 0.4f;
  a.brush.color[0] = 0.9f, a.brush.color[1] = 0.1f, a.brush.opacity = 0.8f;
  a.xyz = circle(0, 0, 0.8f, 0.6f, 24, 1.25f);
  v.push_back(a);
  Stroke b = a;  // across the first, smaller spacing, another colour
  b.brush.spacing = 0.1f, b.brush.color[2] = 0.7f, b.brush.blend = BlendMode::add;
  b.xyz = {-0.9f, 0.05f, 0.5f, 0.0f, 0.0f, 1.0f, 0.9f, -0.05f, 0.5f};
  v.push_back(b);
  Stroke c = a;  // large and soft, deeper, over both
  c.brush.radius = 0.2f, c.brush.depth = 9, c.brush.hardness = 0.0f, c.brush.opacity = 0.5f;
  c.brush.blend = BlendMode::multiply;
  c.xyz = {0.1f, -0.3f, 0.95f, 0.1f, 0.3f, 0.95f};
  v.push_back(c);
  Stroke d = a;  // over the sheets near the equator, both sides of them
  d.brush.radius = 0.08f, d.brush.depth = 8, d.brush.blend = BlendMode::erase;
  d.xyz = {-1.0f, -0.3f, 0.0f, -1.0f, 0.3f, 0.0f, -0.7f, 0.6f, 0.0f};
  v.push_back(d);
  Stroke e;  // screen strokes through the camera
  e.brush.radius = 25, e.brush.depth = 8, e.brush.hardness = 0.6f;
  e.brush.color[1] = 0.9f;
  for (int i = 0; i <= 20; ++i)
    e.xy.push_back(60.0 + 14.0 * i), e.xy.push_back(150.0 + 50.0 * std::sin(0.3 * i));
  v.push_back(e);
  Stroke f = e;
  f.brush.radius = 40, f.brush.spacing = 0.2f, f.brush.blend = BlendMode::mix;
  f.xy = {320, 40, 200, 260, 150, 120};
  v.push_back(f);
  return v;
}

Mesh scene() {
  // Leaves at depth 8 over the cube of side ~2.0 are ~0.008 wide: the sheets are 0.002 apart.
  return test::merge({test::uv_sphere(1.0, 30, 60),
                      test::sheet(-1.2, -0.2, -0.6, 0.6, 0.0, 25, true),
                      test::sheet(-1.2, -0.2, -0.6, 0.6, 0.002, 25, false)});
}

PaintCamera camera() {
  PaintCamera cam;
  cam.eye[0] = 0.4f, cam.eye[1] = -0.6f, cam.eye[2] = 3.0f;
  cam.fovy_deg = 40, cam.width = 400, cam.height = 300;
  return cam;
}

TEST(PaintStrokeReuse, SameBytesAsWithoutReuseStrokeByStroke) {
  const Mesh m = scene();
  const PaintSurface s(m);
  const PaintCamera cam = camera();
  OctreeTexture on = OctreeTexture::create(s), off = OctreeTexture::create(s);
  ASSERT_EQ(words(on), words(off));
  size_t changed = 0, dabs = 0;
  for (const Stroke& st : strokes()) {
    const Counts a = paint(on, s, st, true, &cam, nullptr);
    const Counts b = paint(off, s, st, false, &cam, nullptr);
    EXPECT_EQ(a, b);
    ASSERT_EQ(words(on), words(off)) << "stroke " << dabs;
    changed += a.changed, dabs += a.dabs;
  }
  // The strokes did paint, in many dabs each.
  EXPECT_GT(dabs, 60u);
  EXPECT_GT(changed, 20000u);
}

TEST(PaintStrokeReuse, ScreenPointsFedOneAtATimeGiveTheSameDabsAndBytes) {
  // extend_screen, as the viewer feeds a drag, against stroke_screen over all the points.
  const Mesh m = scene();
  const PaintSurface s(m);
  const PaintCamera cam = camera();
  for (const Stroke& st : strokes()) {
    if (st.xy.empty()) continue;
    OctreeTexture all = OctreeTexture::create(s), fed = OctreeTexture::create(s);
    StrokePainter a(all, s), b(fed, s);
    a.begin(st.brush, &cam);
    a.stroke_screen(st.xy);
    const StrokeStats sa = a.end();
    b.begin(st.brush, &cam);
    for (size_t i = 0; i + 1 < st.xy.size(); i += 2) b.extend_screen(st.xy[i], st.xy[i + 1]);
    const StrokeStats sb = b.end();
    EXPECT_GT(sa.dabs, st.xy.size() / 2);  // more dabs than points: the spacing matters
    EXPECT_EQ(sa.dabs, sb.dabs);
    EXPECT_EQ(sa.samples_changed, sb.samples_changed);
    ASSERT_EQ(words(all), words(fed));
  }
}

TEST(PaintStrokeReuse, RepaintingOverEarlierPaintGivesTheSameBytes) {
  // Every stroke twice over (the second time over the stroke's own paint, all bricks built), in
  // reverse order the second time.
  const Mesh m = scene();
  const PaintSurface s(m);
  const PaintCamera cam = camera();
  OctreeTexture on = OctreeTexture::create(s), off = OctreeTexture::create(s);
  std::vector<Stroke> all = strokes();
  for (int pass = 0; pass < 2; ++pass) {
    for (size_t i = 0; i < all.size(); ++i) {
      Stroke st = all[pass ? all.size() - 1 - i : i];
      st.brush.color[0] = pass ? 0.3f : 0.6f;
      const Counts a = paint(on, s, st, true, &cam, nullptr);
      const Counts b = paint(off, s, st, false, &cam, nullptr);
      EXPECT_EQ(a, b);
      ASSERT_EQ(words(on), words(off)) << "pass " << pass << " stroke " << i;
    }
  }
}

TEST(PaintStrokeReuse, UndoAndRedoGiveBackTheExactBytes) {
  const Mesh m = scene();
  const PaintSurface s(m);
  const PaintCamera cam = camera();
  OctreeTexture t = OctreeTexture::create(s), ref = OctreeTexture::create(s);
  PaintHistory h;
  std::vector<std::vector<uint32_t>> before, after;
  for (const Stroke& st : strokes()) {
    before.push_back(words(t));
    paint(t, s, st, true, &cam, &h);
    paint(ref, s, st, false, &cam, nullptr);
    after.push_back(words(t));
    ASSERT_EQ(after.back(), words(ref));
  }
  // Undo all, each step back to the bytes before that stroke; redo all; then undo two and paint
  // a stroke again with reuse: the same bytes as painting it there without.
  for (size_t i = before.size(); i-- > 0;) {
    ASSERT_TRUE(h.undo(t));
    ASSERT_EQ(words(t), before[i]) << "undo of stroke " << i;
  }
  for (size_t i = 0; i < after.size(); ++i) {
    ASSERT_TRUE(h.redo(t));
    ASSERT_EQ(words(t), after[i]) << "redo of stroke " << i;
  }
  ASSERT_TRUE(h.undo(t));
  ASSERT_TRUE(h.undo(t));
  OctreeTexture t2 = OctreeTexture::create(s);
  for (size_t i = 0; i + 2 < strokes().size(); ++i)
    paint(t2, s, strokes()[i], false, &cam, nullptr);
  ASSERT_EQ(words(t), words(t2));
  const Stroke again = strokes()[1];
  paint(t, s, again, true, &cam, &h);
  paint(t2, s, again, false, &cam, nullptr);
  EXPECT_EQ(words(t), words(t2));
  ASSERT_TRUE(h.undo(t));
  EXPECT_EQ(words(t), before[before.size() - 2]);
}

// The reuse tests' scene, and arenas of one and of four threads (more than this machine may have:
// TBB oversubscribes).
class PaintThreads : public ::testing::Test {
 protected:
  const Mesh m = scene();
  const PaintSurface s{m};
  const PaintCamera cam = camera();
  tbb::global_control allow{tbb::global_control::max_allowed_parallelism, 4};
  tbb::task_arena one{1}, four{4};
};

TEST_F(PaintThreads, SameBytesOnOneThreadAndOnFour) {
  // Both passes of every stroke (the second over built bricks, in reverse order), reuse on and
  // off, world and screen strokes, depths 8 and 9: on four threads against one, every pool
  // word, free list, count and undo step.
  OctreeTexture a = OctreeTexture::create(s), b = OctreeTexture::create(s);
  PaintHistory ha, hb;
  std::vector<Stroke> all = strokes();
  size_t threaded = 0, tasks = 0;
  std::vector<std::vector<uint32_t>> before;
  for (int pass = 0; pass < 2; ++pass)
    for (size_t i = 0; i < all.size(); ++i) {
      Stroke st = all[pass ? all.size() - 1 - i : i];
      st.brush.color[0] = pass ? 0.3f : 0.6f;
      const bool reuse = (i + size_t(pass)) % 2 == 0;
      std::vector<uint32_t> was = words(b);
      StrokeStats ra, rb;
      one.execute([&] { ra = paint_stroke(a, s, st, reuse, &cam, &ha); });
      four.execute([&] { rb = paint_stroke(b, s, st, reuse, &cam, &hb); });
      EXPECT_EQ(ra.dabs, rb.dabs);
      EXPECT_EQ(ra.samples_changed, rb.samples_changed);
      EXPECT_EQ(ra.rays, rb.rays);
      EXPECT_EQ(ra.leaves_created, rb.leaves_created);
      EXPECT_EQ(ra.nodes_created, rb.nodes_created);
      EXPECT_EQ(ra.tasks, rb.tasks);
      EXPECT_EQ(ra.tasks_threaded, 0u);
      ASSERT_TRUE(a == b) << "pass " << pass << " stroke " << i;
      ASSERT_EQ(b.check(), "");
      threaded += rb.tasks_threaded, tasks += rb.tasks;
      // A stroke that changed nothing leaves no undo step.
      if (words(b) != was) before.push_back(std::move(was));
    }
  // The threads did the painting: most task cells were visited beside siblings.
  EXPECT_GT(tasks, 1000u);
  EXPECT_GT(threaded, tasks / 2);
  // Undo on the threaded texture steps back through the same bytes.
  ASSERT_GT(before.size(), 8u);
  for (size_t i = before.size(); i-- > 0;) {
    ASSERT_TRUE(hb.undo(b));
    ASSERT_EQ(words(b), before[i]) << "undo " << i;
  }
  EXPECT_FALSE(hb.undo(b));
}

TEST_F(PaintThreads, RefiningAndFillingTheWholeSurfaceGiveTheSameBytes) {
  // Whole-surface runs (refine_surface, fill at a depth) over painted strokes: on four threads
  // against one, pool, free lists and counts.
  OctreeTexture a = OctreeTexture::create(s), b = OctreeTexture::create(s);
  const std::vector<Stroke> all = strokes();
  auto work = [&](OctreeTexture& t, size_t& filled) {
    paint(t, s, all[0], true, &cam, nullptr);
    refine_surface(t, s, 7);
    const float grey[4] = {0.5f, 0.5f, 0.5f, 1.0f};
    filled = fill(t, s, grey, BlendMode::mix, 0.5f, 8);
    paint(t, s, all[2], false, &cam, nullptr);  // depth 9 over it all
  };
  size_t fa = 0, fb = 0;
  one.execute([&] { work(a, fa); });
  four.execute([&] { work(b, fb); });
  EXPECT_GT(fa, 100000u);
  EXPECT_EQ(fa, fb);
  EXPECT_TRUE(a == b);
  EXPECT_EQ(b.check(), "");
}

}  // namespace
}  // namespace limn
