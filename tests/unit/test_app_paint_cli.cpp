// limn paint and limn bake as scripts see them: a scripted stroke on the bunny baked to a
// coloured mesh, screen strokes to a PNG, stats, and bad input: exit 2, one line naming the file,
// no output file, the previous output untouched.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <tiny_gltf.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_runner.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/paint/file.hpp"
#include "limn/paint/lookup.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
using test::slurp;
using ::testing::HasSubstr;

const fs::path kData = LIMN_TEST_DATA;
const std::string kModels = LIMN_SHARED_MODELS;
const std::string kBunny = kModels + "/tri/stanford-bunny.obj";
const std::string kSpot = kModels + "/tri/spot.obj";

class PaintCli : public test::CliTest {};

// The world-space form scripts depend on, exactly as the issue gives it: a stroke along the
// bunny's flank (points are vertices of the model), radius in model units.
const char* kBunnyStroke = R"({"strokes": [{"points": [[-0.0665, 0.101466, 0.041219],
  [-0.039509, 0.098682, 0.041774], [-0.015394, 0.099814, 0.044364], [0.020477, 0.098952, 0.046347]],
  "radius": 0.006, "color": [1, 0, 0, 1], "opacity": 1.0, "hardness": 1.0, "space": "world"}]})";

double distance_to_polyline(const float* p, const std::vector<std::array<double, 3>>& line) {
  double best = INFINITY;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    double ab[3], ap[3], l2 = 0, t = 0;
    for (int k = 0; k < 3; ++k) {
      ab[k] = line[i + 1][size_t(k)] - line[i][size_t(k)], ap[k] = p[k] - line[i][size_t(k)];
      l2 += ab[k] * ab[k], t += ab[k] * ap[k];
    }
    t = std::clamp(t / l2, 0.0, 1.0);
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += (ap[k] - t * ab[k]) * (ap[k] - t * ab[k]);
    best = std::min(best, std::sqrt(d2));
  }
  return best;
}

TEST_F(PaintCli, AScriptedStrokeOnTheBunnyBakesToAColouredMesh) {
  const fs::path strokes = write("stroke.json", kBunnyStroke), tex = dir_ / "bunny.lot";
  test::CliResult r =
      limn("paint " + q(kBunny) + " --strokes " + q(strokes) + " -o " + q(tex) + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["dabs"].get<int>(), 20);
  EXPECT_EQ(j["dabs_missed"].get<int>(), 0);
  EXPECT_GT(j["samples_changed"].get<int>(), 1000);
  EXPECT_EQ(j["texture"]["max_depth"].get<int>(), 10);

  r = limn("paint --stats " + q(tex) + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json st = nlohmann::json::parse(r.out);
  for (const char* k : {"nodes", "leaves", "bytes", "bytes_per_painted_texel", "max_depth"})
    EXPECT_TRUE(st.contains(k)) << k;
  EXPECT_EQ(st["max_depth"].get<int>(), 10);
  // The file: a 96-byte header, the pool, 8 bytes per free block (no material channels).
  EXPECT_TRUE(st["rmh"].is_null());
  EXPECT_EQ(st["bytes"].get<size_t>() + 8 * st["free_blocks"].get<size_t>() + 96,
            fs::file_size(tex));
  EXPECT_GT(st["bytes_per_painted_texel"].get<double>(), 0.0);

  const fs::path ply = dir_ / "bunny.ply", glb = dir_ / "bunny.glb";
  ASSERT_EQ(limn("bake " + q(tex) + " " + q(kBunny) + " -o " + q(ply)).code, 0);
  r = limn("bake " + q(tex) + " " + q(kBunny) + " -o " + q(glb) + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_GT(nlohmann::json::parse(r.out)["painted_vertices"].get<int>(), 50);

  // The PLY's colours are the lookups at the vertices, red along the stroke and nowhere else.
  const Mesh bunny = read_mesh(kBunny);
  const Mesh baked = read_mesh(ply);
  ASSERT_EQ(baked.colors.size(), 4 * bunny.vertex_count());
  const OctreeTexture t = load_lot(tex).color;
  const std::vector<float> normals = vertex_normals(bunny);
  const std::vector<std::array<double, 3>> line = {{-0.0665, 0.101466, 0.041219},
                                                   {-0.039509, 0.098682, 0.041774},
                                                   {-0.015394, 0.099814, 0.044364},
                                                   {0.020477, 0.098952, 0.046347}};
  const double leaf = t.size() / 1024.0;
  size_t red = 0;
  for (size_t v = 0; v < bunny.vertex_count(); ++v) {
    float want[4];
    if (!lookup_filtered(t, &bunny.positions[3 * v], &normals[3 * v], 0.0f, want))
      rgba8_to_float(t.background(), want);
    for (int k = 0; k < 4; ++k)
      ASSERT_NEAR(baked.colors[4 * v + size_t(k)], want[k], 0.5f / 255.0f) << v;
    if (baked.colors[4 * v + 3] > 0) {
      EXPECT_LT(distance_to_polyline(&bunny.positions[3 * v], line), 0.006 * 1.5 + 2 * leaf) << v;
      red += baked.colors[4 * v] == 1.0f && baked.colors[4 * v + 3] == 1.0f;
    }
  }
  EXPECT_GT(red, 30u);

  // The GLB opens and carries the colours.
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, glb.string())) << err;
  ASSERT_EQ(model.meshes.size(), 1u);
  EXPECT_TRUE(model.meshes[0].primitives[0].attributes.count("COLOR_0"));
}

