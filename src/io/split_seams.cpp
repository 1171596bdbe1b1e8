#include "split_seams.hpp"

#include <array>

namespace limn {

Mesh split_at_seams(const Mesh& m, std::vector<uint32_t>* source) {
  const bool uv = !m.uv_indices.empty(), nrm = !m.normal_indices.empty();
  const bool colors = m.colors.size() == 4 * m.vertex_count();
  Mesh s;
  s.face_offsets = m.face_offsets;
  s.face_vertices.resize(m.corner_count());
  if (source) source->clear();
  std::vector<std::vector<std::array<uint32_t, 3>>> variants(m.vertex_count());
  for (size_t c = 0; c < m.corner_count(); ++c) {
    const uint32_t v = m.face_vertices[c], t = uv ? m.uv_indices[c] : 0,
                   n = nrm ? m.normal_indices[c] : 0;
    uint32_t id = UINT32_MAX;
    for (const auto& x : variants[v])
      if (x[0] == t && x[1] == n) id = x[2];
    if (id == UINT32_MAX) {
      id = uint32_t(s.vertex_count());
      variants[v].push_back({t, n, id});
      if (source) source->push_back(v);
      s.positions.insert(s.positions.end(), &m.positions[3 * size_t(v)],
                         &m.positions[3 * size_t(v)] + 3);
      if (colors)
        s.colors.insert(s.colors.end(), &m.colors[4 * size_t(v)], &m.colors[4 * size_t(v)] + 4);
      if (uv) s.uvs.insert(s.uvs.end(), &m.uvs[2 * size_t(t)], &m.uvs[2 * size_t(t)] + 2);
      if (nrm)
        s.normals.insert(s.normals.end(), &m.normals[3 * size_t(n)], &m.normals[3 * size_t(n)] + 3);
    }
    s.face_vertices[c] = id;
  }
  if (uv) s.uv_indices = s.face_vertices;
  if (nrm) s.normal_indices = s.face_vertices;
  return s;
}

}  // namespace limn
