// Corner table construction.
//
// Edges are found without hashing: every corner is an outgoing half-edge of its vertex, so the
// half-edges joining a and b are among the outgoing corners of a and of b. Each undirected edge
// is owned by the smallest corner on it; owners are numbered in corner order, which makes edge
// ids deterministic and independent of the thread count.
#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/parallel.hpp"
#include "limn/mesh/topology.hpp"

namespace limn {

namespace {

constexpr size_t kGrain = 1 << 14;  // below this, threading costs more than it saves

}  // namespace

Topology build_topology(const Mesh& mesh) {
  return build_topology(mesh.vertex_count(), mesh.face_offsets, mesh.face_vertices);
}

Topology build_topology(size_t nv, std::span<const uint32_t> face_offsets,
                        std::span<const uint32_t> face_vertices) {
  Topology t;
  const size_t nc = face_vertices.size(), nf = face_offsets.size() - 1;
  const uint32_t* fv = face_vertices.data();
  t.corner_face.resize(nc);
  t.corner_next.resize(nc);
  t.corner_prev.resize(nc);
  parallel_range(nf, kGrain, [&](size_t b, size_t e) {
    for (size_t f = b; f < e; ++f) {
      const uint32_t o = face_offsets[f], n = face_offsets[f + 1] - o;
      for (uint32_t i = 0; i < n; ++i) {
        t.corner_face[o + i] = static_cast<uint32_t>(f);
        t.corner_next[o + i] = o + (i + 1 == n ? 0 : i + 1);
        t.corner_prev[o + i] = o + (i == 0 ? n - 1 : i - 1);
      }
    }
  });

  // Vertex -> outgoing corners (CSR), filled in corner order so each star list is sorted.
  t.vertex_offsets.assign(nv + 1, 0);
  for (size_t c = 0; c < nc; ++c) ++t.vertex_offsets[fv[c] + 1];
  for (size_t v = 0; v < nv; ++v) t.vertex_offsets[v + 1] += t.vertex_offsets[v];
  t.vertex_corners.resize(nc);
  // Beside each star entry, the vertex its half-edge points to: the edge search below then reads
  // contiguous memory instead of two dependent random loads per candidate.
  std::vector<uint32_t> star_to(nc);
  {
    std::vector<uint32_t> fill(t.vertex_offsets.begin(), t.vertex_offsets.end() - 1);
    for (size_t c = 0; c < nc; ++c) {
      const uint32_t slot = fill[fv[c]]++;
      t.vertex_corners[slot] = static_cast<uint32_t>(c);
      star_to[slot] = fv[t.corner_next[c]];
    }
  }

  // Per corner: the owner corner of its edge, its twin, and the number of faces on the edge.
  std::vector<uint32_t> owner(nc);
  t.corner_twin.resize(nc);
  std::vector<uint32_t> count(nc);
  const uint32_t* next = t.corner_next.data();
  const uint32_t* vo = t.vertex_offsets.data();
  const uint32_t* vc = t.vertex_corners.data();
  const uint32_t* to = star_to.data();
  parallel_range(nc, kGrain, [&](size_t b, size_t e) {
    for (size_t c = b; c < e; ++c) {
      const uint32_t a = fv[c], bb = fv[next[c]];
      uint32_t own = static_cast<uint32_t>(c), n = 0, other = kNone;
      // Branch-free scans: whether a star entry matches is data, not control flow, and
      // mispredicted branches here used to cost more than the loads.
      for (uint32_t i = vo[a]; i < vo[a + 1]; ++i) {  // same direction a -> b
        const uint32_t d = vc[i];
        const bool hit = to[i] == bb;
        n += hit;
        own = hit && d < own ? d : own;
        other = hit && d != c ? d : other;
      }
      for (uint32_t i = vo[bb]; i < vo[bb + 1]; ++i) {  // opposite direction b -> a
        const uint32_t d = vc[i];
        const bool hit = to[i] == a;
        n += hit;
        own = hit && d < own ? d : own;
        other = hit ? d : other;
      }
      owner[c] = own;
      count[c] = n;
      t.corner_twin[c] = n == 1 ? kNone : n == 2 ? other : kNonManifold;
    }
  });

  // Number the owners in corner order (serial prefix; cheap), then map every corner to its edge.
  t.corner_edge.resize(nc);
  uint32_t ne = 0;
  for (size_t c = 0; c < nc; ++c)
    if (owner[c] == c) t.corner_edge[c] = ne++;
  t.edge_vertices.resize(2 * size_t(ne));
  t.edge_faces.resize(ne);
  parallel_range(nc, kGrain, [&](size_t b, size_t e) {
    for (size_t c = b; c < e; ++c) {
      if (owner[c] != c) continue;
      const uint32_t id = t.corner_edge[c], a = fv[c], bb = fv[next[c]];
      t.edge_vertices[2 * size_t(id)] = std::min(a, bb);
      t.edge_vertices[2 * size_t(id) + 1] = std::max(a, bb);
      t.edge_faces[id] = count[c];
    }
  });
  // Owners precede the corners they own, so one ordered pass would do; parallel needs two.
  parallel_range(nc, kGrain, [&](size_t b, size_t e) {
    for (size_t c = b; c < e; ++c)
      if (owner[c] != c) t.corner_edge[c] = t.corner_edge[owner[c]];
  });
  return t;
}

}  // namespace limn
