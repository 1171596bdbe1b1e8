// Welding by exact position: an open-addressing hash table over the float bits, so the cost is
// linear and no tolerance can merge two points that a file meant to keep apart. Welding within a
// tolerance (repair's) groups those exact groups further, over a grid of tolerance-sized cells.
#include "limn/mesh/weld.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "union_find.hpp"

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

}  // namespace

std::vector<uint32_t> weld_map(std::span<const float> xyz, uint32_t* groups) {
  return group_equal(xyz.data(), xyz.size() / 3, 3, groups);
}

std::vector<uint32_t> weld_map_within(std::span<const float> xyz, double tolerance,
                                      uint32_t* groups) {
  uint32_t exact_groups = 0;
  std::vector<uint32_t> group = weld_map(xyz, &exact_groups);
  if (!(tolerance > 0) || exact_groups < 2) {
    if (groups) *groups = exact_groups;
    return group;
  }
  // One representative (the first point) per bit-equal group; the grid holds those only.
  const size_t n = group.size();
  std::vector<uint32_t> first(exact_groups, kEmpty);
  for (size_t i = 0; i < n; ++i)
    if (first[group[i]] == kEmpty) first[group[i]] = static_cast<uint32_t>(i);
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const uint32_t p : first)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], double(xyz[3 * size_t(p) + k]));
      hi[k] = std::max(hi[k], double(xyz[3 * size_t(p) + k]));
    }
  // Cell coordinates must fit int64; a tolerance this far below the extent welds nothing more
  // than bit-equality does at float precision anyway.
  for (int k = 0; k < 3; ++k)
    if ((hi[k] - lo[k]) / tolerance > 1e15) {
      if (groups) *groups = exact_groups;
      return group;
    }

  // Cells of edge `tolerance`: points within it of each other lie in the same or adjacent cells.
  // Cells sorted lexicographically, so each cell's points form one run of `order`.
  struct Cell {
    int64_t x, y, z;
    auto operator<=>(const Cell&) const = default;
  };
  const auto cell_of = [&](uint32_t p) {
    const float* q = &xyz[3 * size_t(p)];
    return Cell{int64_t((q[0] - lo[0]) / tolerance), int64_t((q[1] - lo[1]) / tolerance),
                int64_t((q[2] - lo[2]) / tolerance)};
  };
  std::vector<Cell> cell(exact_groups);
  for (uint32_t g = 0; g < exact_groups; ++g) cell[g] = cell_of(first[g]);
  std::vector<uint32_t> order(exact_groups);
  for (uint32_t g = 0; g < exact_groups; ++g) order[g] = g;
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return cell[a] < cell[b]; });
  std::vector<uint32_t> run_start;  // run r spans order[run_start[r] .. run_start[r + 1])
  for (uint32_t i = 0; i < exact_groups; ++i)
    if (i == 0 || cell[order[i]] != cell[order[i - 1]]) run_start.push_back(i);
  const uint32_t runs = static_cast<uint32_t>(run_start.size());
  run_start.push_back(exact_groups);

  // Open-addressing table: cell -> run.
  const auto hash = [](const Cell& c) {
    uint64_t h = uint64_t(c.x) * 0x9E3779B97F4A7C15ull ^ uint64_t(c.y) * 0xC2B2AE3D27D4EB4Full ^
                 uint64_t(c.z) * 0x165667B19E3779F9ull;
    h ^= h >> 31;
    return h * 0xBF58476D1CE4E5B9ull;
  };
  size_t cap = 16;
  while (cap < 2 * size_t(runs)) cap *= 2;
  std::vector<uint32_t> table(cap, kEmpty);
  for (uint32_t r = 0; r < runs; ++r)
    for (size_t s = hash(cell[order[run_start[r]]]) & (cap - 1);; s = (s + 1) & (cap - 1))
      if (table[s] == kEmpty) {
        table[s] = r;
        break;
      }
  const auto find_run = [&](const Cell& c) {
    for (size_t s = hash(c) & (cap - 1);; s = (s + 1) & (cap - 1)) {
      const uint32_t r = table[s];
      if (r == kEmpty || cell[order[run_start[r]]] == c) return r;
    }
  };

  // Each pair of cells once: the cell itself and the 13 neighbours that follow it.
  const double tol2 = tolerance * tolerance;
  const auto close = [&](uint32_t a, uint32_t b) {
    const float* p = &xyz[3 * size_t(first[a])];
    const float* q = &xyz[3 * size_t(first[b])];
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += (double(p[k]) - q[k]) * (double(p[k]) - q[k]);
    return d2 <= tol2;
  };
  detail::UnionFind sets(exact_groups);
  for (uint32_t r = 0; r < runs; ++r) {
    const Cell c = cell[order[run_start[r]]];
    for (uint32_t i = run_start[r]; i < run_start[r + 1]; ++i)
      for (uint32_t j = i + 1; j < run_start[r + 1]; ++j)
        if (close(order[i], order[j])) sets.unite(order[i], order[j]);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const Cell d{c.x + dx, c.y + dy, c.z + dz};
          if (!(c < d)) continue;
          const uint32_t s = find_run(d);
          if (s == kEmpty) continue;
          for (uint32_t i = run_start[r]; i < run_start[r + 1]; ++i)
            for (uint32_t j = run_start[s]; j < run_start[s + 1]; ++j)
              if (close(order[i], order[j])) sets.unite(order[i], order[j]);
        }
  }

  // Renumber in order of first point. A set's root is its smallest exact group, and exact
  // groups are numbered in order of their first point, so the root's first point comes first.
  std::vector<uint32_t> number(exact_groups, kEmpty);
  uint32_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t root = sets.find(group[i]);
    if (number[root] == kEmpty) number[root] = count++;
    group[i] = number[root];
  }
  if (groups) *groups = count;
  return group;
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
  std::vector<uint32_t> face, scratch;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const uint32_t o = m.face_offsets[f], n = m.face_size(f);
    face.clear();
    for (uint32_t i = 0; i < n; ++i) face.push_back(map[m.face_vertices[o + i]]);
    if (repeated_vertex(face, scratch) != kNoRepeat) {
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
