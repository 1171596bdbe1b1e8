// limn render as scripts see it: a PNG of the mesh or its adaptive surface, the JSON report,
// bad input and bad usage (exit 2, one line, no image written).
#include <gmock/gmock.h>

#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "limn/mesh/io.hpp"
#include "limn/render/image.hpp"

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

// A path in single quotes for the shell.
std::string q(const fs::path& p) {
  return fmt::format("'{}'", p.string());
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
