// The automatic UV atlas, checked against what does not depend on its code: exact orientation
// predicates (CGAL) for flips and overlaps between every pair of UV triangles, isometric
// unfoldings of developable surfaces, analytic stretch values, and UV islands counted from the
// written indices alone.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>

#include "cli_runner.hpp"
#include "limn/atlas/unwrap.hpp"
#include "limn/atlas/uv_metrics.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"

namespace limn {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = Kernel::Point_2;
using ::testing::HasSubstr;

struct UvTriangle {
  P2 p[3];
  uint32_t face;
};

std::vector<UvTriangle> uv_triangles(const Mesh& m) {
  std::vector<UvTriangle> out;
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    const uint32_t c0 = m.face_offsets[f];
    auto at = [&](uint32_t c) {
      const uint32_t i = m.uv_indices[c];
      return P2(m.uvs[2 * size_t(i)], m.uvs[2 * size_t(i) + 1]);
    };
    for (uint32_t k = 1; k + 1 < m.face_size(f); ++k)
      out.push_back({{at(c0), at(c0 + k), at(c0 + k + 1)}, f});
  }
  return out;
}

// Triangles whose UV image is not strictly counter-clockwise (exact predicate).
size_t exact_flips(const std::vector<UvTriangle>& t) {
  size_t n = 0;
  for (const UvTriangle& x : t) n += CGAL::orientation(x.p[0], x.p[1], x.p[2]) != CGAL::LEFT_TURN;
  return n;
}

// Pairs of counter-clockwise triangles whose interiors overlap: no edge line of either one has
// the other entirely on its closed outer side (separating axes of convex polygons, exact).
size_t exact_overlaps(const std::vector<UvTriangle>& t) {
  auto separated = [](const UvTriangle& a, const UvTriangle& b) {
    for (int e = 0; e < 3; ++e) {
      bool all_out = true;
      for (int k = 0; k < 3 && all_out; ++k)
        all_out = CGAL::orientation(a.p[e], a.p[(e + 1) % 3], b.p[k]) != CGAL::LEFT_TURN;
      if (all_out) return true;
    }
    return false;
  };
  // Buckets of a 128 x 128 grid per unit tile.
  constexpr double kCells = 128;
  std::map<std::pair<long, long>, std::vector<uint32_t>> grid;
  for (uint32_t i = 0; i < t.size(); ++i) {
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (const P2& p : t[i].p)
      for (int k = 0; k < 2; ++k)
        lo[k] = std::min(lo[k], CGAL::to_double(p[k])),
        hi[k] = std::max(hi[k], CGAL::to_double(p[k]));
    for (long y = long(std::floor(lo[1] * kCells)); y <= long(std::floor(hi[1] * kCells)); ++y)
      for (long x = long(std::floor(lo[0] * kCells)); x <= long(std::floor(hi[0] * kCells)); ++x)
        grid[{x, y}].push_back(i);
  }
  std::set<std::pair<uint32_t, uint32_t>> overlapping;
  for (const auto& [cell, ids] : grid)
    for (size_t i = 0; i < ids.size(); ++i)
      for (size_t j = i + 1; j < ids.size(); ++j)
        if (!separated(t[ids[i]], t[ids[j]]) && !separated(t[ids[j]], t[ids[i]]))
          overlapping.insert({ids[i], ids[j]});
  return overlapping.size();
}

// UV islands: faces joined across edges whose two ends have the same UV indices on both sides.
size_t uv_islands(const Mesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> edge_face;  // (uv a, uv b) -> face
  std::vector<uint32_t> parent(m.face_count());
  for (uint32_t f = 0; f < parent.size(); ++f) parent[f] = f;
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (uint32_t f = 0; f < m.face_count(); ++f)
    for (uint32_t k = 0; k < m.face_size(f); ++k) {
      const uint32_t a = m.uv_indices[m.face_offsets[f] + k];
      const uint32_t b = m.uv_indices[m.face_offsets[f] + (k + 1) % m.face_size(f)];
      edge_face[{a, b}] = f;
    }
  for (const auto& [e, f] : edge_face) {
    const auto it = edge_face.find({e.second, e.first});
    if (it != edge_face.end()) parent[find(f)] = find(it->second);
  }
  std::set<uint32_t> roots;
  for (uint32_t f = 0; f < m.face_count(); ++f) roots.insert(find(f));
  return roots.size();
}

