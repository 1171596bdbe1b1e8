// View-dependent depth selection: the eigenvalues of the subdivision matrix, and the screen-space
// error of the adaptive surface against a deep reference (uniform level 7 pushed to the limit,
// which shares no code with the patches) for several cameras.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "deep_reference.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"

namespace limn {
namespace {

// fit_camera: every point inside the image with the margin free, the extent touching the margin
// on both sides of one axis (the tight one) and centred on the other, the direction kept. Shapes
// of different proportions (a flat torus, a tall box, scattered points), seen from an oblique and
// a side view, in a wide and a tall image.
TEST(Depth, FitCameraFillsThePictureWithAnyShape) {
  Mesh tall = make_cube();
  for (size_t v = 0; v < tall.vertex_count(); ++v) tall.positions[3 * v + 2] *= 6.0f;
  std::vector<float> scattered;
  uint64_t x = 7;
  for (int i = 0; i < 300; ++i) {
    x = x * 6364136223846793005ULL + 1442695040888963407ULL;
    scattered.push_back(float((x >> 33) % 1000) / 100.0f - 3.0f);
  }
  const std::vector<std::vector<float>> shapes = {make_shape("torus").positions, tall.positions,
                                                  scattered};
  for (const auto& pts : shapes)
    for (const auto& [w, h] : {std::pair{960, 600}, std::pair{400, 900}})
      for (const float dir : {0.3f, 2.0f}) {
        Camera view;
        view.width = w, view.height = h;
        view.target[0] = view.target[1] = view.target[2] = 1.0f;
        view.eye[0] = 40.0f, view.eye[1] = -25.0f * dir, view.eye[2] = 12.0f;
        view.up[0] = 0, view.up[1] = 0, view.up[2] = 1;
        const double margin = 0.05;
        const Camera c = fit_camera(view, pts, margin);
        double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
        for (size_t i = 0; i < pts.size() / 3; ++i) {
          double px, py;
          ASSERT_TRUE(c.project(&pts[3 * i], px, py));
          lo[0] = std::min(lo[0], px), hi[0] = std::max(hi[0], px);
          lo[1] = std::min(lo[1], py), hi[1] = std::max(hi[1], py);
        }
        const double size[2] = {double(w), double(h)};
        int tight = -1;
        for (int k = 0; k < 2; ++k) {
          const double m = margin * size[k];
          EXPECT_GE(lo[k], m - 1e-3 * size[k]) << k;
          EXPECT_LE(hi[k], size[k] - m + 1e-3 * size[k]) << k;
          // Centred: as much room on both sides.
          EXPECT_NEAR(lo[k], size[k] - hi[k], 0.02 * size[k]) << k;
          if (std::abs(lo[k] - m) < 1e-3 * size[k]) tight = k;
        }
        EXPECT_GE(tight, 0) << "the points touch no margin: not as large as they could be";
        // The view direction is kept.
        double a[3], b[3], la = 0, lb = 0, ab = 0;
        for (int k = 0; k < 3; ++k) {
          a[k] = double(view.target[k]) - view.eye[k], b[k] = double(c.target[k]) - c.eye[k];
          la += a[k] * a[k], lb += b[k] * b[k], ab += a[k] * b[k];
        }
        EXPECT_NEAR(ab / std::sqrt(la * lb), 1.0, 1e-6);
      }
  // Nothing to frame: the view as it was.
  const Camera same = fit_camera(Camera{}, {});
  EXPECT_EQ(same.eye[2], Camera{}.eye[2]);
}

TEST(Depth, EigenvaluesMatchTheDesignTable) {
  // ../shared/design/subdivision.md, from the closed form; valence 4 is the bicubic 1/2, 1/4.
  const int n[] = {3, 4, 5, 6, 7, 8, 10, 12};
  const double lambda[] = {.410, .500, .550, .580, .599, .611, .626, .635};
  const double mu[] = {.167, .250, .340, .410, .462, .500, .550, .580};
  for (int i = 0; i < 8; ++i) {
    double l, m;
    catmark_eigenvalues(n[i], l, m);
    EXPECT_NEAR(l, lambda[i], 6e-3) << n[i];
    EXPECT_NEAR(m, mu[i], 6e-3) << n[i];
  }
}

double max_screen_error(const Mesh& cage, const VertexErrorModel& model, const test::Reference& ref,
                        const Camera& cam, float tolerance, int* deepest) {
  DepthOptions d;
  d.tolerance_px = tolerance;
  d.max_depth = 12;
  const std::vector<uint8_t> depth = select_depths(cage, model, cam, d);
  *deepest = *std::max_element(depth.begin(), depth.end());
  PatchOptions po;
  po.subdiv = subdiv_options(cage);
  po.depth = 12;
  const PatchTable t = build_patches(cage, po, depth);
  const PatchMap map(t);
  const std::vector<float> pts = t.points(cage.positions);

  std::vector<PatchCoord> coords;
  std::vector<uint32_t> at;
  test::reference_samples(ref, map, coords, at);
  std::vector<float> got(3 * coords.size());
  evaluate_patches(t, pts, coords, got.data());
  double worst = 0;
  for (size_t i = 0; i < coords.size(); ++i) {
    const float* q = &ref.limit[3 * size_t(at[i])];
    double x, y;
    if (!cam.project(q, x, y) || x < 0 || y < 0 || x > cam.width || y > cam.height) continue;
    const double dist = std::hypot(got[3 * i] - q[0], got[3 * i + 1] - q[1], got[3 * i + 2] - q[2]);
    worst = std::max(worst, dist * cam.scale_at(q));
  }
  return worst;
}

// Both error sources: the per-valence estimate, and the errors measured on a hierarchy to depth 9
// (which compares end caps with that hierarchy's own deepest surface); the reference is
// independent of both.
TEST(Depth, ScreenErrorStaysWithinTolerance) {
  const int valences[] = {3, 5, 6, 8};
  Mesh torus = make_torus(16, 8, valences);
  for (size_t i = 0; i < torus.positions.size(); ++i)
    torus.positions[i] += 0.03f * std::sin(float(i) * 1.7f);  // break the symmetry
  const Mesh cube = make_shape("cube");
  for (const Mesh* cage : {static_cast<const Mesh*>(&torus), &cube}) {
    const test::Reference ref = test::reference(*cage, 7);
    const VertexErrorModel estimated = vertex_error_model(*cage, subdiv_options(*cage));
    VertexErrorModel measured = estimated;
    PatchOptions ho;
    ho.subdiv = subdiv_options(*cage);
    ho.depth = 9;
    measure_vertex_errors(*cage, build_patch_hierarchy(*cage, ho), measured);
    const Camera far = frame_camera(*cage, 640, 480);
    for (const float t : {0.5f, 2.0f}) {
      for (const float zoom : {1.0f, 0.6f, 0.35f}) {
        Camera c = far;
        for (int k = 0; k < 3; ++k) c.eye[k] = c.target[k] + zoom * (far.eye[k] - far.target[k]);
        for (const VertexErrorModel* m :
             {&estimated, static_cast<const VertexErrorModel*>(&measured)}) {
          const char* label = m == &measured ? "measured " : "estimated";
          int deepest = 0;
          const double e = max_screen_error(*cage, *m, ref, c, t, &deepest);
          EXPECT_LE(e, t) << "zoom " << zoom << " tolerance " << t << " deepest " << deepest << " "
                          << label;
          std::printf("%s zoom %.2f tolerance %.1f px: deepest %d, max error %.3f px\n", label,
                      zoom, t, deepest, e);
        }
      }
    }
  }
}

TEST(Depth, MeasuredErrorsAreTheCagesAndShrinkWithDepth) {
  const int valences[] = {3, 5, 6};
  const Mesh cage = make_torus(12, 8, valences);
  VertexErrorModel m = vertex_error_model(cage, subdiv_options(cage));
  PatchOptions ho;
  ho.subdiv = subdiv_options(cage);
  ho.depth = 6;
  const PatchHierarchy h = build_patch_hierarchy(cage, ho);
  measure_vertex_errors(cage, h, m);
  ASSERT_EQ(m.levels, 6);
  size_t measured = 0;
  for (size_t v = 0; v < cage.vertex_count(); ++v) {
    const float* e = &m.level_error[v * 6];
    if (m.k[v] == 0) {  // regular vertices govern no end cap
      EXPECT_EQ(*std::max_element(e, e + 6), 0.0f) << v;
      continue;
    }
    ++measured;
    EXPECT_GT(e[0], 0.0f) << v;
    // Each level roughly halves the error; never grows by more than noise.
    for (int d = 1; d < 6; ++d) EXPECT_LT(e[d], 0.9f * e[d - 1] + 1e-6f) << v << " " << d;
  }
  EXPECT_GT(measured, 0u);
  // A selection with measured errors rejects tables of another size, and another cage's
  // hierarchy is refused.
  const Mesh other = make_shape("cube");
  VertexErrorModel mo = vertex_error_model(other, subdiv_options(other));
  EXPECT_THROW(measure_vertex_errors(other, h, mo), InputError);
  VertexErrorModel broken = m;
  broken.level_error.pop_back();
  EXPECT_THROW(select_depths(cage, broken, frame_camera(cage, 64, 64), DepthOptions{}), InputError);
}

TEST(Depth, OutsideBallsNeverProjectIntoTheImage) {
  Camera c;
  c.eye[0] = 1, c.eye[1] = 2, c.eye[2] = 6;
  c.width = 640, c.height = 360;
  uint32_t state = 12345;
  auto rnd = [&] {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1u << 24);
  };
  size_t outside = 0, inside = 0;
  for (int i = 0; i < 20000; ++i) {
    const float p[3] = {20 * rnd() - 10, 20 * rnd() - 10, 20 * rnd() - 10};
    const double r = 2.0 * rnd();
    if (!c.ball_outside(p, r)) {
      ++inside;
      continue;
    }
    ++outside;
    // No point of the ball may land in the image.
    for (int k = 0; k < 50; ++k) {
      float d[3] = {2 * rnd() - 1, 2 * rnd() - 1, 2 * rnd() - 1};
      const float l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      const float q[3] = {p[0] + float(r) * d[0] / l, p[1] + float(r) * d[1] / l,
                          p[2] + float(r) * d[2] / l};
      double x, y;
      if (c.project(q, x, y)) {
        EXPECT_FALSE(x >= 0 && y >= 0 && x <= c.width && y <= c.height);
      }
    }
  }
  EXPECT_GT(outside, 1000u);
  EXPECT_GT(inside, 1000u);
}

TEST(Depth, HysteresisHoldsDepthButNeverUnderShoots) {
  const int valences[] = {5};
  const Mesh cage = make_torus(12, 8, valences);
  const VertexErrorModel model = vertex_error_model(cage, subdiv_options(cage));
  Camera c = frame_camera(cage, 640, 480);
  DepthOptions o;
  const std::vector<uint8_t> a = select_depths(cage, model, c, o);
  // Move slightly away: without hysteresis some depths may drop; with it, none drops by the
  // small move, and a depth never goes below what the view needs.
  Camera c2 = c;
  for (int k = 0; k < 3; ++k) c2.eye[k] = c.target[k] + 1.05f * (c.eye[k] - c.target[k]);
  const std::vector<uint8_t> need = select_depths(cage, model, c2, o);
  const std::vector<uint8_t> held = select_depths(cage, model, c2, o, a);
  for (size_t v = 0; v < a.size(); ++v) {
    EXPECT_GE(held[v], need[v]);
    EXPECT_LE(held[v], a[v] > need[v] ? a[v] : need[v]);
  }
  // Overrides pin.
  std::vector<uint8_t> pin(cage.vertex_count(), 255);
  pin[0] = 7;
  EXPECT_EQ(select_depths(cage, model, c, o, {}, pin)[0], 7);
  // Closer cameras need deeper levels.
  Camera near = c;
  for (int k = 0; k < 3; ++k) near.eye[k] = c.target[k] + 0.2f * (c.eye[k] - c.target[k]);
  const std::vector<uint8_t> deep = select_depths(cage, model, near, o);
  int sum_far = 0, sum_near = 0;
  for (size_t v = 0; v < a.size(); ++v) sum_far += a[v], sum_near += deep[v];
  EXPECT_GT(sum_near, sum_far);
}

}  // namespace
}  // namespace limn
