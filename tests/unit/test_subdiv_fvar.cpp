// Face-varying (UV) refinement against OpenSubdiv 3.5 (Far::PrimvarRefiner::InterpolateFace-
// Varying and LimitFaceVarying) on every shared cage with UVs, in each of the six
// FVarLinearInterpolation modes, and on cages built here with seams on purpose (a cube with an
// island per side, a torus cut by two seams, a seam that ends inside the surface).
//
// Corners are matched by position, not by index order: each level's vertices are paired with
// OpenSubdiv's by their refined positions, faces by their vertex sets, corners by their vertex.
// Then every corner's UV must agree to 1e-6.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/refine.hpp"
#include "limn/subdiv/tessellate.hpp"
#include "osd_oracle.hpp"
#include "seam_cages.hpp"

namespace limn {
namespace {

namespace fs = std::filesystem;

constexpr double kTolerance = 1e-6;

// limn vertex -> OpenSubdiv vertex of the same position (nearest within `tol`), or -1.
std::vector<int> match_vertices(const std::vector<float>& mine, const std::vector<double>& theirs,
                                double tol) {
  const size_t n = theirs.size() / 3;
  std::vector<int> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = int(i);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return theirs[3 * size_t(a)] < theirs[3 * size_t(b)]; });
  std::vector<double> xs(n);
  for (size_t i = 0; i < n; ++i) xs[i] = theirs[3 * size_t(order[i])];
  std::vector<int> out(mine.size() / 3, -1);
  for (size_t v = 0; v < out.size(); ++v) {
    const double x = mine[3 * v], y = mine[3 * v + 1], z = mine[3 * v + 2];
    double best = tol;
    auto it = std::lower_bound(xs.begin(), xs.end(), x - tol);
    for (; it != xs.end() && *it <= x + tol; ++it) {
      const size_t j = size_t(order[size_t(it - xs.begin())]);
      const double d = std::hypot(theirs[3 * j] - x, theirs[3 * j + 1] - y, theirs[3 * j + 2] - z);
      if (d <= best) best = d, out[v] = int(j);
    }
  }
  return out;
}

struct Result {
  size_t corners = 0, unmatched = 0;
  double worst = 0;
  std::string where;
};

// Compares limn's level-k UVs per corner with OpenSubdiv's.
// `uv` and `theirs` are the level's values (or their limits) on each side.
Result compare_level(const Mesh& cage, const UniformRefinement& r, const test::OsdFaceVarying& o,
                     size_t k, const std::vector<float>& uv,
                     const std::vector<test::OsdUv>& theirs) {
  Result res;
  const RefinedLevel& L = r.levels[k];
  const FaceVaryingLevels& fl = r.face_varying[0];
  const std::vector<float> pos = r.positions(cage, int(k));
  const auto& T = o.refiner->GetLevel(int(k));
  Box box = bounding_box(cage);
  const double tol = 1e-5 * std::max(1.0f, box.diagonal());
  const std::vector<int> vmap = match_vertices(pos, o.positions[k], tol);
  // OpenSubdiv faces by their sorted vertex sets.
  std::map<std::vector<int>, int> faces;
  for (int f = 0; f < T.GetNumFaces(); ++f) {
    const auto fv = T.GetFaceVertices(f);
    std::vector<int> key(fv.begin(), fv.end());
    std::sort(key.begin(), key.end());
    faces.emplace(key, f);
  }
  for (size_t f = 0; f < L.face_count(); ++f) {
    const uint32_t b = L.face_offsets[f], n = L.face_offsets[f + 1] - b;
    std::vector<int> key;
    for (uint32_t i = 0; i < n; ++i) key.push_back(vmap[L.face_vertices[b + i]]);
    std::sort(key.begin(), key.end());
    const auto it = faces.find(key);
    res.corners += n;
    if (it == faces.end() || key.front() < 0) {
      res.unmatched += n;
      continue;
    }
    const auto fv = T.GetFaceVertices(it->second);
    const auto fvals = T.GetFaceFVarValues(it->second, 0);
    for (uint32_t i = 0; i < n; ++i) {
      const int ov = vmap[L.face_vertices[b + i]];
      int j = 0;
      while (j < fv.size() && fv[j] != ov) ++j;
      const size_t mine = fl.corner_values[k][b + i];
      const test::OsdUv& t = theirs[size_t(fvals[j])];
      const double d = std::max(std::fabs(uv[2 * mine] - t.u), std::fabs(uv[2 * mine + 1] - t.v));
      if (d > res.worst) {
        res.worst = d;
        res.where = fmt::format(
            "level {} face {} corner {}: limn ({:.7g}, {:.7g}) osd ({:.7g}, "
            "{:.7g})",
            k, f, i, uv[2 * mine], uv[2 * mine + 1], t.u, t.v);
      }
    }
  }
  return res;
}