// Everything an atlas must hold, whatever the mesh.
void expect_valid_atlas(const UnwrapResult& r, const std::string& what) {
  SCOPED_TRACE(what);
  const Mesh& m = r.mesh;
  ASSERT_EQ(m.uv_indices.size(), m.corner_count());
  const std::vector<UvTriangle> t = uv_triangles(m);
  EXPECT_EQ(exact_flips(t), 0u);
  EXPECT_EQ(exact_overlaps(t), 0u);
  EXPECT_EQ(uv_islands(m), r.stats.charts);
  // Inside the tiles used, and each face in the tile of its chart.
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    const uint32_t tile = r.chart_tile[r.face_chart[f]];
    ASSERT_LT(tile, r.stats.tiles);
    for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
      const float u = m.uvs[2 * size_t(m.uv_indices[c])],
                  v = m.uvs[2 * size_t(m.uv_indices[c]) + 1];
      EXPECT_GE(u, float(tile % 10));
      EXPECT_LE(u, float(tile % 10 + 1));
      EXPECT_GE(v, float(tile / 10));
      EXPECT_LE(v, float(tile / 10 + 1));
    }
  }
  const UvMetrics metrics = measure_uvs(m, r.stats.size);
  EXPECT_EQ(metrics.flipped, 0u);
  EXPECT_EQ(metrics.overlapping_texels, 0u);
  EXPECT_EQ(metrics.straddling, 0u);
  EXPECT_NEAR(metrics.stretch_l2, r.stats.stretch_l2, 1e-3);
  EXPECT_LE(r.stats.stretch_l2, UnwrapOptions{}.max_stretch + 1e-9);
}

// n x n unit quads in a plane, tilted so no axis is special.
Mesh flat_grid(int n) {
  Mesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.add_vertex(float(x), float(0.5 * x + 0.25 * y), float(y));
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = uint32_t(y * (n + 1) + x);
      m.add_face({a, a + uint32_t(n + 1), a + uint32_t(n + 2), a + 1});
    }
  return m;
}

// The side of a regular prism: `sides` x `rows` quads around the y axis, open at both ends. It is
// developable: each half unrolls flat without stretch.
Mesh prism_band(int sides, int rows) {
  Mesh m;
  for (int r = 0; r <= rows; ++r)
    for (int s = 0; s < sides; ++s) {
      const double a = 2 * std::numbers::pi * s / sides;
      m.add_vertex(float(std::cos(a)), float(0.3 * r), float(std::sin(a)));
    }
  for (int r = 0; r < rows; ++r)
    for (int s = 0; s < sides; ++s) {
      const uint32_t a = uint32_t(r * sides + s), b = uint32_t(r * sides + (s + 1) % sides);
      m.add_face({a, a + uint32_t(sides), b + uint32_t(sides), b});
    }
  return m;
}

TEST(Unwrap, FlatGridIsOneChartMappedBySimilarity) {
  const Mesh grid = flat_grid(10);
  const UnwrapResult r = unwrap_mesh(grid);
  expect_valid_atlas(r, "grid");
  EXPECT_EQ(r.stats.charts, 1u);
  EXPECT_EQ(r.stats.splits, 0u);
  // Every edge keeps its length up to one common scale: the texel density.
  const Mesh& m = r.mesh;
  const double scale = r.stats.texels_per_unit / r.stats.size;
  for (uint32_t c = 0; c < m.corner_count(); ++c) {
    const uint32_t face =
        uint32_t(std::upper_bound(m.face_offsets.begin(), m.face_offsets.end(), c) -
                 m.face_offsets.begin() - 1);
    const uint32_t next = m.face_offsets[face] + (c + 1 - m.face_offsets[face]) % m.face_size(face);
    const float* p = &m.positions[3 * size_t(m.face_vertices[c])];
    const float* q = &m.positions[3 * size_t(m.face_vertices[next])];
    const float* u = &m.uvs[2 * size_t(m.uv_indices[c])];
    const float* w = &m.uvs[2 * size_t(m.uv_indices[next])];
    const double len3 = std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                  (p[2] - q[2]) * (p[2] - q[2]));
    const double len2 = std::hypot(u[0] - w[0], u[1] - w[1]);
    EXPECT_NEAR(len2 / len3, scale, 1e-4 * scale);
  }
  EXPECT_NEAR(r.stats.stretch_l2, 1.0, 1e-9);
  EXPECT_GT(r.stats.utilization, 0.5);  // one square chart in a square atlas
}

