// Stencil tables: composition and cage-flattened tables agree with applying level by level.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/refine.hpp"
#include "subdiv/shared_weights.hpp"

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
        const float* w = flat.row_weights(p);
        for (uint32_t j = 0; j < flat.offsets[p + 1] - flat.offsets[p]; ++j) sum += w[j];
        ASSERT_NEAR(sum, 1.0, 1e-5) << "point " << p;
      }
    }
  }
}

TEST(Stencils, SharedWeightsKeepEachDistinctRowOnce) {
  // Rows drawn from a few templates (as refinement's smooth rules are) and some unique ones;
  // -0.0 and 0.0 differ in their bits, so they are different rows.
  std::mt19937 rng(7);
  std::vector<std::vector<float>> templates = {{}, {0.25f, 0.25f, 0.25f, 0.25f}, {0.0f}, {-0.0f}};
  for (int i = 0; i < 3000; ++i) {  // enough distinct rows to grow the slots many times
    std::vector<float> row(1 + rng() % 12);
    for (float& x : row) x = float(rng() % 1000) / 999.0f;
    templates.push_back(row);
  }
  std::vector<float> pool;
  detail::SharedWeights shared;
  std::map<std::vector<uint32_t>, uint32_t> seen;  // a row's bits -> its offset
  for (int i = 0; i < 20000; ++i) {
    const std::vector<float>& row = templates[i < 3004 ? size_t(i) : rng() % templates.size()];
    const uint32_t n = uint32_t(row.size());
    const uint32_t at = shared.add(pool, row.data(), n);
    ASSERT_LE(size_t(at) + n, pool.size());
    if (n) {
      ASSERT_EQ(std::memcmp(pool.data() + at, row.data(), n * sizeof(float)), 0) << i;
    }
    std::vector<uint32_t> bits(n);
    if (n) std::memcpy(bits.data(), row.data(), n * sizeof(float));
    const auto [it, fresh] = seen.emplace(bits, at);
    if (!fresh) {
      EXPECT_EQ(it->second, at) << "row " << i << " stored twice";
    }
  }
  size_t distinct = 0;
  for (const auto& [bits, at] : seen) distinct += bits.size();
  EXPECT_EQ(pool.size(), distinct);  // each distinct row once, nothing else
}

TEST(Stencils, SharedLevelsApplyLikeDenseRows) {
  // Refinement tables share their rows' weights; applying them must give what one weight per
  // entry gives (the AVX2 three-channel path and the generic path), and the pool is a small
  // fraction of the entries.
  for (const char* name : {"cage", "terrain-small"}) {
    SCOPED_TRACE(name);
    const Mesh m = make_shape(name);
    const int depth = 4;
    const UniformRefinement r = refine_uniform(m, depth, subdiv_options(m));
    std::vector<float> level = m.positions;
    for (int k = 0; k < depth; ++k) {
      const StencilTable& t = r.stencils[size_t(k)];
      ASSERT_TRUE(t.shared());
      ASSERT_EQ(t.weight_offsets.size(), t.size());
      EXPECT_LT(10 * t.weights.size(), t.indices.size()) << "level " << k + 1;
      StencilTable dense;
      dense.offsets = t.offsets;
      dense.indices = t.indices;
      for (size_t i = 0; i < t.size(); ++i)
        dense.weights.insert(dense.weights.end(), t.row_weights(i),
                             t.row_weights(i) + (t.offsets[i + 1] - t.offsets[i]));
      ASSERT_EQ(dense.weights.size(), dense.indices.size());
      for (const int channels : {3, 1}) {
        std::vector<float> in(level.size() / 3 * size_t(channels));
        for (size_t i = 0; i < in.size(); ++i) in[i] = level[i / size_t(channels) * 3];
        std::vector<float> a(t.size() * size_t(channels)), b(a.size());
        apply_stencils(t, in.data(), a.data(), channels);
        apply_stencils(dense, in.data(), b.data(), channels);
        EXPECT_EQ(a, b) << "level " << k + 1 << ", " << channels << " channels";
      }
      std::vector<float> next(3 * t.size());
      apply_stencils(t, level.data(), next.data(), 3);
      level = std::move(next);
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
