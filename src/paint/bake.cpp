// Baking: per-vertex colours and UV textures (rasterised in UV space, looked up in parallel,
// then dilated into a gutter).
#include "limn/paint/bake.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "limn/paint/lookup.hpp"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wdouble-promotion"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#endif
#include <stb/stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace limn {

namespace {

void lookup(OctreeSampler& s, const OctreeTexture& t, const float p[3], const float n[3],
            bool filtered, float out[4]) {
  if (filtered) {
    if (!s.filtered(p, n, 0.0f, out)) rgba8_to_float(t.background(), out);
  } else {
    Rgba8 c;
    s.nearest(p, n, c);
    rgba8_to_float(c, out);
  }
}

// The UDIM tile (0-99) holding the centre of the UV triangle over corners c, or -1 when the
// centre lies outside u, v in [0, 10) or is not a number. Tiles own their lower and left edges.
int uv_triangle_tile(const Mesh& mesh, const uint32_t c[3]) {
  double centre[2] = {0, 0};
  for (int i = 0; i < 3; ++i)
    for (int a = 0; a < 2; ++a) centre[a] += mesh.uvs[2 * size_t(mesh.uv_indices[c[i]]) + a] / 3.0;
  if (!(centre[0] >= 0 && centre[0] < 10 && centre[1] >= 0 && centre[1] < 10)) return -1;
  return int(std::floor(centre[0])) + 10 * int(std::floor(centre[1]));
}

}  // namespace

std::vector<float> bake_vertex_colors(const OctreeTexture& t, const Mesh& mesh,
                                      const BakeOptions& opt) {
  const size_t nv = mesh.vertex_count();
  const std::vector<float> normals = vertex_normals(mesh);
  std::vector<float> out(4 * nv);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, nv, 4096), [&](const tbb::blocked_range<size_t>& r) {
        OctreeSampler s(t);
        for (size_t v = r.begin(); v < r.end(); ++v)
          lookup(s, t, &mesh.positions[3 * v], &normals[3 * v], opt.filtered, &out[4 * v]);
      });
  return out;
}

