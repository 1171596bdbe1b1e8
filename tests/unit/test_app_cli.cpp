// The limn executable as scripts see it: exit codes, one-line errors, no partial output files.
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
#include "limn/mesh/topology.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/refine.hpp"
#include "limn/subdiv/tessellate.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
using test::slurp;
using ::testing::HasSubstr;

class Cli : public test::CliTest {};

const fs::path kData = LIMN_TEST_DATA;

TEST_F(Cli, VersionAndHelp) {
  test::CliResult r = limn("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_THAT(r.out, HasSubstr("limn 0."));
  EXPECT_EQ(limn("--help").code, 0);
  for (const char* sub : {"info", "convert", "shape", "subdivide", "demo"}) {
    r = limn(std::string(sub) + " --help");
    EXPECT_EQ(r.code, 0) << sub;
    EXPECT_THAT(r.out, HasSubstr("Usage")) << sub;
  }
}

TEST_F(Cli, BadUsageExitsTwo) {
  EXPECT_EQ(limn("").code, 2);
  EXPECT_EQ(limn("frobnicate").code, 2);
  EXPECT_EQ(limn("info").code, 2);
  EXPECT_EQ(limn("info --no-such-flag x.obj").code, 2);
  EXPECT_EQ(limn("convert only-one-arg.obj").code, 2);
  EXPECT_EQ(limn("shape no-such-shape -o " + q(dir_ / "x.obj")).code, 2);
}

TEST_F(Cli, EveryBadFileExitsTwoWithOneLineNamingIt) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(kData / "bad")) {
    SCOPED_TRACE(e.path().string());
    const test::CliResult r = limn("info " + q(e.path()));
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.err, HasSubstr(e.path().filename().string()));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty());
    ++n;
  }
  EXPECT_GE(n, 12u);
}

TEST_F(Cli, FailedConvertLeavesNoFileAndKeepsTheOldOne) {
  const fs::path out = dir_ / "out.obj";
  for (const auto& e : fs::directory_iterator(kData / "bad")) {
    SCOPED_TRACE(e.path().string());
    EXPECT_EQ(limn("convert " + q(e.path()) + " " + q(out)).code, 2);
    EXPECT_EQ(files(), std::vector<std::string>{});
  }
  { std::ofstream(out) << "precious"; }
  EXPECT_EQ(limn("convert " + q(kData / "bad" / "bad_nan.obj") + " " + q(out)).code, 2);
  EXPECT_EQ(slurp(out), "precious");
  EXPECT_EQ(files(), std::vector<std::string>{"out.obj"});
}

TEST_F(Cli, DirectoryAndMissingPaths) {
  test::CliResult r = limn("info " + q(dir_));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("directory"));
  r = limn("info " + q(dir_ / "does-not-exist.obj"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("does-not-exist.obj"));
  r = limn("info " + q(kData / "nonmanifold.obj" / "below-a-file.obj"));
  EXPECT_EQ(r.code, 2);
  // Writing into a folder that does not exist is an error, and nothing is created.
  r = limn("convert " + q(kData / "nonmanifold.obj") + " " + q(dir_ / "no" / "such" / "x.ply"));
  EXPECT_NE(r.code, 0);
  EXPECT_FALSE(fs::exists(dir_ / "no"));
}

TEST_F(Cli, UnknownOutputExtensionIsBadUsage) {
  for (const char* name : {"x.xyz", "x.gltf"}) {
    const test::CliResult r =
        limn("convert " + q(kData / "nonmanifold.obj") + " " + q(dir_ / name));
    EXPECT_EQ(r.code, 2) << name;
    EXPECT_THAT(r.err, HasSubstr(name));
    EXPECT_EQ(files(), std::vector<std::string>{});
  }
}

