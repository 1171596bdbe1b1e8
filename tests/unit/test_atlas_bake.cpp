// Baking into an automatic atlas, checked against the octree itself: at random surface points
// (chart borders and seams included), the baked image sampled bilinearly through the point's
// UVs equals the texture's filtered lookup there, within a few 8-bit steps; UDIM tiles each hold
// their charts; a texture painted on another mesh is refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>

#include "bake_oracle.hpp"
#include "cli_runner.hpp"
#include "limn/atlas/unwrap.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/paint/bake.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn {
namespace {

using ::testing::HasSubstr;

// A smooth painting: a fill, then soft wide dabs at a coarse depth, so the colour changes over
// several texels and a bilinear sample of the bake can match the lookup closely.
OctreeTexture smooth_paint(const Mesh& m, uint32_t seed) {
  const PaintSurface s(m);
  OctreeTexture t = OctreeTexture::create(s, pack_rgba8(30, 90, 160, 255));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < 12; ++i) {
    Brush b;
    b.depth = 7, b.radius = t.size() * 0.12f, b.hardness = 0;
    for (int k = 0; k < 3; ++k) b.color[k] = u(rng);
    b.color[3] = 1;
    const size_t v = rng() % m.vertex_count();
    StrokePainter p(t, s);
    p.begin(b);
    p.dab_world(&m.positions[3 * v]);
    p.end();
  }
  return t;
}

struct Errors {
  std::vector<double> steps;  // per sample: the largest channel difference, in 8-bit steps
  double quantile(double q) { return test::quantile(steps, q); }
};

// Compares `samples` random surface points of `m` (area-weighted) between the baked tiles and
// the texture's filtered lookup.
Errors compare(const OctreeTexture& t, const Mesh& m, const std::vector<Image>& tiles,
               const std::vector<int>& tile_ids, int samples) {
  Errors e;
  for (const test::SurfacePoint& s : test::random_surface_points(m, samples, 7)) {
    float want[4];
    if (!lookup_filtered(t, s.p, s.n, 0.0f, want)) rgba8_to_float(t.background(), want);
    const int tile = s.tile();
    const size_t at = size_t(std::find(tile_ids.begin(), tile_ids.end(), tile) - tile_ids.begin());
    EXPECT_LT(at, tile_ids.size()) << "a point in tile " << tile << ", which was not baked";
    if (at >= tile_ids.size()) continue;
    double got[4];
    const Image& img = tiles[at];
    test::sample_bilinear(img.rgba.data(), 4, img.width, img.height, tile, s.uv[0], s.uv[1], got);
    double worst = 0;
    for (int k = 0; k < 4; ++k) worst = std::max(worst, std::abs(got[k] - 255.0 * want[k]));
    e.steps.push_back(worst);
  }
  return e;
}

TEST(AtlasBake, TheBakeSampledThroughTheAtlasEqualsTheOctree) {
  const Mesh torus = make_shape("torus");
  const OctreeTexture t = smooth_paint(torus, 3);
  UnwrapOptions o;
  o.size = 512;
  const UnwrapResult r = unwrap_mesh(torus, o);
  const Image img = bake_uv_texture(t, r.mesh, 512, 512, 8);
  Errors e = compare(t, r.mesh, {img}, {0}, 20000);
  ASSERT_EQ(e.steps.size(), 20000u);
  // Measured: median 0.00001, 99% 0.44, largest 2.7 steps.
  test::expect_steps_within(e.steps, 0.5, 1.5, 6.0);
}

TEST(AtlasBake, UdimTilesEachHoldTheirCharts) {
  const Mesh torus = make_shape("torus");
  const OctreeTexture t = smooth_paint(torus, 5);
  UnwrapOptions o;
  o.size = 128, o.tiles = 10, o.texels_per_unit = 50;
  const UnwrapResult r = unwrap_mesh(torus, o);
  const std::vector<int> ids = uv_tiles(r.mesh);
  ASSERT_EQ(ids.size(), r.stats.tiles);
  ASSERT_GE(ids.size(), 2u);
  std::vector<Image> tiles;
  for (int id : ids) {
    BakeOptions bo;
    bo.tile = id;
    tiles.push_back(bake_uv_texture(t, r.mesh, 128, 128, 4, bo));
  }
  Errors e = compare(t, r.mesh, tiles, ids, 10000);
  ASSERT_EQ(e.steps.size(), 10000u);
  EXPECT_LE(e.quantile(0.5), 1.5);
  EXPECT_LE(e.quantile(0.99), 8.0);
  // A tile holds texels only around its own charts: every tile has some, none is full.
  for (const Image& img : tiles) {
    size_t opaque = 0;
    for (size_t i = 3; i < img.rgba.size(); i += 4) opaque += img.rgba[i] != 0;
    EXPECT_GT(opaque, 0u);
    EXPECT_LT(opaque, img.rgba.size() / 4);
  }
}

