// The simplify layer's partition side: energy bookkeeping, the greedy optimiser's contract
// (every move lowers E, clusters stay connected, it stops at a local minimum), curvature,
// seeding, Lloyd, the controls, and the input it refuses. References are independent
// (simplify_oracle.hpp): energies from labels and positions, adjacency from a map, plain BFS.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <set>

#include "limn/io/mesh_io.hpp"
#include "limn/simplify/vsa.hpp"
#include "simplify/cluster_edit.hpp"
#include "simplify/curvature.hpp"
#include "simplify/greedy.hpp"
#include "simplify/lloyd.hpp"
#include "simplify/seeding.hpp"
#include "simplify_oracle.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
const fs::path kModels = LIMN_SHARED_MODELS;
const fs::path kData = LIMN_TEST_DATA;

Mesh model(const char* name) {
  return read_mesh(kModels / "tri" / name);
}

// Complete partition: seeding, then the unassigned faces flooded in (what the greedy starts from).
Partition seeded(const VsaSurface& s, size_t K, SeedingMethod method, uint64_t seed = 1) {
  SeedingOptions so;
  so.clusters = K;
  so.method = method;
  so.seed = seed;
  Partition p = seed_partition(s, so);
  absorb_unassigned(s, p);
  return p;
}

TEST(SimplifyEnergy, ClusterSumsMatchAnIndependentRecomputation) {
  for (const auto& [name, K] :
       {std::pair{"spot.obj", 20}, {"fandisk.obj", 30}, {"blade.off", 60}}) {
    SCOPED_TRACE(name);
    const Mesh m = model(name);
    const VsaSurface s = prepare_surface(m, name);
    VsaOptions o;
    o.proxies = size_t(K);
    Partition p = vsa_partition(s, o);
    const double e_sums = test::energy_from_sums(m, p.label);
    const double e_def = test::energy_from_definition(m, p.label);
    const double tol = 1e-9 * s.total_area;
    // Eq. 7 (sums) and eq. 5 (the definition) agree, and so does limn's running total.
    EXPECT_NEAR(e_sums, e_def, tol);
    EXPECT_NEAR(p.energy(), e_sums, tol);
    EXPECT_GT(e_sums, 0);
    // Labels alone give the same partition energy again.
    EXPECT_NEAR(partition_from_labels(s, p.label, p.cluster_count()).energy(), e_sums, tol);
    // The driver's report is the same number.
    VsaStats st;
    vsa_partition(s, o, &st);
    EXPECT_NEAR(st.energy, e_sums, tol);
  }
}

