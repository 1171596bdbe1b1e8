// Every shared model loads, and limn's analysis agrees with brute force and with the published
// counts in ../shared/models/tri/SOURCES.md and ../shared/README.md.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/topology.hpp"
#include "oracle.hpp"

#ifndef LIMN_SHARED_MODELS
#define LIMN_SHARED_MODELS "../shared/models"
#endif

namespace limn {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> shared_models() {
  std::vector<fs::path> out;
  for (const char* sub : {"osd", "quads", "tri"}) {
    const fs::path dir = fs::path(LIMN_SHARED_MODELS) / sub;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir))
      if (format_from_path(e.path()) != MeshFormat::automatic) out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Independent reading of the element counts: OBJ statements counted line by line.
std::pair<size_t, size_t> count_obj_lines(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  size_t v = 0, f = 0;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) ++v;
    if (line.rfind("f ", 0) == 0) ++f;
  }
  return {v, f};
}

MeshStats info(const std::string& rel) {
  const Mesh m = read_mesh(fs::path(LIMN_SHARED_MODELS) / rel);
  return analyze(m, build_topology(m));
}

TEST(SharedModels, AllPresent) {
  // ../shared/models is part of the test environment (CI clones it beside the repo).
  ASSERT_GE(shared_models().size(), 35u) << "missing " << LIMN_SHARED_MODELS;
}

TEST(SharedModels, EveryModelLoadsAndMatchesBruteForce) {
  for (const fs::path& p : shared_models()) {
    SCOPED_TRACE(p.string());
    Mesh m;
    ASSERT_NO_THROW(m = read_mesh(p));
    if (p.extension() == ".obj") {
      const auto [v, f] = count_obj_lines(p);
      EXPECT_EQ(m.vertex_count(), v);
      EXPECT_EQ(m.face_count(), f);
    }
    const MeshStats s = analyze(m, build_topology(m));
    const test::BruteStats b = test::brute_stats(m);
    EXPECT_EQ(s.edges, b.edges);
    EXPECT_EQ(s.boundary_edges, b.boundary_edges);
    EXPECT_EQ(s.non_manifold_edges, b.non_manifold_edges);
    EXPECT_EQ(s.inconsistent_edges, b.inconsistent_edges);
    EXPECT_EQ(s.components, b.components);
    EXPECT_EQ(s.referenced_vertices, b.referenced);
    if (s.non_manifold_vertices == 0) {
      EXPECT_EQ(s.boundary_loops, b.boundary_loops);
    }
  }
}

TEST(SharedModels, Fandisk) {
  const MeshStats s = info("tri/fandisk.obj");
  EXPECT_EQ(s.faces, 12946u);
  EXPECT_EQ(s.vertices, 6475u);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.genus, 0);
  EXPECT_EQ(s.components, 1u);
}

TEST(SharedModels, BunnyHasFiveHolesAndUnreferencedVertices) {
  const MeshStats s = info("tri/stanford-bunny.obj");
  EXPECT_EQ(s.faces, 69451u);
  EXPECT_EQ(s.boundary_loops, 5u);
  EXPECT_EQ(s.boundary_edges, 223u);
  EXPECT_EQ(s.unreferenced_vertices, 1113u);
  EXPECT_EQ(s.referenced_vertices, 34834u);
}

TEST(SharedModels, GenusOfClosedScans) {
  EXPECT_EQ(info("tri/feline.obj").genus, 2);
  EXPECT_EQ(info("tri/rocker-arm.obj").genus, 1);
  EXPECT_EQ(info("tri/spot.obj").genus, 0);
  const MeshStats igea = info("tri/igea.obj");
  EXPECT_EQ(igea.faces, 268686u);
  EXPECT_EQ(igea.vertices, 134345u);
  EXPECT_EQ(igea.genus, 0);
  EXPECT_EQ(igea.boundary_edges, 0u);
}

TEST(SharedModels, BladeOffHasTwoBoundaryLoops) {
  const MeshStats s = info("tri/blade.off");
  EXPECT_EQ(s.faces, 16222u);
  EXPECT_EQ(s.vertices, 8231u);
  EXPECT_EQ(s.boundary_loops, 2u);
  EXPECT_EQ(s.boundary_edges, 240u);
}

TEST(SharedModels, FasBenchmarkCages) {
  const MeshStats big = info("quads/bigguy.obj");
  EXPECT_EQ(big.vertices, 1452u);
  ASSERT_EQ(big.faces_by_arity.size(), 1u);
  EXPECT_EQ(big.faces_by_arity[0], (std::pair<uint32_t, size_t>{4, 1450}));
  const MeshStats frog = info("quads/monsterfrog.obj");
  EXPECT_EQ(frog.vertices, 1308u);
  EXPECT_EQ(frog.faces, 1292u);
}

TEST(SharedModels, OpenSubdivTagsAreRead) {
  // Count the tags straight from the text: one crease edge per `t crease 2/1/0` line here.
  for (const char* name : {"osd/catmark_car.obj", "osd/catmark_cube_creases2.obj"}) {
    SCOPED_TRACE(name);
    std::ifstream in(fs::path(LIMN_SHARED_MODELS) / name);
    std::string line;
    size_t creases = 0;
    while (std::getline(in, line)) creases += line.rfind("t crease 2/1/0", 0) == 0;
    EXPECT_EQ(info(name).crease_edges, creases);
  }
  const MeshStats hole = info("osd/catmark_hole_test3.obj");
  EXPECT_EQ(hole.hole_faces, 8u);
  const Mesh pole = read_mesh(fs::path(LIMN_SHARED_MODELS) / "osd/catmark_pole360.obj");
  const MeshStats ps = analyze(pole, build_topology(pole));
  EXPECT_EQ(ps.valence_histogram.back().first, 360u);
}

}  // namespace
}  // namespace limn