TEST_F(Cli, NonManifoldIsReportedNotRejected) {
  const test::CliResult r = limn("info --json " + q(kData / "nonmanifold.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["non_manifold_edges"], 1);
  EXPECT_EQ(j["non_manifold_vertices"], 2);  // the two ends of the shared edge (one also a bowtie)
  EXPECT_EQ(j["manifold"], false);
  EXPECT_TRUE(j["genus"].is_null());
  EXPECT_EQ(j["faces"], 4);
}

TEST_F(Cli, BomAndMixedLineEndings) {
  const test::CliResult r = limn("info --json " + q(kData / "bom_mixed_endings.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["vertices"], 4);
  EXPECT_EQ(j["faces_by_arity"]["4"], 1);
  EXPECT_EQ(j["boundary_loops"], 1);
}

TEST_F(Cli, InfoTextAndJsonAgree) {
  const fs::path cube = dir_ / "cube.obj";
  ASSERT_EQ(limn("shape cube -o " + q(cube)).code, 0);
  const test::CliResult text = limn("info " + q(cube));
  ASSERT_EQ(text.code, 0);
  EXPECT_THAT(text.out, HasSubstr("genus           0"));
  const auto j = nlohmann::json::parse(limn("info --json " + q(cube)).out);
  EXPECT_EQ(j["vertices"], 8);
  EXPECT_EQ(j["edges"], 12);
  EXPECT_EQ(j["extraordinary_vertices"], 8);
  EXPECT_EQ(j["valence_histogram"]["3"], 8);
  EXPECT_EQ(j["closed"], true);
  EXPECT_TRUE(j.contains("timings_ms"));
}

TEST_F(Cli, ConvertChainKeepsTheMesh) {
  const fs::path a = dir_ / "t.obj", b = dir_ / "t.ply", c = dir_ / "t.off", d = dir_ / "t2.obj";
  ASSERT_EQ(limn("shape torus -o " + q(a)).code, 0);
  ASSERT_EQ(limn("convert " + q(a) + " " + q(b)).code, 0);
  ASSERT_EQ(limn("convert " + q(b) + " " + q(c)).code, 0);
  ASSERT_EQ(limn("convert " + q(c) + " " + q(d)).code, 0);
  const Mesh m0 = read_mesh(a), m3 = read_mesh(d);
  EXPECT_EQ(m0.positions, m3.positions);
  EXPECT_EQ(m0.face_offsets, m3.face_offsets);
  EXPECT_EQ(m0.face_vertices, m3.face_vertices);
  // --from/--to override extensions.
  const fs::path odd = dir_ / "mesh.data";
  ASSERT_EQ(limn("convert --to ply " + q(a) + " " + q(odd)).code, 0);
  EXPECT_EQ(limn("info --format ply " + q(odd)).code, 0);
}

TEST_F(Cli, GlbOpensInAGltfLoader) {
  const fs::path cage = dir_ / "cage.obj", glb = dir_ / "cage.glb";
  ASSERT_EQ(limn("shape cage -o " + q(cage)).code, 0);
  ASSERT_EQ(limn("convert " + q(cage) + " " + q(glb)).code, 0);
  const Mesh m = read_mesh(cage);
  size_t tris = 0;
  for (size_t f = 0; f < m.face_count(); ++f) tris += m.face_size(f) - 2;

  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, glb.string())) << err;
  ASSERT_EQ(model.meshes.size(), 1u);
  const auto& prim = model.meshes[0].primitives[0];
  EXPECT_EQ(prim.mode, TINYGLTF_MODE_TRIANGLES);
  EXPECT_EQ(model.accessors[prim.indices].count, 3 * tris);
  ASSERT_TRUE(prim.attributes.count("NORMAL"));
  ASSERT_TRUE(prim.attributes.count("POSITION"));
  const auto& pa = model.accessors[prim.attributes.at("POSITION")];
  EXPECT_EQ(pa.count, m.vertex_count());  // no per-corner attributes: no splitting
}

TEST_F(Cli, ShapeListAndDemo) {
  const test::CliResult l = limn("shape --list");
  EXPECT_EQ(l.code, 0);
  for (const char* n : {"cube", "torus", "cage", "terrain", "torus-dense"})
    EXPECT_THAT(l.out, HasSubstr(n));
  const test::CliResult d = limn("demo --quick -o " + q(dir_ / "demo"));
  ASSERT_EQ(d.code, 0) << d.err;
  const std::string md = slurp(dir_ / "demo" / "report.md");
  EXPECT_THAT(md, HasSubstr("| torus |"));
  const auto j = nlohmann::json::parse(slurp(dir_ / "demo" / "report.json"));
  EXPECT_EQ(j["shapes"].size(), 5u);
  EXPECT_TRUE(fs::exists(dir_ / "demo" / "cage.glb"));
  // The workflow: adaptive surface at two cameras, paint, bake, simplify, each with its images.
  const auto& w = j["workflow"];
  for (const char* f : {"surface-far.png", "surface-near.png", "painted.png", "partition.png",
                        "simplified.png", "torus-painted.glb", "torus.lot", "torus-simplified.obj"})
    EXPECT_GT(fs::file_size(dir_ / "demo" / f), 100u) << f;
  // The near camera looks at the valence-8 vertex: deeper there than from afar.
  EXPECT_GT(w["surface"]["near"]["deepest_level"].get<int>(),
            w["surface"]["far"]["deepest_level"].get<int>());
  EXPECT_GT(w["paint"]["painted_texels"].get<int>(), 0);
  EXPECT_EQ(w["simplify"]["clusters"].get<int>(), 40);
  EXPECT_GE(w["simplify"]["polygons"].get<int>(), 40);
  // The baked mesh opens with a colour per vertex.
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn,
                                        (dir_ / "demo" / "torus-painted.glb").string()))
      << err;
  const auto& attrs = model.meshes.at(0).primitives.at(0).attributes;
  ASSERT_TRUE(attrs.count("COLOR_0"));
  EXPECT_EQ(model.accessors[attrs.at("COLOR_0")].count,
            model.accessors[attrs.at("POSITION")].count);
  // A file where the folder should be is bad usage.
  { std::ofstream(dir_ / "afile") << "x"; }
  EXPECT_EQ(limn("demo --quick -o " + q(dir_ / "afile")).code, 2);
}