TEST_F(PaintCli, ScreenStrokesUndoPickAndAPngBake) {
  const std::string script = R"({
    "camera": {"eye": [0, 0.3, 2.5], "target": [0, 0.3, 0], "up": [0, 1, 0], "fovy": 40,
               "width": 640, "height": 480},
    "strokes": [
      {"type": "stroke", "space": "screen", "points": [[300, 200], [340, 220]], "radius": 20,
       "color": [1, 0, 0, 1], "hardness": 1, "depth": 9},
      {"type": "stroke", "space": "screen", "points": [[320, 210]], "radius": 10,
       "color": [0, 0, 1, 1], "hardness": 1, "depth": 9, "blend": "mix"},
      {"type": "undo"},
      {"type": "pick", "pixel": [320, 210]},
      {"type": "fill", "color": [1, 1, 1, 1], "opacity": 0.0}
    ]})";
  const fs::path strokes = write("screen.json", script), tex = dir_ / "spot.lot";
  test::CliResult r = limn("paint " + q(kSpot) + " --strokes " + q(strokes) + " -o " + q(tex) +
                           " --background 1,1,1,1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["undos"].get<int>(), 1);
  ASSERT_EQ(j["picks"].size(), 1u);
  EXPECT_TRUE(j["picks"][0]["found"].get<bool>());
  EXPECT_EQ(j["picks"][0]["rgba"], nlohmann::json({1.0, 0.0, 0.0, 1.0}));  // blue was undone
  const fs::path png = dir_ / "spot.png";
  r = limn("bake " + q(tex) + " " + q(kSpot) + " -o " + q(png) + " --size 256 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json b = nlohmann::json::parse(r.out);
  EXPECT_EQ(b["image"]["width"].get<int>(), 256);
  EXPECT_GT(b["image"]["opaque_texels"].get<int>(), 256 * 256 / 4);
  EXPECT_EQ(slurp(png).substr(1, 3), "PNG");
}

TEST_F(PaintCli, ThreadsCapLeavesTheTextureAsItIs) {
  // A dab's cells are painted on several threads; --threads 1 must write the same bytes.
  const fs::path mesh = dir_ / "torus.obj";
  ASSERT_EQ(limn("shape torus -o " + q(mesh)).code, 0);
  const fs::path strokes = write("s.json", R"({"strokes": [{"points": [[1.0, 0.0, 0.3],
    [0.7, 0.7, 0.3], [0.0, 1.0, 0.3]], "radius": 0.15, "color": [1, 0, 0, 1], "opacity": 1.0,
    "hardness": 0.5, "space": "world"}]})");
  std::string bytes[3];
  const char* caps[3] = {"--threads 1 ", "--threads 4 ", ""};
  for (int i = 0; i < 3; ++i) {
    const fs::path tex = dir_ / ("t" + std::to_string(i) + ".lot");
    const test::CliResult r = limn(std::string(caps[i]) + "paint " + q(mesh) + " --strokes " +
                                   q(strokes) + " -o " + q(tex) + " --depth 9 --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_GT(j["samples_changed"].get<int>(), 10000);
    EXPECT_GT(j["threads"]["task_cells"].get<int>(), 0);
    if (i == 0) {
      EXPECT_EQ(j["threads"]["max"].get<int>(), 1);
      EXPECT_EQ(j["threads"]["task_cells_threaded"].get<int>(), 0);
    }
    bytes[i] = slurp(tex);
  }
  EXPECT_EQ(bytes[0], bytes[1]);
  EXPECT_EQ(bytes[0], bytes[2]);
  const test::CliResult bad = limn("--threads 0 paint " + q(mesh) + " --strokes " + q(strokes) +
                                   " -o " + q(dir_ / "bad.lot"));
  EXPECT_EQ(bad.code, 2);
  EXPECT_THAT(bad.err, HasSubstr("--threads"));
  EXPECT_FALSE(fs::exists(dir_ / "bad.lot"));
}

