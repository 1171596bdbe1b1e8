// limn's VSA against CGAL 5.5's Variational_shape_approximation, run here: L21 metric,
// hierarchical seeding, 30 iterations, meshes scaled to a unit bounding-box diagonal. Both
// energies are recomputed the same independent way from each side's face labels.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "cgal_vsa.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/simplify/vsa.hpp"
#include "simplify_oracle.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;
const fs::path kModels = LIMN_SHARED_MODELS;

class SimplifyCgal : public ::testing::TestWithParam<std::pair<const char*, size_t>> {};

TEST_P(SimplifyCgal, EnergyIsAtMostTwoPercentAboveCgals) {
  const auto [file, K] = GetParam();
  const Mesh m = test::unit_diagonal(read_mesh(kModels / "tri" / file));
  const test::CgalVsaResult cgal = test::run_cgal_vsa(m, K, 30, false);
  ASSERT_EQ(cgal.labels.size(), m.face_count());
  const double e_cgal = test::energy_from_sums(m, cgal.labels);
  // limn with its defaults (the CLI's), at the same K.
  const VsaSurface s = prepare_surface(m, file);
  VsaOptions o;
  o.proxies = K;
  const Partition p = vsa_partition(s, o);
  EXPECT_EQ(p.cluster_count(), K);
  EXPECT_EQ(cgal.proxies, K);
  const double e_limn = test::energy_from_sums(m, p.label);
  RecordProperty("energy_limn", std::to_string(e_limn));
  RecordProperty("energy_cgal", std::to_string(e_cgal));
  EXPECT_LE(e_limn, 1.02 * e_cgal) << "limn " << e_limn << " CGAL " << e_cgal;
  EXPECT_GT(e_limn, 0);
}

// The seed's two cases (fandisk K=30, bunny K=100), and each model at the other's K so the bound
// is also checked away from the one K per model it was first measured at.
INSTANTIATE_TEST_SUITE_P(Seed003, SimplifyCgal,
                         ::testing::Values(std::pair{"fandisk.obj", size_t(30)},
                                           std::pair{"stanford-bunny.obj", size_t(100)},
                                           std::pair{"fandisk.obj", size_t(100)},
                                           std::pair{"stanford-bunny.obj", size_t(30)}),
                         [](const auto& param_info) {
                           std::string n = param_info.param.first;
                           n = n.substr(0, n.find('.'));
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n + "_K" + std::to_string(param_info.param.second);
                         });

}  // namespace
}  // namespace limn
