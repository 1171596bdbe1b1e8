// limn simplify as scripts see it: outputs, labels and the JSON report, bad input and bad usage
// (exit 2, one line naming the problem, nothing written, an old output left untouched).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "cli_runner.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/simplify/validate.hpp"
#include "simplify_oracle.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
using test::slurp;
using ::testing::HasSubstr;
using ::testing::Not;

const fs::path kModels = LIMN_SHARED_MODELS;
const fs::path kData = LIMN_TEST_DATA;

class SimplifyCli : public test::CliTest {};

TEST_F(SimplifyCli, WritesAValidMeshTheLabelsAndAReport) {
  const fs::path in = kModels / "tri" / "spot.obj", out = dir_ / "spot.obj",
                 labels = dir_ / "labels.txt";
  const test::CliResult r = limn("simplify " + q(in) + " -o " + q(out) + " --proxies 30 --labels " +
                                 q(labels) + " --json --distance=20000");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const Mesh input = read_mesh(in), output = read_mesh(out);
  EXPECT_EQ(j["clusters"], 30);
  EXPECT_EQ(j["output_faces"], output.face_count());
  EXPECT_EQ(j["output_vertices"], output.vertex_count());
  EXPECT_EQ(j["input_faces"], input.face_count());
  const SimplifiedCheck check = validate_simplified(output, bounding_box(input));
  EXPECT_TRUE(check.ok()) << check.first_problem;
  // One label per input face, in file order; the report's energy is the labels' energy.
  std::istringstream lines(slurp(labels));
  std::vector<uint32_t> l;
  for (std::string line; std::getline(lines, line);) l.push_back(uint32_t(std::stoul(line)));
  ASSERT_EQ(l.size(), input.face_count());
  EXPECT_EQ(std::set<uint32_t>(l.begin(), l.end()).size(), 30u);
  EXPECT_EQ(*std::max_element(l.begin(), l.end()), 29u);
  const double e = test::energy_from_sums(input, l);
  EXPECT_NEAR(j["energy"].get<double>(), e, 1e-6 * e);
  EXPECT_NEAR(j["energy_per_area"].get<double>(), e / j["surface_area"].get<double>(), 1e-9);
  EXPECT_EQ(test::disconnected_clusters(test::face_neighbours(input), l), 0u);
  const auto& d = j["distance"];
  EXPECT_GT(d["hausdorff"].get<double>(), 0);
  EXPECT_LT(d["hausdorff"].get<double>(), 0.5);
  EXPECT_LE(d["rms"].get<double>(), d["hausdorff"].get<double>());
  EXPECT_EQ(d["samples"], 20000);
  for (const char* phase : {"seeding", "optimisation", "meshing", "distance", "total"})
    EXPECT_TRUE(j["timings_ms"][phase].is_number()) << phase;
  EXPECT_EQ(j["valid"], true);
  EXPECT_EQ(files(), (std::vector<std::string>{"labels.txt", "spot.obj"}));
}

TEST_F(SimplifyCli, PolygonsLloydRandomSeedingAndATargetError) {
  const fs::path in = kModels / "tri" / "fandisk.obj";
  test::CliResult r =
      limn("simplify " + q(in) + " -o " + q(dir_ / "p.ply") + " --proxies 20 --polygons --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const Mesh poly = read_mesh(dir_ / "p.ply");
  size_t big = 0;
  for (size_t f = 0; f < poly.face_count(); ++f) big += poly.face_size(f) > 3;
  EXPECT_GT(big, 10u);
  EXPECT_EQ(nlohmann::json::parse(r.out)["output_polygons"], big);
  r = limn("simplify " + q(in) + " -o " + q(dir_ / "l.off") +
           " --proxies 20 --method lloyd --seeding random --iterations 5 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["method"], "lloyd");
  EXPECT_EQ(j["seeding"], "random");
  EXPECT_LE(j["lloyd_iterations"].get<int>(), 5);
  r = limn("simplify " + q(in) + " -o " + q(dir_ / "t.obj") + " --target-error 0.01 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_LE(j["energy_per_area"].get<double>(), 0.01);
  EXPECT_TRUE(j["distance"].is_null());  // measured only with --distance
  EXPECT_TRUE(j["timings_ms"]["distance"].is_null());
  // Text mode: one line.
  r = limn("simplify " + q(in) + " -o " + q(dir_ / "x.glb") + " --proxies 10");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1);
  EXPECT_THAT(r.out, HasSubstr("10 clusters"));
  EXPECT_THAT(r.out, Not(HasSubstr("Hausdorff")));
  r = limn("simplify " + q(in) + " -o " + q(dir_ / "x.glb") + " --proxies 10 --distance=1000");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("Hausdorff"));
}

TEST_F(SimplifyCli, BadInputExitsTwoAndWritesNothing) {
  const fs::path out = dir_ / "out.obj";
  for (const fs::path& bad : {kData / "nonmanifold.obj", kData / "bad" / "bad_nan.obj",
                              kData / "bad" / "bad_index_past_end.off"}) {
    SCOPED_TRACE(bad.string());
    const test::CliResult r = limn("simplify " + q(bad) + " -o " + q(out) + " --proxies 5");
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.err, HasSubstr(bad.filename().string()));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(files(), std::vector<std::string>{});
  }
  EXPECT_THAT(limn("simplify " + q(kData / "nonmanifold.obj") + " -o " + q(out)).err,
              HasSubstr("non-manifold edge"));
  // A failure leaves an existing output alone.
  { std::ofstream(out) << "precious"; }
  EXPECT_EQ(limn("simplify " + q(kData / "nonmanifold.obj") + " -o " + q(out)).code, 2);
  EXPECT_EQ(slurp(out), "precious");
  EXPECT_EQ(files(), std::vector<std::string>{"out.obj"});
}

TEST_F(SimplifyCli, BadUsageExitsTwo) {
  const std::string in = q(kModels / "tri" / "spot.obj"), out = q(dir_ / "o.obj");
  for (const std::string& args :
       {"simplify " + in, "simplify " + in + " -o " + q(dir_ / "o.xyz"),
        "simplify " + in + " -o " + out + " --method annealing",
        "simplify " + in + " -o " + out + " --seeding psychic",
        "simplify " + in + " -o " + out + " --proxies 0",
        "simplify " + in + " -o " + out + " --target-error -1",
        "simplify " + in + " -o " + out + " --split-threshold -0.5",
        "simplify " + in + " -o " + out + " --distance=0",
        "simplify " + in + " -o " + out + " --distance=many",
        "simplify " + in + " -o " + q(dir_ / "no" / "such" / "o.obj"),
        "simplify " + in + " -o " + out + " --labels " + q(dir_ / "no" / "labels.txt")}) {
    SCOPED_TRACE(args);
    const test::CliResult r = limn(args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(files(), std::vector<std::string>{});
  }
}

TEST_F(SimplifyCli, HelpNamesEveryOption) {
  const test::CliResult r = limn("simplify --help");
  ASSERT_EQ(r.code, 0);
  for (const char* opt :
       {"--proxies", "--method", "--seeding", "--labels", "--polygons", "--json", "--target-error",
        "--split-threshold", "--teleports", "--no-fill", "--distance"})
    EXPECT_THAT(r.out, HasSubstr(opt)) << opt;
}

}  // namespace
}  // namespace limn
