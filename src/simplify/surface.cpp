// Preparation of a mesh for VSA: validation of what the clustering and meshing rely on.
#include "limn/simplify/surface.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/parallel.hpp"
#include "core/vec3.hpp"

namespace limn {

void VsaSurface::normal(uint32_t f, double out[3]) const {
  const double a = area[f];
  const double inv = a > 0 ? 1.0 / a : 0.0;
  for (int k = 0; k < 3; ++k) out[k] = vec[3 * size_t(f) + k] * inv;
}

VsaSurface prepare_surface(const Mesh& mesh, std::string_view name) {
  const size_t nf = mesh.face_count();
  if (nf == 0) throw InputError(fmt::format("{}: no faces to simplify", name));
  VsaSurface s;
  s.mesh = &mesh;
  s.topo = build_topology(mesh);
  const Topology& t = s.topo;
  const uint32_t* fv = mesh.face_vertices.data();
  for (size_t c = 0; c < mesh.corner_count(); ++c) {
    const uint32_t tw = t.corner_twin[c];
    if (tw == kNonManifold) {
      const uint32_t e = t.corner_edge[c];
      throw RepairableError(fmt::format(
          "{}: non-manifold edge {}-{} (shared by {} faces); simplify needs an edge-manifold mesh",
          name, t.edge_vertices[2 * size_t(e)], t.edge_vertices[2 * size_t(e) + 1],
          t.edge_faces[e]));
    }
    if (tw != kNone && fv[tw] == fv[c])
      throw RepairableError(
          fmt::format("{}: faces {} and {} disagree on orientation across edge {}-{}", name,
                      t.corner_face[c], t.corner_face[tw], fv[c], fv[t.corner_next[c]]));
  }

  // Two faces over one vertex set would come out as duplicate output faces. In an oriented,
  // edge-manifold mesh such faces are twins across every edge, so only neighbours are compared.
  for (uint32_t f = 0; f < nf; ++f) {
    const uint32_t o = mesh.face_offsets[f], n = mesh.face_offsets[f + 1] - o;
    const uint32_t tw = t.corner_twin[o];
    if (tw == kNone) continue;
    const uint32_t g = t.corner_face[tw];
    if (g < f || mesh.face_size(g) != n) continue;
    bool same = true;
    for (uint32_t i = 0; i < n && same; ++i)
      same = t.corner_twin[o + i] != kNone && t.corner_face[t.corner_twin[o + i]] == g;
    if (same)
      throw RepairableError(fmt::format("{}: faces {} and {} use the same vertices", name, f, g));
  }

  s.area.resize(nf);
  s.vec.resize(3 * nf);
  const float* P = mesh.positions.data();
  // parallel_range: a small mesh's faces in one go, without starting TBB's threads for them.
  parallel_range(nf, size_t(1) << 14, [&](size_t fb, size_t fe) {
    for (size_t f = fb; f < fe; ++f) {
      const auto v = mesh.face(f);
      double n[3];
      newell_double(P, v.data(), v.size(), n);
      double len = 0;
      for (int k = 0; k < 3; ++k) {
        s.vec[3 * f + k] = 0.5 * n[k];
        len += 0.25 * n[k] * n[k];
      }
      s.area[f] = std::sqrt(len);
    }
  });
  s.total_area = std::accumulate(s.area.begin(), s.area.end(), 0.0);
  s.bbox = bounding_box(mesh);

  // Components over edge adjacency (the only way a cluster can grow).
  std::vector<uint32_t> comp(nf, kNone), stack;
  for (uint32_t f0 = 0; f0 < nf; ++f0) {
    if (comp[f0] != kNone) continue;
    const uint32_t id = static_cast<uint32_t>(s.components++);
    comp[f0] = id;
    stack.push_back(f0);
    while (!stack.empty()) {
      const uint32_t f = stack.back();
      stack.pop_back();
      for (uint32_t c = mesh.face_offsets[f]; c < mesh.face_offsets[f + 1]; ++c) {
        const uint32_t g = s.across(c);
        if (g != kNone && comp[g] == kNone) comp[g] = id, stack.push_back(g);
      }
    }
  }
  // Vertex kinds: walk each vertex's fan from one outgoing corner both ways; a fan that closes
  // or ends on boundaries having seen every face at the vertex means a single fan.
  const size_t nv = mesh.vertex_count();
  s.vertex_kind.assign(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    const uint32_t n = t.vertex_face_count(static_cast<uint32_t>(v));
    if (n == 0) continue;
    const uint32_t c0 = t.vertex_corners[t.vertex_offsets[v]];
    uint32_t seen = 1, c = s.rotate(c0);
    while (c != kNone && c != c0 && seen <= n) ++seen, c = s.rotate(c);
    if (c == c0) {
      s.vertex_kind[v] = seen == n ? 1 : 3;
      continue;
    }
    // Open fan: walk back from c0 as well.
    for (uint32_t b = t.corner_twin[c0]; b != kNone && seen <= n; b = t.corner_twin[b]) {
      b = t.corner_next[b];
      ++seen;
    }
    s.vertex_kind[v] = seen == n ? 2 : 3;
  }
  return s;
}

}  // namespace limn