TEST(AtlasBake, UvTilesGoByTriangleCentres) {
  Mesh m;
  m.add_vertex(0, 0, 0), m.add_vertex(1, 0, 0), m.add_vertex(0, 1, 0);
  m.add_face({0, 1, 2});
  m.uv_indices = {0, 1, 2};
  size_t outside = 9;
  m.uvs = {1.2f, 0.1f, 1.8f, 0.1f, 1.2f, 0.9f};
  EXPECT_EQ(uv_tiles(m, &outside), std::vector<int>{1});
  EXPECT_EQ(outside, 0u);
  m.uvs = {2.2f, 3.1f, 2.8f, 3.1f, 2.2f, 3.9f};
  EXPECT_EQ(uv_tiles(m), std::vector<int>{32});
  m.uvs = {0.8f, 0.1f, 1.3f, 0.1f, 0.8f, 0.9f};  // across u = 1, centre in tile 0
  EXPECT_EQ(uv_tiles(m), std::vector<int>{0});
  for (float bad : {-0.5f, 10.5f, NAN}) {
    m.uvs = {bad, 0.1f, bad, 0.2f, bad, 0.9f};
    EXPECT_TRUE(uv_tiles(m, &outside).empty());
    EXPECT_EQ(outside, 1u);
  }
  Mesh no_uv = m;
  no_uv.uvs.clear(), no_uv.uv_indices.clear();
  EXPECT_THROW(uv_tiles(no_uv), InputError);
  BakeOptions bo;
  bo.tile = 100;
  const OctreeTexture t = OctreeTexture::create(make_shape("cube"));
  EXPECT_THROW(bake_uv_texture(t, m, 16, 16, 0, bo), InputError);
}

TEST(AtlasBake, ATextureOfAnotherMeshIsRefused) {
  const Mesh torus = make_shape("torus");
  const OctreeTexture t = smooth_paint(torus, 9);
  // The same surface refined, or unwrapped, passes.
  EXPECT_NO_THROW(check_texture_fits(t, torus, "t.lot", "torus"));
  EXPECT_NO_THROW(
      check_texture_fits(t, subdivide_uniform(torus, 1, SubdivOptions{}), "t.lot", "torus L1"));
  // Another surface in the same space does not: a plane through the torus's middle.
  Mesh plane;
  for (int z = 0; z <= 20; ++z)
    for (int x = 0; x <= 20; ++x)
      plane.add_vertex(-1.4f + 0.14f * float(x), 0.0f, -1.4f + 0.14f * float(z));
  for (uint32_t z = 0; z < 20; ++z)
    for (uint32_t x = 0; x < 20; ++x)
      plane.add_face({z * 21 + x, z * 21 + x + 21, z * 21 + x + 22, z * 21 + x + 1});
  try {
    check_texture_fits(t, plane, "t.lot", "plane.obj");
    FAIL() << "the plane passed";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("t.lot: painted on another mesh"));
    EXPECT_THAT(e.what(), HasSubstr("plane.obj"));
  }
}

using AtlasBakeCli = test::CliTest;