TEST(SimplifyGreedy, EveryAcceptedMoveLowersTheEnergyAndKeepsClustersConnected) {
  // Random seeds make a poor start, so the optimiser has thousands of moves to make.
  const Mesh m = model("spot.obj");
  const VsaSurface s = prepare_surface(m);
  Partition p = seeded(s, 40, SeedingMethod::random, 7);
  const auto nb = test::face_neighbours(m);
  ASSERT_EQ(test::disconnected_clusters(nb, p.label), 0u);
  // The test's own sums, in long double from its own face vector areas.
  std::vector<test::LVec> fv(m.face_count());
  std::vector<long double> fa(m.face_count());
  std::vector<long double> S(p.cluster_count(), 0);
  std::vector<test::LVec> N(p.cluster_count());
  std::vector<uint32_t> labels = p.label;
  for (size_t f = 0; f < m.face_count(); ++f) {
    fv[f] = test::face_vector_area(m, f);
    fa[f] = std::sqrt(fv[f].x * fv[f].x + fv[f].y * fv[f].y + fv[f].z * fv[f].z);
    S[labels[f]] += fa[f];
    N[labels[f]].x += fv[f].x, N[labels[f]].y += fv[f].y, N[labels[f]].z += fv[f].z;
  }
  auto ce = [&](uint32_t k) {
    return 2 * (S[k] - std::sqrt(N[k].x * N[k].x + N[k].y * N[k].y + N[k].z * N[k].z));
  };
  size_t moves = 0, raised = 0, split = 0, mispredicted = 0;
  GreedyOptions go;
  go.on_move = [&](uint32_t f, uint32_t from, uint32_t to, double drop) {
    ++moves;
    ASSERT_EQ(labels[f], from);
    const long double before = ce(from) + ce(to);
    S[from] -= fa[f], S[to] += fa[f];
    N[from].x -= fv[f].x, N[from].y -= fv[f].y, N[from].z -= fv[f].z;
    N[to].x += fv[f].x, N[to].y += fv[f].y, N[to].z += fv[f].z;
    labels[f] = to;
    const long double after = ce(from) + ce(to);
    if (!(after < before)) ++raised;
    if (std::abs(double(before - after) - drop) > 1e-6 * double(fa[f]) + 1e-15) ++mispredicted;
    // The cluster the face left is still in one piece (BFS from one of its faces).
    uint32_t start = kNone;
    size_t members = 0;
    for (uint32_t g = 0; g < labels.size(); ++g)
      if (labels[g] == from) ++members, start = g;
    std::vector<uint8_t> seen(labels.size(), 0);
    std::vector<uint32_t> stack{start};
    seen[start] = 1;
    size_t reached = 1;
    while (!stack.empty()) {
      const uint32_t g = stack.back();
      stack.pop_back();
      for (uint32_t h : nb[g])
        if (!seen[h] && labels[h] == from) seen[h] = 1, ++reached, stack.push_back(h);
    }
    if (reached != members) ++split;
  };
  const double e0 = test::energy_from_sums(m, p.label);
  GreedyOptimizer g(s, p, go);
  const GreedyStats st = g.run();
  EXPECT_GT(moves, 500u);
  EXPECT_EQ(st.moves, moves);
  EXPECT_EQ(raised, 0u);
  EXPECT_EQ(split, 0u);
  EXPECT_EQ(mispredicted, 0u);
  EXPECT_EQ(labels, p.label);
  EXPECT_LT(test::energy_from_sums(m, p.label), e0);
  // Most connectivity questions are settled around the face, without a search.
  EXPECT_GT(st.local_checks, st.search_checks);
}

TEST(SimplifyGreedy, StopsWhereNoBoundaryMoveLowersTheEnergy) {
  for (const char* name : {"spot.obj", "fandisk.obj"}) {
    SCOPED_TRACE(name);
    const Mesh m = model(name);
    const VsaSurface s = prepare_surface(m);
    Partition p = seeded(s, 30, SeedingMethod::random, 3);
    GreedyOptions go;
    go.drift = 0;                 // exact: every change re-examines the cluster's boundary
    go.search_budget = 1u << 30;  // connectivity always decided, never refused for cost
    greedy_optimize(s, p, go);
    const auto nb = test::face_neighbours(m);
    std::map<uint32_t, std::pair<long double, test::LVec>> sums;
    std::vector<test::LVec> fv(m.face_count());
    for (size_t f = 0; f < m.face_count(); ++f) {
      fv[f] = test::face_vector_area(m, f);
      auto& [S, N] = sums[p.label[f]];
      S += std::sqrt(fv[f].x * fv[f].x + fv[f].y * fv[f].y + fv[f].z * fv[f].z);
      N.x += fv[f].x, N.y += fv[f].y, N.z += fv[f].z;
    }
    auto len = [](const test::LVec& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); };
    size_t improving = 0, checked = 0;
    for (uint32_t f = 0; f < m.face_count(); ++f)
      for (uint32_t g : nb[f]) {
        const uint32_t from = p.label[f], to = p.label[g];
        if (from == to) continue;
        ++checked;
        // Moving f into g's cluster: change of |N_from| + |N_to| (E drops by twice it).
        test::LVec a = sums[from].second, b = sums[to].second;
        const long double before = len(a) + len(b);
        a.x -= fv[f].x, a.y -= fv[f].y, a.z -= fv[f].z;
        b.x += fv[f].x, b.y += fv[f].y, b.z += fv[f].z;
        const long double gain = len(a) + len(b) - before;
        if (gain > 1e-9 * len(fv[f]) && !test::removal_disconnects(nb, p.label, f)) ++improving;
      }
    EXPECT_GT(checked, 100u);
    EXPECT_EQ(improving, 0u);
  }
}

