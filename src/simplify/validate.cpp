// Validity checks of a simplified mesh by sorting edge and face keys.
#include "limn/simplify/validate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace limn {

SimplifiedCheck validate_simplified(const Mesh& out, const Box& box) {
  SimplifiedCheck r;
  auto problem = [&](std::string s) {
    if (r.first_problem.empty()) r.first_problem = std::move(s);
  };
  const size_t nv = out.vertex_count(), nf = out.face_count();
  r.faces = nf;
  for (size_t v = 0; v < nv; ++v) {
    const float* p = &out.positions[3 * v];
    bool inside = true;
    for (int k = 0; k < 3; ++k)
      inside = inside && std::isfinite(p[k]) && p[k] >= box.min[k] && p[k] <= box.max[k];
    if (!inside) {
      ++r.outside_bbox;
      problem(fmt::format("vertex {} ({}, {}, {}) lies outside the input's bounding box", v, p[0],
                          p[1], p[2]));
    }
  }
  const double diag = box.diagonal();
  const double eps = 1e-12 * diag * diag;
  std::vector<uint8_t> used(nv, 0);
  std::vector<uint64_t> directed;
  std::vector<std::vector<uint32_t>> keys(nf);
  for (size_t f = 0; f < nf; ++f) {
    const auto fv = out.face(f);
    for (uint32_t v : fv) used[v] = 1;
    keys[f].assign(fv.begin(), fv.end());
    std::sort(keys[f].begin(), keys[f].end());
    const bool repeated = std::adjacent_find(keys[f].begin(), keys[f].end()) != keys[f].end();
    float a[3];
    face_area_vector(out, f, a);
    const double area = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
    if (repeated || fv.size() < 3 || !(area > eps)) {
      ++r.degenerate_faces;
      problem(fmt::format("face {} is degenerate ({} vertices, area {:.3g})", f, fv.size(), area));
    }
    for (size_t i = 0; i < fv.size(); ++i)
      directed.push_back(uint64_t(fv[i]) << 32 | fv[(i + 1) % fv.size()]);
  }
  for (size_t v = 0; v < nv; ++v)
    if (!used[v]) {
      ++r.unreferenced_vertices;
      problem(fmt::format("vertex {} is used by no face", v));
    }
  // Directed edges: each at most once. Undirected: at most two uses.
  std::sort(directed.begin(), directed.end());
  for (size_t i = 1; i < directed.size(); ++i)
    if (directed[i] == directed[i - 1]) {
      ++r.inconsistent_edges;
      problem(fmt::format("edge {}-{} is used twice in the same direction",
                          uint32_t(directed[i] >> 32), uint32_t(directed[i])));
    }
  std::vector<uint64_t> undirected(directed.size());
  for (size_t i = 0; i < directed.size(); ++i) {
    const uint32_t a = uint32_t(directed[i] >> 32), b = uint32_t(directed[i]);
    undirected[i] = uint64_t(std::min(a, b)) << 32 | std::max(a, b);
  }
  std::sort(undirected.begin(), undirected.end());
  for (size_t i = 0; i < undirected.size();) {
    size_t j = i + 1;
    while (j < undirected.size() && undirected[j] == undirected[i]) ++j;
    ++r.edges;
    if (j - i == 1) ++r.boundary_edges;
    if (j - i > 2) {
      ++r.non_manifold_edges;
      problem(fmt::format("edge {}-{} is shared by {} faces", uint32_t(undirected[i] >> 32),
                          uint32_t(undirected[i]), j - i));
    }
    i = j;
  }
  std::vector<uint32_t> order(nf);
  for (uint32_t f = 0; f < nf; ++f) order[f] = f;
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return keys[a] < keys[b]; });
  for (size_t i = 1; i < nf; ++i)
    if (keys[order[i]] == keys[order[i - 1]]) {
      ++r.duplicate_faces;
      problem(fmt::format("faces {} and {} use the same vertices", order[i - 1], order[i]));
    }
  return r;
}

}  // namespace limn
