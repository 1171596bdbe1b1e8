// The simplify layer's meshing side: every output passes the validity contract (checked by
// validate_simplified, which is itself tested on broken meshes here) on every shared triangle
// mesh and on hundreds of random partitions; boundaries, holes and components survive; chains
// are split by the threshold; the polygon triangulation respects its vetoes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <string>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/simplify/validate.hpp"
#include "limn/simplify/vsa.hpp"
#include "simplify/polygonize.hpp"
#include "simplify/triangulate.hpp"
#include "simplify_oracle.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
const fs::path kModels = LIMN_SHARED_MODELS;

long long euler(const Mesh& m) {
  std::set<std::pair<uint32_t, uint32_t>> edges;
  std::set<uint32_t> verts;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    for (size_t i = 0; i < v.size(); ++i) {
      const uint32_t a = v[i], b = v[(i + 1) % v.size()];
      edges.insert({std::min(a, b), std::max(a, b)});
      verts.insert(a);
    }
  }
  return (long long)verts.size() - (long long)edges.size() + (long long)m.face_count();
}

// What every simplified mesh must satisfy, whatever the input.
void expect_valid(const Mesh& in, const SimplifiedMesh& out, size_t clusters) {
  const SimplifiedCheck c = validate_simplified(out.mesh, bounding_box(in));
  EXPECT_TRUE(c.ok()) << c.first_problem;
  ASSERT_GT(out.mesh.face_count(), 0u);
  ASSERT_EQ(out.face_cluster.size(), out.mesh.face_count());
  ASSERT_EQ(out.vertex_source.size(), out.mesh.vertex_count());
  for (size_t v = 0; v < out.mesh.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(out.mesh.positions[3 * v + k], in.positions[3 * size_t(out.vertex_source[v]) + k]);
  std::set<uint32_t> seen(out.face_cluster.begin(), out.face_cluster.end());
  EXPECT_EQ(seen.size(), clusters);  // every cluster is drawn
  EXPECT_EQ(test::boundary_loops(out.mesh), test::boundary_loops(in));
}

struct ModelCase {
  const char* file;
  size_t K;
};

class SimplifyModels : public ::testing::TestWithParam<ModelCase> {};

TEST_P(SimplifyModels, OutputIsValidInTrianglesAndPolygons) {
  const ModelCase c = GetParam();
  const Mesh m = read_mesh(kModels / "tri" / c.file);
  const SimplifiedCheck input = validate_simplified(m, bounding_box(m));
  for (bool polygons : {false, true}) {
    SCOPED_TRACE(polygons ? "polygons" : "triangles");
    VsaOptions o;
    o.proxies = c.K;
    o.meshing.polygons = polygons;
    const VsaResult r = simplify_vsa(m, o, c.file);
    expect_valid(m, r.output, r.stats.clusters);
    EXPECT_GE(r.stats.clusters, c.K);
    if (input.boundary_edges == 0) {
      EXPECT_EQ(validate_simplified(r.output.mesh, bounding_box(m)).boundary_edges, 0u);
    }
    size_t big = 0;
    for (size_t f = 0; f < r.output.mesh.face_count(); ++f) big += r.output.mesh.face_size(f) > 3;
    if (polygons) {
      EXPECT_GT(big, r.stats.clusters / 2);  // most clusters are one polygon
      EXPECT_LT(r.output.mesh.face_count(), 3 * r.stats.clusters);
    } else {
      EXPECT_EQ(big, 0u);
    }
    // Labels: one per input face, every one a cluster.
    ASSERT_EQ(r.labels.size(), m.face_count());
    for (uint32_t l : r.labels) ASSERT_LT(l, r.stats.clusters);
  }
}

// Every shared triangle mesh; the two largest at the benchmark's K. SimplifyModelsList checks
// that no mesh in the folder is missing here.
const ModelCase kModelCases[] = {{"fandisk.obj", 30},
                                 {"stanford-bunny.obj", 100},
                                 {"feline.obj", 200},
                                 {"armadillo-100k.obj", 200},
                                 {"armadillo-cgal-52k.off", 100},
                                 {"igea.obj", 300},
                                 {"nefertiti.obj", 100},
                                 {"ogre.obj", 100},
                                 {"homer.obj", 50},
                                 {"rocker-arm.obj", 50},
                                 {"spot.obj", 30},
                                 {"blade.off", 60}};

INSTANTIATE_TEST_SUITE_P(Shared, SimplifyModels, ::testing::ValuesIn(kModelCases),
                         [](const auto& param_info) {
                           std::string n = param_info.param.file;
                           n = n.substr(0, n.find('.'));
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

// A mesh added to ../shared/models/tri later must get a case above (with a K chosen for it)
// rather than be skipped silently: every obj/ply/off file there is in the list, and every listed
// file is there.
TEST(SimplifyModelsList, CoversEveryMeshInTheSharedFolder) {
  const fs::path dir = kModels / "tri";
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  std::set<std::string> listed;
  for (const ModelCase& c : kModelCases) listed.insert(c.file);
  std::set<std::string> found;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char ch) { return char(std::tolower(ch)); });
    if (ext == ".obj" || ext == ".ply" || ext == ".off") found.insert(e.path().filename().string());
  }
  EXPECT_FALSE(found.empty()) << dir;
  for (const std::string& f : found)
    EXPECT_TRUE(listed.count(f)) << f << " in " << dir << " has no SimplifyModels case";
  for (const std::string& f : listed)
    EXPECT_TRUE(found.count(f)) << f << " is listed but not in " << dir;
}

