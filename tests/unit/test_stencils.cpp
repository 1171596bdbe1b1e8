// Stencil tables: composition and cage-flattened tables agree with applying level by level.
#include <gtest/gtest.h>

#include <cmath>

#include "limn/mesh/io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn {
namespace {

TEST(Stencils, ComposeMatchesSequentialApplication) {
  // Two random-ish tables over small point sets, checked against applying one after the other.
  StencilTable inner, outer;
  for (uint32_t p = 0; p < 5; ++p) {
    for (uint32_t k = 0; k < 3; ++k) {
      inner.indices.push_back((p + k) % 4);
      inner.weights.push_back(0.1f * float(p + k + 1));
    }
    inner.offsets.push_back(uint32_t(inner.indices.size()));
  }
  for (uint32_t p = 0; p < 3; ++p) {
    outer.indices.insert(outer.indices.end(), {p, 4 - p});
    outer.weights.insert(outer.weights.end(), {0.75f, -0.25f});
    outer.offsets.push_back(uint32_t(outer.indices.size()));
  }
  const std::vector<float> src = {1, -2, 3.5f, 0.25f};
  std::vector<float> mid(5), seq(3), direct(3);
  apply_stencils(inner, src.data(), mid.data(), 1);
  apply_stencils(outer, mid.data(), seq.data(), 1);
  const StencilTable c = compose_stencils(outer, inner);
  apply_stencils(c, src.data(), direct.data(), 1);
  for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(direct[i], seq[i], 1e-6f);
  for (size_t p = 0; p < c.size(); ++p)  // merged: each source at most once per point
    for (uint32_t j = c.offsets[p] + 1; j < c.offsets[p + 1]; ++j)
      EXPECT_LT(c.indices[j - 1], c.indices[j]);
}

TEST(Stencils, CageStencilsMatchLevelByLevel) {
  for (const char* name : {"cage", "torus", "terrain-small"}) {
    SCOPED_TRACE(name);
    const Mesh m = make_shape(name);
    const UniformRefinement r = refine_uniform(m, 3, subdiv_options(m));
    const float tol = 1e-6f * bounding_box(m).diagonal();
    for (int level = 1; level <= 3; ++level) {
      const std::vector<float> chained = r.positions(m, level);
      const StencilTable flat = cage_stencils(r, level);
      ASSERT_EQ(flat.size(), r.levels[size_t(level)].vertex_count());
      std::vector<float> direct(chained.size());
      apply_stencils(flat, m.positions.data(), direct.data(), 3);
      float worst = 0;
      for (size_t i = 0; i < direct.size(); ++i)
        worst = std::max(worst, std::fabs(direct[i] - chained[i]));
      EXPECT_LE(worst, tol) << "level " << level;
      // Weights of an affine-invariant scheme sum to one.
      for (size_t p = 0; p < flat.size(); ++p) {
        double sum = 0;
        for (uint32_t j = flat.offsets[p]; j < flat.offsets[p + 1]; ++j) sum += flat.weights[j];
        ASSERT_NEAR(sum, 1.0, 1e-5) << "point " << p;
      }
    }
  }
}

TEST(Stencils, ApplyRejectsBadChannelCounts) {
  StencilTable t;
  float x = 0;
  EXPECT_THROW(apply_stencils(t, &x, &x, 0), std::invalid_argument);
  EXPECT_THROW(apply_stencils(t, &x, &x, 17), std::invalid_argument);
}

}  // namespace
}  // namespace limn