void check_cage(const Mesh& cage, int depth, FVarInterpolation mode) {
  SubdivOptions opt = subdiv_options(cage);
  opt.face_varying = mode;
  const FaceVaryingInput in{cage.uv_indices, cage.uvs.size() / 2, true};
  const UniformRefinement r = refine_uniform(cage, depth, opt, {&in, 1});
  const test::OsdFaceVarying o = test::osd_refine_uvs(cage, depth, opt);
  ASSERT_EQ(r.face_varying.size(), 1u);
  for (size_t k = 0; k <= size_t(depth); ++k) {
    EXPECT_EQ(r.face_varying[0].value_counts[k],
              size_t(o.refiner->GetLevel(int(k)).GetNumFVarValues(0)))
        << "value count, level " << k;
    const std::vector<float> uv = r.face_varying[0].values(cage.uvs.data(), 2, int(k));
    const Result res = compare_level(cage, r, o, k, uv, o.uvs[k]);
    EXPECT_EQ(res.unmatched, 0u) << "corners not matched by position at level " << k;
    EXPECT_LE(res.worst, kTolerance) << res.where;
  }
  // Limits of the last level's values.
  const FaceVaryingLevels& fl = r.face_varying[0];
  ASSERT_EQ(fl.limit.size(), fl.value_counts.back());
  const std::vector<float> last = fl.values(cage.uvs.data(), 2, depth);
  std::vector<float> limit(last.size());
  apply_stencils(fl.limit, last.data(), limit.data(), 2);
  const Result res = compare_level(cage, r, o, size_t(depth), limit, o.limit);
  EXPECT_LE(res.worst, kTolerance) << "limit: " << res.where;
}

std::vector<fs::path> cages_with_uvs() {
  std::vector<fs::path> out;
  for (const fs::path& p : test::shared_cages(LIMN_SHARED_MODELS)) {
    const Mesh m = read_mesh(p.string());
    if (!m.uv_indices.empty()) out.push_back(p);
  }
  return out;
}

struct Case {
  fs::path path;
  int mode;
};

// A test name for a case: the cage's stem and the mode.
std::string case_name(const ::testing::TestParamInfo<Case>& p) {
  std::string name = p.param.path.stem().string() + "_mode" + std::to_string(p.param.mode);
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

std::vector<Case> model_cases() {
  std::vector<Case> out;
  for (const fs::path& p : cages_with_uvs())
    for (int m = 0; m <= 5; ++m) out.push_back({p, m});
  return out;
}

class FVarModel : public ::testing::TestWithParam<Case> {};

TEST_P(FVarModel, MatchesOpenSubdiv) {
  const Mesh cage = read_mesh(GetParam().path.string());
  const int depth = cage.face_count() > 500 ? 2 : 3;
  check_cage(cage, depth, static_cast<FVarInterpolation>(GetParam().mode));
}

INSTANTIATE_TEST_SUITE_P(Models, FVarModel, ::testing::ValuesIn(model_cases()), case_name);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(FVarModel);

TEST(FVarModels, SharedCagesWithUvsPresent) {
  if (!fs::is_directory(fs::path(LIMN_SHARED_MODELS) / "osd")) GTEST_SKIP() << "no shared models";
  EXPECT_GE(cages_with_uvs().size(), 20u);
}

struct Built {
  const char* name;
  Mesh (*make)();
};

class FVarBuilt : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(FVarBuilt, MatchesOpenSubdiv) {
  static const Built built[] = {{"cube_islands", test::cube_islands},
                                {"torus_seams", test::torus_seams},
                                {"dart_grid", test::dart_grid}};
  const auto [which, mode] = GetParam();
  SCOPED_TRACE(built[which].name);
  const Mesh cage = built[which].make();
  validate(cage);
  check_cage(cage, 3, static_cast<FVarInterpolation>(mode));
}

INSTANTIATE_TEST_SUITE_P(Seams, FVarBuilt,
                         ::testing::Combine(::testing::Range(0, 3), ::testing::Range(0, 6)));

// The torus's seams really are seams: its cage has more UV values than vertices, and a
// junction where four meet.
TEST(FVarBuilt, TorusSeamsHaveAJunction) {
  const Mesh m = test::torus_seams();
  EXPECT_GT(m.uvs.size() / 2, m.vertex_count());
  std::map<uint32_t, std::set<uint32_t>> values;
  for (size_t c = 0; c < m.corner_count(); ++c) values[m.face_vertices[c]].insert(m.uv_indices[c]);
  size_t four = 0;
  for (const auto& [v, set] : values) four += set.size() == 4;
  EXPECT_EQ(four, 1u);
}

// Every adaptive level's UVs in one buffer (OpenSubdiv's patch tables index them so), with room
// for `extra` values after them.
std::vector<test::OsdUv> osd_level_uvs(const test::osd::Far::TopologyRefiner& refiner,
                                       const Mesh& cage, size_t extra) {
  std::vector<test::OsdUv> uv(size_t(refiner.GetNumFVarValuesTotal(0)) + extra);
  for (size_t i = 0; i < cage.uvs.size() / 2; ++i) uv[i] = {cage.uvs[2 * i], cage.uvs[2 * i + 1]};
  const test::osd::Far::PrimvarRefiner primvar(refiner);
  test::OsdUv* src = uv.data();
  for (int k = 1; k <= refiner.GetMaxLevel(); ++k) {
    test::OsdUv* dst = src + refiner.GetLevel(k - 1).GetNumFVarValues(0);
    primvar.InterpolateFaceVarying(k, src, dst, 0);
    src = dst;
  }
  return uv;
}

// A flat 4 x 4 grid of unit quads whose UVs are its (x, y).
Mesh flat_grid() {
  Mesh grid;
  const int n = 4;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) grid.add_vertex(float(x), float(y), 0.0f);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const uint32_t v = uint32_t((n + 1) * y + x);
      grid.add_face({v, v + 1, v + uint32_t(n) + 2, v + uint32_t(n) + 1});
    }
  for (size_t v = 0; v < grid.vertex_count(); ++v)
    grid.uvs.insert(grid.uvs.end(), {grid.positions[3 * v], grid.positions[3 * v + 1]});
  grid.uv_indices = grid.face_vertices;
  return grid;
}

