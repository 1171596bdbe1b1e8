// Baking: vertex colours equal the lookups at the vertices (against the map-of-cells reference
// too) and survive the PLY writer; UV texels equal the lookups at the matching surface points;
// the gutter is filled and nothing beyond it; the PNG decodes to the same texels.
#include <gtest/gtest.h>

#include <random>

#include "limn/io/mesh_io.hpp"
#include "limn/paint/bake.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/lookup.hpp"
#include "paint_oracle.hpp"

#include "stb_image_reader.hpp"

namespace limn {
namespace {

const std::string kModels = LIMN_SHARED_MODELS;

void paint_dabs(OctreeTexture& t, const PaintSurface& s, const Mesh& m, int n, int depth,
                float radius, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < n; ++i) {
    Brush b;
    b.depth = depth, b.radius = radius, b.hardness = u(rng);
    for (float& c : b.color) c = u(rng);
    const size_t v = rng() % m.vertex_count();
    StrokePainter p(t, s);
    p.begin(b);
    p.dab_world(&m.positions[3 * v]);
    p.end();
  }
}

TEST(PaintBake, VertexColorsEqualTheLookupsAtTheVertices) {
  const Mesh m = read_mesh(kModels + "/tri/spot.obj");
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(20, 40, 60, 255));
  paint_dabs(t, s, m, 25, 9, t.size() * 0.05f, 4);
  const std::vector<float> baked = bake_vertex_colors(t, m);
  const std::vector<float> normals = vertex_normals(m);
  ASSERT_EQ(baked.size(), 4 * m.vertex_count());
  const test::CellMap map(t);
  size_t painted = 0, referenced = 0;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    float want[4];
    if (!lookup_filtered(t, &m.positions[3 * v], &normals[3 * v], 0.0f, want))
      rgba8_to_float(t.background(), want);
    for (int k = 0; k < 4; ++k) ASSERT_EQ(baked[4 * v + size_t(k)], want[k]) << v;
    float ref[4];
    if (map.filtered(&m.positions[3 * v], &normals[3 * v], ref)) {
      for (int k = 0; k < 4; ++k) ASSERT_NEAR(baked[4 * v + size_t(k)], ref[k], 2e-4) << v;
      ++referenced;
    }
    painted += std::fabs(baked[4 * v] - 20 / 255.0f) > 1e-3f;
  }
  EXPECT_GT(painted, m.vertex_count() / 20);
  EXPECT_GT(referenced, m.vertex_count() * 9 / 10);
  // Nearest: the leaf sample at the vertex.
  BakeOptions nearest;
  nearest.filtered = false;
  const std::vector<float> nb = bake_vertex_colors(t, m, nearest);
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    Rgba8 want;
    map.nearest(&m.positions[3 * v], &normals[3 * v], want);
    float f[4];
    rgba8_to_float(want, f);
    for (int k = 0; k < 4; ++k) ASSERT_EQ(nb[4 * v + size_t(k)], f[k]);
  }
  // Through the PLY writer and reader: 8-bit colours, the nearest value, at every corner (the
  // writer splits spot's UV seams into separate vertices).
  Mesh coloured = m;
  coloured.colors = nb;
  const Mesh back = read_ply(write_mesh_memory(coloured, MeshFormat::ply), "baked.ply");
  ASSERT_EQ(back.corner_count(), m.corner_count());
  ASSERT_EQ(back.colors.size(), 4 * back.vertex_count());
  for (size_t c = 0; c < m.corner_count(); ++c)
    for (size_t k = 0; k < 4; ++k)
      ASSERT_NEAR(back.colors[4 * back.face_vertices[c] + k], nb[4 * m.face_vertices[c] + k],
                  0.5f / 255.0f);
}

TEST(PaintBake, UvTexelsEqualTheLookupsAndTheGutterIsFilled) {
  // A sheet over [-1,1]^2 whose uvs fill the chart [0.25, 0.75]^2 of the image.
  Mesh m = test::sheet(-1, 1, -1, 1, 0.0, 6, true);
  for (float& x : m.uvs) x = 0.25f + 0.5f * x;
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(255, 255, 255, 255));
  paint_dabs(t, s, m, 12, 8, 0.3f, 8);
  const int W = 96, H = 64, gutter = 3;
  const Image img = bake_uv_texture(t, m, W, H, gutter);
  ASSERT_EQ(img.rgba.size(), size_t(4 * W * H));
  const float up[3] = {0, 0, 1};
  size_t compared = 0, coloured = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double u = (x + 0.5) / W, v = 1 - (y + 0.5) / H;
      // Texel distance outside the chart (Chebyshev, in texels).
      const double ox = std::max({0.25 * W - (x + 0.5), (x + 0.5) - 0.75 * W, 0.0});
      const double oy = std::max({0.25 * H - (H - (y + 0.5)), (H - (y + 0.5)) - 0.75 * H, 0.0});
      const double out = std::max(ox, oy);
      const uint8_t* px = &img.rgba[4 * size_t(y * W + x)];
      if (out == 0 && u > 0.2501 && u < 0.7499 && v > 0.2501 && v < 0.7499) {
        const float p[3] = {float((u - 0.25) / 0.5 * 2 - 1), float((v - 0.25) / 0.5 * 2 - 1), 0};
        float want[4];
        ASSERT_TRUE(lookup_filtered(t, p, up, 0.0f, want));
        for (int k = 0; k < 4; ++k)
          ASSERT_NEAR(double(px[k]), double(want[k]) * 255.0, 1.0) << x << "," << y;
        ++compared;
        coloured += px[0] != 255 || px[1] != 255 || px[2] != 255;
      } else if (out > 0.5 && out < gutter - 0.5) {
        EXPECT_EQ(px[3], 255) << "gutter texel " << x << "," << y << " left empty";
      } else if (out > gutter + 0.5) {
        EXPECT_EQ(px[3], 0) << "texel " << x << "," << y << " beyond the gutter";
      }
    }
  EXPECT_GT(compared, size_t(W * H / 5));
  EXPECT_GT(coloured, compared / 10);
  // The PNG holds the same texels.
  const std::string png = encode_png(img);
  int w = 0, h = 0, c = 0;
  unsigned char* d = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                           int(png.size()), &w, &h, &c, 4);
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(w, W);
  EXPECT_EQ(h, H);
  EXPECT_TRUE(std::equal(img.rgba.begin(), img.rgba.end(), d));
  stbi_image_free(d);
}

TEST(PaintBake, SpotBakesIntoItsUvsAndBadRequestsAreRefused) {
  const Mesh m = read_mesh(kModels + "/tri/spot.obj");
  ASSERT_FALSE(m.uvs.empty());
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(255, 255, 255, 255));
  paint_dabs(t, s, m, 10, 8, t.size() * 0.05f, 2);
  const Image img = bake_uv_texture(t, m, 128, 128, 2);
  size_t opaque = 0;
  for (size_t i = 3; i < img.rgba.size(); i += 4) opaque += img.rgba[i] == 255;
  EXPECT_GT(opaque, size_t(128 * 128 / 4));
  Mesh no_uv = m;
  no_uv.uvs.clear(), no_uv.uv_indices.clear();
  EXPECT_THROW(bake_uv_texture(t, no_uv, 64, 64), InputError);
  EXPECT_THROW(bake_uv_texture(t, m, 0, 64), InputError);
  EXPECT_THROW(bake_uv_texture(t, m, 64, 20000), InputError);
  EXPECT_THROW(bake_uv_texture(t, m, 64, 64, -1), InputError);
}

}  // namespace
}  // namespace limn