TEST(SimplifyMeshing, ClosedGenusZeroModelsKeepTheirEulerCharacteristic) {
  for (const char* name : {"spot.obj", "fandisk.obj", "homer.obj", "rocker-arm.obj"}) {
    SCOPED_TRACE(name);
    const Mesh m = read_mesh(kModels / "tri" / name);
    VsaOptions o;
    o.proxies = 40;
    const VsaResult r = simplify_vsa(m, o);
    EXPECT_EQ(euler(r.output.mesh), euler(m));
  }
}

// A cube of planar sides (each an n x n triangle grid).
Mesh fine_cube(int n) {
  Mesh m;
  std::map<std::array<int, 3>, uint32_t> ids;
  auto vid = [&](int x, int y, int z) {
    auto [it, fresh] = ids.try_emplace({x, y, z}, 0u);
    if (fresh) it->second = m.add_vertex(float(x), float(y), float(z));
    return it->second;
  };
  const int sides[6][9] = {{0, 0, 0, 0, 1, 0, 1, 0, 0}, {0, 0, n, 1, 0, 0, 0, 1, 0},
                           {0, 0, 0, 1, 0, 0, 0, 0, 1}, {0, n, 0, 0, 0, 1, 1, 0, 0},
                           {0, 0, 0, 0, 0, 1, 0, 1, 0}, {n, 0, 0, 0, 1, 0, 0, 0, 1}};
  for (const auto& sd : sides)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        auto P = [&](int a, int b) {
          return vid(sd[0] + a * sd[3] + b * sd[6], sd[1] + a * sd[4] + b * sd[7],
                     sd[2] + a * sd[5] + b * sd[8]);
        };
        m.add_face({P(i, j), P(i + 1, j), P(i + 1, j + 1)});
        m.add_face({P(i, j), P(i + 1, j + 1), P(i, j + 1)});
      }
  return m;
}

TEST(SimplifyMeshing, ACubeBecomesSixQuads) {
  const Mesh cube = fine_cube(5);
  VsaOptions o;
  o.proxies = 6;
  o.meshing.polygons = true;
  VsaResult r = simplify_vsa(cube, o);
  EXPECT_NEAR(r.stats.energy, 0.0, 1e-9);
  ASSERT_EQ(r.output.mesh.face_count(), 6u);
  EXPECT_EQ(r.output.mesh.vertex_count(), 8u);
  for (size_t f = 0; f < 6; ++f) EXPECT_EQ(r.output.mesh.face_size(f), 4u);
  expect_valid(cube, r.output, 6);
  o.meshing.polygons = false;
  r = simplify_vsa(cube, o);
  EXPECT_EQ(r.output.mesh.face_count(), 12u);
  expect_valid(cube, r.output, 6);
}

TEST(SimplifyMeshing, AClusterWithAHoleAndAnIsland) {
  // A plane with a square hole in one cluster: its two loops are cut into simple polygons.
  std::set<int> hole;
  for (int j = 4; j < 7; ++j)
    for (int i = 4; i < 7; ++i) hole.insert(j * 12 + i);
  const Mesh annulus = test::grid_mesh(12, hole);
  for (bool polygons : {false, true}) {
    VsaOptions o;
    o.proxies = 1;
    o.meshing.polygons = polygons;
    const VsaResult r = simplify_vsa(annulus, o);
    EXPECT_EQ(r.stats.clusters, 1u);
    expect_valid(annulus, r.output, 1);
    EXPECT_EQ(test::boundary_loops(r.output.mesh), 2u);
    EXPECT_GT(r.output.stats.bridges, 0u);
    if (polygons) {
      EXPECT_GE(r.output.stats.polygons, 2u);
    }
  }
  // An island cluster: a block of the plane labelled apart from the rest.
  const Mesh plane = test::grid_mesh(12);
  const VsaSurface s = prepare_surface(plane);
  std::vector<uint32_t> labels(plane.face_count(), 0);
  for (int j = 3; j < 8; ++j)
    for (int i = 3; i < 8; ++i)
      labels[2 * size_t(j * 12 + i)] = labels[2 * size_t(j * 12 + i) + 1] = 1;
  Partition p = partition_from_labels(s, labels, 2);
  for (bool polygons : {false, true}) {
    MeshingOptions mo;
    mo.polygons = polygons;
    const SimplifiedMesh out = polygonize(s, p, mo);
    expect_valid(plane, out, 2);
    // The island's loop and the plane's rim meet no third cluster: one anchor forced on each.
    EXPECT_EQ(out.stats.forced_anchors, 2u);
  }
}

