// Welding by exact position: an open-addressing hash table over the float bits, so the cost is
// linear and no tolerance can merge two points that a file meant to keep apart.
#include "limn/mesh/weld.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace limn {

namespace {

constexpr uint32_t kEmpty = 0xFFFFFFFFu;

// Bits of a coordinate with -0.0 folded onto 0.0, so that both zeros hash and compare equal.
inline uint32_t key_bits(float x) {
  const uint32_t b = std::bit_cast<uint32_t>(x);
  return b == 0x80000000u ? 0u : b;
}

// Groups n tuples of `dim` floats (dim <= 3) by bit-equal keys; see weld_map.
std::vector<uint32_t> group_equal(const float* data, size_t n, size_t dim, uint32_t* groups) {
  std::vector<uint32_t> group(n);
  size_t cap = 16;
  while (cap < 2 * n) cap *= 2;
  const size_t mask = cap - 1;
  std::vector<uint32_t> slot(cap, kEmpty);  // first tuple of the group stored there
  uint32_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    uint32_t k[3] = {0, 0, 0};
    for (size_t d = 0; d < dim; ++d) k[d] = key_bits(data[dim * i + d]);
    uint64_t h = (uint64_t(k[0]) * 0x9E3779B97F4A7C15ull) ^
                 (uint64_t(k[1]) * 0xC2B2AE3D27D4EB4Full) ^
                 (uint64_t(k[2]) * 0x165667B19E3779F9ull);
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 32;
    for (size_t s = h & mask;; s = (s + 1) & mask) {
      const uint32_t first = slot[s];
      if (first == kEmpty) {
        slot[s] = static_cast<uint32_t>(i);
        group[i] = count++;
        break;
      }
      bool same = true;
      for (size_t d = 0; d < dim; ++d) same &= key_bits(data[dim * first + d]) == k[d];
      if (same) {
        group[i] = group[first];
        break;
      }
    }
  }
  if (groups) *groups = count;
  return group;
}

// Deduplicates an attribute table (dim floats per entry) and re-indexes the corners that use it:
// the result holds only the distinct values the corners reference, in order of first use.
void dedupe_attribute(const std::vector<float>& values, const std::vector<uint32_t>& corner_index,
                      const std::vector<uint32_t>& kept_corners, size_t dim,
                      std::vector<float>& out_values, std::vector<uint32_t>& out_index) {
  const std::vector<uint32_t> group = group_equal(values.data(), values.size() / dim, dim, nullptr);
  std::vector<uint32_t> renumber(values.size() / dim, kEmpty);
  out_values.clear();
  out_index.clear();
  out_index.reserve(kept_corners.size());
  for (const uint32_t c : kept_corners) {
    const uint32_t t = corner_index[c], g = group[t];
    if (renumber[g] == kEmpty) {
      renumber[g] = static_cast<uint32_t>(out_values.size() / dim);
      out_values.insert(out_values.end(), &values[dim * t], &values[dim * t] + dim);
    }
    out_index.push_back(renumber[g]);
  }
}

// Small faces: a quadratic scan beats sorting; large ones (a hostile file can hold a 10^6-gon)
// stay O(n log n).
bool repeats_vertex(const std::vector<uint32_t>& face) {
  const size_t n = face.size();
  if (n <= 16) {
    for (size_t i = 1; i < n; ++i)
      for (size_t j = 0; j < i; ++j)
        if (face[i] == face[j]) return true;
    return false;
  }
  std::vector<uint32_t> sorted = face;
  std::sort(sorted.begin(), sorted.end());
  return std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
}

}  // namespace

std::vector<uint32_t> weld_map(std::span<const float> xyz, uint32_t* groups) {
  return group_equal(xyz.data(), xyz.size() / 3, 3, groups);
}

Mesh weld_vertices(const Mesh& m, size_t* dropped_faces) {
  uint32_t nv = 0;
  const std::vector<uint32_t> map = weld_map(m.positions, &nv);
  Mesh out;
  out.tags = m.tags;
  out.positions.resize(3 * size_t(nv));
  const bool colors = !m.colors.empty();
  if (colors) out.colors.resize(4 * size_t(nv));
  std::vector<bool> seen(nv, false);
  for (size_t v = 0; v < map.size(); ++v) {
    const uint32_t g = map[v];
    if (seen[g]) continue;
    seen[g] = true;
    std::memcpy(&out.positions[3 * size_t(g)], &m.positions[3 * v], 3 * sizeof(float));
    if (colors) std::memcpy(&out.colors[4 * size_t(g)], &m.colors[4 * v], 4 * sizeof(float));
  }

  // Faces, dropping those that now repeat a vertex; kept_corners lists the surviving corners.
  std::vector<uint32_t> kept_corners, face_renumber(m.face_count(), kEmpty);
  kept_corners.reserve(m.corner_count());
  out.face_vertices.reserve(m.corner_count());
  size_t dropped = 0;
  std::vector<uint32_t> face;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const uint32_t o = m.face_offsets[f], n = m.face_size(f);
    face.clear();
    for (uint32_t i = 0; i < n; ++i) face.push_back(map[m.face_vertices[o + i]]);
    if (repeats_vertex(face)) {
      ++dropped;
      continue;
    }
    face_renumber[f] = static_cast<uint32_t>(out.face_count());
    for (uint32_t i = 0; i < n; ++i) kept_corners.push_back(o + i);
    out.face_vertices.insert(out.face_vertices.end(), face.begin(), face.end());
    out.face_offsets.push_back(static_cast<uint32_t>(out.face_vertices.size()));
  }
  if (dropped_faces) *dropped_faces = dropped;

  if (!m.uv_indices.empty())
    dedupe_attribute(m.uvs, m.uv_indices, kept_corners, 2, out.uvs, out.uv_indices);
  if (!m.normal_indices.empty())
    dedupe_attribute(m.normals, m.normal_indices, kept_corners, 3, out.normals, out.normal_indices);

  for (size_t e = 0; e < m.crease_sharpness.size(); ++e) {
    const uint32_t a = map[m.crease_edges[2 * e]], b = map[m.crease_edges[2 * e + 1]];
    if (a == b) continue;
    out.crease_edges.insert(out.crease_edges.end(), {a, b});
    out.crease_sharpness.push_back(m.crease_sharpness[e]);
  }
  for (size_t i = 0; i < m.corner_vertices.size(); ++i) {
    out.corner_vertices.push_back(map[m.corner_vertices[i]]);
    out.corner_sharpness.push_back(m.corner_sharpness[i]);
  }
  for (const uint32_t f : m.hole_faces)
    if (f < face_renumber.size() && face_renumber[f] != kEmpty)
      out.hole_faces.push_back(face_renumber[f]);
  return out;
}

}  // namespace limn