TEST_F(PaintCli, BadStrokeScriptsExitTwoAndLeaveThePreviousOutput) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"not json", "{\"strokes\": [}"},
      {"nan", R"({"strokes": [{"points": [[0,0,0]], "radius": NaN, "color": [1,0,0,1]}]})"},
      {"top array", "[1, 2]"},
      {"no strokes", R"({"camera": 1})"},
      {"unknown key", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "colour": [1,0,0]}]})"},
      {"no radius", R"({"strokes": [{"points": [[0,0,0]], "color": [1,0,0,1]}]})"},
      {"negative radius", R"({"strokes": [{"points": [[0,0,0]], "radius": -1}]})"},
      {"radius string", R"({"strokes": [{"points": [[0,0,0]], "radius": "nan"}]})"},
      {"huge radius", R"({"strokes": [{"points": [[0,0,0]], "radius": 1e300}]})"},
      {"colour range", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "color": [2,0,0]}]})"},
      {"colour size", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "color": [1,0]}]})"},
      {"opacity", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "opacity": 1.5}]})"},
      {"hardness", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "hardness": -0.1}]})"},
      {"space", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "space": "moon"}]})"},
      {"no points", R"({"strokes": [{"points": [], "radius": 1}]})"},
      {"2d point", R"({"strokes": [{"points": [[0,0]], "radius": 1}]})"},
      {"text point", R"({"strokes": [{"points": [[0,"a",0]], "radius": 1}]})"},
      {"blend", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "blend": "burn"}]})"},
      {"depth", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "depth": 17}]})"},
      {"fractional depth", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "depth": 9.5}]})"},
      {"screen no camera", R"({"strokes": [{"points": [[1,2]], "radius": 1, "space": "screen"}]})"},
      {"type", R"({"strokes": [{"type": "zap"}]})"},
      {"dabs", R"({"strokes": [{"points": [[0,0,0],[1e6,0,0]], "radius": 1e-4}]})"},
      {"camera", R"({"camera": {"eye": [0,0,0], "target": [0,0,0], "fovy": 40, "width": 10,
                    "height": 10}, "strokes": []})"},
      {"pick both", R"({"strokes": [{"type": "pick", "point": [0,0,0], "pixel": [1,1]}]})"},
      {"spacing", R"({"strokes": [{"points": [[0,0,0]], "radius": 1, "spacing": 0}]})"},
  };
  const fs::path out = dir_ / "out.lot";
  for (const auto& [what, text] : bad) {
    SCOPED_TRACE(what);
    const fs::path s = write("bad.json", text);
    test::CliResult r = limn("paint " + q(kSpot) + " --strokes " + q(s) + " -o " + q(out));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_THAT(r.err, HasSubstr("bad.json"));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(files(), std::vector<std::string>{"bad.json"});
  }
  // The previous texture survives a failed run.
  write("out.lot", "precious");
  const fs::path s = write("bad.json", bad[0].second);
  EXPECT_EQ(limn("paint " + q(kSpot) + " --strokes " + q(s) + " -o " + q(out)).code, 2);
  EXPECT_EQ(slurp(out), "precious");
}