TEST(SimplifyMeshing, SeveralComponentsAndOpenBoundaries) {
  // A sphere and a plane with holes in one mesh.
  Mesh m = test::uv_sphere(12, 24, 1.0f);
  const Mesh plane = test::grid_mesh(8, {9, 10, 27, 44, 45, 46});
  const uint32_t base = uint32_t(m.vertex_count());
  for (size_t v = 0; v < plane.vertex_count(); ++v)
    m.add_vertex(plane.positions[3 * v] + 3.0f, plane.positions[3 * v + 1],
                 plane.positions[3 * v + 2]);
  for (size_t f = 0; f < plane.face_count(); ++f) {
    const auto fv = plane.face(f);
    m.add_face({fv[0] + base, fv[1] + base, fv[2] + base});
  }
  for (size_t K : {2u, 5u, 40u}) {
    VsaOptions o;
    o.proxies = K;
    const VsaResult r = simplify_vsa(m, o);
    expect_valid(m, r.output, r.stats.clusters);
    EXPECT_GE(r.stats.clusters, K);
  }
}

// Random edge-connected partitions: K random seeds, regions grown in random order (ragged
// shapes, islands, pinches), one extra seed per component no seed reached.
std::vector<uint32_t> random_partition(const Mesh& m, size_t K, std::mt19937& rng) {
  const auto nb = test::face_neighbours(m);
  std::vector<uint32_t> labels(m.face_count(), kNone);
  std::vector<std::pair<uint32_t, uint32_t>> frontier;
  uint32_t next = 0;
  auto seed = [&](uint32_t f) {
    labels[f] = next++;
    for (uint32_t g : nb[f]) frontier.push_back({g, labels[f]});
  };
  for (size_t k = 0; k < K; ++k) {
    const uint32_t f = uint32_t(rng() % m.face_count());
    if (labels[f] == kNone) seed(f);
  }
  for (;;) {
    while (!frontier.empty()) {
      const size_t i = rng() % frontier.size();
      const auto [f, l] = frontier[i];
      frontier[i] = frontier.back();
      frontier.pop_back();
      if (labels[f] != kNone) continue;
      labels[f] = l;
      for (uint32_t g : nb[f])
        if (labels[g] == kNone) frontier.push_back({g, l});
    }
    const auto it = std::find(labels.begin(), labels.end(), kNone);
    if (it == labels.end()) break;
    seed(uint32_t(it - labels.begin()));
  }
  return labels;
}

TEST(SimplifyMeshing, RandomPartitionsAlwaysGiveValidMeshes) {
  Mesh two = test::uv_sphere(10, 20, 1.0f);
  {
    const Mesh g = test::grid_mesh(7, {8, 16, 24, 30});
    const uint32_t base = uint32_t(two.vertex_count());
    for (size_t v = 0; v < g.vertex_count(); ++v)
      two.add_vertex(g.positions[3 * v] * 0.3f, g.positions[3 * v + 1] * 0.3f + 2.0f, 0.5f);
    for (size_t f = 0; f < g.face_count(); ++f) {
      const auto fv = g.face(f);
      two.add_face({fv[0] + base, fv[1] + base, fv[2] + base});
    }
  }
  const Mesh meshes[] = {test::uv_sphere(14, 28, 1.0f),
                         test::grid_mesh(14, {20, 21, 50, 99, 100, 114}), fine_cube(4), two};
  std::mt19937 rng(12345);
  size_t runs = 0, fixes = 0;
  for (const Mesh& m : meshes) {
    const VsaSurface s = prepare_surface(m);
    for (int trial = 0; trial < 40; ++trial) {
      const size_t K = 1 + rng() % 60;
      const std::vector<uint32_t> labels = random_partition(m, K, rng);
      const size_t n = *std::max_element(labels.begin(), labels.end()) + 1;
      Partition p = partition_from_labels(s, labels, n);
      MeshingOptions mo;
      mo.polygons = trial % 2 == 1;
      const double thresholds[] = {0.0, 0.1, 0.5, 2.0, 1e9};
      mo.split_threshold = thresholds[trial % 5];
      SCOPED_TRACE(::testing::Message() << "trial " << trial << " K " << n << " threshold "
                                        << mo.split_threshold << " polygons " << mo.polygons);
      const SimplifiedMesh out = polygonize(s, p, mo);
      expect_valid(m, out, p.cluster_count());
      fixes += out.stats.cluster_splits + out.stats.fans;
      ++runs;
    }
  }
  EXPECT_EQ(runs, 160u);
  RecordProperty("fixes", int(fixes));
}