TEST_F(Cli, SubdivideUniformAndLimit) {
  const fs::path cage = dir_ / "cage.obj", out = dir_ / "s.obj";
  ASSERT_EQ(limn("shape cage -o " + q(cage)).code, 0);
  const Mesh m = read_mesh(cage);
  const test::CliResult r =
      limn("subdivide " + q(cage) + " -o " + q(out) + " --uniform 2 --limit --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  // Level 1 has one quad per cage corner, level 2 four times as many; hole faces are dropped.
  EXPECT_EQ(j["levels"][1]["faces"], m.corner_count());
  EXPECT_EQ(j["levels"][2]["faces"], 4 * m.corner_count());
  const size_t hole_quads = 4 * m.face_size(m.hole_faces.at(0));
  const Mesh s = read_mesh(out);
  EXPECT_EQ(s.face_count(), 4 * m.corner_count() - hole_quads);
  ASSERT_EQ(s.normal_indices.size(), s.corner_count());
  for (size_t i = 0; i < s.normals.size(); i += 3) {
    const float l = std::sqrt(s.normals[i] * s.normals[i] + s.normals[i + 1] * s.normals[i + 1] +
                              s.normals[i + 2] * s.normals[i + 2]);
    ASSERT_NEAR(l, 1.0f, 1e-4f) << "normal " << i / 3;
  }
  EXPECT_FALSE(s.crease_sharpness.empty());  // the infinitely sharp rim survives as tags
  for (const char* bad : {"--uniform 9", "--uniform -1", ""}) {
    const test::CliResult b = limn("subdivide " + q(cage) + " -o " + q(dir_ / "x.obj") + " " + bad);
    EXPECT_EQ(b.code, 2) << bad;
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.obj"));
}

TEST_F(Cli, SubdivideLeanWritesTheLastLevel) {
  const fs::path cage = dir_ / "cage.obj", out = dir_ / "lean.ply";
  ASSERT_EQ(limn("shape cage -o " + q(cage)).code, 0);
  const Mesh m = read_mesh(cage);
  const test::CliResult r = limn("subdivide " + q(cage) + " -o " + q(out) + " --uniform 3 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["levels"].size(), 4u);
  EXPECT_EQ(j["levels"][3]["faces"], 16 * m.corner_count());
  EXPECT_TRUE(j["timings_ms"].contains("stencils_and_apply"));
  EXPECT_TRUE(j["timings_ms"].contains("topology"));
  // The written points are the uniform refinement's (PLY keeps floats exactly).
  const Mesh s = read_mesh(out);
  const UniformRefinement ur = refine_uniform(m, 3, subdiv_options(m));
  EXPECT_EQ(s.positions, ur.positions(m, 3));
  EXPECT_EQ(j["output_faces"], s.face_count());
}

TEST_F(Cli, SubdivideAdaptiveWritesAWatertightLimitSurface) {
  const fs::path cage = dir_ / "torus.obj", out = dir_ / "a.ply";
  ASSERT_EQ(limn("shape torus -o " + q(cage)).code, 0);
  const Mesh m = read_mesh(cage);
  const test::CliResult r =
      limn("subdivide " + q(cage) + " -o " + q(out) + " --adaptive --depth 2 --tess 3 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  PatchOptions po;
  po.subdiv = subdiv_options(m);
  po.depth = 2;
  const PatchTable t = build_patches(m, po);
  EXPECT_EQ(j["patches"]["total"], t.patch_count());
  EXPECT_EQ(j["patches"]["regular"], t.regular_params.size());
  EXPECT_EQ(j["patches"]["gregory"], t.gregory_params.size());
  size_t by_level = 0;
  for (const auto& l : j["patches"]["by_level"])
    by_level += size_t(l["regular"]) + size_t(l["gregory"]);
  EXPECT_EQ(by_level, t.patch_count());
  const Mesh s = read_mesh(out);
  EXPECT_EQ(j["output_faces"], s.face_count());
  const MeshStats st = analyze(s, build_topology(s));
  EXPECT_EQ(st.boundary_edges, 0u);  // the torus is closed, so its tessellation must be
  EXPECT_EQ(st.non_manifold_edges, 0u);
  EXPECT_TRUE(j["timings_ms"].contains("tessellate"));
  EXPECT_TRUE(j["vertex_depth_histogram"].contains("2"));
}

TEST_F(Cli, SubdivideAdaptiveToleranceFollowsTheCamera) {
  const fs::path cage = dir_ / "torus.obj";
  ASSERT_EQ(limn("shape torus -o " + q(cage)).code, 0);
  auto patches = [&](const std::string& camera) {
    const test::CliResult r =
        limn("subdivide " + q(cage) + " -o " + q(dir_ / "d.ply") +
             " --adaptive --tolerance 1 --resolution 640x480 --depth-colors --json" + " --camera " +
             camera);
    EXPECT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_LE(double(j["estimated_max_error_px"]), 1.0);
    return size_t(j["patches"]["total"]);
  };
  const size_t near = patches("0,2,2.5,0,0,0,45"), far = patches("0,8,10,0,0,0,45");
  EXPECT_GT(near, far);
  // Both error sources give a watertight surface within the tolerance they estimate.
  for (const char* errors : {"measured", "estimated"}) {
    const test::CliResult r =
        limn("subdivide " + q(cage) + " -o " + q(dir_ / "e.ply") +
             " --adaptive --tolerance 1 --json --camera 0,2,2.5,0,0,0,45 --errors " + errors);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["errors"], errors);
    EXPECT_LE(double(j["estimated_max_error_px"]), 1.0);
    const Mesh m = read_mesh(dir_ / "e.ply");
    EXPECT_EQ(analyze(m, build_topology(m)).boundary_edges, 0u) << errors;
    EXPECT_EQ(j["output_faces"], m.face_count());
  }
  // Screen-space tessellation: a closer camera gives more triangles, and stays watertight.
  auto triangles = [&](const std::string& camera) {
    const test::CliResult r = limn("subdivide " + q(cage) + " -o " + q(dir_ / "s.ply") +
                                   " --adaptive --depth 2 --tess-px 5 --json --camera " + camera);
    EXPECT_EQ(r.code, 0) << r.err;
    const Mesh m = read_mesh(dir_ / "s.ply");
    EXPECT_EQ(analyze(m, build_topology(m)).boundary_edges, 0u);
    return m.face_count();
  };
  EXPECT_GT(triangles("0,2,2.5,0,0,0,45"), triangles("0,8,10,0,0,0,45"));
  const Mesh s = read_mesh(dir_ / "d.ply");
  EXPECT_EQ(s.colors.size(), 4 * s.vertex_count());
}

TEST_F(Cli, SubdivideAdaptiveRejectsBadOptions) {
  const fs::path cage = dir_ / "cube.obj";
  ASSERT_EQ(limn("shape cube -o " + q(cage)).code, 0);
  for (const char* bad : {"--adaptive --uniform 2",
                          "--uniform 2 --tess 3",
                          "--adaptive --tess 0",
                          "--adaptive --tess 65",
                          "--adaptive --depth 13",
                          "--adaptive --depth 2 --tolerance 1",
                          "--adaptive --tolerance 0",
                          "--adaptive --tolerance -3",
                          "--adaptive --camera 1,2,3",
                          "--adaptive --camera 0,0,5,0,0,0,200",
                          "--adaptive --camera a,0,5,0,0,0,45",
                          "--adaptive --tolerance 1 --resolution 640",
                          "--adaptive --tolerance 1 --resolution 0x10",
                          "--adaptive --limit",
                          "--adaptive --max-depth 20",
                          "--adaptive --tess-px 0",
                          "--adaptive --tess 3 --tess-px 4",
                          "--uniform 1 --tess-px 4",
                          "--adaptive --tolerance 1 --errors guessed",
                          "--uniform 1 --errors estimated"}) {
    const test::CliResult r = limn("subdivide " + q(cage) + " -o " + q(dir_ / "x.ply") + " " + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << bad << ": " << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.ply"));
}

// The "done when": BigGuy's adaptive surface with depth colours is deeper near the
// camera (levels read back from the colours).
TEST_F(Cli, SubdivideAdaptiveDepthColoursAreDeeperNearTheCamera) {
  const fs::path big = fs::path(LIMN_SHARED_MODELS) / "quads/bigguy.obj";
  if (!fs::exists(big)) GTEST_SKIP() << "no shared models";
  const Mesh cage = read_mesh(big);
  const Box b = bounding_box(cage);
  // Looking along -z at the model's +x half from close by.
  const float cx = b.max[0], cy = 0.5f * (b.min[1] + b.max[1]), cz = 0.5f * (b.min[2] + b.max[2]);
  const float d = b.diagonal();
  const std::string camera = std::to_string(cx) + "," + std::to_string(cy) + "," +
                             std::to_string(cz + 0.6f * d) + "," + std::to_string(cx - 0.5f * d) +
                             "," + std::to_string(cy) + "," + std::to_string(cz) + ",50";
  const fs::path out = dir_ / "bigguy.ply";
  const test::CliResult r =
      limn("subdivide " + q(big) + " -o " + q(out) +
           " --adaptive --tolerance 0.5 --tess 2 --depth-colors --camera " + camera);
  ASSERT_EQ(r.code, 0) << r.err;
  const Mesh m = read_mesh(out);
  ASSERT_EQ(m.colors.size(), 4 * m.vertex_count());
  const float eye[3] = {cx, cy, cz + 0.6f * d};
  std::vector<std::pair<float, int>> by_distance;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    int level = -1;
    for (int l = 0; l < 8 && level < 0; ++l) {
      float rgb[3];
      depth_color(l, rgb);
      if (std::abs(rgb[0] - m.colors[4 * v]) < 0.01f &&
          std::abs(rgb[1] - m.colors[4 * v + 1]) < 0.01f &&
          std::abs(rgb[2] - m.colors[4 * v + 2]) < 0.01f)
        level = l;
    }
    ASSERT_GE(level, 0) << "vertex " << v << " has no depth colour";
    const float dx = m.positions[3 * v] - eye[0], dy = m.positions[3 * v + 1] - eye[1],
                dz = m.positions[3 * v + 2] - eye[2];
    by_distance.emplace_back(std::sqrt(dx * dx + dy * dy + dz * dz), level);
  }
  std::sort(by_distance.begin(), by_distance.end());
  const size_t q4 = by_distance.size() / 4;
  double near = 0, far = 0;
  for (size_t i = 0; i < q4; ++i) near += by_distance[i].second;
  for (size_t i = by_distance.size() - q4; i < by_distance.size(); ++i)
    far += by_distance[i].second;
  EXPECT_GT(near / double(q4), far / double(q4) + 0.25);
}

}  // namespace
}  // namespace limn

namespace limn {
namespace {

// Subdivision carries the cage's UVs: OBJ `vt` with `f v/vt`, GLB TEXCOORD_0, PLY (seams split),
// equal to the library's face-varying refinement (which test_subdiv_fvar.cpp checks against
// OpenSubdiv); outputs that cannot hold them say so.
class CliUv : public test::CliTest {};

TEST_F(CliUv, UniformAndLimitWriteTheRefinedUvs) {
  const fs::path car = fs::path(LIMN_SHARED_MODELS) / "osd" / "catmark_car.obj";
  if (!fs::exists(car)) GTEST_SKIP() << "no shared models";
  const Mesh cage = read_mesh(car);
  ASSERT_FALSE(cage.uv_indices.empty());
  const SubdivOptions opt = subdiv_options(cage);
  const FaceVaryingInput in{cage.uv_indices, cage.uvs.size() / 2, true};
  const UniformRefinement r = refine_uniform(cage, 2, opt, {&in, 1});
  const FaceVaryingLevels& fl = r.face_varying[0];
  const std::vector<float> uv = fl.values(cage.uvs.data(), 2, 2);
  std::vector<float> limit(uv.size());
  apply_stencils(fl.limit, uv.data(), limit.data(), 2);
  for (const bool lim : {false, true}) {
    const fs::path out = dir() / (lim ? "limit.obj" : "uniform.obj");
    const test::CliResult res = limn("subdivide " + q(car) + " -o " + q(out) + " --uniform 2" +
                                     (lim ? " --limit" : "") + " --json");
    ASSERT_EQ(res.code, 0) << res.err;
    EXPECT_EQ(nlohmann::json::parse(res.out)["dropped"], nlohmann::json::array());
    EXPECT_EQ(res.err, "");
    const Mesh m = read_mesh(out);
    ASSERT_EQ(m.uv_indices.size(), m.corner_count());
    ASSERT_EQ(m.face_vertices, r.levels.back().face_vertices);
    const std::vector<float>& want = lim ? limit : uv;
    double worst = 0;
    for (size_t c = 0; c < m.corner_count(); ++c)
      for (size_t k = 0; k < 2; ++k)
        worst = std::max(worst, double(std::fabs(m.uvs[2 * m.uv_indices[c] + k] -
                                                 want[2 * fl.corner_values.back()[c] + k])));
    EXPECT_LE(worst, 1e-6) << (lim ? "limit" : "uniform");
  }
  // GLB: TEXCOORD_0 on split seam vertices; PLY: per-vertex u, v after splitting.
  for (const char* ext : {".glb", ".ply"}) {
    const fs::path out = dir() / (std::string("car") + ext);
    const test::CliResult res = limn("subdivide " + q(car) + " -o " + q(out) + " --uniform 1");
    ASSERT_EQ(res.code, 0) << res.err;
    if (std::string(ext) == ".ply") {
      const Mesh m = read_mesh(out);
      EXPECT_EQ(m.uv_indices.size(), m.corner_count());
      continue;
    }
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, out.string())) << err;
    const auto& attrs = model.meshes.at(0).primitives.at(0).attributes;
    ASSERT_EQ(attrs.count("TEXCOORD_0"), 1u);
    EXPECT_EQ(model.accessors[size_t(attrs.at("TEXCOORD_0"))].count,
              model.accessors[size_t(attrs.at("POSITION"))].count);
  }
}

TEST_F(CliUv, WhatAnOutputCannotHoldIsNamed) {
  const fs::path car = fs::path(LIMN_SHARED_MODELS) / "osd" / "catmark_car.obj";
  if (!fs::exists(car)) GTEST_SKIP() << "no shared models";
  test::CliResult res =
      limn("subdivide " + q(car) + " -o " + q(dir() / "car.off") + " --uniform 1 --json");
  ASSERT_EQ(res.code, 0) << res.err;
  const nlohmann::json dropped = nlohmann::json::parse(res.out)["dropped"];
  EXPECT_EQ(dropped, nlohmann::json({"uv", "creases", "corners"}));
  EXPECT_THAT(res.err, HasSubstr("warning"));
  EXPECT_THAT(res.err, HasSubstr("uv"));
  // The adaptive surface carries linear UVs (the default) and smooth ones (through face-varying
  // patches): the two differ inside the faces.
  res =
      limn("subdivide " + q(car) + " -o " + q(dir() / "car.obj") + " --adaptive --depth 1 --json");
  ASSERT_EQ(res.code, 0) << res.err;
  EXPECT_EQ(nlohmann::json::parse(res.out)["dropped"], nlohmann::json::array());
  const Mesh adaptive = read_mesh(dir() / "car.obj");
  EXPECT_EQ(adaptive.uv_indices.size(), adaptive.corner_count());
  const fs::path smooth =
      write("smooth.obj", slurp(car) + "\nt facevaryinginterpolateboundary 1/0/0 0\n");
  res = limn("subdivide " + q(smooth) + " -o " + q(dir() / "smooth-out.obj") +
             " --adaptive --depth 1 --json");
  ASSERT_EQ(res.code, 0) << res.err;
  EXPECT_EQ(nlohmann::json::parse(res.out)["dropped"], nlohmann::json::array());
  const Mesh smooth_out = read_mesh(dir() / "smooth-out.obj");
  ASSERT_EQ(smooth_out.uv_indices.size(), smooth_out.corner_count());
  ASSERT_EQ(smooth_out.corner_count(), adaptive.corner_count());
  double differ = 0;
  for (size_t c = 0; c < adaptive.corner_count(); ++c)
    for (size_t k = 0; k < 2; ++k)
      differ = std::max(differ, double(std::fabs(smooth_out.uvs[2 * smooth_out.uv_indices[c] + k] -
                                                 adaptive.uvs[2 * adaptive.uv_indices[c] + k])));
  EXPECT_GT(differ, 1e-3);
  // And render draws them.
  res = limn("render " + q(smooth) + " -o " + q(dir() / "smooth.png") +
             " --adaptive --depth 1 --uv-checker 8 --samples 1");
  ASSERT_EQ(res.code, 0) << res.err;
  EXPECT_TRUE(fs::exists(dir() / "smooth.png"));
}

}  // namespace
}  // namespace limn