TEST(Unwrap, DevelopableBandIsCutAndUnrolledWithoutStretch) {
  const UnwrapResult r = unwrap_mesh(prism_band(12, 4));
  expect_valid_atlas(r, "prism band");
  EXPECT_GE(r.stats.charts, 2u);  // an annulus is no disk
  EXPECT_NEAR(r.stats.stretch_l2, 1.0, 1e-6);
  EXPECT_NEAR(r.stats.stretch_linf, 1.0, 1e-6);
}

TEST(Unwrap, ClosedShapesGetValidAtlases) {
  for (const char* name : {"cube", "torus", "cage", "torus-dense-small"}) {
    const Mesh m = make_shape(name);
    expect_valid_atlas(unwrap_mesh(m), name);
  }
}

TEST(Unwrap, SharedScanGetsAValidLowStretchAtlas) {
  const std::string path = std::string(LIMN_SHARED_MODELS) + "/tri/spot.obj";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is missing";
  const UnwrapResult r = unwrap_mesh(read_mesh(path));
  expect_valid_atlas(r, "spot");
  EXPECT_LE(r.stats.stretch_l2, 1.01);
  EXPECT_GT(r.stats.utilization, 0.4);
}

TEST(Unwrap, UdimTilesHoldChartsAtTheDensityAsked) {
  const Mesh torus = make_shape("torus");
  UnwrapOptions o;
  o.size = 64;
  o.tiles = 12;
  // The torus has 4 pi^2 0.4 = 15.8 units^2 of surface: over 9000 texels at 24 per unit, more
  // than two 64 x 64 tiles hold; its charts are cut to fit a tile.
  o.texels_per_unit = 24;
  const UnwrapResult r = unwrap_mesh(torus, o);
  expect_valid_atlas(r, "udim");
  EXPECT_GE(r.stats.tiles, 3u);
  EXPECT_LE(r.stats.tiles, 12u);
  EXPECT_DOUBLE_EQ(r.stats.texels_per_unit, 24);
  std::set<uint32_t> used(r.chart_tile.begin(), r.chart_tile.end());
  EXPECT_EQ(used.size(), r.stats.tiles);

  o.tiles = 1;
  EXPECT_THROW(
      {
        try {
          unwrap_mesh(torus, o, "torus.obj");
        } catch (const InputError& e) {
          EXPECT_THAT(e.what(), HasSubstr("torus.obj: 24 texels per unit is too dense"));
          throw;
        }
      },
      InputError);
}

TEST(Unwrap, RefusesNonManifoldMeshesAndBadOptions) {
  Mesh fin = flat_grid(2);
  const uint32_t v = fin.add_vertex(1, 5, 1);
  fin.add_face({4, 5, v});  // a third face on the edge (4, 5)
  fin.add_face({5, 4, v});
  EXPECT_THROW(unwrap_mesh(fin, {}, "fin.obj"), RepairableError);
  EXPECT_THROW(unwrap_mesh(Mesh{}), InputError);
  const Mesh grid = flat_grid(2);
  for (auto bad : {UnwrapOptions{.max_stretch = 0.5}, UnwrapOptions{.size = 8},
                   UnwrapOptions{.texels_per_unit = -1}, UnwrapOptions{.tiles = 101},
                   UnwrapOptions{.padding = 300}})
    EXPECT_THROW(unwrap_mesh(grid, bad), InputError);
}

