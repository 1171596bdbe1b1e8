// `limn repair` and the --repair option of simplify, subdivide, paint and bake, run as a user
// would: counts in --json and one line on stderr, refusals that suggest --repair without it, and
// bad input that exits 2 with one line and leaves no file behind.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/topology.hpp"

namespace limn {
namespace {

using test::CliTest;
using ::testing::HasSubstr;

// A cube as a soup: 12 triangles, each with its own three vertices, 5 of them reversed, one
// duplicated and one degenerate (a repeated vertex).
std::string cube_soup_obj() {
  const float p[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                         {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const int tris[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                           {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::string s, f;
  int n = 0;
  for (int t = 0; t < 12; ++t) {
    for (int k = 0; k < 3; ++k) {
      const float* q = p[tris[t][k]];
      s += "v " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) +
           "\n";
    }
    if (t % 2 == 0 && t < 10)
      f += "f " + std::to_string(n + 1) + " " + std::to_string(n + 3) + " " + std::to_string(n + 2);
    else
      f += "f " + std::to_string(n + 1) + " " + std::to_string(n + 2) + " " + std::to_string(n + 3);
    f += "\n";
    n += 3;
  }
  f += "f 1 2 3\n";  // a duplicate of the first triangle
  f += "f 4 5 4\n";  // repeats a vertex
  return s + f;
}

void expect_one_line_error(const test::CliResult& r, const std::string& fragment) {
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr(fragment));
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

class RepairCli : public CliTest {};

TEST_F(RepairCli, RepairsASoupAndReportsEveryChange) {
  const auto in = write("soup.obj", cube_soup_obj());
  const auto r = limn("repair " + q(in) + " -o " + q(dir() / "clean.obj") + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["input_faces"], 14);
  EXPECT_EQ(j["faces"], 12);
  EXPECT_EQ(j["vertices"], 8);
  const auto& c = j["repair"];
  EXPECT_EQ(c["welded_vertices"], 36 - 8);
  EXPECT_EQ(c["duplicate_faces"], 1);
  EXPECT_EQ(c["degenerate_faces"], 1);
  EXPECT_EQ(c["flipped_faces"], 5);
  EXPECT_EQ(c["closed_components"], 1);
  // One line on stderr with the same counts.
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("28 vertices welded"));
  EXPECT_THAT(r.err, HasSubstr("5 faces flipped"));
  // The output is clean by limn's own analysis, and strict reading accepts it.
  const Mesh out = read_mesh(dir() / "clean.obj");
  const MeshStats s = analyze(out, build_topology(out));
  EXPECT_EQ(s.inconsistent_edges + s.non_manifold_edges + s.non_manifold_vertices, 0u);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.genus, 0);
}

TEST_F(RepairCli, CommandsRefuseWithAHintAndRepairWhenAsked) {
  const auto in = write("soup.obj", cube_soup_obj());
  const auto out = dir() / "out.obj";
  // Strict reading refuses the repeated vertex, and says what fixes it.
  for (const std::string cmd : {"simplify --proxies 4", "subdivide --uniform 1"}) {
    SCOPED_TRACE(cmd);
    const auto r = limn(cmd + " " + q(in) + " -o " + q(out));
    expect_one_line_error(r, "repeats vertex");
    EXPECT_THAT(r.err, HasSubstr("--repair"));
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  // A soup without repeated vertices but disagreeing faces: simplify refuses that too.
  std::string flipped = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\n";
  flipped += "f 1 2 5\nf 2 3 5\nf 5 3 4\nf 4 1 5\nf 1 4 3\nf 1 2 3\n";  // the last reversed
  const auto pyramid = write("pyramid.obj", flipped);
  expect_one_line_error(limn("simplify --proxies 2 " + q(pyramid) + " -o " + q(out)),
                        "rerun with --repair");
  const auto r = limn("simplify --proxies 2 --repair --json " + q(pyramid) + " -o " + q(out));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["repair"]["flipped_faces"], 1);
  EXPECT_THAT(r.err, HasSubstr("1 face flipped"));
  // Without --repair the JSON says so with null.
  const auto ok =
      limn("simplify --proxies 2 --json " + q(dir() / "out.obj") + " -o " + q(dir() / "again.obj"));
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_TRUE(nlohmann::json::parse(ok.out)["repair"].is_null());

  for (const std::string cmd : {"simplify --proxies 4", "subdivide --uniform 1"}) {
    SCOPED_TRACE(cmd);
    const auto rr = limn(cmd + " --repair --json " + q(in) + " -o " + q(out));
    ASSERT_EQ(rr.code, 0) << rr.err;
    const auto j = nlohmann::json::parse(rr.out);
    EXPECT_EQ(j["repair"]["degenerate_faces"], 1);
    EXPECT_EQ(j["repair"]["flipped_faces"], 5);
  }
  const auto strokes = write("s.json", R"({"strokes": [{"points": [[0.5, 0.5, 1.0]],
      "radius": 0.2, "color": [1, 0, 0, 1], "space": "world"}]})");
  const auto lot = dir() / "t.lot";
  const auto p =
      limn("paint --repair --json " + q(in) + " --strokes " + q(strokes) + " -o " + q(lot));
  ASSERT_EQ(p.code, 0) << p.err;
  EXPECT_EQ(nlohmann::json::parse(p.out)["repair"]["welded_vertices"], 28);
  const auto b = limn("bake --repair " + q(lot) + " " + q(in) + " -o " + q(dir() / "baked.ply"));
  EXPECT_EQ(b.code, 0) << b.err;
}

TEST_F(RepairCli, BadInputExitsTwoWithOneLineAndNoFile) {
  const auto out = dir() / "out.obj";
  const std::pair<std::string, std::string> cases[] = {
      {"nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"},
      {"empty.obj", ""},
      {"nofaces.obj", "v 0 0 0\nv 1 0 0\n"},
      {"hostile.off", "OFF\n3 1000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"allbad.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n"},
      {"short.stl", std::string("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n")},
  };
  for (const auto& [name, text] : cases) {
    SCOPED_TRACE(name);
    const auto in = write(name, text);
    const auto r = limn("repair " + q(in) + " -o " + q(out));
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_THAT(r.err, HasSubstr(name));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
  const auto in = write("ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(limn("repair " + q(in) + " -o " + q(out) + " --weld-tolerance 0.5").code, 2);
  EXPECT_EQ(limn("repair " + q(in) + " -o " + q(dir() / "out.xyz")).code, 2);
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace limn
