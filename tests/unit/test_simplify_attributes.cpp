// Simplification keeps the input's attributes (VSA output vertices are input vertices):
// per-vertex colours exactly, and per output corner the UV (and normal) its source vertex has
// in an input face of the output face's cluster -- so a seam between clusters stays a seam.
// Checked against a brute-force reading of the input, not against limn's own bookkeeping only.
#include <gtest/gtest.h>

#include <set>

#include "limn/simplify/vsa.hpp"
#include "seam_cages.hpp"

namespace limn {
namespace {

TEST(SimplifyAttributes, ColoursUvsAndNormalsComeAlong) {
  Mesh in = test::torus_seams();
  in.colors.resize(4 * in.vertex_count());
  for (size_t i = 0; i < in.colors.size(); ++i) in.colors[i] = float(i % 11) / 11.0f;
  in.normals = {0, 0, 1, 0, 1, 0};
  for (size_t c = 0; c < in.corner_count(); ++c) in.normal_indices.push_back(uint32_t(c % 2));
  VsaOptions o;
  o.proxies = 24;
  const VsaResult r = simplify_vsa(in, o);
  const Mesh& out = r.output.mesh;
  ASSERT_GT(out.face_count(), 0u);
  ASSERT_EQ(out.colors.size(), 4 * out.vertex_count());
  ASSERT_EQ(out.uv_indices.size(), out.corner_count());
  ASSERT_EQ(out.normal_indices.size(), out.corner_count());
  for (size_t v = 0; v < out.vertex_count(); ++v)
    for (size_t k = 0; k < 4; ++k)
      EXPECT_EQ(out.colors[4 * v + k], in.colors[4 * r.output.vertex_source[v] + k]);
  size_t in_cluster = 0, uv_values = 0;
  std::set<std::pair<float, float>> distinct_at_seams;
  for (size_t g = 0; g < out.face_count(); ++g) {
    const uint32_t cluster = r.output.face_cluster[g];
    for (uint32_t c = out.face_offsets[g]; c < out.face_offsets[g + 1]; ++c) {
      const uint32_t v = r.output.vertex_source[out.face_vertices[c]];
      const float u = out.uvs[2 * out.uv_indices[c]], w = out.uvs[2 * out.uv_indices[c] + 1];
      // The first input face at v in this cluster (by face order), else the first at v.
      int pick = -1, first = -1;
      for (size_t f = 0; f < in.face_count() && pick < 0; ++f)
        for (uint32_t k = in.face_offsets[f]; k < in.face_offsets[f + 1]; ++k) {
          if (in.face_vertices[k] != v) continue;
          if (first < 0) first = int(k);
          if (r.labels[f] == cluster && pick < 0) pick = int(k);
        }
      ASSERT_GE(first, 0);
      in_cluster += pick >= 0;
      const uint32_t want = in.uv_indices[size_t(pick >= 0 ? pick : first)];
      EXPECT_EQ(u, in.uvs[2 * want]);
      EXPECT_EQ(w, in.uvs[2 * want + 1]);
      const uint32_t wn = in.normal_indices[size_t(pick >= 0 ? pick : first)];
      for (size_t k = 0; k < 3; ++k)
        EXPECT_EQ(out.normals[3 * out.normal_indices[c] + k], in.normals[3 * wn + k]);
      ++uv_values;
    }
  }
  // Output faces' vertices lie on their cluster's faces.
  EXPECT_EQ(in_cluster, uv_values);
  // The torus's seams survive: the output has more UV values than vertices.
  EXPECT_GT(out.uvs.size() / 2, out.vertex_count());
}

}  // namespace
}  // namespace limn
