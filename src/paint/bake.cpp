// Baking: per-vertex colours and UV textures (rasterised in UV space, looked up in parallel,
// then dilated into a gutter).
#include "limn/paint/bake.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "limn/paint/file.hpp"
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

namespace {

// Which fan triangle of the mesh covers each texel centre of one UDIM tile, with the texel's
// barycentric coordinates in it.
struct UvRaster {
  size_t W = 0, H = 0;
  struct Tri {
    uint32_t face, k;  // corners 0, k, k+1 of the face
    // Model units one texel step covers on the surface: to the right (+u) and up (+v).
    float right, up;
  };
  std::vector<Tri> tris;
  std::vector<int64_t> owner;  // per texel: index in tris, -1 where no triangle is
  std::vector<float> bary;
  bool covered(size_t i) const { return owner[i] >= 0; }
};

void check_bake_args(const Mesh& mesh, int width, int height, int gutter, int tile) {
  if (mesh.uvs.empty() || mesh.uv_indices.size() != mesh.corner_count())
    throw InputError("mesh: no texture coordinates (uvs) to bake into");
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InputError("image size " + std::to_string(width) + "x" + std::to_string(height) +
                     ": each side must be 1-16384");
  if (gutter < 0 || gutter > 1024) throw InputError("gutter: must be 0-1024 pixels");
  if (tile < 0 || tile > 99) throw InputError("UDIM tile: must be 0-99 (1001-1100)");
}

UvRaster rasterise(const Mesh& mesh, int width, int height, int tile) {
  const float tile_u = float(tile % 10), tile_v = float(tile / 10);
  UvRaster r;
  r.W = size_t(width), r.H = size_t(height);
  r.owner.assign(r.W * r.H, -1);
  r.bary.resize(3 * r.W * r.H);
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t o = mesh.face_offsets[f], n = mesh.face_size(f);
    for (uint32_t k = 1; k + 1 < n; ++k) {
      const uint32_t corner[3] = {o, o + k, o + k + 1};
      if (uv_triangle_tile(mesh, corner) != tile) continue;  // another tile's triangle
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
      // The surface's derivatives along texel x and texel "up" (-y): the 2x2 system of the
      // triangle's edges in both spaces.
      const float* P[3];
      for (int i = 0; i < 3; ++i) P[i] = &mesh.positions[3 * size_t(mesh.face_vertices[corner[i]])];
      const float dx1 = uv[1][0] - uv[0][0], dx2 = uv[2][0] - uv[0][0];
      const float du1 = uv[0][1] - uv[1][1], du2 = uv[0][1] - uv[2][1];  // up = -y
      const float det = dx1 * du2 - dx2 * du1;
      float right2 = 0, up2 = 0;
      for (int c = 0; c < 3; ++c) {
        const float e1 = P[1][c] - P[0][c], e2 = P[2][c] - P[0][c];
        const float dpx = (e1 * du2 - e2 * du1) / det, dpu = (e2 * dx1 - e1 * dx2) / det;
        right2 += dpx * dpx, up2 += dpu * dpu;
      }
      const float xmin = std::min({uv[0][0], uv[1][0], uv[2][0]});
      const float xmax = std::max({uv[0][0], uv[1][0], uv[2][0]});
      const float ymin = std::min({uv[0][1], uv[1][1], uv[2][1]});
      const float ymax = std::max({uv[0][1], uv[1][1], uv[2][1]});
      const int x0 = std::max(0, int(std::floor(xmin - 0.5f))),
                x1 = std::min(width - 1, int(std::ceil(xmax - 0.5f)));
      const int y0 = std::max(0, int(std::floor(ymin - 0.5f))),
                y1 = std::min(height - 1, int(std::ceil(ymax - 0.5f)));
      const int64_t id = int64_t(r.tris.size());
      r.tris.push_back({uint32_t(f), k, std::sqrt(right2), std::sqrt(up2)});
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
          const size_t i = size_t(y) * r.W + size_t(x);
          r.owner[i] = id;
          r.bary[3 * i] = a, r.bary[3 * i + 1] = b, r.bary[3 * i + 2] = c;
        }
    }
  }
  return r;
}

// The lookup (straight RGBA in [0,1]) at every covered texel's surface point, seen along its
// triangle's normal; 0 elsewhere. Parallel.
std::vector<float> sample_texels(const OctreeTexture& t, const Mesh& mesh, const UvRaster& r,
                                 bool filtered) {
  std::vector<float> out(4 * r.W * r.H, 0.0f);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, r.H), [&](const tbb::blocked_range<size_t>& rows) {
        OctreeSampler s(t);
        for (size_t y = rows.begin(); y < rows.end(); ++y)
          for (size_t x = 0; x < r.W; ++x) {
            const size_t i = y * r.W + x;
            if (!r.covered(i)) continue;
            const UvRaster::Tri tri = r.tris[size_t(r.owner[i])];
            const uint32_t o = mesh.face_offsets[tri.face];
            const uint32_t v[3] = {mesh.face_vertices[o], mesh.face_vertices[o + tri.k],
                                   mesh.face_vertices[o + tri.k + 1]};
            float p[3] = {0, 0, 0};
            for (int j = 0; j < 3; ++j)
              for (int k = 0; k < 3; ++k)
                p[k] += r.bary[3 * i + size_t(j)] * mesh.positions[3 * v[j] + size_t(k)];
            const float* a = &mesh.positions[3 * v[0]];
            const float* b = &mesh.positions[3 * v[1]];
            const float* c = &mesh.positions[3 * v[2]];
            const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
            const float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                e1[0] * e2[1] - e1[1] * e2[0]};
            lookup(s, t, p, n, filtered, &out[4 * i]);
          }
      });
  return out;
}

