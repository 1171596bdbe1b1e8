// Material channels from the command line: limn paint with a material script, limn bake to PNGs
// (base colour, metallic-roughness, 16-bit height, normal map; UDIM tiles) and to a GLB whose
// material carries them with a tangent frame; what an output cannot hold named in a warning and
// in --json's "dropped"; bad requests exit 2 and write nothing.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "limn/paint/file.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class MaterialCli : public test::CliTest {
 protected:
  void SetUp() override {
    test::CliTest::SetUp();
    ASSERT_EQ(limn("shape torus -o " + q(dir() / "torus.obj")).code, 0);
    write("m.json", R"({"strokes": [{"type": "fill", "color": [0.7, 0.5, 0.3, 1]},
      {"points": [[1.4, 0, 0], [0, 1.4, 0]], "radius": 0.3, "color": [0.9, 0.1, 0.1],
       "metallic": 1, "roughness": 0.2, "depth": 7},
      {"points": [[0, -1.4, 0.3], [1.0, -1.0, 0.3]], "radius": 0.25, "height": 1, "depth": 7}]})");
    const auto r =
        limn("paint " + q(dir() / "torus.obj") + " --strokes " + q(dir() / "m.json") + " -o " +
             q(dir() / "m.lot") + " --channel-defaults 0.6,0.1,0.5 --height-scale 0.05");
    ASSERT_EQ(r.code, 0) << r.err;
    bake_ = "bake " + q(dir() / "m.lot") + " " + q(dir() / "torus.obj") + " ";
  }
  std::string bake_;
};

nlohmann::json gltf_json(const std::string& glb) {
  const uint32_t n = uint32_t(uint8_t(glb[12])) | uint32_t(uint8_t(glb[13])) << 8 |
                     uint32_t(uint8_t(glb[14])) << 16 | uint32_t(uint8_t(glb[15])) << 24;
  return nlohmann::json::parse(glb.substr(20, n));
}

// A float accessor of the GLB's binary chunk, as floats.
std::vector<float> accessor(const std::string& glb, const nlohmann::json& g, int index) {
  const uint32_t n = uint32_t(uint8_t(glb[12])) | uint32_t(uint8_t(glb[13])) << 8 |
                     uint32_t(uint8_t(glb[14])) << 16 | uint32_t(uint8_t(glb[15])) << 24;
  const size_t bin = 20 + n + 8;
  const auto& a = g["accessors"][size_t(index)];
  const auto& v = g["bufferViews"][a["bufferView"].get<size_t>()];
  const size_t comps = a["type"] == "VEC4" ? 4 : a["type"] == "VEC3" ? 3 : 2;
  const size_t at = bin + v.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0));
  std::vector<float> out(comps * a["count"].get<size_t>());
  std::memcpy(out.data(), glb.data() + at, 4 * out.size());
  return out;
}

TEST_F(MaterialCli, StatsShowTheChannelsAndTheirDefaults) {
  const auto r = limn("paint --stats " + q(dir() / "m.lot") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j["rmh"].is_object());
  EXPECT_NEAR(j["rmh"]["defaults"]["roughness"].get<double>(), 0.6, 0.51 / 255);
  EXPECT_NEAR(j["rmh"]["defaults"]["metallic"].get<double>(), 0.1, 0.51 / 255);
  EXPECT_NEAR(j["height_scale"].get<double>(), 0.05, 1e-7);
  EXPECT_GT(j["rmh"]["painted_samples"].get<size_t>(), 1000u);
  // The file: 96-byte header, both pools, 8 bytes per free block.
  EXPECT_EQ(fs::file_size(dir() / "m.lot"),
            96 + j["bytes"].get<size_t>() + j["rmh"]["bytes"].get<size_t>() +
                8 * (j["free_blocks"].get<size_t>() + j["rmh"]["free_blocks"].get<size_t>()));
}