TEST_F(AtlasBakeCli, PaintedShapeToGlbAndUdimPngsWithOneCommandEach) {
  ASSERT_EQ(limn("shape torus -o " + q(dir() / "torus.obj")).code, 0);
  write("s.json", R"({"strokes": [{"type": "fill", "color": [0.2, 0.6, 0.3, 1]},
    {"points": [[1.4, 0, 0], [0, 1.4, 0]], "radius": 0.3, "color": [1, 0, 0, 1]}]})");
  ASSERT_EQ(limn("paint " + q(dir() / "torus.obj") + " --strokes " + q(dir() / "s.json") + " -o " +
                 q(dir() / "t.lot"))
                .code,
            0);
  const std::string bake = "bake " + q(dir() / "t.lot") + " " + q(dir() / "torus.obj") + " ";

  // A GLB whose material carries the baked texture.
  auto r = limn(bake + "--atlas --size 256 -o " + q(dir() / "asset.glb") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["mode"], "glb");
  EXPECT_EQ(j["tiles"].size(), 1u);
  EXPECT_GT(j["atlas"]["charts"].get<int>(), 1);
  const std::string glb = test::slurp(dir() / "asset.glb");
  const uint32_t json_length = uint32_t(uint8_t(glb[12])) | uint32_t(uint8_t(glb[13])) << 8 |
                               uint32_t(uint8_t(glb[14])) << 16 | uint32_t(uint8_t(glb[15])) << 24;
  const nlohmann::json gltf = nlohmann::json::parse(glb.substr(20, json_length));
  EXPECT_EQ(gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"], 0);
  EXPECT_EQ(gltf["materials"][0]["pbrMetallicRoughness"]["metallicFactor"], 0.0);
  EXPECT_EQ(gltf["images"][0]["mimeType"], "image/png");
  EXPECT_TRUE(gltf["meshes"][0]["primitives"][0]["attributes"].contains("TEXCOORD_0"));
  EXPECT_FALSE(read_mesh((dir() / "asset.glb").string()).uvs.empty());

  // UDIM tiles: one PNG per tile and the mesh with its UVs.
  r = limn(bake + "--atlas --size 64 --tiles 8 --texels-per-unit 20 -o " +
           q(dir() / "p.<UDIM>.png") + " --mesh-out " + q(dir() / "uv.obj") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  const size_t tiles = j["tiles"].size();
  ASSERT_GE(tiles, 2u);
  for (size_t t = 0; t < tiles; ++t) {
    EXPECT_EQ(j["tiles"][t]["udim"], 1001 + int(t));
    EXPECT_TRUE(std::filesystem::exists(dir() / ("p." + std::to_string(1001 + t) + ".png")));
  }
  EXPECT_EQ(uv_tiles(read_mesh((dir() / "uv.obj").string())).size(), tiles);

  // One tile: OUT as given, or with <UDIM> replaced by 1001.
  r = limn(bake + "--atlas --size 128 -o " + q(dir() / "one.<UDIM>.png") + " --mesh-out " +
           q(dir() / "one.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir() / "one.1001.png"));
}

TEST_F(AtlasBakeCli, BadRequestsExitTwoAndWriteNothing) {
  ASSERT_EQ(limn("shape torus -o " + q(dir() / "torus.obj")).code, 0);
  // A plane through the torus's middle: another surface in the same space.
  std::string plane;
  for (int z = 0; z <= 10; ++z)
    for (int x = 0; x <= 10; ++x)
      plane +=
          "v " + std::to_string(-1.4 + 0.28 * x) + " 0 " + std::to_string(-1.4 + 0.28 * z) + "\n";
  for (int z = 0; z < 10; ++z)
    for (int x = 0; x < 10; ++x) {
      const int a = z * 11 + x + 1;
      plane += "f " + std::to_string(a) + " " + std::to_string(a + 11) + " " +
               std::to_string(a + 12) + " " + std::to_string(a + 1) + "\n";
    }
  write("plane.obj", plane);
  write("s.json", R"({"strokes": [{"type": "fill", "color": [1, 1, 1, 1]}]})");
  ASSERT_EQ(limn("paint " + q(dir() / "torus.obj") + " --strokes " + q(dir() / "s.json") + " -o " +
                 q(dir() / "t.lot"))
                .code,
            0);
  const std::string bake = "bake " + q(dir() / "t.lot") + " " + q(dir() / "torus.obj") + " ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--atlas -o " + q(dir() / "x.png"), "--mesh-out"},
      {"--tiles 4 -o " + q(dir() / "x.glb"), "--tiles needs --atlas"},
      {"--atlas --size 64 --tiles 8 --texels-per-unit 20 -o " + q(dir() / "x.glb"), "UDIM"},
      {"--atlas --size 64 --texels-per-unit 500 -o " + q(dir() / "x.glb"), "too dense"},
      {"--atlas --size 64 --tiles 2 --texels-per-unit 20 -o " + q(dir() / "p.<UDIM>.png") +
           " --mesh-out " + q(dir() / "uv.obj"),
       "too dense"},
      {"--atlas -o " + q(dir() / "x.ply"), "must be .png or .glb"},
      {"--atlas -o " + q(dir() / "x.png") + " --mesh-out " + q(dir() / "uv.xyz"),
       "cannot tell the mesh format"},
      {"-o " + q(dir() / "x.png"), "--atlas"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = limn(bake + args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_THAT(r.err, HasSubstr(message)) << args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  const auto other = limn("bake " + q(dir() / "t.lot") + " " + q(dir() / "plane.obj") +
                          " --atlas -o " + q(dir() / "x.glb"));
  EXPECT_EQ(other.code, 2);
  EXPECT_THAT(other.err, HasSubstr("painted on another mesh"));
  EXPECT_EQ(files(), (std::vector<std::string>{"plane.obj", "s.json", "t.lot", "torus.obj"}));
}

}  // namespace
}  // namespace limn