TEST(SimplifyMeshing, TheSplitThresholdDecidesWhichChainVerticesStay) {
  const Mesh sphere = test::uv_sphere(16, 32, 1.0f);
  const VsaSurface s = prepare_surface(sphere);
  std::mt19937 rng(7);
  const std::vector<uint32_t> labels = random_partition(sphere, 12, rng);
  Partition p =
      partition_from_labels(s, labels, *std::max_element(labels.begin(), labels.end()) + 1);
  // Vertices on a cluster boundary, found independently: faces of two labels around them.
  std::map<uint32_t, std::set<uint32_t>> around;
  for (size_t f = 0; f < sphere.face_count(); ++f)
    for (uint32_t v : sphere.face(f)) around[v].insert(labels[f]);
  std::set<uint32_t> boundary, corners;
  for (const auto& [v, ls] : around) {
    if (ls.size() >= 2) boundary.insert(v);
    if (ls.size() >= 3) corners.insert(v);
  }
  MeshingOptions mo;
  mo.split_threshold = 0;  // every vertex off its chord is kept: no three are collinear here
  const SimplifiedMesh all = polygonize(s, p, mo);
  std::set<uint32_t> kept(all.vertex_source.begin(), all.vertex_source.end());
  EXPECT_EQ(kept, boundary);
  mo.split_threshold = 1e9;  // only where three clusters meet (and on loops meeting none)
  const SimplifiedMesh few = polygonize(s, p, mo);
  std::set<uint32_t> anchors(few.vertex_source.begin(), few.vertex_source.end());
  for (uint32_t v : corners) EXPECT_TRUE(anchors.count(v)) << v;
  EXPECT_LT(anchors.size(), kept.size());
  mo.split_threshold = 0.3;
  const SimplifiedMesh mid = polygonize(s, p, mo);
  EXPECT_GT(mid.mesh.vertex_count(), few.mesh.vertex_count());
  EXPECT_LT(mid.mesh.vertex_count(), all.mesh.vertex_count());
  for (const SimplifiedMesh* o : {&all, &few, &mid}) expect_valid(sphere, *o, p.cluster_count());
}

TEST(SimplifyTriangulate, MinimumAreaWithVetoes) {
  // A folded quad: diagonal 1-3 gives two flat triangles of less area than 0-2.
  const double P[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 1}, {0, 1, 0}};
  auto area = [&](uint32_t a, uint32_t b, uint32_t c) {
    double u[3], w[3];
    for (int k = 0; k < 3; ++k) u[k] = P[b][k] - P[a][k], w[k] = P[c][k] - P[a][k];
    const double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2],
                 z = u[0] * w[1] - u[1] * w[0];
    return 0.5 * std::sqrt(x * x + y * y + z * z);
  };
  std::vector<uint32_t> out;
  auto sorted = [](const std::vector<uint32_t>& t) {
    std::vector<std::array<uint32_t, 3>> tris;
    for (size_t i = 0; i < t.size(); i += 3) tris.push_back({t[i], t[i + 1], t[i + 2]});
    std::sort(tris.begin(), tris.end());
    return tris;
  };
  using Tris = std::vector<std::array<uint32_t, 3>>;
  ASSERT_TRUE(triangulate_polygon(
      4, [](uint32_t, uint32_t) { return true; }, area, out));
  const double via13 = area(0, 1, 3) + area(1, 2, 3), via02 = area(0, 1, 2) + area(0, 2, 3);
  ASSERT_LT(via13, via02);
  EXPECT_EQ(sorted(out), (Tris{{0, 1, 3}, {1, 2, 3}}));
  // Veto 1-3: the other diagonal.
  out.clear();
  ASSERT_TRUE(triangulate_polygon(
      4, [](uint32_t i, uint32_t j) { return !(i == 1 && j == 3); }, area, out));
  EXPECT_EQ(sorted(out), (Tris{{0, 1, 2}, {0, 2, 3}}));
  // Both vetoed: no triangulation, nothing appended.
  out.clear();
  EXPECT_FALSE(triangulate_polygon(
      4, [](uint32_t, uint32_t) { return false; }, area, out));
  EXPECT_TRUE(out.empty());
  // A triangle vetoed by weight.
  EXPECT_FALSE(triangulate_polygon(
      3, [](uint32_t, uint32_t) { return true; },
      [](uint32_t, uint32_t, uint32_t) { return std::numeric_limits<double>::infinity(); }, out));
}

