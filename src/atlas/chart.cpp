#include "atlas/chart.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <utility>

#include "atlas/stretch.hpp"
#include "limn/simplify/vsa.hpp"
#include "mesh/union_find.hpp"

namespace limn::atlas {

Chart build_chart(const VsaSurface& s, std::vector<uint32_t> faces, uint32_t id,
                  ChartScratch& scratch) {
  const Mesh& mesh = *s.mesh;
  const Topology& t = s.topo;
  Chart ch;
  ch.faces = std::move(faces);
  uint32_t corners = 0;
  double n[3] = {0, 0, 0};
  for (uint32_t f : ch.faces) {
    scratch.face_owner[f] = id;
    for (uint32_t c = mesh.face_offsets[f]; c < mesh.face_offsets[f + 1]; ++c)
      scratch.corner_slot[c] = corners++;
    ch.area += s.area[f];
    for (int k = 0; k < 3; ++k) n[k] += s.vec[3 * size_t(f) + k];
  }
  ch.normal_sum = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);

  auto inner_twin = [&](uint32_t c) {
    const uint32_t tw = t.corner_twin[c];
    return tw < kNonManifold && scratch.face_owner[t.corner_face[tw]] == id ? tw : kNone;
  };
  detail::UnionFind classes(corners);
  long edges = 0;
  for (uint32_t f : ch.faces)
    for (uint32_t c = mesh.face_offsets[f]; c < mesh.face_offsets[f + 1]; ++c) {
      const uint32_t tw = inner_twin(c);
      if (tw == kNone) {
        ++edges;
        continue;
      }
      // The twin runs the other way: its next corner sits on c's vertex.
      classes.unite(scratch.corner_slot[c], scratch.corner_slot[t.corner_next[tw]]);
      edges += c < tw;
    }

  ch.corner_vertex.resize(corners);
  std::vector<uint32_t> vertex_of_root(corners, kNone);
  uint32_t slot = 0;
  for (uint32_t f : ch.faces)
    for (uint32_t c = mesh.face_offsets[f]; c < mesh.face_offsets[f + 1]; ++c, ++slot) {
      uint32_t& v = vertex_of_root[classes.find(slot)];
      if (v == kNone) {
        v = uint32_t(ch.vertex_source.size());
        ch.vertex_source.push_back(mesh.face_vertices[c]);
      }
      ch.corner_vertex[slot] = v;
    }
  ch.euler = long(ch.vertex_source.size()) - edges + long(ch.faces.size());

  slot = 0;
  for (uint32_t f : ch.faces) {
    const uint32_t first = slot, size = mesh.face_size(f);
    for (uint32_t k = 1; k + 1 < size; ++k)
      ch.triangles.insert(ch.triangles.end(), {ch.corner_vertex[first], ch.corner_vertex[first + k],
                                               ch.corner_vertex[first + k + 1]});
    for (uint32_t k = 0; k < size; ++k)
      if (inner_twin(mesh.face_offsets[f] + k) == kNone)
        ch.boundary.insert(ch.boundary.end(),
                           {ch.corner_vertex[first + k], ch.corner_vertex[first + (k + 1) % size]});
    slot += size;
  }
  return ch;
}

namespace {

void triangle_points(const VsaSurface& s, const Chart& ch, size_t tri, double q[3][3],
                     double uv[3][2]) {
  for (int i = 0; i < 3; ++i) {
    const uint32_t v = ch.triangles[3 * tri + i];
    const float* p = &s.mesh->positions[3 * size_t(ch.vertex_source[v])];
    q[i][0] = p[0], q[i][1] = p[1], q[i][2] = p[2];
    uv[i][0] = ch.uv[2 * size_t(v)], uv[i][1] = ch.uv[2 * size_t(v) + 1];
  }
}

}  // namespace

ChartQuality chart_quality(const VsaSurface& s, const Chart& ch) {
  ChartQuality q;
  const double diag = s.bbox.diagonal();
  const double tiny = 1e-12 * diag * diag;
  double area3 = 0, area_uv = 0, l2 = 0, linf = 0;
  for (size_t i = 0; i < ch.triangles.size() / 3; ++i) {
    double p[3][3], uv[3][2];
    triangle_points(s, ch, i, p, uv);
    const TriangleStretch ts = triangle_stretch(p, uv);
    if (!(ts.area3 > tiny)) continue;
    if (!(ts.area_uv > 0)) {
      ++q.flipped;
      continue;
    }
    area3 += ts.area3;
    area_uv += ts.area_uv;
    l2 += ts.area3 * ts.l2_sq;
    linf = std::max(linf, ts.gamma);
  }
  if (area3 > 0 && area_uv > 0) {
    const double norm = std::sqrt(area_uv / area3);
    q.stretch_l2 = std::sqrt(l2 / area3) * norm;
    q.stretch_linf = linf * norm;
  }
  return q;
}

