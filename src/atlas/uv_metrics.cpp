#include "limn/atlas/uv_metrics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "atlas/stretch.hpp"

namespace limn {

namespace {

// Calls f(px, py) for each texel centre (px + 0.5, py + 0.5) of a size x size grid inside the
// triangle (x, y in texels, either orientation). A centre on an edge belongs to one side only
// (the edge's direction decides, as GPUs' top-left rule does), so two triangles sharing an edge
// never both take it and never leave it out.
template <class F>
void for_texels_inside(double x[3], double y[3], int size, F&& f) {
  const double area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
  if (!(area != 0)) return;
  if (area < 0) std::swap(x[1], x[2]), std::swap(y[1], y[2]);  // a mirrored triangle still covers
  const int x0 = std::max(0, int(std::floor(std::min({x[0], x[1], x[2]}) - 0.5)));
  const int x1 = std::min(size - 1, int(std::ceil(std::max({x[0], x[1], x[2]}) - 0.5)));
  const int y0 = std::max(0, int(std::floor(std::min({y[0], y[1], y[2]}) - 0.5)));
  const int y1 = std::min(size - 1, int(std::ceil(std::max({y[0], y[1], y[2]}) - 0.5)));
  for (int py = y0; py <= y1; ++py)
    for (int px = x0; px <= x1; ++px) {
      const double cx = px + 0.5, cy = py + 0.5;
      bool inside = true;
      for (int e = 0; e < 3 && inside; ++e) {
        const int a = e, b = (e + 1) % 3;
        const double dx = x[b] - x[a], dy = y[b] - y[a];
        const double w = dx * (cy - y[a]) - dy * (cx - x[a]);
        inside = w > 0 || (w == 0 && (dy < 0 || (dy == 0 && dx > 0)));
      }
      if (inside) f(px, py);
    }
}

// Counts, per texel centre of one tile, the triangles that hold it.
class TileRaster {
 public:
  explicit TileRaster(int size) : size_(size), count_(size_t(size) * size, 0) {}
  // (u, v) in tile units [0,1]; v up, as the rows of the count image.
  void add(const double u[3], const double v[3]) {
    double x[3], y[3];
    for (int i = 0; i < 3; ++i) x[i] = u[i] * size_, y[i] = v[i] * size_;
    for_texels_inside(x, y, size_, [&](int px, int py) {
      uint8_t& c = count_[size_t(py) * size_ + px];
      if (c < 255) ++c;
    });
  }
  void tally(size_t& covered, size_t& overlapping) const {
    for (uint8_t c : count_) covered += c > 0, overlapping += c > 1;
  }

