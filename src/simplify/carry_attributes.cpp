#include "carry_attributes.hpp"

#include <vector>

namespace limn {

namespace {

// One per-corner channel (UVs or normals): values re-indexed to those the output uses.
void carry_channel(const Mesh& in, const std::vector<float>& values,
                   const std::vector<uint32_t>& indices, size_t width,
                   std::span<const uint32_t> labels, const std::vector<uint32_t>& vertex_corners,
                   const std::vector<uint32_t>& vertex_offsets, const SimplifiedMesh& s,
                   std::vector<float>& out_values, std::vector<uint32_t>& out_indices) {
  std::vector<uint32_t> corner_face(in.corner_count());
  for (size_t f = 0; f < in.face_count(); ++f)
    for (uint32_t c = in.face_offsets[f]; c < in.face_offsets[f + 1]; ++c)
      corner_face[c] = uint32_t(f);
  std::vector<uint32_t> remap(values.size() / width, UINT32_MAX);
  const Mesh& m = s.mesh;
  out_values.clear();
  out_indices.assign(m.corner_count(), 0);
  for (size_t g = 0; g < m.face_count(); ++g) {
    const uint32_t cluster = s.face_cluster[g];
    for (uint32_t c = m.face_offsets[g]; c < m.face_offsets[g + 1]; ++c) {
      const uint32_t v = s.vertex_source[m.face_vertices[c]];
      // Corners of v sorted by face: the first of the cluster, else the first.
      uint32_t pick = UINT32_MAX;
      for (uint32_t i = vertex_offsets[v]; i < vertex_offsets[v + 1] && pick == UINT32_MAX; ++i)
        if (labels[corner_face[vertex_corners[i]]] == cluster) pick = vertex_corners[i];
      if (pick == UINT32_MAX) pick = vertex_corners[vertex_offsets[v]];
      const uint32_t x = indices[pick];
      if (remap[x] == UINT32_MAX) {
        remap[x] = uint32_t(out_values.size() / width);
        out_values.insert(out_values.end(), values.begin() + std::ptrdiff_t(width * x),
                          values.begin() + std::ptrdiff_t(width * (x + 1)));
      }
      out_indices[c] = remap[x];
    }
  }
}

}  // namespace

void carry_attributes(const Mesh& in, std::span<const uint32_t> labels, SimplifiedMesh& s) {
  Mesh& m = s.mesh;
  if (in.colors.size() == 4 * in.vertex_count()) {
    m.colors.resize(4 * m.vertex_count());
    for (size_t o = 0; o < m.vertex_count(); ++o)
      for (size_t k = 0; k < 4; ++k) m.colors[4 * o + k] = in.colors[4 * s.vertex_source[o] + k];
  }
  if (in.uv_indices.empty() && in.normal_indices.empty()) return;
  // Input corners per vertex, in corner (so face) order.
  std::vector<uint32_t> offsets(in.vertex_count() + 1, 0), corners(in.corner_count());
  for (uint32_t v : in.face_vertices) ++offsets[v + 1];
  for (size_t v = 0; v < in.vertex_count(); ++v) offsets[v + 1] += offsets[v];
  std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
  for (size_t c = 0; c < in.corner_count(); ++c) corners[fill[in.face_vertices[c]]++] = uint32_t(c);
  if (!in.uv_indices.empty())
    carry_channel(in, in.uvs, in.uv_indices, 2, labels, corners, offsets, s, m.uvs, m.uv_indices);
  if (!in.normal_indices.empty())
    carry_channel(in, in.normals, in.normal_indices, 3, labels, corners, offsets, s, m.normals,
                  m.normal_indices);
}

}  // namespace limn
