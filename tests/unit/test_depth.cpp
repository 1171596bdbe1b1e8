// View-dependent depth selection: the eigenvalues of the subdivision matrix, and the screen-space
// error of the adaptive surface against a deep reference (uniform level 7 pushed to the limit,
// which shares no code with the patches) for several cameras.
#include <gtest/gtest.h>

#include <cmath>

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

// Ptex coordinates of the corners of every face of a uniform level, by following child faces
// (child face c of a level is the parent's corner c, its corner 0 the parent's corner).
struct FaceParam {
  uint32_t ptex;
  double u, v, size;
  int rot;
};

std::vector<FaceParam> uniform_params(const UniformRefinement& r, const Mesh& cage) {
  std::vector<FaceParam> cur;
  uint32_t ptex = 0;
  const RefinedLevel& L0 = r.levels[0];
  std::vector<uint32_t> first(cage.face_count());
  for (size_t f = 0; f < cage.face_count(); ++f) {
    first[f] = ptex;
    cur.push_back({ptex, 0, 0, 1, 0});
    ptex += cage.face_size(f) == 4 ? 1 : cage.face_size(f);
  }
  for (size_t k = 1; k < r.levels.size(); ++k) {
    const RefinedLevel& P = r.levels[k - 1];
    std::vector<FaceParam> next(r.levels[k].face_count());
    for (uint32_t f = 0; f < P.face_count(); ++f)
      for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c) {
        const uint32_t child = c - P.face_offsets[f];
        FaceParam p = cur[f];
        if (k == 1 && P.face_offsets[f + 1] - P.face_offsets[f] != 4) {
          p = {first[f] + child, 0, 0, 1, 0};
        } else {
          const int q = int(child + uint32_t(p.rot)) % 4;
          p.size *= 0.5;
          p.u += (q == 1 || q == 2) ? p.size : 0.0;
          p.v += q >= 2 ? p.size : 0.0;
          p.rot = q;
        }
        next[c] = p;
      }
    cur = std::move(next);
  }
  (void)L0;
  return cur;
}

// The deep reference: limit points at the corners of every face of uniform level 7, with their
// ptex coordinates.
struct Reference {
  std::vector<float> limit;
  std::vector<FaceParam> faces;
  RefinedLevel level;
};

Reference reference(const Mesh& cage) {
  const int ref_level = 7;
  const UniformRefinement r = refine_uniform(cage, ref_level, subdiv_options(cage));
  const std::vector<float> pos = r.positions(cage, ref_level);
  const LimitStencils ls = limit_stencils(r, ref_level);
  Reference out;
  out.limit.resize(pos.size());
  apply_stencils(ls.position, pos.data(), out.limit.data(), 3);
  out.faces = uniform_params(r, cage);
  out.level = r.levels.back();
  return out;
}

double max_screen_error(const Mesh& cage, const Reference& ref, const Camera& cam, float tolerance,
                        int* deepest) {
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

  const RefinedLevel& L = ref.level;
  static constexpr double kCu[4] = {0, 1, 1, 0}, kCv[4] = {0, 0, 1, 1};
  std::vector<PatchCoord> coords;
  std::vector<uint32_t> at;
  for (uint32_t f = 0; f < L.face_count(); ++f) {
    if (L.face_hole[f]) continue;
    for (int j = 0; j < 4; ++j) {
      const FaceParam& p = ref.faces[f];
      const int s = (j + p.rot) % 4;
      coords.push_back(map.find(p.ptex, p.u + kCu[s] * p.size, p.v + kCv[s] * p.size));
      at.push_back(L.face_vertices[L.face_offsets[f] + uint32_t(j)]);
    }
  }
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
    const Reference ref = reference(*cage);
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