 private:
  int size_;
  std::vector<uint8_t> count_;
};

}  // namespace

UvMetrics measure_uvs(const Mesh& mesh, int size) {
  if (mesh.uvs.empty() || mesh.uv_indices.size() != mesh.corner_count())
    throw InputError("mesh: no texture coordinates to measure");
  if (size < 1 || size > 16384)
    throw InputError(fmt::format("texture size {}: must be 1-16384", size));
  const Box box = bounding_box(mesh);
  const double diag = box.diagonal();
  const double tiny = 1e-12 * diag * diag;

  UvMetrics m;
  std::map<std::pair<long, long>, TileRaster> tiles;
  double area3 = 0, area_uv = 0, l2_sum = 0, linf = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t first = mesh.face_offsets[f];
    for (uint32_t k = 1; k + 1 < mesh.face_size(f); ++k) {
      const uint32_t c[3] = {first, first + k, first + k + 1};
      double q[3][3], uv[3][2];
      for (int i = 0; i < 3; ++i) {
        const float* p = &mesh.positions[3 * size_t(mesh.face_vertices[c[i]])];
        const float* w = &mesh.uvs[2 * size_t(mesh.uv_indices[c[i]])];
        q[i][0] = p[0], q[i][1] = p[1], q[i][2] = p[2], uv[i][0] = w[0], uv[i][1] = w[1];
      }
      const atlas::TriangleStretch ts = atlas::triangle_stretch(q, uv);
      if (!(ts.area3 > tiny)) continue;
      ++m.triangles;
      if (!(ts.area_uv > 0)) ++m.flipped;
      if (ts.gamma > 0) {
        area3 += ts.area3;
        area_uv += std::abs(ts.area_uv);
        l2_sum += ts.area3 * ts.l2_sq;
        linf = std::max(linf, ts.gamma);
      }
      double s[3] = {uv[0][0], uv[1][0], uv[2][0]}, t[3] = {uv[0][1], uv[1][1], uv[2][1]};
      const double cu = (s[0] + s[1] + s[2]) / 3, cv = (t[0] + t[1] + t[2]) / 3;
      if (!(std::abs(cu) < 1e6 && std::abs(cv) < 1e6)) {  // NaN, or no tile to draw in
        ++m.straddling;
        continue;
      }
      const double fu = std::floor(cu), fv = std::floor(cv);
      const long tu = long(fu), tv = long(fv);
      bool inside_tile = true;
      for (int i = 0; i < 3; ++i)
        inside_tile = inside_tile && s[i] >= fu && s[i] <= fu + 1 && t[i] >= fv && t[i] <= fv + 1;
      if (!inside_tile) ++m.straddling;
      auto it = tiles.find({tu, tv});
      if (it == tiles.end()) {
        if ((tiles.size() + 1) * size_t(size) * size > (size_t(1) << 31))
          throw InputError(
              fmt::format("mesh: UVs over {} tiles of {}^2 texels: too many to measure",
                          tiles.size() + 1, size));
        it = tiles.emplace(std::pair{tu, tv}, TileRaster(size)).first;
      }
      for (int i = 0; i < 3; ++i) s[i] -= fu, t[i] -= fv;
      it->second.add(s, t);
    }
  }
  for (const auto& [key, raster] : tiles) raster.tally(m.covered_texels, m.overlapping_texels);
  m.tiles = tiles.size();
  if (m.tiles) m.coverage = double(m.covered_texels) / (double(m.tiles) * size * size);
  if (area3 > 0) {
    const double norm = std::sqrt(area_uv / area3);
    m.stretch_l2 = std::sqrt(l2_sum / area3) * norm;
    m.stretch_linf = linf * norm;
  }
  return m;
}

std::vector<uint8_t> uv_layout_image(const Mesh& mesh, std::span<const uint32_t> face_chart,
                                     int size, int tile) {
  if (mesh.uvs.empty() || mesh.uv_indices.size() != mesh.corner_count())
    throw InputError("mesh: no texture coordinates to draw");
  if (size < 1 || size > 16384)
    throw InputError(fmt::format("image size {}: must be 1-16384", size));
  const double tu = tile % 10, tv = tile / 10;
  std::vector<uint8_t> rgba(size_t(size) * size * 4, 255);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    // A colour per chart from a hash, kept away from white.
    uint32_t h = (f < face_chart.size() ? face_chart[f] : 0) * 2654435761u + 0x9e3779b9u;
    h ^= h >> 15, h *= 0x85ebca6bu, h ^= h >> 13;
    const uint8_t color[3] = {uint8_t(40 + (h & 0xff) * 170 / 255),
                              uint8_t(40 + ((h >> 8) & 0xff) * 170 / 255),
                              uint8_t(40 + ((h >> 16) & 0xff) * 170 / 255)};
    const uint32_t first = mesh.face_offsets[f];
    for (uint32_t k = 1; k + 1 < mesh.face_size(f); ++k) {
      double x[3], y[3];
      const uint32_t c[3] = {first, first + k, first + k + 1};
      for (int i = 0; i < 3; ++i) {
        const float* w = &mesh.uvs[2 * size_t(mesh.uv_indices[c[i]])];
        x[i] = (w[0] - tu) * size, y[i] = (1 - (w[1] - tv)) * size;
      }
      for_texels_inside(x, y, size, [&](int px, int py) {
        uint8_t* out = &rgba[(size_t(py) * size + px) * 4];
        out[0] = color[0], out[1] = color[1], out[2] = color[2];
      });
    }
  }
  return rgba;
}

}  // namespace limn