TEST(SimplifyTriangulate, LargePolygonsAreCutAndStayOneDisk) {
  for (uint32_t n : {5u, 191u, 192u, 193u, 700u}) {
    SCOPED_TRACE(n);
    std::vector<uint32_t> out;
    auto w = [&](uint32_t a, uint32_t b, uint32_t c) { return double((b - a) * (c - b)) + 1.0; };
    ASSERT_TRUE(triangulate_polygon(
        n, [](uint32_t, uint32_t) { return true; }, w, out));
    ASSERT_EQ(out.size(), 3 * size_t(n - 2));
    // Sides once, diagonals twice, every triangle in increasing (polygon) order.
    std::map<std::pair<uint32_t, uint32_t>, int> uses;
    for (size_t t = 0; t < out.size(); t += 3) {
      ASSERT_LT(out[t], out[t + 1]);
      ASSERT_LT(out[t + 1], out[t + 2]);
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = out[t + e], b = out[t + (e + 1) % 3];
        ++uses[{std::min(a, b), std::max(a, b)}];
      }
    }
    for (const auto& [e, k] : uses) {
      const bool side = e.second == e.first + 1 || (e.first == 0 && e.second == n - 1);
      EXPECT_EQ(k, side ? 1 : 2) << e.first << "-" << e.second;
    }
    EXPECT_EQ(uses.size(), size_t(n) + size_t(n - 3));
  }
}

TEST(SimplifyValidate, FindsEachKindOfProblem) {
  Box box;
  for (int k = 0; k < 3; ++k) box.min[k] = -1, box.max[k] = 2;
  auto mesh = [](std::initializer_list<std::array<float, 3>> pts,
                 std::initializer_list<std::vector<uint32_t>> faces) {
    Mesh m;
    for (const auto& p : pts) m.add_vertex(p[0], p[1], p[2]);
    for (const auto& f : faces) m.add_face(f);
    return m;
  };
  const auto sq = {std::array<float, 3>{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const auto five = {std::array<float, 3>{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}};
  EXPECT_TRUE(validate_simplified(mesh(sq, {{0, 1, 2}, {0, 2, 3}}), box).ok());
  EXPECT_TRUE(validate_simplified(mesh(sq, {{0, 1, 2, 3}}), box).ok());
  // Edge 0-2 on three faces.
  const SimplifiedCheck fan =
      validate_simplified(mesh(five, {{0, 1, 2}, {0, 2, 3}, {0, 2, 4}}), box);
  EXPECT_EQ(fan.non_manifold_edges, 1u);
  EXPECT_FALSE(fan.ok());
  // The second face turned over: 2->0 twice.
  EXPECT_EQ(validate_simplified(mesh(sq, {{0, 1, 2}, {0, 3, 2}}), box).inconsistent_edges, 1u);
  // The same triangle both ways round (a closed two-face pillow).
  EXPECT_EQ(validate_simplified(mesh(sq, {{0, 1, 2}, {0, 2, 1}, {0, 2, 3}}), box).duplicate_faces,
            1u);
  // Collinear corners, and a repeated corner.
  EXPECT_EQ(validate_simplified(mesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}}), box)
                .degenerate_faces,
            1u);
  EXPECT_EQ(validate_simplified(mesh(sq, {{0, 1, 2}, {0, 2, 2, 3}}), box).degenerate_faces, 1u);
  EXPECT_EQ(validate_simplified(mesh(five, {{0, 1, 2}}), box).unreferenced_vertices, 2u);
  Box small;
  for (int k = 0; k < 3; ++k) small.min[k] = 0, small.max[k] = 0.5f;
  const SimplifiedCheck out = validate_simplified(mesh(sq, {{0, 1, 2}, {0, 2, 3}}), small);
  EXPECT_EQ(out.outside_bbox, 3u);
  EXPECT_NE(out.first_problem.find("outside"), std::string::npos);
}

}  // namespace
}  // namespace limn