bool boundary_crosses(const Chart& ch) {
  const size_t m = ch.boundary.size() / 2;
  if (m < 4) return false;
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (uint32_t v : ch.boundary)
    for (int k = 0; k < 2; ++k)
      lo[k] = std::min(lo[k], ch.uv[2 * size_t(v) + k]),
      hi[k] = std::max(hi[k], ch.uv[2 * size_t(v) + k]);
  const int cells = std::clamp(int(std::sqrt(double(m))), 1, 1024);
  const double cw = std::max(hi[0] - lo[0], 1e-300) / cells,
               chh = std::max(hi[1] - lo[1], 1e-300) / cells;
  auto cell = [&](double x, double lo_, double w) {
    return std::clamp(int((x - lo_) / w), 0, cells - 1);
  };
  std::vector<std::vector<uint32_t>> grid(size_t(cells) * cells);
  auto at = [&](uint32_t v, int k) { return ch.uv[2 * size_t(v) + k]; };
  for (uint32_t e = 0; e < m; ++e) {
    const uint32_t a = ch.boundary[2 * e], b = ch.boundary[2 * e + 1];
    const int x0 = cell(std::min(at(a, 0), at(b, 0)), lo[0], cw),
              x1 = cell(std::max(at(a, 0), at(b, 0)), lo[0], cw);
    const int y0 = cell(std::min(at(a, 1), at(b, 1)), lo[1], chh),
              y1 = cell(std::max(at(a, 1), at(b, 1)), lo[1], chh);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) grid[size_t(y) * cells + x].push_back(e);
  }
  auto orient = [&](uint32_t a, uint32_t b, uint32_t c) {
    const double o = (at(b, 0) - at(a, 0)) * (at(c, 1) - at(a, 1)) -
                     (at(b, 1) - at(a, 1)) * (at(c, 0) - at(a, 0));
    return (o > 0) - (o < 0);
  };
  for (const auto& bucket : grid)
    for (size_t i = 0; i < bucket.size(); ++i)
      for (size_t j = i + 1; j < bucket.size(); ++j) {
        const uint32_t a = ch.boundary[2 * bucket[i]], b = ch.boundary[2 * bucket[i] + 1];
        const uint32_t c = ch.boundary[2 * bucket[j]], d = ch.boundary[2 * bucket[j] + 1];
        if (a == c || a == d || b == c || b == d) continue;
        if (orient(a, b, c) * orient(a, b, d) < 0 && orient(c, d, a) * orient(c, d, b) < 0)
          return true;
      }
  return false;
}

namespace {

// Hop distances across edges from face `from`; returns the farthest face.
uint32_t face_distances(const VsaSurface& sub, uint32_t from, std::vector<uint32_t>& dist) {
  dist.assign(sub.face_count(), kNone);
  std::deque<uint32_t> queue{from};
  dist[from] = 0;
  uint32_t last = from;
  while (!queue.empty()) {
    const uint32_t f = queue.front();
    queue.pop_front();
    last = f;
    for (uint32_t c = sub.mesh->face_offsets[f]; c < sub.mesh->face_offsets[f + 1]; ++c) {
      const uint32_t g = sub.across(c);
      if (g != kNone && dist[g] == kNone) dist[g] = dist[f] + 1, queue.push_back(g);
    }
  }
  return last;
}

}  // namespace

std::vector<std::vector<uint32_t>> label_pieces(const VsaSurface& s,
                                                std::span<const uint32_t> label,
                                                std::span<const uint32_t> names) {
  std::vector<std::vector<uint32_t>> pieces;
  std::vector<uint8_t> seen(label.size(), 0);
  std::vector<uint32_t> stack;
  for (uint32_t f0 = 0; f0 < label.size(); ++f0) {
    if (seen[f0]) continue;
    pieces.emplace_back();
    seen[f0] = 1;
    stack.push_back(f0);
    while (!stack.empty()) {
      const uint32_t f = stack.back();
      stack.pop_back();
      pieces.back().push_back(names.empty() ? f : names[f]);
      for (uint32_t c = s.mesh->face_offsets[f]; c < s.mesh->face_offsets[f + 1]; ++c) {
        const uint32_t g = s.across(c);
        if (g != kNone && !seen[g] && label[g] == label[f]) seen[g] = 1, stack.push_back(g);
      }
    }
  }
  return pieces;
}

std::vector<std::vector<uint32_t>> split_faces(const VsaSurface& s,
                                               std::span<const uint32_t> faces) {
  const Mesh& mesh = *s.mesh;
  // The chart's faces as a mesh of their own (vertices renumbered), for VSA.
  std::vector<uint32_t> verts;
  for (uint32_t f : faces)
    for (uint32_t v : mesh.face(f)) verts.push_back(v);
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  Mesh sub;
  sub.positions.reserve(3 * verts.size());
  for (uint32_t v : verts)
    sub.positions.insert(sub.positions.end(), &mesh.positions[3 * size_t(v)],
                         &mesh.positions[3 * size_t(v)] + 3);
  sub.face_offsets.reserve(faces.size() + 1);
  for (uint32_t f : faces) {
    for (uint32_t v : mesh.face(f))
      sub.face_vertices.push_back(
          uint32_t(std::lower_bound(verts.begin(), verts.end(), v) - verts.begin()));
    sub.face_offsets.push_back(uint32_t(sub.face_vertices.size()));
  }
  const VsaSurface ss = prepare_surface(sub);

  std::vector<uint32_t> label(faces.size(), 0);
  bool two = false;
  if (faces.size() > 2) {
    VsaOptions o;
    o.proxies = 2;
    o.teleports = 0;
    const Partition p = vsa_partition(ss, o);
    if (p.cluster_count() == 2) {
      for (size_t f = 0; f < faces.size(); ++f) label[f] = p.label[f] == 1;
      const size_t ones = size_t(std::count(label.begin(), label.end(), 1u));
      two = ones > 0 && ones < faces.size();
    }
  }
  if (!two) {
    // Two halves by hop distance from the ends of an approximate diameter.
    std::vector<uint32_t> da, db;
    const uint32_t b = face_distances(ss, face_distances(ss, 0, da), da);
    face_distances(ss, b, db);
    for (size_t f = 0; f < faces.size(); ++f) label[f] = db[f] < da[f];
  }
  return label_pieces(ss, label, faces);
}

}  // namespace limn::atlas