TEST(SimplifyGreedy, ClustersAreEdgeConnectedAfterThePipeline) {
  for (const auto& [name, K] :
       {std::pair{"stanford-bunny.obj", 100}, {"blade.off", 50}, {"ogre.obj", 150}}) {
    SCOPED_TRACE(name);
    const Mesh m = model(name);
    const VsaSurface s = prepare_surface(m);
    VsaOptions o;
    o.proxies = size_t(K);
    const Partition p = vsa_partition(s, o);
    EXPECT_EQ(test::disconnected_clusters(test::face_neighbours(m), p.label), 0u);
    for (uint32_t l : p.label) ASSERT_LT(l, p.cluster_count());
    for (size_t k = 0; k < p.cluster_count(); ++k) EXPECT_GT(p.size[k], 0u);
  }
}

TEST(SimplifyCurvature, SphereIsOneOverRSquaredAndPlaneIsFlat) {
  const float r = 2.0f;
  const Mesh sphere = test::uv_sphere(40, 80, r);
  const VsaSurface s = prepare_surface(sphere);
  const std::vector<double> K = gaussian_curvature(s);
  size_t near = 0, n = 0;
  for (size_t v = 0; v < sphere.vertex_count(); ++v) {
    const float z = sphere.positions[3 * v + 2];
    if (std::abs(z) > 0.8f * r) continue;  // away from the poles' skinny triangles
    ++n;
    near += std::abs(K[v] - 1.0 / (r * r)) < 0.02 / (r * r);
  }
  EXPECT_GT(n, 1000u);
  EXPECT_EQ(near, n);
  // Plane: zero inside, zero on the boundary by definition.
  const Mesh plane = test::grid_mesh(6);
  const std::vector<double> K0 = gaussian_curvature(prepare_surface(plane));
  for (double k : K0) EXPECT_NEAR(k, 0.0, 1e-9);
  // The face value is the mean |K| of the corners.
  const std::vector<double> kf = face_abs_curvature(s, K);
  const auto f0 = sphere.face(100);
  EXPECT_NEAR(kf[100], (std::abs(K[f0[0]]) + std::abs(K[f0[1]]) + std::abs(K[f0[2]])) / 3, 1e-12);
}

