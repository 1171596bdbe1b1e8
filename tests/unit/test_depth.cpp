// View-dependent depth selection: the eigenvalues of the subdivision matrix, and the screen-space
// error of the adaptive surface against a deep reference (uniform level 7 pushed to the limit,
// which shares no code with the patches) for several cameras.
#include <gtest/gtest.h>

#include <cmath>

#include "deep_reference.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"

namespace limn {
namespace {

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

double max_screen_error(const Mesh& cage, const test::Reference& ref, const Camera& cam,
                        float tolerance, int* deepest) {
  const VertexErrorModel model = vertex_error_model(cage, subdiv_options(cage));
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

TEST(Depth, ScreenErrorStaysWithinTolerance) {
  const int valences[] = {3, 5, 6, 8};
  Mesh torus = make_torus(16, 8, valences);
  for (size_t i = 0; i < torus.positions.size(); ++i)
    torus.positions[i] += 0.03f * std::sin(float(i) * 1.7f);  // break the symmetry
  const Mesh cube = make_shape("cube");
  for (const Mesh* cage : {static_cast<const Mesh*>(&torus), &cube}) {
    const test::Reference ref = test::reference(*cage, 7);
    const Camera far = frame_camera(*cage, 640, 480);
    for (const float t : {0.5f, 2.0f}) {
      for (const float zoom : {1.0f, 0.6f, 0.35f}) {
        Camera c = far;
        for (int k = 0; k < 3; ++k) c.eye[k] = c.target[k] + zoom * (far.eye[k] - far.target[k]);
        int deepest = 0;
        const double e = max_screen_error(*cage, ref, c, t, &deepest);
        EXPECT_LE(e, t) << "zoom " << zoom << " tolerance " << t << " deepest " << deepest;
        std::printf("zoom %.2f tolerance %.1f px: deepest %d, max error %.3f px\n", zoom, t,
                    deepest, e);
      }
    }
  }
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