// Gutter: `gutter` rings of texels around the covered ones, each the mean of its filled
// 8-neighbours, over `channels` floats per texel. Returns which texels hold a value (covered or
// filled).
std::vector<uint8_t> dilate(std::vector<float>& img, int channels, const UvRaster& r, int gutter) {
  const size_t W = r.W, H = r.H, C = size_t(channels);
  std::vector<uint8_t> filled(W * H);
  for (size_t i = 0; i < W * H; ++i) filled[i] = r.covered(i);
  std::vector<size_t> ring;
  std::vector<float> sum(C);
  for (int g = 0; g < gutter; ++g) {
    ring.clear();
    for (size_t y = 0; y < H; ++y)
      for (size_t x = 0; x < W; ++x) {
        if (filled[y * W + x]) continue;
        std::fill(sum.begin(), sum.end(), 0.0f);
        int cnt = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int64_t nx = int64_t(x) + dx, ny = int64_t(y) + dy;
            if (nx < 0 || ny < 0 || nx >= int64_t(W) || ny >= int64_t(H)) continue;
            const size_t j = size_t(ny) * W + size_t(nx);
            if (!filled[j]) continue;
            for (size_t k = 0; k < C; ++k) sum[k] += img[C * j + k];
            ++cnt;
          }
        if (!cnt) continue;
        for (size_t k = 0; k < C; ++k) img[C * (y * W + x) + k] = sum[k] / float(cnt);
        ring.push_back(y * W + x);
      }
    if (ring.empty()) break;
    for (size_t i : ring) filled[i] = 1;
  }
  return filled;
}

uint8_t to_byte(float v) {
  return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
}

Image rgba8_image(const std::vector<float>& rgba, const UvRaster& r) {
  Image img;
  img.width = int(r.W), img.height = int(r.H);
  img.rgba.resize(rgba.size());
  for (size_t i = 0; i < rgba.size(); ++i) img.rgba[i] = to_byte(rgba[i]);
  return img;
}

// Tangent-space normals (OpenGL convention: x along +u, y along +v) of the height field
// h * scale over the texels: the slope along each texel axis from its neighbours that hold a
// height (`known`: covered or dilated; central where both are, one-sided where one is), over the
// model units a texel step covers on the texel's triangle. RGBA8, n * 0.5 + 0.5, alpha 255.
Image normals_from_height(const std::vector<float>& h, const std::vector<uint8_t>& known,
                          const UvRaster& r, int gutter, float scale) {
  const size_t W = r.W, H = r.H;
  std::vector<float> n(4 * W * H, 0.0f);
  auto slope = [&](size_t i, int64_t x, int64_t y, int64_t dx, int64_t dy) {
    auto at = [&](int64_t a, int64_t b) -> int64_t {
      if (a < 0 || b < 0 || a >= int64_t(W) || b >= int64_t(H)) return -1;
      const size_t j = size_t(b) * W + size_t(a);
      return known[j] ? int64_t(j) : -1;
    };
    const int64_t p = at(x + dx, y + dy), m = at(x - dx, y - dy);
    if (p >= 0 && m >= 0) return (h[size_t(p)] - h[size_t(m)]) / 2;
    if (p >= 0) return h[size_t(p)] - h[i];
    if (m >= 0) return h[i] - h[size_t(m)];
    return 0.0f;
  };
  for (size_t y = 0; y < H; ++y)
    for (size_t x = 0; x < W; ++x) {
      const size_t i = y * W + x;
      if (!r.covered(i)) continue;
      const UvRaster::Tri& t = r.tris[size_t(r.owner[i])];
      // Texel steps: +x is +u; -y (the row above) is +v.
      const float gu = slope(i, int64_t(x), int64_t(y), 1, 0) * scale / t.right;
      const float gv = slope(i, int64_t(x), int64_t(y), 0, -1) * scale / t.up;
      const float len = std::sqrt(gu * gu + gv * gv + 1);
      const float v[3] = {-gu / len, -gv / len, 1 / len};
      for (int k = 0; k < 3; ++k) n[4 * i + size_t(k)] = v[k] * 0.5f + 0.5f;
      n[4 * i + 3] = 1;
    }
  dilate(n, 4, r, gutter);
  return rgba8_image(n, r);
}

}  // namespace