// A cube whose sides are n x n grids of triangles (planar sides, sharp edges).
Mesh fine_cube(int n) {
  Mesh m;
  std::map<std::array<int, 3>, uint32_t> ids;
  auto vid = [&](int x, int y, int z) {
    auto [it, fresh] = ids.try_emplace({x, y, z}, 0u);
    if (fresh)
      it->second = m.add_vertex(float(x) / float(n), float(y) / float(n), float(z) / float(n));
    return it->second;
  };
  // Each side: origin corner, two in-plane axes (right-handed with the outward normal).
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

TEST(SimplifySeeding, PlanarRegionsBecomeOneClusterEach) {
  const Mesh cube = fine_cube(8);
  const VsaSurface s = prepare_surface(cube);
  ASSERT_EQ(s.components, 1u);
  SeedingOptions so;
  so.clusters = 6;
  SeedingStats st;
  Partition p = seed_partition(s, so, &st);
  EXPECT_EQ(st.clusters, 6u);
  EXPECT_EQ(st.left_over, 0u);
  EXPECT_NEAR(p.energy(), 0.0, 1e-9);
  // Each cluster is exactly one side: all its faces share one normal.
  for (uint32_t f = 0; f < cube.face_count(); ++f) {
    double n[3], c[3];
    s.normal(f, n);
    p.proxy_normal(p.label[f], c);
    ASSERT_NEAR(n[0] * c[0] + n[1] * c[1] + n[2] * c[2], 1.0, 1e-9);
  }
}

TEST(SimplifySeeding, CurvatureSeedingMakesAtMostKClustersAndFillReachesK) {
  const Mesh m = model("spot.obj");
  const VsaSurface s = prepare_surface(m);
  for (size_t K : {5u, 50u, 200u}) {
    SCOPED_TRACE(K);
    SeedingOptions so;
    so.clusters = K;
    SeedingStats st;
    Partition p = seed_partition(s, so, &st);
    EXPECT_LE(p.cluster_count(), K);
    EXPECT_GT(st.budget, 0);
    EXPECT_EQ(absorb_unassigned(s, p), 0u);  // one component, already seeded
    for (uint32_t l : p.label) ASSERT_NE(l, kUnassigned);
    EXPECT_EQ(test::disconnected_clusters(test::face_neighbours(m), p.label), 0u);
    VsaOptions o;
    o.proxies = K;
    VsaStats vs;
    const Partition full = vsa_partition(s, o, &vs);
    EXPECT_EQ(full.cluster_count(), K);
    EXPECT_EQ(vs.clusters, K);
    o.fill = false;
    o.teleports = 0;
    const Partition paper = vsa_partition(s, o, &vs);
    EXPECT_EQ(paper.cluster_count(), vs.seeded);  // Jin et al.: K becomes the number reached
  }
}

TEST(SimplifySeeding, RandomSeedingGivesKConnectedClusters) {
  const Mesh m = model("fandisk.obj");
  const VsaSurface s = prepare_surface(m);
  SeedingOptions so;
  so.clusters = 64;
  so.method = SeedingMethod::random;
  Partition p = seed_partition(s, so);
  EXPECT_EQ(p.cluster_count(), 64u);
  for (uint32_t l : p.label) ASSERT_NE(l, kUnassigned);
  EXPECT_EQ(test::disconnected_clusters(test::face_neighbours(m), p.label), 0u);
  // Another random seed, another partition.
  so.seed = 2;
  EXPECT_NE(seed_partition(s, so).label, p.label);
}

TEST(SimplifySeeding, EveryComponentGetsAClusterOfItsOwn) {
  const Mesh m = model("ogre.obj");
  const VsaSurface s = prepare_surface(m);
  // Components over edges (ogre's 44 by vertices are 45 by edges: one bowtie vertex joins two).
  const auto nb = test::face_neighbours(m);
  std::vector<uint32_t> comp(m.face_count(), kNone);
  size_t components = 0;
  for (uint32_t f0 = 0; f0 < m.face_count(); ++f0) {
    if (comp[f0] != kNone) continue;
    std::vector<uint32_t> stack{f0};
    comp[f0] = uint32_t(components);
    while (!stack.empty()) {
      const uint32_t f = stack.back();
      stack.pop_back();
      for (uint32_t g : nb[f])
        if (comp[g] == kNone) comp[g] = uint32_t(components), stack.push_back(g);
    }
    ++components;
  }
  EXPECT_EQ(s.components, components);
  VsaOptions o;
  o.proxies = 10;
  VsaStats st;
  const Partition p = vsa_partition(s, o, &st);
  EXPECT_GE(p.cluster_count(), components);
  EXPECT_EQ(st.clusters, p.cluster_count());
  EXPECT_EQ(st.component_clusters, p.cluster_count() - st.seeded - st.split_clusters);
  EXPECT_EQ(test::disconnected_clusters(nb, p.label), 0u);
  // No cluster spans two components.
  for (size_t k = 0; k < p.cluster_count(); ++k) {
    std::set<uint32_t> in;
    for (uint32_t f = 0; f < m.face_count(); ++f)
      if (p.label[f] == k) in.insert(comp[f]);
    EXPECT_EQ(in.size(), 1u) << k;
  }
}

TEST(SimplifyLloyd, RegionsStayConnectedAndTheEnergyIsTheSameMeasure) {
  const Mesh m = model("fandisk.obj");
  const VsaSurface s = prepare_surface(m);
  Partition p = seeded(s, 30, SeedingMethod::curvature);
  LloydOptions lo;
  lo.iterations = 12;
  const LloydStats st = lloyd_optimize(s, p, lo);
  EXPECT_GE(st.iterations, 1u);
  EXPECT_LE(st.iterations, 12u);
  ASSERT_EQ(st.energy.size(), st.iterations);
  EXPECT_NEAR(st.energy.back(), test::energy_from_sums(m, p.label), 1e-9 * s.total_area);
  EXPECT_EQ(p.cluster_count(), 30u);
  for (size_t k = 0; k < 30; ++k) EXPECT_GT(p.size[k], 0u);
  EXPECT_EQ(test::disconnected_clusters(test::face_neighbours(m), p.label), 0u);
}

TEST(SimplifyLloyd, StopsWhenAnIterationChangesNothing) {
  const Mesh cube = fine_cube(6);
  const VsaSurface s = prepare_surface(cube);
  // From the curvature seeding Lloyd settles on the six sides; run again, its first iteration
  // changes nothing and it stops there.
  Partition p = seeded(s, 6, SeedingMethod::curvature);
  LloydOptions lo;
  lo.iterations = 100;
  const LloydStats st = lloyd_optimize(s, p, lo);
  EXPECT_LT(st.iterations, 100u);
  EXPECT_NEAR(st.energy.back(), 0.0, 1e-9);
  const std::vector<uint32_t> settled = p.label;
  EXPECT_EQ(lloyd_optimize(s, p, lo).iterations, 1u);
  EXPECT_EQ(p.label, settled);
  lo.stop_when_stable = false;
  lo.iterations = 4;
  EXPECT_EQ(lloyd_optimize(s, p, lo).iterations, 4u);
}

TEST(SimplifyControls, TargetErrorAddsClustersUntilMet) {
  const Mesh m = model("spot.obj");
  const VsaSurface s = prepare_surface(m);
  for (VsaMethod method : {VsaMethod::greedy, VsaMethod::lloyd}) {
    VsaOptions o;
    o.proxies = 5;
    o.target_error = 0.05;
    o.method = method;
    o.lloyd.iterations = 5;
    VsaStats st;
    const Partition p = vsa_partition(s, o, &st);
    const double e = test::energy_from_sums(m, p.label);
    EXPECT_LE(e / s.total_area, 0.05);
    EXPECT_GT(p.cluster_count(), 5u);
    EXPECT_GT(st.split_clusters, 0u);
  }
}

TEST(SimplifyControls, TeleportsOnlyEverLowerTheEnergy) {
  const Mesh m = model("fandisk.obj");
  const VsaSurface s = prepare_surface(m);
  VsaOptions o;
  o.proxies = 30;
  o.teleports = 0;
  const double e0 = test::energy_from_sums(m, vsa_partition(s, o).label);
  o.teleports = 16;
  VsaStats st;
  const Partition p = vsa_partition(s, o, &st);
  EXPECT_EQ(p.cluster_count(), 30u);
  EXPECT_LE(test::energy_from_sums(m, p.label), e0 * (1 + 1e-9));
  EXPECT_EQ(test::disconnected_clusters(test::face_neighbours(m), p.label), 0u);
}

TEST(SimplifyInput, MeshesVsaCannotTakeAreInputErrors) {
  auto message = [](const Mesh& m) {
    try {
      prepare_surface(m, "bad.obj");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message(read_mesh(kData / "nonmanifold.obj")).find("non-manifold edge"),
            std::string::npos);
  Mesh flipped = test::grid_mesh(2);
  std::swap(flipped.face_vertices[1], flipped.face_vertices[2]);  // face 0 turned over
  EXPECT_NE(message(flipped).find("disagree on orientation"), std::string::npos);
  Mesh twice;
  for (float x : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) twice.positions.push_back(x);
  twice.add_face({0, 1, 2});
  twice.add_face({0, 2, 1});
  EXPECT_NE(message(twice).find("use the same vertices"), std::string::npos);
  EXPECT_NE(message(Mesh{}).find("no faces"), std::string::npos);
  for (const std::string& msg : {message(flipped), message(twice)})
    EXPECT_EQ(msg.rfind("bad.obj: ", 0), 0u) << msg;
}

}  // namespace
}  // namespace limn