TEST_F(MaterialCli, PngsOfEveryChannel) {
  auto r = limn(bake_ + "--atlas --size 128 -o " + q(dir() / "base.png") + " --mesh-out " +
                q(dir() / "uv.obj") + " --metallic-roughness " + q(dir() / "mr.png") +
                " --height " + q(dir() / "h.png") + " --normal " + q(dir() / "n.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["dropped"].empty()) << j["dropped"];
  EXPECT_EQ(j["tiles"][0]["height"], (dir() / "h.png").string());
  // The height PNG is 16-bit greyscale (IHDR: bit depth 16, colour type 0).
  const std::string h = test::slurp(dir() / "h.png");
  ASSERT_GT(h.size(), 26u);
  EXPECT_EQ(h.substr(12, 4), "IHDR");
  EXPECT_EQ(int(h[24]), 16);
  EXPECT_EQ(int(h[25]), 0);
  for (const char* f : {"base.png", "mr.png", "n.png", "uv.obj"})
    EXPECT_TRUE(fs::exists(dir() / f)) << f;

  // Without the channel outputs, the channels are named as dropped.
  r = limn(bake_ + "--atlas --size 128 -o " + q(dir() / "only.png") + " --mesh-out " +
           q(dir() / "uv2.obj") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["dropped"], nlohmann::json({"roughness", "metallic", "height"}));
  EXPECT_THAT(r.err, HasSubstr("dropped roughness, metallic, height"));

  // UDIM tiles: every output names its tiles.
  r = limn(bake_ + "--atlas --size 64 --tiles 8 --texels-per-unit 20 -o " +
           q(dir() / "c.<UDIM>.png") + " --mesh-out " + q(dir() / "uv3.obj") + " --height " +
           q(dir() / "h.<UDIM>.png") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  ASSERT_GE(j["tiles"].size(), 2u);
  for (size_t t = 0; t < j["tiles"].size(); ++t) {
    const std::string n = std::to_string(1001 + t);
    EXPECT_TRUE(fs::exists(dir() / ("c." + n + ".png")));
    EXPECT_TRUE(fs::exists(dir() / ("h." + n + ".png")));
  }
  EXPECT_EQ(j["dropped"], nlohmann::json({"roughness", "metallic"}));
}

TEST_F(MaterialCli, GlbCarriesTheMaterialAndATangentFrame) {
  auto r = limn(bake_ + "--atlas --size 128 --normal-map -o " + q(dir() / "a.glb") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["dropped"].empty());
  const std::string glb = test::slurp(dir() / "a.glb");
  const nlohmann::json g = gltf_json(glb);
  const auto& m = g["materials"][0];
  EXPECT_TRUE(m["pbrMetallicRoughness"].contains("metallicRoughnessTexture"));
  EXPECT_TRUE(m.contains("normalTexture"));
  // With a texture the factors keep its values.
  EXPECT_EQ(m["pbrMetallicRoughness"].value("metallicFactor", 1.0), 1.0);
  EXPECT_EQ(m["pbrMetallicRoughness"].value("roughnessFactor", 1.0), 1.0);
  const auto& attrs = g["meshes"][0]["primitives"][0]["attributes"];
  ASSERT_TRUE(attrs.contains("TANGENT"));
  const std::vector<float> t = accessor(glb, g, attrs["TANGENT"]);
  const std::vector<float> n = accessor(glb, g, attrs["NORMAL"]);
  ASSERT_EQ(t.size() / 4, n.size() / 3);
  for (size_t i = 0; i < n.size() / 3; ++i) {
    const float* a = &t[4 * i];
    const float* b = &n[3 * i];
    ASSERT_NEAR(a[0] * a[0] + a[1] * a[1] + a[2] * a[2], 1.0f, 1e-4f);
    ASSERT_NEAR(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], 0.0f, 1e-4f);
    ASSERT_TRUE(a[3] == 1.0f || a[3] == -1.0f);
  }

  // Without --normal-map the height has no place in glTF: named as dropped.
  r = limn(bake_ + "--atlas --size 128 -o " + q(dir() / "b.glb") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["dropped"], nlohmann::json({"height"}));
  EXPECT_FALSE(
      gltf_json(test::slurp(dir() / "b.glb"))["meshes"][0]["primitives"][0]["attributes"].contains(
          "TANGENT"));
  // Vertex colours hold none of the channels.
  r = limn(bake_ + "-o " + q(dir() / "v.ply") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["dropped"],
            nlohmann::json({"roughness", "metallic", "height"}));
}

TEST_F(MaterialCli, BadRequestsExitTwoAndWriteNothing) {
  const auto before = files();
  for (const std::string& args :
       {bake_ + "--atlas -o " + q(dir() / "x.glb") + " --normal " + q(dir() / "n.png"),
        bake_ + "--atlas -o " + q(dir() / "x.png") + " --mesh-out " + q(dir() / "u.obj") +
            " --height " + q(dir() / "h.exr"),
        bake_ + "--atlas -o " + q(dir() / "x.png") + " --mesh-out " + q(dir() / "u.obj") +
            " --normal-map",
        std::string("paint ") + q(dir() / "torus.obj") + " --strokes " + q(dir() / "m.json") +
            " -o " + q(dir() / "y.lot") + " --channel-defaults 2,0,0",
        std::string("paint ") + q(dir() / "torus.obj") + " --strokes " + q(dir() / "m.json") +
            " -o " + q(dir() / "y.lot") + " --height-scale -1"}) {
    const auto r = limn(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_EQ(files(), before);
}

}  // namespace
}  // namespace limn