TEST(UvMetrics, StretchOfAnAnisotropicMapIsSandersValue) {
  // A 2 x 1 rectangle mapped onto the unit UV square: the map from texture to surface stretches
  // s by 2 and t by 1, so L2 = sqrt((4 + 1) / 2) and Linf = 2, both times sqrt(1 / 2).
  Mesh m;
  m.add_vertex(0, 0, 0), m.add_vertex(2, 0, 0), m.add_vertex(2, 1, 0), m.add_vertex(0, 1, 0);
  m.add_face({0, 1, 2, 3});
  m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  m.uv_indices = {0, 1, 2, 3};
  const UvMetrics x = measure_uvs(m, 32);
  EXPECT_NEAR(x.stretch_l2, std::sqrt(2.5) * std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(x.stretch_linf, 2 * std::sqrt(0.5), 1e-9);
  EXPECT_EQ(x.flipped, 0u);
  EXPECT_EQ(x.overlapping_texels, 0u);
  EXPECT_EQ(x.covered_texels, 32u * 32u);
  EXPECT_EQ(x.tiles, 1u);
}

TEST(UvMetrics, CountsFlipsOverlapsAndTiles) {
  Mesh m;
  m.add_vertex(0, 0, 0), m.add_vertex(1, 0, 0), m.add_vertex(0, 1, 0);
  m.add_face({0, 1, 2}), m.add_face({0, 1, 2}), m.add_face({0, 2, 1});
  // Two copies of one UV triangle (an overlap) and a third, mirrored, in tile (1, 0).
  m.uvs = {0, 0, 0.5f, 0, 0, 0.5f, 1.1f, 0.1f, 1.6f, 0.1f, 1.1f, 0.6f};
  m.uv_indices = {0, 1, 2, 0, 1, 2, 3, 4, 5};
  const UvMetrics x = measure_uvs(m, 16);
  EXPECT_EQ(x.triangles, 3u);
  EXPECT_EQ(x.flipped, 0u);  // UV orientation alone decides: all three are counter-clockwise
  EXPECT_GT(x.overlapping_texels, 0u);
  EXPECT_EQ(x.tiles, 2u);
  m.uv_indices = {0, 2, 1, 3, 5, 4, 3, 4, 5};
  EXPECT_EQ(measure_uvs(m, 16).flipped, 2u);
  EXPECT_THROW(measure_uvs(Mesh{}, 16), InputError);
}

using UnwrapCli = test::CliTest;

TEST_F(UnwrapCli, WritesTheMeshWithItsAtlasAndReports) {
  ASSERT_EQ(limn("shape torus -o " + q(dir() / "torus.obj")).code, 0);
  const auto r = limn("unwrap " + q(dir() / "torus.obj") + " -o " + q(dir() / "out.obj") +
                      " --size 256 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const Mesh out = read_mesh((dir() / "out.obj").string());
  const Mesh in = make_shape("torus");
  EXPECT_EQ(out.face_count(), in.face_count());
  EXPECT_EQ(out.vertex_count(), in.vertex_count());
  EXPECT_EQ(uv_islands(out), j["charts"].get<size_t>());
  EXPECT_EQ(j["size"], 256);
  EXPECT_EQ(j["tiles"], 1);
  EXPECT_EQ(j["udim"], nlohmann::json::array({1001}));
  EXPECT_EQ(j["check"]["flipped"], 0);
  EXPECT_EQ(j["check"]["overlapping_texels"], 0);
  EXPECT_EQ(j["dropped"], nlohmann::json::array());
  EXPECT_FALSE(j["replaced_uvs"].get<bool>());
  const UvMetrics m = measure_uvs(out, 256);
  EXPECT_NEAR(m.stretch_l2, j["stretch_l2"].get<double>(), 1e-3);

  // A format without UVs says what it dropped.
  const auto ply = limn("unwrap " + q(dir() / "torus.obj") + " -o " + q(dir() / "out.off") +
                        " --size 128 --json");
  ASSERT_EQ(ply.code, 0) << ply.err;
  EXPECT_THAT(nlohmann::json::parse(ply.out)["dropped"].dump(), HasSubstr("uv"));
  EXPECT_THAT(ply.err, HasSubstr("uv"));
}

TEST_F(UnwrapCli, BadInputExitsTwoWithOneLineAndNoFile) {
  write("fin.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n");
  const auto fin = limn("unwrap " + q(dir() / "fin.obj") + " -o " + q(dir() / "out.obj"));
  EXPECT_EQ(fin.code, 2);
  EXPECT_THAT(fin.err, HasSubstr("fin.obj"));
  EXPECT_THAT(fin.err, HasSubstr("--repair"));
  EXPECT_EQ(std::count(fin.err.begin(), fin.err.end(), '\n'), 1);

  ASSERT_EQ(limn("shape torus -o " + q(dir() / "torus.obj")).code, 0);
  const auto dense = limn("unwrap " + q(dir() / "torus.obj") + " -o " + q(dir() / "out.obj") +
                          " --size 64 --texels-per-unit 1000");
  EXPECT_EQ(dense.code, 2);
  EXPECT_THAT(dense.err, HasSubstr("too dense"));
  for (const char* bad :
       {"--max-stretch 0.9", "--size 4", "--tiles 0", "--padding -1", "--texels-per-unit 0"}) {
    const auto r =
        limn("unwrap " + q(dir() / "torus.obj") + " -o " + q(dir() / "out.obj") + " " + bad);
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << bad << ": " << r.err;
  }
  EXPECT_EQ(files(), (std::vector<std::string>{"fin.obj", "torus.obj"}));
}

}  // namespace
}  // namespace limn