Image bake_uv_texture(const OctreeTexture& t, const Mesh& mesh, int width, int height, int gutter,
                      const BakeOptions& opt) {
  check_bake_args(mesh, width, height, gutter, opt.tile);
  const UvRaster r = rasterise(mesh, width, height, opt.tile);
  std::vector<float> rgba = sample_texels(t, mesh, r, opt.filtered);
  dilate(rgba, 4, r, gutter);
  return rgba8_image(rgba, r);
}

MaterialImages bake_material(const MaterialTexture& m, const Mesh& mesh, int width, int height,
                             int gutter, const BakeOptions& opt, bool normal_map) {
  check_bake_args(mesh, width, height, gutter, opt.tile);
  const UvRaster r = rasterise(mesh, width, height, opt.tile);
  MaterialImages out;
  {
    std::vector<float> rgba = sample_texels(m.color, mesh, r, opt.filtered);
    dilate(rgba, 4, r, gutter);
    out.base_color = rgba8_image(rgba, r);
  }
  if (!m.rmh && !normal_map) return out;
  // Channel values over the defaults (an absent RMH texture: the defaults everywhere).
  const size_t n = r.W * r.H;
  std::vector<float> ch(3 * n, 0.0f);
  {
    std::vector<float> rgba;
    if (m.rmh) rgba = sample_texels(*m.rmh, mesh, r, opt.filtered);
    const Rgba8 bg = m.rmh ? m.rmh->background() : rmh_background(MaterialDefaults{});
    const float none[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < n; ++i) {
      if (!r.covered(i)) continue;
      const std::array<float, 3> v = material_value(m.rmh ? &rgba[4 * i] : none, bg);
      for (int k = 0; k < 3; ++k) ch[3 * i + size_t(k)] = v[size_t(k)];
    }
  }
  const std::vector<uint8_t> known = dilate(ch, 3, r, gutter);
  if (m.rmh) {
    out.metallic_roughness.width = out.height.width = width;
    out.metallic_roughness.height = out.height.height = height;
    out.metallic_roughness.rgba.assign(4 * n, 0);
    out.height.values.assign(n, 0);
    for (size_t i = 0; i < n; ++i) {
      uint8_t* px = &out.metallic_roughness.rgba[4 * i];
      const float* v = &ch[3 * i];
      // glTF: roughness in green, metalness in blue (red, often occlusion, left at 1).
      px[0] = 255, px[1] = to_byte(v[0]), px[2] = to_byte(v[1]), px[3] = 255;
      out.height.values[i] = uint16_t(std::lround(std::clamp(v[2], 0.0f, 1.0f) * 65535.0f));
    }
  }
  if (normal_map) {
    std::vector<float> h(n);
    for (size_t i = 0; i < n; ++i) h[i] = ch[3 * i + 2];
    out.normal = normals_from_height(h, known, r, gutter, m.height_scale);
  }
  return out;
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

std::string encode_png16(const Image16& image) {
  // PNG by hand (stb writes 8 bits only): signature, IHDR (16-bit greyscale), one IDAT of the
  // rows (filter 0, big-endian samples) deflated by stb's zlib, IEND.
  const size_t W = size_t(image.width), H = size_t(image.height);
  if (W == 0 || H == 0 || image.values.size() != W * H)
    throw std::runtime_error("PNG encoding failed: image size and values disagree");
  std::string raw;
  raw.reserve(H * (1 + 2 * W));
  for (size_t y = 0; y < H; ++y) {
    raw.push_back(0);
    for (size_t x = 0; x < W; ++x) {
      const uint16_t v = image.values[y * W + x];
      raw.push_back(char(v >> 8)), raw.push_back(char(v & 255));
    }
  }
  int zlen = 0;
  unsigned char* z =
      stbi_zlib_compress(reinterpret_cast<unsigned char*>(raw.data()), int(raw.size()), &zlen, 8);
  if (!z) throw std::runtime_error("PNG encoding failed");
  const std::string idat(reinterpret_cast<const char*>(z), size_t(zlen));
  STBIW_FREE(z);
  auto be32 = [](std::string& s, uint32_t v) {
    for (int k = 3; k >= 0; --k) s.push_back(char(v >> (8 * k) & 255u));
  };
  std::string out("\x89PNG\r\n\x1a\n", 8);
  auto chunk = [&](const char* type, const std::string& data) {
    be32(out, uint32_t(data.size()));
    const std::string body = std::string(type, 4) + data;
    out += body;
    be32(out, crc32(body));
  };
  std::string ihdr;
  be32(ihdr, uint32_t(W));
  be32(ihdr, uint32_t(H));
  ihdr += std::string("\x10\x00\x00\x00\x00", 5);  // depth 16, grey, deflate, filters, no interlace
  chunk("IHDR", ihdr);
  chunk("IDAT", idat);
  chunk("IEND", "");
  return out;
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
