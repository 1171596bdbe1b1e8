// Structural analysis behind `limn info`.
#include <algorithm>
#include <map>
#include <numeric>

#include "limn/mesh/topology.hpp"
#include "union_find.hpp"

namespace limn {

namespace {

using detail::UnionFind;

std::vector<std::pair<uint32_t, size_t>> to_pairs(const std::map<uint32_t, size_t>& m) {
  return {m.begin(), m.end()};
}

}  // namespace

MeshStats analyze(const Mesh& mesh, const Topology& topo) {
  MeshStats s;
  const size_t nv = mesh.vertex_count(), nf = mesh.face_count(), ne = topo.edge_count();
  const uint32_t* fv = mesh.face_vertices.data();
  s.vertices = nv;
  s.faces = nf;
  s.corners = mesh.corner_count();
  s.edges = ne;
  s.bbox = bounding_box(mesh);
  s.has_normals = !mesh.normal_indices.empty();
  s.has_uvs = !mesh.uv_indices.empty();
  if (s.has_uvs) {
    s.uv_values = mesh.uvs.size() / 2;
    const uint32_t* uv = mesh.uv_indices.data();
    for (uint32_t c = 0; c < mesh.corner_count(); ++c) {
      const uint32_t t = topo.corner_twin[c];
      if (t >= kNonManifold || t < c) continue;  // boundary, non-manifold, or counted from t
      const uint32_t cn = topo.corner_next[c], tn = topo.corner_next[t];
      s.uv_seam_edges += uv[c] != uv[tn] || uv[cn] != uv[t];
    }
  }
  s.has_colors = !mesh.colors.empty();

  std::map<uint32_t, size_t> arity;
  const double diag = s.bbox.diagonal();
  // Relative to the model's size: float round-off makes "exactly zero" meaningless.
  const double eps_area = 1e-12 * diag * diag;
  for (size_t f = 0; f < nf; ++f) {
    ++arity[mesh.face_size(f)];
    const double a = face_area(mesh, f);
    s.surface_area += a;
    if (a <= eps_area) ++s.degenerate_faces;
  }
  s.faces_by_arity = to_pairs(arity);

  for (size_t e = 0; e < ne; ++e) {
    s.boundary_edges += topo.edge_faces[e] == 1;
    s.non_manifold_edges += topo.edge_faces[e] > 2;
  }
  for (size_t c = 0; c < s.corners; ++c) {
    const uint32_t t = topo.corner_twin[c];
    if (t < kNonManifold && c < t && fv[t] == fv[c]) ++s.inconsistent_edges;
  }

  // Components: vertices joined through faces. Boundary loops: vertices joined by boundary edges.
  UnionFind comp(nv), loops(nv);
  for (size_t f = 0; f < nf; ++f) {
    const auto face = mesh.face(f);
    for (size_t i = 1; i < face.size(); ++i) comp.unite(face[0], face[i]);
  }
  std::vector<uint8_t> on_boundary(nv, 0);
  for (size_t e = 0; e < ne; ++e) {
    if (topo.edge_faces[e] != 1) continue;
    const uint32_t a = topo.edge_vertices[2 * e], b = topo.edge_vertices[2 * e + 1];
    loops.unite(a, b);
    on_boundary[a] = on_boundary[b] = 1;
  }

  // Per vertex: fans of faces around it (1 for a manifold vertex), distinct edges (valence).
  std::map<uint32_t, size_t> valences;
  std::vector<std::pair<uint32_t, uint32_t>> star;  // (edge, local corner index)
  std::vector<uint32_t> local;
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t b = topo.vertex_offsets[v], n = topo.vertex_offsets[v + 1] - b;
    if (n == 0) {
      ++s.unreferenced_vertices;
      continue;
    }
    ++s.referenced_vertices;
    if (comp.find(v) == v) ++s.components;
    if (on_boundary[v] && loops.find(v) == v) ++s.boundary_loops;

    star.clear();
    bool nm_edge = false;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t c = topo.vertex_corners[b + i];
      const uint32_t e_out = topo.corner_edge[c], e_in = topo.corner_edge[topo.corner_prev[c]];
      star.emplace_back(e_out, i);
      star.emplace_back(e_in, i);
      nm_edge |= topo.edge_faces[e_out] > 2 || topo.edge_faces[e_in] > 2;
    }
    std::sort(star.begin(), star.end());
    local.resize(n);
    std::iota(local.begin(), local.end(), 0u);
    auto root = [&](uint32_t x) {
      while (local[x] != x) x = local[x] = local[local[x]];
      return x;
    };
    uint32_t valence = 0, fans = n;
    for (size_t i = 0; i < star.size(); ++i) {
      if (i > 0 && star[i].first == star[i - 1].first) {
        const uint32_t x = root(star[i].second), y = root(star[i - 1].second);
        if (x != y) local[std::max(x, y)] = std::min(x, y), --fans;
      } else {
        ++valence;
      }
    }
    if (nm_edge || fans > 1) {
      ++s.non_manifold_vertices;
      continue;
    }
    ++valences[valence];
    const bool extraordinary = on_boundary[v] ? (n != 1 && n != 2) : valence != 4;
    s.extraordinary_vertices += extraordinary;
  }
  s.valence_histogram = to_pairs(valences);

  s.euler_characteristic = static_cast<long long>(s.referenced_vertices) -
                           static_cast<long long>(ne) + static_cast<long long>(nf);
  if (s.non_manifold_edges == 0 && s.non_manifold_vertices == 0) {
    // chi = sum over components of (2 - 2 g_i - b_i).
    const long long twice_g = 2LL * static_cast<long long>(s.components) -
                              static_cast<long long>(s.boundary_loops) - s.euler_characteristic;
    s.genus = twice_g >= 0 && twice_g % 2 == 0 ? twice_g / 2 : -1;
  }

  s.crease_edges = mesh.crease_sharpness.size();
  for (float sh : mesh.crease_sharpness) s.infinitely_sharp_creases += sh >= kInfiniteSharpness;
  s.corner_vertices = mesh.corner_vertices.size();
  std::vector<uint32_t> holes = mesh.hole_faces;
  std::sort(holes.begin(), holes.end());
  s.hole_faces = static_cast<size_t>(std::unique(holes.begin(), holes.end()) - holes.begin());
  return s;
}

}  // namespace limn