// Adaptive surfaces, linear channel (FVarInterpolation::all, OpenSubdiv's default): UVs at ptex
// coordinates against OpenSubdiv's face-varying patch table (Far::PatchTableFactory with
// generateFVarTables, its legacy linear patches over InterpolateFaceVarying's values at every
// adaptive level, EvaluateBasisFaceVarying), values and derivatives.
void check_adaptive_linear(const Mesh& cage, int depth) {
  namespace osd = test::osd;
  SubdivOptions opt = subdiv_options(cage);
  opt.face_varying = FVarInterpolation::all;
  auto refiner = test::osd_refiner(cage, opt, true);
  osd::Far::PatchTableFactory::Options po(depth);
  po.generateFVarTables = true;
  po.SetEndCapType(osd::Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  refiner->RefineAdaptive(po.GetRefineAdaptiveOptions());
  std::unique_ptr<osd::Far::PatchTable> table(osd::Far::PatchTableFactory::Create(*refiner, po));
  ASSERT_TRUE(table);
  ASSERT_EQ(table->GetNumFVarChannels(), 1);
  const std::vector<test::OsdUv> uv = osd_level_uvs(*refiner, cage, 0);
  ASSERT_EQ(table->GetLocalPointFaceVaryingStencilTable(0) == nullptr ||
                table->GetLocalPointFaceVaryingStencilTable(0)->GetNumStencils() == 0,
            true)
      << "legacy linear face-varying patches need no local points";
  const osd::Far::PatchMap map(*table);
  const int nptex = osd::Far::PtexIndices(*refiner).GetNumFaces();
  std::vector<PtexCoord> coords;
  for (int p = 0; p < nptex; ++p)
    for (float u : {0.0f, 0.13f, 0.5f, 0.77f, 1.0f})
      for (float v : {0.0f, 0.31f, 0.5f, 0.94f}) coords.push_back({uint32_t(p), u, v});
  std::vector<float> mine(2 * coords.size()), mdu(2 * coords.size()), mdv(2 * coords.size());
  const FaceVaryingInput in{cage.uv_indices, cage.uvs.size() / 2};
  evaluate_linear_face_varying(cage, in, cage.uvs.data(), 2, coords, mine.data(), mdu.data(),
                               mdv.data());
  std::vector<uint8_t> quad_ptex;
  for (size_t f = 0; f < cage.face_count(); ++f)
    quad_ptex.insert(quad_ptex.end(), cage.face_size(f) == 4 ? 1 : cage.face_size(f),
                     cage.face_size(f) == 4);
  double worst = 0, worst_d = 0;
  size_t compared = 0;
  std::string where;
  for (size_t i = 0; i < coords.size(); ++i) {
    const auto* h = map.FindPatch(int(coords[i].ptex), coords[i].u, coords[i].v);
    if (!h) continue;  // a hole
    float w[20], wu[20], wv[20];
    table->EvaluateBasisFaceVarying(*h, coords[i].u, coords[i].v, w, wu, wv, nullptr, nullptr,
                                    nullptr, 0);
    const auto cvs = table->GetPatchFVarValues(*h, 0);
    double t[2] = {0, 0}, tu[2] = {0, 0}, tv[2] = {0, 0};
    for (int j = 0; j < cvs.size(); ++j) {
      const test::OsdUv& x = uv[size_t(cvs[j])];
      t[0] += w[j] * x.u, t[1] += w[j] * x.v;
      tu[0] += wu[j] * x.u, tu[1] += wu[j] * x.v;
      tv[0] += wv[j] * x.u, tv[1] += wv[j] * x.v;
    }
    ++compared;
    for (size_t k = 0; k < 2; ++k) {
      const double d = std::fabs(mine[2 * i + k] - t[k]);
      if (d > worst) {
        worst = d;
        where = fmt::format("ptex {} ({}, {}): limn ({:.7g}, {:.7g}) osd ({:.7g}, {:.7g})",
                            coords[i].ptex, coords[i].u, coords[i].v, mine[2 * i], mine[2 * i + 1],
                            t[0], t[1]);
      }
      // limn differentiates per ptex unit; OpenSubdiv, on the corner faces of a non-quad, per
      // unit of twice their size.
      const double unit = quad_ptex[coords[i].ptex] ? 1.0 : 2.0;
      worst_d = std::max({worst_d, std::fabs(unit * mdu[2 * i + k] - tu[k]),
                          std::fabs(unit * mdv[2 * i + k] - tv[k])});
    }
  }
  EXPECT_GT(compared, coords.size() / 3);
  EXPECT_LE(worst, kTolerance) << where;
  EXPECT_LE(worst_d, 1e-5);
}

// Adaptive surfaces, smooth channels (the other five modes): UVs at ptex coordinates against
// OpenSubdiv's own face-varying patches (PatchTableFactory with generateFVarLegacyLinearPatches
// off: regular patches and Gregory end caps over the channel's values and its local points),
// values and derivatives, on the same vertex patches (limn's options set as OpenSubdiv's).
std::string check_adaptive_smooth(const Mesh& cage, int depth, FVarInterpolation mode,
                                  bool inf_sharp, uint32_t batch_faces = 0) {
  namespace osd = test::osd;
  SubdivOptions opt = subdiv_options(cage);
  opt.face_varying = mode;
  auto refiner = test::osd_refiner(cage, opt, true);
  osd::Far::TopologyRefiner::AdaptiveOptions ao(depth);
  ao.useSingleCreasePatch = false;
  ao.useInfSharpPatch = inf_sharp;
  ao.considerFVarChannels = false;
  refiner->RefineAdaptive(ao);
  osd::Far::PatchTableFactory::Options po(depth);
  po.generateFVarTables = true;
  po.generateFVarLegacyLinearPatches = false;
  po.useInfSharpPatch = inf_sharp;
  po.useSingleCreasePatch = false;
  po.SetEndCapType(osd::Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  std::unique_ptr<osd::Far::PatchTable> table(osd::Far::PatchTableFactory::Create(*refiner, po));
  if (!table || table->GetNumFVarChannels() != 1) return "no face-varying channel from OpenSubdiv";
  // Every level's values, then the channel's local points (end caps).
  const auto* local = table->GetLocalPointFaceVaryingStencilTable<float>(0);
  const size_t refined = size_t(refiner->GetNumFVarValuesTotal(0));
  std::vector<test::OsdUv> uv =
      osd_level_uvs(*refiner, cage, local ? size_t(local->GetNumStencils()) : 0);
  for (int i = 0; local && i < local->GetNumStencils(); ++i) {
    const auto st = local->GetStencil(i);
    double acc[2] = {0, 0};
    for (int j = 0; j < st.GetSize(); ++j) {
      const test::OsdUv& x = uv[size_t(st.GetVertexIndices()[j])];
      acc[0] += double(st.GetWeights()[j]) * x.u, acc[1] += double(st.GetWeights()[j]) * x.v;
    }
    uv[refined + size_t(i)] = {float(acc[0]), float(acc[1])};
  }
  PatchOptions lo;
  lo.subdiv = opt;
  lo.depth = depth;
  lo.inf_sharp_patches = inf_sharp;
  lo.single_crease_patches = false;
  lo.batch_faces = batch_faces;
  const PatchTable mine_table = build_patches(cage, lo);
  if (int(mine_table.patch_count()) != table->GetNumPatchesTotal())
    return fmt::format("{} vertex patches, OpenSubdiv {}", mine_table.patch_count(),
                       table->GetNumPatchesTotal());
  const FaceVaryingInput in{cage.uv_indices, cage.uvs.size() / 2};
  const FaceVaryingPatches fvp = build_face_varying_patches(cage, mine_table, in, lo);
  const osd::Far::PatchMap map(*table);
  const int nptex = osd::Far::PtexIndices(*refiner).GetNumFaces();
  std::vector<PtexCoord> coords;
  for (int p = 0; p < nptex; ++p)
    for (float u : {0.0f, 0.13f, 0.5f, 0.77f, 1.0f})
      for (float v : {0.0f, 0.31f, 0.5f, 0.94f}) coords.push_back({uint32_t(p), u, v});
  std::vector<PtexCoord> covered;
  std::vector<const osd::Far::PatchTable::PatchHandle*> handles;
  for (const PtexCoord& c : coords)
    if (const auto* h = map.FindPatch(int(c.ptex), c.u, c.v))
      covered.push_back(c), handles.push_back(h);
  const size_t n = covered.size();
  std::vector<float> mine(2 * n), mdu(2 * n), mdv(2 * n);
  evaluate_face_varying(cage, in, fvp, cage.uvs.data(), 2, covered, mine.data(), mdu.data(),
                        mdv.data());
  std::vector<uint8_t> quad_ptex;
  for (size_t f = 0; f < cage.face_count(); ++f)
    quad_ptex.insert(quad_ptex.end(), cage.face_size(f) == 4 ? 1 : cage.face_size(f),
                     cage.face_size(f) == 4);
  double worst = 0, worst_d = 0;
  std::string where, where_d;
  for (size_t i = 0; i < n; ++i) {
    float w[20], wu[20], wv[20];
    table->EvaluateBasisFaceVarying(*handles[i], covered[i].u, covered[i].v, w, wu, wv, nullptr,
                                    nullptr, nullptr, 0);
    const auto cvs = table->GetPatchFVarValues(*handles[i], 0);
    double t[2] = {0, 0}, tu[2] = {0, 0}, tv[2] = {0, 0};
    for (int j = 0; j < cvs.size(); ++j) {
      const test::OsdUv& x = uv[size_t(cvs[j])];
      t[0] += w[j] * x.u, t[1] += w[j] * x.v;
      tu[0] += wu[j] * x.u, tu[1] += wu[j] * x.v;
      tv[0] += wv[j] * x.u, tv[1] += wv[j] * x.v;
    }
    const double unit = quad_ptex[covered[i].ptex] ? 1.0 : 2.0;
    for (size_t k = 0; k < 2; ++k) {
      const double d = std::fabs(mine[2 * i + k] - t[k]);
      if (d > worst) {
        worst = d;
        const PatchCoord lc = PatchMap(fvp.table).find(covered[i].ptex, covered[i].u, covered[i].v);
        const bool end_cap = lc.patch >= fvp.table.regular_params.size();
        where = fmt::format(
            "ptex {} ({}, {}): limn ({:.7g}, {:.7g}) from {}, osd ({:.7g}, {:.7g}) from {}",
            covered[i].ptex, covered[i].u, covered[i].v, mine[2 * i], mine[2 * i + 1],
            end_cap ? "an end cap" : "a B-spline patch", t[0], t[1],
            cvs.size() == 20 ? "an end cap" : "a B-spline patch");
      }
      // OpenSubdiv differentiates end caps approximately (test_subdiv_patches.cpp): compare
      // derivatives on regular patches only.
      if (cvs.size() != 16) continue;
      const double dd = std::max(std::fabs(unit * mdu[2 * i + k] - tu[k]),
                                 std::fabs(unit * mdv[2 * i + k] - tv[k]));
      if (dd > worst_d)
        worst_d = dd,
        where_d = fmt::format("ptex {} ({}, {}), {} cvs: du {} vs {}, dv {} vs {}", covered[i].ptex,
                              covered[i].u, covered[i].v, cvs.size(), unit * mdu[2 * i + k], tu[k],
                              unit * mdv[2 * i + k], tv[k]);
    }
  }
  if (n < coords.size() / 3)
    return fmt::format("only {} of {} coordinates covered", n, coords.size());
  if (worst > kTolerance) return fmt::format("worst {:.3g} at {}", worst, where);
  if (worst_d > 1e-4)
    return fmt::format("worst derivative difference {:.3g} at {}", worst_d, where_d);
  return "";
}

class FVarAdaptiveSmooth : public ::testing::TestWithParam<Case> {};

TEST_P(FVarAdaptiveSmooth, UvsMatchOpenSubdivsPatches) {
  const Mesh cage = read_mesh(GetParam().path);
  for (bool inf_sharp : {false, true})
    EXPECT_EQ(check_adaptive_smooth(cage, 3, FVarInterpolation(GetParam().mode), inf_sharp), "")
        << "inf_sharp_patches " << inf_sharp;
  // Small batches: the channel's mesh is made in blocks of 16 vertices whose seams, creases and
  // holes cross blocks, and the tables in regions.
  EXPECT_EQ(check_adaptive_smooth(cage, 3, FVarInterpolation(GetParam().mode), true, 16), "")
      << "batches of 16";
}

std::vector<Case> smooth_cases() {
  std::vector<Case> out;
  for (const Case& c : model_cases())
    if (c.mode != int(FVarInterpolation::all)) out.push_back(c);
  return out;
}

INSTANTIATE_TEST_SUITE_P(Models, FVarAdaptiveSmooth, ::testing::ValuesIn(smooth_cases()),
                         case_name);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(FVarAdaptiveSmooth);

// Region builds (large cages are cut into batches of faces) replay the vertex table's regions'
// refinement: the same patches, held to OpenSubdiv the same way.
TEST(FVarAdaptiveBuilt, RegionBuildsMatchOpenSubdivsPatches) {
  for (const char* name : {"osd/catmark_car.obj", "quads/monsterfrog.obj"}) {
    const fs::path path = fs::path(LIMN_SHARED_MODELS) / name;
    if (!fs::exists(path)) GTEST_SKIP() << "no shared models";
    const Mesh cage = read_mesh(path);
    for (int mode : {0, 3})
      EXPECT_EQ(check_adaptive_smooth(cage, 3, FVarInterpolation(mode), true, 64), "")
          << name << " mode " << mode;
  }
}

TEST(FVarAdaptiveBuilt, SmoothSeamCagesMatchOpenSubdivsPatches) {
  for (const Mesh& cage : {test::cube_islands(), test::torus_seams(), test::dart_grid()})
    for (int mode = 0; mode < 5; ++mode)
      for (bool inf_sharp : {false, true})
        for (uint32_t batch : {0u, 8u})
          EXPECT_EQ(check_adaptive_smooth(cage, 4, FVarInterpolation(mode), inf_sharp, batch), "")
              << "mode " << mode << " inf_sharp_patches " << inf_sharp << " batch " << batch;
}

class FVarAdaptive : public ::testing::TestWithParam<fs::path> {};

TEST_P(FVarAdaptive, LinearUvsMatchOpenSubdivsPatches) {
  const Mesh cage = read_mesh(GetParam());
  check_adaptive_linear(cage, 3);
}

INSTANTIATE_TEST_SUITE_P(Models, FVarAdaptive, ::testing::ValuesIn(cages_with_uvs()),
                         [](const ::testing::TestParamInfo<fs::path>& p) {
                           std::string name = p.param.stem().string();
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(FVarAdaptive);

TEST(FVarAdaptiveBuilt, SeamCagesMatchOpenSubdivsPatches) {
  for (const Mesh& cage : {test::cube_islands(), test::torus_seams(), test::dart_grid()})
    check_adaptive_linear(cage, 4);
}

// Tessellated adaptive surfaces carry linear UVs. On a flat regular grid whose UVs are its
// (x, y), the limit surface is the bilinear map itself (B-splines reproduce linear functions,
// the boundary rule too), so every corner's UV must equal its vertex's position.
TEST(FVarAdaptiveBuilt, TessellatedUvsFollowAFlatGrid) {
  const Mesh grid = flat_grid();
  PatchOptions po;
  po.subdiv = subdiv_options(grid);
  po.depth = 2;
  const PatchTable table = build_patches(grid, po);
  TessellateOptions to;
  to.factor = 5;
  const Mesh out = tessellate_patches(grid, table, table.points(grid.positions), to);
  ASSERT_EQ(out.uv_indices.size(), out.corner_count());
  double worst = 0;
  for (size_t c = 0; c < out.corner_count(); ++c)
    for (size_t k = 0; k < 2; ++k)
      worst = std::max(worst, double(std::fabs(out.uvs[2 * out.uv_indices[c] + k] -
                                               out.positions[3 * out.face_vertices[c] + k])));
  EXPECT_LE(worst, 1e-5);
  // No seams on this grid: one UV per vertex.
  EXPECT_EQ(out.uvs.size() / 2, out.vertex_count());
}

// evaluate_face_varying_grids follows evaluate_grids point for point. On a flat regular grid
// whose UVs are its (x, y), B-splines and the boundary rules reproduce linear functions, so
// wherever the corners are pinned (modes 1-5) every grid point's UV is its limit position's
// (x, y), and the derivatives are the position's.
TEST(FVarAdaptiveBuilt, GridUvsFollowAFlatGrid) {
  const Mesh grid = flat_grid();
  const FaceVaryingInput in{grid.uv_indices, grid.uvs.size() / 2};
  for (int mode = 1; mode <= 5; ++mode) {
    PatchOptions po;
    po.subdiv = subdiv_options(grid);
    po.subdiv.face_varying = FVarInterpolation(mode);
    po.depth = 2;
    const PatchTable table = build_patches(grid, po);
    const FaceVaryingPatches fvp = build_face_varying_patches(grid, table, in, po);
    const int n = 5;
    const size_t total = size_t(table.ptex_count) * n * n;
    std::vector<float> pos(3 * total), pu(3 * total), pv(3 * total);
    std::vector<float> uv(2 * total), uu(2 * total), uvv(2 * total);
    evaluate_grids(table, table.points(grid.positions), n, pos.data(), pu.data(), pv.data());
    evaluate_face_varying_grids(grid, in, fvp, grid.uvs.data(), 2, n, uv.data(), uu.data(),
                                uvv.data());
    double worst = 0;
    for (size_t i = 0; i < total; ++i)
      for (size_t k = 0; k < 2; ++k)
        worst = std::max({worst, double(std::fabs(uv[2 * i + k] - pos[3 * i + k])),
                          double(std::fabs(uu[2 * i + k] - pu[3 * i + k])),
                          double(std::fabs(uvv[2 * i + k] - pv[3 * i + k]))});
    EXPECT_LE(worst, 1e-4) << "mode " << mode;
  }
}

// FaceVaryingPatches::points takes any three components of a wider channel. Its rows are affine
// combinations (weights summing to one), so a component that is twice another stays twice it
// and a constant stays constant, on every point of the car's table, seams and end caps included.
TEST(FVarAdaptiveBuilt, PointsTakeAnyComponentsOfAWideChannel) {
  const fs::path path = fs::path(LIMN_SHARED_MODELS) / "osd/catmark_car.obj";
  if (!fs::exists(path)) GTEST_SKIP() << "no shared models";
  const Mesh cage = read_mesh(path);
  const FaceVaryingInput in{cage.uv_indices, cage.uvs.size() / 2};
  PatchOptions po;
  po.subdiv = subdiv_options(cage);
  po.subdiv.face_varying = FVarInterpolation::none;
  const FaceVaryingPatches fvp = build_face_varying_patches(cage, build_patches(cage, po), in, po);
  std::vector<float> wide;  // (u, v, 2u, 7) per value
  for (size_t x = 0; x < in.value_count; ++x)
    wide.insert(wide.end(), {cage.uvs[2 * x], cage.uvs[2 * x + 1], 2 * cage.uvs[2 * x], 7.0f});
  const std::vector<float> uv = fvp.points(cage.uvs.data(), 2);
  const std::vector<float> first = fvp.points(wide.data(), 4);
  const std::vector<float> last = fvp.points(wide.data(), 4, 3);
  ASSERT_EQ(uv.size(), 3 * fvp.table.point_count());
  ASSERT_EQ(first.size(), uv.size());
  ASSERT_EQ(last.size(), uv.size());
  double worst = 0;
  for (size_t i = 0; i < uv.size(); i += 3) {
    EXPECT_EQ(uv[i + 2], 0.0f);
    worst = std::max(
        {worst, double(std::fabs(first[i] - uv[i])), double(std::fabs(first[i + 1] - uv[i + 1])),
         double(std::fabs(first[i + 2] - 2 * uv[i])), double(std::fabs(last[i] - 7.0f)),
         double(std::fabs(last[i + 1])), double(std::fabs(last[i + 2]))});
  }
  EXPECT_LE(worst, 1e-5);
}

// Smooth channels are tessellated through their face-varying patches: every corner's UV is
// evaluate_face_varying's at its ptex coordinate (independent: the corner's place is found again
// from its position on the flat grid), and seams keep one UV per side.
TEST(FVarAdaptiveBuilt, TessellatedSmoothUvsAreTheirPatches) {
  for (const Mesh& cage : {test::cube_islands(), test::torus_seams()})
    for (int mode : {0, 2, 4}) {
      PatchOptions po;
      po.subdiv = subdiv_options(cage);
      po.subdiv.face_varying = FVarInterpolation(mode);
      po.depth = 2;
      const PatchTable table = build_patches(cage, po);
      const FaceVaryingInput in{cage.uv_indices, cage.uvs.size() / 2};
      const FaceVaryingPatches fvp = build_face_varying_patches(cage, table, in, po);
      ASSERT_GT(fvp.table.patch_count(), 0u);
      TessellateOptions to;
      to.factor = 3;
      const Mesh out = tessellate_patches(cage, table, table.points(cage.positions), to);
      ASSERT_EQ(out.uv_indices.size(), out.corner_count());
      EXPECT_GT(out.uvs.size() / 2, out.vertex_count()) << "seams keep a UV per side";
      // Each output UV must be some patch's value at that vertex: evaluate at all the vertex's
      // patch coordinates via the vertex table and compare with the nearest.
      std::vector<PtexCoord> grid_at;
      for (uint32_t p = 0; p < table.ptex_count; ++p)
        for (int i = 0; i <= 6; ++i)
          for (int j = 0; j <= 6; ++j) grid_at.push_back({p, float(i) / 6, float(j) / 6});
      std::vector<float> uv(2 * grid_at.size()), pos(3 * grid_at.size());
      evaluate_face_varying(cage, in, fvp, cage.uvs.data(), 2, grid_at, uv.data());
      const PatchMap map(table);
      std::vector<PatchCoord> pc;
      for (const PtexCoord& c : grid_at) pc.push_back(map.find(c.ptex, c.u, c.v));
      evaluate_patches(table, table.points(cage.positions), pc, pos.data());
      // Grid points sorted by x, so each corner looks only at those within reach.
      std::vector<size_t> by_x(grid_at.size());
      for (size_t g = 0; g < by_x.size(); ++g) by_x[g] = g;
      std::sort(by_x.begin(), by_x.end(),
                [&](size_t x, size_t y) { return pos[3 * x] < pos[3 * y]; });
      double worst = 0;
      size_t matched = 0;
      for (size_t c = 0; c < out.corner_count(); ++c) {
        const float* p = &out.positions[3 * out.face_vertices[c]];
        const float* t = &out.uvs[2 * out.uv_indices[c]];
        double best = 1e9;
        auto it = std::lower_bound(by_x.begin(), by_x.end(), p[0] - 1e-5f,
                                   [&](size_t g, float x) { return pos[3 * g] < x; });
        for (; it != by_x.end() && pos[3 * *it] <= p[0] + 1e-5f; ++it) {
          const size_t g = *it;
          if (std::hypot(pos[3 * g] - p[0], pos[3 * g + 1] - p[1], pos[3 * g + 2] - p[2]) > 1e-5)
            continue;
          best = std::min(best, std::hypot(double(uv[2 * g] - t[0]), double(uv[2 * g + 1] - t[1])));
        }
        if (best < 1e9) worst = std::max(worst, best), ++matched;
      }
      EXPECT_GT(matched, out.corner_count() / 8) << "mode " << mode;
      EXPECT_LE(worst, 1e-5) << "mode " << mode;
    }
}

// On the seamed torus, a vertex on a seam carries one UV per side.
TEST(FVarAdaptiveBuilt, TessellationKeepsSeams) {
  const Mesh cage = test::torus_seams();
  PatchOptions po;
  po.subdiv = subdiv_options(cage);
  po.depth = 2;
  const PatchTable table = build_patches(cage, po);
  TessellateOptions to;
  to.factor = 2;
  const Mesh out = tessellate_patches(cage, table, table.points(cage.positions), to);
  ASSERT_EQ(out.uv_indices.size(), out.corner_count());
  EXPECT_GT(out.uvs.size() / 2, out.vertex_count());
  for (float x : out.uvs) EXPECT_TRUE(x >= -1e-6f && x <= 2.0f + 1e-6f);
}

// The lean path (subdivide_uniform) carries the UVs, per-corner normals (renormalised) and
// vertex colours of refine_uniform, corner by corner, holes dropped on both.
TEST(FVarLean, CarriesWhatRefineUniformComputes) {
  std::vector<Mesh> cages = {test::torus_seams(), test::dart_grid()};
  const fs::path holes = fs::path(LIMN_SHARED_MODELS) / "osd" / "catmark_hole_test3.obj";
  if (fs::exists(holes)) cages.push_back(read_mesh(holes));
  for (Mesh& cage : cages) {
    cage.colors.resize(4 * cage.vertex_count());
    for (size_t i = 0; i < cage.colors.size(); ++i) cage.colors[i] = float(i % 7) / 7.0f;
    cage.normals = {0, 0, 1, 0, 1, 0, 1, 0, 0};
    cage.normal_indices.assign(cage.corner_count(), 0);
    for (size_t c = 0; c < cage.corner_count(); ++c) cage.normal_indices[c] = uint32_t(c % 3);
    for (int mode : {0, 3, 5}) {
      SubdivOptions opt = subdiv_options(cage);
      opt.face_varying = FVarInterpolation(mode);
      const FaceVaryingInput in[2] = {{cage.uv_indices, cage.uvs.size() / 2},
                                      {cage.normal_indices, 3}};
      for (int depth : {0, 2}) {
        const UniformRefinement r = refine_uniform(cage, depth, opt, in);
        const Mesh lean = subdivide_uniform(cage, depth, opt);
        const RefinedLevel& L = r.levels.back();
        const std::vector<float> uv = r.face_varying[0].values(cage.uvs.data(), 2, depth);
        const std::vector<float> nrm = r.face_varying[1].values(cage.normals.data(), 3, depth);
        ASSERT_EQ(lean.uv_indices.size(), lean.corner_count());
        ASSERT_EQ(lean.normal_indices.size(), lean.corner_count());
        size_t c = 0;
        double worst_uv = 0, worst_n = 0;
        for (size_t f = 0; f < L.face_count(); ++f) {
          if (L.face_hole[f]) continue;
          for (uint32_t i = L.face_offsets[f]; i < L.face_offsets[f + 1]; ++i, ++c) {
            ASSERT_EQ(lean.face_vertices[c], L.face_vertices[i]);
            const size_t a = r.face_varying[0].corner_values.back()[i], b = lean.uv_indices[c];
            for (size_t k = 0; k < 2; ++k)
              worst_uv = std::max(worst_uv, double(std::fabs(uv[2 * a + k] - lean.uvs[2 * b + k])));
            const size_t na = r.face_varying[1].corner_values.back()[i],
                         nb = lean.normal_indices[c];
            const double len = std::hypot(nrm[3 * na], nrm[3 * na + 1], nrm[3 * na + 2]);
            for (size_t k = 0; k < 3; ++k)
              worst_n =
                  std::max(worst_n, std::fabs(nrm[3 * na + k] / len - lean.normals[3 * nb + k]));
          }
        }
        EXPECT_EQ(c, lean.corner_count());
        EXPECT_LE(worst_uv, 1e-6) << "mode " << mode << " depth " << depth;
        EXPECT_LE(worst_n, 1e-6) << "mode " << mode << " depth " << depth;
        // Colours follow the vertex stencils.
        std::vector<float> col = cage.colors, next;
        for (const StencilTable& t : r.stencils) {
          next.assign(4 * t.size(), 0.0f);
          apply_stencils(t, col.data(), next.data(), 4);
          col.swap(next);
        }
        ASSERT_EQ(lean.colors.size(), col.size());
        for (size_t i = 0; i < col.size(); ++i) ASSERT_NEAR(lean.colors[i], col[i], 1e-6);
      }
    }
  }
}

}  // namespace
}  // namespace limn

namespace limn {
namespace {

// limn info's seam count: the cube of six islands has every edge a seam; the seamed torus's
// seams are its two cut circles; a cage with one UV per vertex has none.
TEST(FVarInfo, SeamEdgesAreCounted) {
  const Mesh cube = test::cube_islands();
  EXPECT_EQ(analyze(cube, build_topology(cube)).uv_seam_edges, 12u);
  EXPECT_EQ(analyze(cube, build_topology(cube)).uv_values, 24u);
  const Mesh torus = test::torus_seams();
  const MeshStats ts = analyze(torus, build_topology(torus));
  // Brute force: edges (as vertex pairs) whose faces see different UVs at an end.
  std::map<std::pair<uint32_t, uint32_t>, std::vector<std::pair<uint32_t, uint32_t>>> sides;
  for (size_t f = 0; f < torus.face_count(); ++f) {
    const uint32_t b = torus.face_offsets[f], n = torus.face_size(f);
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t c = b + i, d = b + (i + 1) % n;
      uint32_t x = torus.face_vertices[c], y = torus.face_vertices[d];
      uint32_t ux = torus.uv_indices[c], uy = torus.uv_indices[d];
      if (x > y) std::swap(x, y), std::swap(ux, uy);
      sides[{x, y}].push_back({ux, uy});
    }
  }
  size_t seams = 0;
  for (const auto& [e, s] : sides) seams += s.size() == 2 && s[0] != s[1];
  EXPECT_EQ(ts.uv_seam_edges, seams);
  EXPECT_GT(seams, 0u);
  Mesh plain = make_cube();
  plain.uvs.assign(2 * plain.vertex_count(), 0.5f);
  plain.uv_indices = plain.face_vertices;
  EXPECT_EQ(analyze(plain, build_topology(plain)).uv_seam_edges, 0u);
}

}  // namespace
}  // namespace limn