TEST_F(PaintCli, BadTexturesMeshesAndUsageExitTwo) {
  const fs::path strokes = write("s.json", R"({"strokes": []})");
  const fs::path good = dir_ / "good.lot";
  ASSERT_EQ(limn("paint " + q(kSpot) + " --strokes " + q(strokes) + " -o " + q(good)).code, 0);
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(kData / "bad")) {
    if (e.path().extension() != ".lot") continue;
    SCOPED_TRACE(e.path().string());
    const fs::path out = dir_ / "out.ply";
    test::CliResult r = limn("bake " + q(e.path()) + " " + q(kSpot) + " -o " + q(out));
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.err, HasSubstr(e.path().filename().string()));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out));
    r = limn("paint --stats " + q(e.path()));
    EXPECT_EQ(r.code, 2);
    r = limn("paint " + q(kSpot) + " --strokes " + q(strokes) + " --texture " + q(e.path()) +
             " -o " + q(dir_ / "x.lot"));
    EXPECT_EQ(r.code, 2);
    EXPECT_FALSE(fs::exists(dir_ / "x.lot"));
    ++n;
  }
  EXPECT_GE(n, 10u);
  const Mesh cube_mesh = read_mesh(kData / "nonmanifold.obj");
  // A PNG needs uvs; the bunny has none.
  test::CliResult r = limn("bake " + q(good) + " " + q(kBunny) + " -o " + q(dir_ / "b.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("texture coordinates"));
  EXPECT_FALSE(fs::exists(dir_ / "b.png"));
  EXPECT_EQ(limn("bake " + q(good) + " " + q(kSpot) + " -o " + q(dir_ / "b.xyz")).code, 2);
  EXPECT_EQ(
      limn("bake " + q(good) + " " + q(kSpot) + " -o " + q(dir_ / "b.png") + " --size 0").code, 2);
  EXPECT_EQ(
      limn("bake " + q(good) + " " + q(kData / "bad" / "bad_nan.obj") + " -o " + q(dir_ / "b.ply"))
          .code,
      2);
  EXPECT_EQ(
      limn("paint " + q(kSpot) + " --strokes " + q(strokes) + " -o " + q(dir_ / "t.png")).code, 2);
  EXPECT_EQ(limn("paint " + q(kSpot) + " -o " + q(dir_ / "t.lot")).code, 2);
  EXPECT_EQ(limn("paint " + q(kSpot) + " --strokes " + q(strokes) + " -o " + q(dir_ / "t.lot") +
                 " --depth 20")
                .code,
            2);
  EXPECT_EQ(
      limn("paint " + q(kSpot) + " --strokes " + q(strokes) + " -o " + q(dir_ / "no" / "t.lot"))
          .code,
      2);
  EXPECT_EQ(limn("paint " + q(kSpot) + " --strokes " + q(dir_ / "missing.json") + " -o " +
                 q(dir_ / "t.lot"))
                .code,
            2);
  EXPECT_EQ(limn("paint --stats " + q(good) + " " + q(kSpot)).code, 2);
  EXPECT_EQ(limn("paint " + q(kSpot) + " --strokes " + q(strokes) + " -o " + q(dir_ / "t.lot") +
                 " --background 2,0,0")
                .code,
            2);
  EXPECT_EQ(files(), (std::vector<std::string>{"good.lot", "s.json"}));
  EXPECT_EQ(limn("paint --help").code, 0);
  EXPECT_EQ(limn("bake --help").code, 0);
}

}  // namespace
}  // namespace limn