Image bake_uv_texture(const OctreeTexture& t, const Mesh& mesh, int width, int height, int gutter,
                      const BakeOptions& opt) {
  if (mesh.uvs.empty() || mesh.uv_indices.size() != mesh.corner_count())
    throw InputError("mesh: no texture coordinates (uvs) to bake into");
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InputError("image size " + std::to_string(width) + "x" + std::to_string(height) +
                     ": each side must be 1-16384");
  if (gutter < 0 || gutter > 1024) throw InputError("gutter: must be 0-1024 pixels");
  if (opt.tile < 0 || opt.tile > 99) throw InputError("UDIM tile: must be 0-99 (1001-1100)");
  const float tile_u = float(opt.tile % 10), tile_v = float(opt.tile / 10);
  const size_t W = size_t(width), H = size_t(height);
  // Which fan triangle covers each texel centre (rasterised serially, looked up in parallel).
  struct Tri {
    uint32_t face, k;  // corners 0, k, k+1 of the face
  };
  std::vector<Tri> tris;
  std::vector<int64_t> owner(W * H, -1);
  std::vector<float> bary(3 * W * H);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t o = mesh.face_offsets[f], n = mesh.face_size(f);
    for (uint32_t k = 1; k + 1 < n; ++k) {
      const uint32_t corner[3] = {o, o + k, o + k + 1};
      if (uv_triangle_tile(mesh, corner) != opt.tile) continue;  // another tile's triangle
      float uv[3][2];
      for (int i = 0; i < 3; ++i) {
        const size_t ui = mesh.uv_indices[corner[i]];
        // Texel space: x right, y down from the top row (v = 1).
        uv[i][0] = (mesh.uvs[2 * ui] - tile_u) * float(width);
        uv[i][1] = (1.0f - (mesh.uvs[2 * ui + 1] - tile_v)) * float(height);
      }
      const float den = (uv[1][1] - uv[2][1]) * (uv[0][0] - uv[2][0]) +
                        (uv[2][0] - uv[1][0]) * (uv[0][1] - uv[2][1]);
      if (!(std::fabs(den) > 0) || !std::isfinite(den)) continue;
      const float xmin = std::min({uv[0][0], uv[1][0], uv[2][0]});
      const float xmax = std::max({uv[0][0], uv[1][0], uv[2][0]});
      const float ymin = std::min({uv[0][1], uv[1][1], uv[2][1]});
      const float ymax = std::max({uv[0][1], uv[1][1], uv[2][1]});
      const int x0 = std::max(0, int(std::floor(xmin - 0.5f))),
                x1 = std::min(width - 1, int(std::ceil(xmax - 0.5f)));
      const int y0 = std::max(0, int(std::floor(ymin - 0.5f))),
                y1 = std::min(height - 1, int(std::ceil(ymax - 0.5f)));
      const int64_t id = int64_t(tris.size());
      tris.push_back({uint32_t(f), k});
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const float px = float(x) + 0.5f, py = float(y) + 0.5f;
          const float a =
              ((uv[1][1] - uv[2][1]) * (px - uv[2][0]) + (uv[2][0] - uv[1][0]) * (py - uv[2][1])) /
              den;
          const float b =
              ((uv[2][1] - uv[0][1]) * (px - uv[2][0]) + (uv[0][0] - uv[2][0]) * (py - uv[2][1])) /
              den;
          const float c = 1 - a - b;
          const float e = -1e-5f;
          if (a < e || b < e || c < e) continue;
          const size_t i = size_t(y) * W + size_t(x);
          owner[i] = id;
          bary[3 * i] = a, bary[3 * i + 1] = b, bary[3 * i + 2] = c;
        }
    }
  }
  Image img;
  img.width = width, img.height = height;
  img.rgba.assign(4 * W * H, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, H), [&](const tbb::blocked_range<size_t>& rows) {
    OctreeSampler s(t);
    for (size_t y = rows.begin(); y < rows.end(); ++y)
      for (size_t x = 0; x < W; ++x) {
        const size_t i = y * W + x;
        if (owner[i] < 0) continue;
        const Tri tri = tris[size_t(owner[i])];
        const uint32_t o = mesh.face_offsets[tri.face];
        const uint32_t v[3] = {mesh.face_vertices[o], mesh.face_vertices[o + tri.k],
                               mesh.face_vertices[o + tri.k + 1]};
        float p[3] = {0, 0, 0};
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k)
            p[k] += bary[3 * i + size_t(j)] * mesh.positions[3 * v[j] + size_t(k)];
        const float* a = &mesh.positions[3 * v[0]];
        const float* b = &mesh.positions[3 * v[1]];
        const float* c = &mesh.positions[3 * v[2]];
        const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                            e1[0] * e2[1] - e1[1] * e2[0]};
        float col[4];
        lookup(s, t, p, n, opt.filtered, col);
        for (int k = 0; k < 4; ++k)
          img.rgba[4 * i + size_t(k)] =
              uint8_t(std::lround(std::clamp(col[k], 0.0f, 1.0f) * 255.0f));
      }
  });
  // Gutter: rings of texels around the charts, each the mean of its filled neighbours.
  std::vector<uint8_t> filled(W * H);
  for (size_t i = 0; i < W * H; ++i) filled[i] = owner[i] >= 0;
  std::vector<size_t> ring;
  for (int g = 0; g < gutter; ++g) {
    ring.clear();
    for (size_t y = 0; y < H; ++y)
      for (size_t x = 0; x < W; ++x) {
        if (filled[y * W + x]) continue;
        int sum[4] = {0, 0, 0, 0}, cnt = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int64_t nx = int64_t(x) + dx, ny = int64_t(y) + dy;
            if (nx < 0 || ny < 0 || nx >= int64_t(W) || ny >= int64_t(H)) continue;
            const size_t j = size_t(ny) * W + size_t(nx);
            if (!filled[j]) continue;
            for (int k = 0; k < 4; ++k) sum[k] += img.rgba[4 * j + size_t(k)];
            ++cnt;
          }
        if (!cnt) continue;
        for (int k = 0; k < 4; ++k)
          img.rgba[4 * (y * W + x) + size_t(k)] = uint8_t((sum[k] + cnt / 2) / cnt);
        ring.push_back(y * W + x);
      }
    if (ring.empty()) break;
    for (size_t i : ring) filled[i] = 1;
  }
  return img;
}

void check_texture_fits(const OctreeTexture& t, const Mesh& mesh, const std::string& texture_name,
                        const std::string& mesh_name) {
  const size_t nv = mesh.vertex_count();
  if (nv == 0) return;
  const size_t step = std::max<size_t>(1, nv / 4096);
  OctreeSampler s(t);
  size_t tried = 0, inside = 0;
  for (size_t v = 0; v < nv; v += step) {
    Rgba8 c;
    inside += s.nearest(&mesh.positions[3 * v], nullptr, c) ? 1 : 0;
    ++tried;
  }
  if (2 * inside < tried)
    throw InputError(texture_name + ": painted on another mesh: only " + std::to_string(inside) +
                     " of " + std::to_string(tried) + " vertices of " + mesh_name +
                     " fall in its cells");
}

std::vector<int> uv_tiles(const Mesh& mesh, size_t* outside) {
  if (mesh.uvs.empty() || mesh.uv_indices.size() != mesh.corner_count())
    throw InputError("mesh: no texture coordinates (uvs)");
  std::vector<uint8_t> used(100, 0);
  size_t lost = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t o = mesh.face_offsets[f], n = mesh.face_size(f);
    for (uint32_t k = 1; k + 1 < n; ++k) {
      const uint32_t corner[3] = {o, o + k, o + k + 1};
      const int tile = uv_triangle_tile(mesh, corner);
      if (tile < 0)
        ++lost;
      else
        used[size_t(tile)] = 1;
    }
  }
  if (outside) *outside = lost;
  std::vector<int> tiles;
  for (int t = 0; t < 100; ++t)
    if (used[size_t(t)]) tiles.push_back(t);
  return tiles;
}

std::string encode_png(const Image& image) {
  std::string out;
  auto write = [](void* ctx, void* data, int size) {
    static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), size_t(size));
  };
  if (!stbi_write_png_to_func(write, &out, image.width, image.height, 4, image.rgba.data(),
                              image.width * 4))
    throw std::runtime_error("PNG encoding failed");
  return out;
}

}  // namespace limn
