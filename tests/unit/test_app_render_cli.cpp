// limn render as scripts see it: a PNG of the mesh or its adaptive surface, the JSON report,
// bad input and bad usage (exit 2, one line, no image written).
#include <gmock/gmock.h>

#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/render/image.hpp"
#include "limn/subdiv/depth.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
const fs::path kModels = LIMN_SHARED_MODELS;

class RenderCli : public test::CliTest {};

// Pixels that are not the background.
size_t drawn(const fs::path& png, int& w, int& h) {
  const std::vector<uint8_t> px = read_png(png, w, h);
  size_t n = 0;
  for (size_t i = 0; i < px.size(); i += 4)
    n += px[i] != 255 || px[i + 1] != 255 || px[i + 2] != 255;
  return n;
}

TEST_F(RenderCli, AdaptiveSurfaceToPng) {
  const fs::path png = dir() / "bigguy.png";
  const test::CliResult r = limn(fmt::format(
      "render {} --adaptive --tolerance 1 --depth-colors --wireframe --resolution 320x240 "
      "--json -o {}",
      q(kModels / "quads/bigguy.obj"), q(png)));
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["triangles"].get<uint64_t>(), 1000u);
  EXPECT_EQ(j["drawn"].get<size_t>(),
            j["patches"]["regular"].get<size_t>() + j["patches"]["gregory"].get<size_t>());
  int w = 0, h = 0;
  const size_t n = drawn(png, w, h);
  EXPECT_EQ(w, 320);
  EXPECT_EQ(h, 240);
  // The default camera frames the model: it covers a good part of the image, not all of it.
  EXPECT_GT(n, size_t(w * h) / 20);
  EXPECT_LT(n, size_t(w * h));
}

TEST_F(RenderCli, MeshToPng) {
  const fs::path png = dir() / "fandisk.png";
  const test::CliResult r = limn(
      fmt::format("render {} --resolution 200x150 -o {}", q(kModels / "tri/fandisk.obj"), q(png)));
  ASSERT_EQ(r.code, 0) << r.err;
  int w = 0, h = 0;
  EXPECT_GT(drawn(png, w, h), size_t(w * h) / 20);
}

// Paint a red disc on the cube's front face, render the cube with the texture: red in the
// middle of the image (where the default camera sees that face), not at the face's corner.
TEST_F(RenderCli, PaintedTextureToPng) {
  const fs::path cube = dir() / "cube.obj", lot = dir() / "cube.lot", png = dir() / "cube.png";
  ASSERT_EQ(limn("shape cube -o " + q(cube)).code, 0);
  write_file_atomic(dir() / "s.json",
                    R"({"strokes": [{"points": [[0, 0, 0.5]], "radius": 0.2, "color": [1, 0, 0, 1],
                    "hardness": 1, "space": "world"}]})");
  const test::CliResult p =
      limn(fmt::format("paint {} --strokes {} -o {} --depth 8 --background 1,1,1,1", q(cube),
                       q(dir() / "s.json"), q(lot)));
  ASSERT_EQ(p.code, 0) << p.err;
  for (const char* mode : {"", "--nearest"}) {
    const test::CliResult r =
        limn(fmt::format("render {} --texture {} {} --flat --resolution 200x200 --json -o {}",
                         q(cube), q(lot), mode, q(png)));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["texture"], lot.string());
    int w = 0, h = 0;
    const std::vector<uint8_t> px = read_png(png, w, h);
    // Around where the default camera sees the disc's centre.
    const Camera cam = frame_camera(read_mesh(cube), w, h);
    const float centre[3] = {0, 0, 0.5f};
    double cx = 0, cy = 0;
    ASSERT_TRUE(cam.project(centre, cx, cy));
    size_t red = 0;
    for (int y = int(cy) - 10; y < int(cy) + 10; ++y)
      for (int x = int(cx) - 10; x < int(cx) + 10; ++x) {
        const uint8_t* c = &px[4 * size_t(y * w + x)];
        red += c[0] > 100 && c[1] < 40 && c[2] < 40;
      }
    // The face's corner is white (shaded).
    const float corner[3] = {0.45f, -0.45f, 0.5f};
    ASSERT_TRUE(cam.project(corner, cx, cy));
    const uint8_t* c = &px[4 * size_t(int(cy) * w + int(cx))];
    EXPECT_GT(c[1], 100) << mode;
    EXPECT_EQ(red, 400u) << mode;
  }
  // A texture file that is not one: exit 2 naming it, no image.
  fs::remove(png);
  write_file_atomic(dir() / "bad.lot", "not a texture");
  const test::CliResult b =
      limn(fmt::format("render {} --texture {} -o {}", q(cube), q(dir() / "bad.lot"), q(png)));
  EXPECT_EQ(b.code, 2);
  EXPECT_THAT(b.err, HasSubstr("bad.lot"));
  EXPECT_FALSE(fs::exists(png));
  EXPECT_EQ(limn(fmt::format("render {} --nearest -o {}", q(cube), q(png))).code, 2);
}

TEST_F(RenderCli, BadInputAndUsageExitTwoWithoutAnImage) {
  const fs::path bad = dir() / "bad.obj";
  write_file_atomic(bad, "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
  const fs::path png = dir() / "out.png";
  const std::string model = q(kModels / "quads/bigguy.obj"), out = q(png);
  const std::vector<std::string> bad_args = {
      fmt::format("render {} -o {}", q(bad), out),
      fmt::format("render {} -o {}", model, q(dir() / "out.jpg")),
      fmt::format("render {} --tolerance 1 -o {}", model, out),
      fmt::format("render {} --adaptive --tess 40 -o {}", model, out),
      fmt::format("render {} --adaptive --tolerance -2 -o {}", model, out),
      fmt::format("render {} --resolution 0x10 -o {}", model, out),
      fmt::format("render {} --camera 1,2,3 -o {}", model, out),
      fmt::format("render {} --samples 99 -o {}", model, out),
      fmt::format("render {} --background 2,0,0 -o {}", model, out)};
  for (const std::string& args : bad_args) {
    const test::CliResult r = limn(args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(files().empty() || (files().size() == 1 && files()[0] == "bad.obj")) << args;
  }
  EXPECT_THAT(limn(bad_args[0]).err, HasSubstr("bad.obj"));
}

}  // namespace
}  // namespace limn
