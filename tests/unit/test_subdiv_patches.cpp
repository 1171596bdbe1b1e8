// Feature-adaptive patch tables against OpenSubdiv's adaptive PatchTable (same isolation level,
// Gregory-basis end caps), evaluated on a grid of every ptex face.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numbers>
#include <string>
#include <tuple>

#include "deep_reference.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/tessellate.hpp"
#include "osd_oracle.hpp"
#include "random_cage.hpp"

namespace limn {
namespace {

namespace osd = test::osd;

// OpenSubdiv's adaptive surface: patch table, all refined points and its local (end-cap) points.
struct OsdAdaptive {
  std::unique_ptr<osd::Far::TopologyRefiner> refiner;
  std::unique_ptr<osd::Far::PatchTable> table;
  std::vector<test::OsdPoint> points;  // refined vertices of every level, then local points
  int ptex_faces = 0;
};

OsdAdaptive osd_adaptive(const Mesh& cage, int depth, const SubdivOptions& options,
                         bool inf_sharp) {
  OsdAdaptive a;
  a.refiner = test::osd_refiner(cage, options);
  osd::Far::TopologyRefiner::AdaptiveOptions ao(depth);
  ao.useSingleCreasePatch = false;
  ao.useInfSharpPatch = inf_sharp;
  ao.considerFVarChannels = false;
  a.refiner->RefineAdaptive(ao);
  osd::Far::PatchTableFactory::Options po(depth);
  po.SetEndCapType(osd::Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  po.useInfSharpPatch = inf_sharp;
  po.useSingleCreasePatch = false;
  a.table.reset(osd::Far::PatchTableFactory::Create(*a.refiner, po));
  const int nrefined = a.refiner->GetNumVerticesTotal();
  const int nlocal = a.table->GetNumLocalPoints();
  a.points.resize(size_t(nrefined + nlocal));
  for (size_t v = 0; v < cage.vertex_count(); ++v)
    a.points[v] = {cage.positions[3 * v], cage.positions[3 * v + 1], cage.positions[3 * v + 2]};
  const osd::Far::PrimvarRefiner primvar(*a.refiner);
  test::OsdPoint* src = a.points.data();
  for (int k = 1; k <= a.refiner->GetMaxLevel(); ++k) {
    test::OsdPoint* dst = src + a.refiner->GetLevel(k - 1).GetNumVertices();
    primvar.Interpolate(k, src, dst);
    src = dst;
  }
  if (nlocal) a.table->ComputeLocalPointValues(a.points.data(), a.points.data() + nrefined);
  a.ptex_faces = osd::Far::PtexIndices(*a.refiner).GetNumFaces();
  return a;
}

// 1 for each ptex face some patch covers (hole faces have none).
std::vector<uint8_t> covered_ptex(const PatchTable& table) {
  std::vector<uint8_t> covered(table.ptex_count, 0);
  for (const auto* params : {&table.regular_params, &table.gregory_params})
    for (const PatchParam& p : *params) covered[p.ptex] = 1;
  return covered;
}

double bbox_diagonal(const Mesh& m) {
  return bounding_box(m).diagonal();
}

struct Comparison {
  double max_position = 0;  // relative to the bbox diagonal
  double max_normal = 0;    // |n_limn - n_osd|
  size_t samples = 0;
  std::string worst;
};

// `oracle_cage`: OpenSubdiv refines this cage instead (the same cage with other hole tags);
// only the ptex faces limn covers are compared.
Comparison compare_with_osd(const Mesh& cage, int depth, const SubdivOptions& options,
                            bool inf_sharp = false, const Mesh* oracle_cage = nullptr) {
  const OsdAdaptive ref =
      osd_adaptive(oracle_cage ? *oracle_cage : cage, depth, options, inf_sharp);
  PatchOptions po;
  po.subdiv = options;
  po.depth = depth;
  po.inf_sharp_patches = inf_sharp;
  po.single_crease_patches = false;  // OpenSubdiv's CPU evaluation ignores crease sharpness
  const PatchTable table = build_patches(cage, po);
  EXPECT_EQ(int(table.ptex_count), ref.ptex_faces);
  if (!oracle_cage) {
    EXPECT_EQ(int(table.patch_count()), ref.table->GetNumPatchesTotal());
  }
  const std::vector<uint8_t> covered = covered_ptex(table);
  const std::vector<float> pts = table.points(cage.positions);
  const PatchMap map(table);
  const osd::Far::PatchMap osd_map(*ref.table);

  static constexpr double kUV[] = {0.0, 0.13, 0.37, 0.5, 0.71, 0.96, 1.0};
  std::vector<PatchCoord> coords;
  std::vector<double> expected, expected_n;
  std::vector<std::string> where;
  for (uint32_t ptex = 0; ptex < table.ptex_count; ++ptex)
    if (covered[ptex])
      for (double u : kUV)
        for (double v : kUV) {
          const osd::Far::PatchTable::PatchHandle* h = osd_map.FindPatch(int(ptex), u, v);
          if (!h) continue;  // a hole
          double wp[20], wu[20], wv[20];
          ref.table->EvaluateBasis(*h, u, v, wp, wu, wv);
          const auto cvs = ref.table->GetPatchVertices(*h);
          double p[3] = {}, du[3] = {}, dv[3] = {};
          for (int i = 0; i < cvs.size(); ++i) {
            const test::OsdPoint& q = ref.points[size_t(cvs[i])];
            const double c[3] = {q.x, q.y, q.z};
            for (int k = 0; k < 3; ++k)
              p[k] += wp[i] * c[k], du[k] += wu[i] * c[k], dv[k] += wv[i] * c[k];
          }
          coords.push_back(map.find(ptex, u, v));
          expected.insert(expected.end(), p, p + 3);
          double n[3] = {du[1] * dv[2] - du[2] * dv[1], du[2] * dv[0] - du[0] * dv[2],
                         du[0] * dv[1] - du[1] * dv[0]};
          const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
          for (double& x : n) x = l > 0 ? x / l : 0.0;
          expected_n.insert(expected_n.end(), n, n + 3);
          where.push_back("ptex " + std::to_string(ptex) + " u " + std::to_string(u) + " v " +
                          std::to_string(v));
        }
  std::vector<float> pos(3 * coords.size()), du(pos.size()), dv(pos.size());
  evaluate_patches(table, pts, coords, pos.data(), du.data(), dv.data());
  const double diag = bbox_diagonal(cage);
  Comparison c;
  c.samples = coords.size();
  for (size_t i = 0; i < coords.size(); ++i) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += std::pow(pos[3 * i + k] - expected[3 * i + k], 2);
    const double d = std::sqrt(d2) / diag;
    if (d > c.max_position) {
      c.max_position = d;
      const size_t nr = table.regular_params.size();
      c.worst = where[i] + (coords[i].patch < nr ? " regular" : " gregory") + " limn (" +
                std::to_string(pos[3 * i]) + " " + std::to_string(pos[3 * i + 1]) + " " +
                std::to_string(pos[3 * i + 2]) + ") osd (" + std::to_string(expected[3 * i]) + " " +
                std::to_string(expected[3 * i + 1]) + " " + std::to_string(expected[3 * i + 2]) +
                ")";
    }
    double n[3] = {double(du[3 * i + 1]) * dv[3 * i + 2] - double(du[3 * i + 2]) * dv[3 * i + 1],
                   double(du[3 * i + 2]) * dv[3 * i] - double(du[3 * i]) * dv[3 * i + 2],
                   double(du[3 * i]) * dv[3 * i + 1] - double(du[3 * i + 1]) * dv[3 * i]};
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    // OpenSubdiv differentiates end caps approximately (it drops the derivative of the rational
    // interior weights); limn's are exact, checked against finite differences below.
    // Where the tangents are (nearly) parallel the normal is ill-conditioned: skip those.
    double lu = 0, lv = 0;
    for (int k = 0; k < 3; ++k) lu += double(du[3 * i + k]) * du[3 * i + k];
    for (int k = 0; k < 3; ++k) lv += double(dv[3 * i + k]) * dv[3 * i + k];
    if (l <= 0.05 * std::sqrt(lu * lv) || coords[i].patch >= table.regular_params.size()) continue;
    double e2 = 0;
    for (int k = 0; k < 3; ++k) e2 += std::pow(n[k] / l - expected_n[3 * i + k], 2);
    c.max_normal = std::max(c.max_normal, std::sqrt(e2));
  }
  return c;
}

TEST(Patches, ProceduralShapesMatchOpenSubdiv) {
  for (const char* name : {"cube", "torus", "cage"}) {
    const Mesh cage = make_shape(name);
    for (int depth : {0, 1, 2, 3, 4}) {
      const Comparison c = compare_with_osd(cage, depth, subdiv_options(cage));
      EXPECT_LT(c.max_position, 1e-5) << name << " depth " << depth << " worst " << c.worst;
      EXPECT_LT(c.max_normal, 1e-3) << name << " depth " << depth;
    }
  }
}

// Random cages: every boundary and crease rule, semi-sharp creases and corners, n-gons, holes.
// A hole removes its face's surface and changes no other face's (OpenSubdiv's definition: its
// uniform limit is the same with and without the hole tags), so the faces limn keeps must equal
// OpenSubdiv's surface of the cage without holes to 1e-5. OpenSubdiv's own adaptive table with
// the holes strays from that (2e-4 of the diagonal in one of these cages: an end cap whose ring
// touches a hole beside non-quads, at a crease); limn's does not, so against it the bound is
// looser.
TEST(Patches, RandomCagesMatchOpenSubdiv) {
  int with_holes = 0;
  for (int i = 0; i < 60; ++i) {
    Mesh cage = test::random_cage(20261201 + uint64_t(i / 2));
    const bool holes = i % 2 == 1;
    if (!holes) cage.hole_faces.clear();
    SubdivOptions o;
    const int j = i / 2;
    o.boundary = j % 2 ? BoundaryInterpolation::edge_only : BoundaryInterpolation::edge_and_corner;
    o.crease_method = j % 3 == 0 ? CreaseMethod::chaikin : CreaseMethod::uniform;
    const int depth = 1 + j % 3;
    Comparison c;
    const bool inf = j % 4 >= 2;  // half with infinitely sharp patches
    try {
      c = compare_with_osd(cage, depth, o, inf);
    } catch (const InputError&) {
      continue;  // a cage limn rejects (checked elsewhere)
    }
    EXPECT_LT(c.max_position, holes ? 1e-3 : 1e-5)
        << "cage " << i << " depth " << depth << " " << c.worst;
    EXPECT_LT(c.max_normal, holes ? 1e-2 : 1e-3) << "cage " << i;
    if (holes) {
      Mesh whole = cage;
      whole.hole_faces.clear();
      const Comparison w = compare_with_osd(cage, depth, o, inf, &whole);
      EXPECT_GT(w.samples, 0u);
      EXPECT_LT(w.max_position, 1e-5) << "cage " << i << " depth " << depth << " " << w.worst;
      EXPECT_LT(w.max_normal, 1e-3) << "cage " << i;
      ++with_holes;
    }
  }
  EXPECT_GE(with_holes, 20);
}

// The grid evaluator (no lookups, 8 points at a time) gives what PatchMap::find and
// evaluate_patches give at the same ptex coordinates: every patch type, boundaries, creases,
// n-gons, per-vertex depths, grids that do and do not line up with patch edges.
TEST(Patches, GridsEqualLookups) {
  std::vector<Mesh> cages = {make_shape("torus"), make_shape("cage"), make_shape("cube")};
  for (uint64_t seed : {3u, 5u, 11u}) cages.push_back(test::random_cage(seed));
  int checked = 0;
  for (size_t ci = 0; ci < cages.size(); ++ci) {
    const Mesh& cage = cages[ci];
    PatchOptions po;
    po.subdiv = subdiv_options(cage);
    po.depth = 3;
    std::vector<uint8_t> depth(cage.vertex_count());
    for (size_t v = 0; v < depth.size(); ++v) depth[v] = uint8_t((v * 7 + ci) % 4);
    PatchTable table;
    try {
      table = build_patches(cage, po,
                            ci % 2 ? std::span<const uint8_t>(depth) : std::span<const uint8_t>());
    } catch (const InputError&) {
      continue;  // a random cage limn rejects (checked elsewhere)
    }
    const std::vector<float> pts = table.points(cage.positions);
    const PatchMap map(table);
    const double diag = bbox_diagonal(cage);
    for (int n : {2, 7, 9}) {
      const size_t per = size_t(n) * size_t(n), total = table.ptex_count * per;
      std::vector<float> gp(3 * total, NAN), gu(3 * total, NAN), gv(3 * total, NAN);
      evaluate_grids(table, pts, n, gp.data(), gu.data(), gv.data());
      // Hole faces have no patches: their grid points stay as they were.
      const std::vector<uint8_t> covered = covered_ptex(table);
      std::vector<PatchCoord> coords(total);
      for (size_t i = 0; i < total; ++i) {
        const size_t f = i / per, k = i % per;
        if (covered[f])
          coords[i] = map.find(uint32_t(f), double(k % size_t(n)) / (n - 1),
                               double(k / size_t(n)) / (n - 1));
      }
      std::vector<float> lp(3 * total), lu(3 * total), lv(3 * total);
      evaluate_patches(table, pts, coords, lp.data(), lu.data(), lv.data());
      double worst_p = 0, worst_d = 0;
      size_t worst_at = 0;
      for (size_t i = 0; i < 3 * total; ++i) {
        if (!covered[i / 3 / per]) {
          ASSERT_TRUE(std::isnan(gp[i])) << "a hole face's grid was written";
          continue;
        }
        ASSERT_TRUE(std::isfinite(gp[i]) && std::isfinite(gu[i]) && std::isfinite(gv[i]))
            << "cage " << ci << " n " << n << " point " << i / 3 << " not written";
        worst_p = std::max(worst_p, std::abs(double(gp[i]) - lp[i]) / diag);
        // Derivatives relative to the point's largest derivative component.
        const size_t q = i - i % 3;
        double len = 1e-3 * diag;
        for (size_t k = q; k < q + 3; ++k)
          len = std::max({len, std::abs(double(lu[k])), std::abs(double(lv[k]))});
        const double d = std::max(std::abs(double(gu[i]) - lu[i]), std::abs(double(gv[i]) - lv[i]));
        if (d / len > worst_d) worst_d = d / len, worst_at = i / 3;
      }
      const PatchCoord& w = coords[worst_at];
      EXPECT_LT(worst_p, 1e-6) << "cage " << ci << " n " << n;
      EXPECT_LT(worst_d, 1e-4) << "cage " << ci << " n " << n << " point " << worst_at << " patch "
                               << w.patch << " s " << w.s << " t " << w.t;
      ++checked;
    }
  }
  EXPECT_GE(checked, 12);
  const Mesh cube = make_shape("cube");
  const PatchTable t = build_patches(cube, PatchOptions{});
  std::vector<float> out(3 * t.ptex_count * 4);
  EXPECT_THROW(evaluate_grids(t, t.points(cube.positions), 1, out.data()), InputError);
  EXPECT_THROW(evaluate_grids(t, std::vector<float>(3), 2, out.data()), InputError);
}

// End caps meeting at a corner share its limit point, and those on either side of a patch edge
// share its edge point (one row each, not one per end cap): on a cube at depth 2 the three end
// caps around each valence-3 vertex. points() into a buffer equals the returned points.
TEST(Patches, EndCapsShareCornerPoints) {
  const Mesh cube = make_shape("cube");
  PatchOptions o;
  o.depth = 2;
  const PatchTable t = build_patches(cube, o);
  const size_t caps = t.gregory_params.size();
  ASSERT_EQ(caps, 24u);
  std::map<uint32_t, int> uses;  // P id -> end caps using it
  for (size_t c = 0; c < caps; ++c)
    for (int i = 0; i < 4; ++i) ++uses[t.gregory_points[20 * c + 5 * size_t(i)]];
  int shared_by_three = 0;
  for (const auto& [id, n] : uses) shared_by_three += n == 3;
  EXPECT_EQ(shared_by_three, 8);  // the cube's corners
  int edges = 0;
  for (size_t a = 0; a < caps; ++a)
    for (size_t b = 0; b < caps; ++b)
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          const uint32_t* pa = &t.gregory_points[20 * a];
          const uint32_t* pb = &t.gregory_points[20 * b];
          // a's edge from corner i to i + 1 is b's edge from corner j to j - 1.
          if (a == b || pa[5 * i] != pb[5 * j] || pa[5 * ((i + 1) & 3)] != pb[5 * ((j + 3) & 3)])
            continue;
          EXPECT_EQ(pa[5 * i + 1], pb[5 * j + 2]) << a << " " << b;
          ++edges;
        }
  EXPECT_GE(edges, 24);  // the three patch edges at each cube corner, from both sides
  EXPECT_LT(t.gregory_stencils.size(), 12 * caps);
  const std::vector<float> pts = t.points(cube.positions);
  std::vector<float> into(pts.size(), -1.0f);
  t.points(cube.positions, into);
  EXPECT_EQ(pts, into);
  std::vector<float> short_buffer(pts.size() - 3);
  EXPECT_THROW(t.points(cube.positions, short_buffer), InputError);
}

// A fan of n quads around a centre vertex, bumped out of the plane: closed round the centre
// (an interior vertex of valence n) or open over 3/4 of a turn (a boundary vertex of n faces).
Mesh fan_cage(int n, bool closed) {
  Mesh m;
  const double turn = closed ? 2 * std::numbers::pi : 1.5 * std::numbers::pi;
  const int spokes = closed ? n : n + 1;
  m.positions = {0.0f, 0.0f, 0.3f};
  for (int i = 0; i < spokes; ++i) {  // spoke i at 1 + 2i, the rim point after it at 2 + 2i
    const double a = turn * i / n, b = turn * (i + 0.5) / n;
    m.positions.insert(m.positions.end(),
                       {float(std::cos(a)), float(std::sin(a)), float(0.1 * std::sin(3 * a))});
    m.positions.insert(m.positions.end(), {float(1.7 * std::cos(b)), float(1.7 * std::sin(b)),
                                           float(-0.2 + 0.15 * std::cos(5 * b))});
  }
  for (int i = 0; i < n; ++i) {
    const uint32_t s = uint32_t(1 + 2 * i), next = uint32_t(1 + 2 * ((i + 1) % spokes));
    m.face_vertices.insert(m.face_vertices.end(), {0u, s, s + 1, next});
    m.face_offsets.push_back(uint32_t(m.face_vertices.size()));
  }
  return m;
}

// Fans of many faces (their end caps keep one ring for the fan, turned to each cap's start)
// match OpenSubdiv, interior and boundary, with and without infinitely sharp patches.
TEST(Patches, HighValenceFansMatchOpenSubdiv) {
  for (const bool closed : {true, false})
    for (const int n : {17, 40}) {
      const Mesh cage = fan_cage(n, closed);
      for (const bool inf : {false, true})
        for (int depth : {1, 2, 3}) {
          const Comparison c = compare_with_osd(cage, depth, subdiv_options(cage), inf);
          EXPECT_GT(c.samples, 0u);
          EXPECT_LT(c.max_position, 1e-5) << (closed ? "interior" : "boundary") << " fan of " << n
                                          << " depth " << depth << " worst " << c.worst;
          EXPECT_LT(c.max_normal, 1e-3) << n << " depth " << depth;
        }
    }
}

// End-cap derivatives are exact: central differences of positions agree.
TEST(Patches, DerivativesMatchFiniteDifferences) {
  const Mesh cage = make_shape("cube");
  PatchOptions po;
  po.depth = 2;
  const PatchTable table = build_patches(cage, po);
  ASSERT_GT(table.gregory_params.size(), 0u);
  const std::vector<float> pts = table.points(cage.positions);
  const double h = 1e-3;
  double worst = 0;
  for (uint32_t p = 0; p < table.patch_count(); ++p)
    for (double s : {0.2, 0.5, 0.8})
      for (double t : {0.3, 0.6}) {
        const PatchCoord c[5] = {{p, float(s), float(t)},
                                 {p, float(s + h), float(t)},
                                 {p, float(s - h), float(t)},
                                 {p, float(s), float(t + h)},
                                 {p, float(s), float(t - h)}};
        float pos[15], du[15], dv[15];
        evaluate_patches(table, pts, c, pos, du, dv);
        const size_t nr = table.regular_params.size();
        const int depth =
            p < nr ? table.regular_params[p].depth : table.gregory_params[p - nr].depth;
        const double scale = double(1 << depth) / (2 * h);
        double len = 0, err = 0;
        for (int k = 0; k < 3; ++k) {
          const double fu = (pos[3 + k] - pos[6 + k]) * scale,
                       fv = (pos[9 + k] - pos[12 + k]) * scale;
          err = std::max({err, std::abs(fu - du[k]), std::abs(fv - dv[k])});
          len = std::max({len, std::abs(double(du[k])), std::abs(double(dv[k]))});
        }
        worst = std::max(worst, err / len);
      }
  EXPECT_LT(worst, 2e-3);
}

// Every shared cage at the given depths, against OpenSubdiv with or without its infinitely sharp
// patches. limn's refined points are floats: on the tiny deep patches at a pole (bishop, depth
// 4) that leaves ~2e-3 in normals.
void expect_shared_cages_match(std::initializer_list<int> depths, bool inf_sharp) {
  const auto cages = test::shared_cages(LIMN_SHARED_MODELS);
  if (cages.empty()) GTEST_SKIP() << "no shared models";
  for (const auto& path : cages) {
    const Mesh cage = read_mesh(path.string());
    const SubdivOptions options = subdiv_options(cage);
    for (int depth : depths) {
      Comparison c;
      try {
        c = compare_with_osd(cage, depth, options, inf_sharp);
      } catch (const std::exception& e) {
        ADD_FAILURE() << path.filename() << " depth " << depth << ": " << e.what();
        continue;
      }
      EXPECT_LT(c.max_position, 1e-5)
          << path.filename() << " depth " << depth << " worst " << c.worst;
      EXPECT_LT(c.max_normal, 5e-3) << path.filename() << " depth " << depth;
    }
  }
}

// Infinitely sharp creases and corners as regular boundary/corner patches (OpenSubdiv's
// useInfSharpPatch, limn's default).
TEST(Patches, SharedCagesMatchOpenSubdivWithInfSharpPatches) {
  expect_shared_cages_match({1, 2, 3}, true);
}

TEST(Patches, SharedCagesMatchOpenSubdiv) {
  expect_shared_cages_match({1, 2, 3, 4}, false);
}

}  // namespace
}  // namespace limn

namespace limn {
namespace {

// Region builds (cages cut into regions isolated one at a time): the same patches, with the
// same placement, type, boundary and transition bits, and the same surface as the whole-cage
// build, for regions down to a single face, where every patch lies on a region border.
void expect_regions_equal_whole(const Mesh& cage, const PatchOptions& base,
                                std::span<const uint8_t> vertex_depth, const std::string& name) {
  PatchOptions whole = base;
  whole.batch_faces = 0xFFFFFFFFu;
  const PatchTable a = build_patches(cage, whole, vertex_depth);
  const std::vector<float> pa = a.points(cage.positions);
  const double diag = bbox_diagonal(cage);
  using Key = std::tuple<uint32_t, uint16_t, uint16_t, uint8_t, uint8_t, uint8_t, uint8_t, uint8_t,
                         float, uint32_t>;
  auto keys = [](const PatchTable& t) {
    std::map<Key, uint32_t> k;
    const size_t nr = t.regular_params.size();
    for (uint32_t i = 0; i < t.patch_count(); ++i) {
      const PatchParam& p = i < nr ? t.regular_params[i] : t.gregory_params[i - nr];
      k.emplace(Key{p.ptex, p.u, p.v, p.depth, uint8_t(p.type), p.boundary, p.transition,
                    p.crease_edge, p.sharpness, p.base_face},
                i);
    }
    return k;
  };
  const auto ka = keys(a);
  EXPECT_EQ(ka.size(), a.patch_count()) << name;  // no two patches in one place
  for (const uint32_t batch : {1u, 5u, 23u}) {
    PatchOptions o = base;
    o.batch_faces = batch;
    const PatchTable b = build_patches(cage, o, vertex_depth);
    EXPECT_EQ(b.ptex_count, a.ptex_count) << name;
    EXPECT_EQ(b.ptex_of_face, a.ptex_of_face) << name;
    const auto kb = keys(b);
    ASSERT_EQ(kb.size(), ka.size()) << name << " regions of " << batch;
    const std::vector<float> pb = b.points(cage.positions);
    std::vector<PatchCoord> ca, cb;
    for (const auto& [key, i] : ka) {
      const auto it = kb.find(key);
      ASSERT_NE(it, kb.end()) << name << " regions of " << batch << ": ptex " << std::get<0>(key)
                              << " has no matching patch";
      for (const float s : {0.0f, 0.4f, 1.0f})
        for (const float t : {0.0f, 0.7f, 1.0f}) {
          ca.push_back({i, s, t});
          cb.push_back({it->second, s, t});
        }
    }
    std::vector<float> xa(3 * ca.size()), xb(3 * cb.size());
    evaluate_patches(a, pa, ca, xa.data());
    evaluate_patches(b, pb, cb, xb.data());
    double worst = 0;
    for (size_t i = 0; i < xa.size(); ++i) worst = std::max(worst, double(std::abs(xa[i] - xb[i])));
    EXPECT_LE(worst, 1e-6 * diag) << name << " regions of " << batch;
  }
}

TEST(Patches, RegionBuildsEqualTheWholeCage) {
  for (const auto& path : test::shared_cages(LIMN_SHARED_MODELS)) {
    const Mesh cage = read_mesh(path.string());
    PatchOptions o;
    o.subdiv = subdiv_options(cage);
    o.depth = 3;
    expect_regions_equal_whole(cage, o, {}, path.filename().string());
  }
  // Regions run in parallel, but the table does not depend on the thread count.
  {
    const int valences[] = {3, 5, 6};
    const Mesh cage = make_torus(24, 12, valences);
    PatchOptions o;
    o.subdiv = subdiv_options(cage);
    o.depth = 3;
    o.batch_faces = 9;
    const PatchTable many = build_patches(cage, o);
    PatchTable one;
    {
      const tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
      one = build_patches(cage, o);
    }
    EXPECT_EQ(one.level_offsets, many.level_offsets);
    EXPECT_EQ(one.regular_points, many.regular_points);
    EXPECT_EQ(one.gregory_points, many.gregory_points);
    EXPECT_EQ(one.gregory_stencils.indices, many.gregory_stencils.indices);
    EXPECT_EQ(one.gregory_stencils.weights, many.gregory_stencils.weights);
    EXPECT_EQ(one.gregory_stencils.weight_offsets, many.gregory_stencils.weight_offsets);
    EXPECT_EQ(one.gregory_face_stencils.indices, many.gregory_face_stencils.indices);
    EXPECT_EQ(one.gregory_face_stencils.weights, many.gregory_face_stencils.weights);
    EXPECT_EQ(one.gregory_face_stencils.weight_offsets, many.gregory_face_stencils.weight_offsets);
    ASSERT_EQ(one.level_stencils.size(), many.level_stencils.size());
    for (size_t k = 0; k < one.level_stencils.size(); ++k) {
      EXPECT_EQ(one.level_stencils[k].offsets, many.level_stencils[k].offsets) << k;
      EXPECT_EQ(one.level_stencils[k].indices, many.level_stencils[k].indices) << k;
      EXPECT_EQ(one.level_stencils[k].weights, many.level_stencils[k].weights) << k;
      EXPECT_EQ(one.level_stencils[k].weight_offsets, many.level_stencils[k].weight_offsets) << k;
    }
    ASSERT_EQ(one.regular_params.size(), many.regular_params.size());
    for (size_t i = 0; i < one.regular_params.size(); ++i)
      ASSERT_EQ(std::memcmp(&one.regular_params[i], &many.regular_params[i], sizeof(PatchParam)), 0)
          << i;
  }
  // A crease tag between vertices that share no edge is refused by both.
  Mesh bad = make_shape("torus");
  bad.crease_edges = {0, 2};
  bad.crease_sharpness = {1.0f};
  for (const uint32_t batch : {0xFFFFFFFFu, 4u}) {
    PatchOptions o;
    o.batch_faces = batch;
    EXPECT_THROW(build_patches(bad, o), InputError) << batch;
  }
  // Random cages: n-gons, holes, semi-sharp creases and corners, every boundary rule, with and
  // without the special patches, and per-vertex depths.
  for (int i = 0; i < 12; ++i) {
    const Mesh cage = test::random_cage(20261202 + uint64_t(i));
    PatchOptions o;
    o.subdiv.boundary =
        i % 3 == 0 ? BoundaryInterpolation::edge_only : BoundaryInterpolation::edge_and_corner;
    if (i % 5 == 0) o.subdiv.boundary = BoundaryInterpolation::none;
    o.subdiv.crease_method = i % 2 ? CreaseMethod::chaikin : CreaseMethod::uniform;
    o.inf_sharp_patches = o.single_crease_patches = i % 4 < 2;
    o.depth = 2 + i % 3;
    std::vector<uint8_t> depth;
    if (i % 3 == 1) {
      test::Rng rng{uint64_t(i)};
      for (size_t v = 0; v < cage.vertex_count(); ++v) depth.push_back(uint8_t(rng.below(5)));
    }
    try {
      expect_regions_equal_whole(cage, o, depth, "random cage " + std::to_string(i));
    } catch (const InputError&) {
      // a cage limn rejects (checked elsewhere); both paths must reject it alike
      PatchOptions r = o;
      r.batch_faces = 3;
      EXPECT_THROW(build_patches(cage, r, depth), InputError);
    }
  }
}

// Per-vertex depths: the patches tile every ptex face exactly once (PatchMap rejects overlaps and
// finds a patch everywhere), regular patches are the exact limit surface (they agree with the
// fixed-depth table that matches OpenSubdiv wherever both have a regular patch), and transition
// bits mark exactly the patch edges whose neighbour across is finer.
TEST(Patches, PerVertexDepthTilesAndStaysExact) {
  const Mesh cage = make_shape("torus");
  test::Rng rng(7);
  std::vector<uint8_t> depth(cage.vertex_count());
  for (uint8_t& d : depth) d = uint8_t(rng.below(5));
  PatchOptions po;
  po.subdiv = subdiv_options(cage);
  po.depth = 4;
  const PatchTable dyn = build_patches(cage, po, depth);
  const PatchTable fixed = build_patches(cage, po);
  EXPECT_LT(dyn.patch_count(), fixed.patch_count());
  const PatchMap dmap(dyn), fmap(fixed);
  const std::vector<float> dpts = dyn.points(cage.positions), fpts = fixed.points(cage.positions);
  const double diag = bounding_box(cage).diagonal();
  const size_t dnr = dyn.regular_params.size(), fnr = fixed.regular_params.size();
  size_t compared = 0;
  for (uint32_t ptex = 0; ptex < dyn.ptex_count; ++ptex)
    for (double u : {0.05, 0.3, 0.5, 0.77, 0.95})
      for (double v : {0.1, 0.45, 0.62, 0.9}) {
        const PatchCoord a = dmap.find(ptex, u, v), b = fmap.find(ptex, u, v);
        if (a.patch >= dnr || b.patch >= fnr) continue;
        float pa[3], pb[3];
        evaluate_patches(dyn, dpts, std::span(&a, 1), pa);
        evaluate_patches(fixed, fpts, std::span(&b, 1), pb);
        const double d = std::hypot(pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]) / diag;
        EXPECT_LT(d, 1e-6) << "ptex " << ptex << " u " << u << " v " << v;
        ++compared;
      }
  EXPECT_GT(compared, dyn.ptex_count);

  // Transition bits, checked inside each ptex face: just across an edge's midpoint.
  for (size_t i = 0; i < dyn.patch_count(); ++i) {
    const PatchParam& p = i < dnr ? dyn.regular_params[i] : dyn.gregory_params[i - dnr];
    const double size = 1.0 / double(1u << p.depth), eps = size * 1e-3;
    const double u0 = p.u * size, v0 = p.v * size;
    const double across[4][2] = {{u0 + size / 2, v0 - eps},
                                 {u0 + size + eps, v0 + size / 2},
                                 {u0 + size / 2, v0 + size + eps},
                                 {u0 - eps, v0 + size / 2}};
    for (int e = 0; e < 4; ++e) {
      const double x = across[e][0], y = across[e][1];
      if (x <= 0 || x >= 1 || y <= 0 || y >= 1) continue;  // the neighbour is another ptex face
      const PatchCoord c = dmap.find(p.ptex, x, y);
      const PatchParam& q =
          c.patch < dnr ? dyn.regular_params[c.patch] : dyn.gregory_params[c.patch - dnr];
      EXPECT_EQ(bool(p.transition & (1u << e)), q.depth > p.depth)
          << "patch " << i << " edge " << e;
    }
  }
}

}  // namespace
}  // namespace limn

namespace limn {
namespace {

// Depth 0 next to a non-quad (a fuzz finding: an end cap saw the n-gon in its ring and broke an
// invariant): the faces around a non-quad go down once too, so every patch has quads all round.
TEST(Patches, DepthZeroNextToNonQuads) {
  const Mesh cage =
      read_mesh(std::string(LIMN_SOURCE_DIR) + "/fuzz/corpus/subdiv/patch_endcap_next_to_ngon.obj");
  PatchOptions po;
  po.subdiv = subdiv_options(cage);
  po.depth = 0;
  const std::vector<uint8_t> zero(cage.vertex_count(), 0);
  for (const bool per_vertex : {false, true}) {
    const PatchTable t = build_patches(cage, po, per_vertex ? zero : std::vector<uint8_t>{});
    EXPECT_GT(t.patch_count(), 0u);
    const PatchMap map(t);
    const std::vector<float> pts = t.points(cage.positions);
    for (const float x : pts) EXPECT_TRUE(std::isfinite(x));
  }
}

// A cage whose n-gons balance to four corners per face (a triangle and a pentagon among quads)
// is still told from an all-quad cage: corner c is not corner c % 4 of face c / 4 there.
TEST(Patches, BalancedNonQuadsMatchOpenSubdiv) {
  Mesh cage;
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 6; ++x)
      cage.add_vertex(float(x), float(y), 0.2f * std::sin(float(x * 3 + y * 5)));
  auto id = [](int x, int y) { return uint32_t(6 * y + x); };
  // The two quads (1..3, 2..3) as a triangle and a pentagon split along a diagonal, first and
  // last, so that every quad's corners sit one off from 4f.
  cage.add_face({id(1, 2), id(2, 2), id(1, 3)});
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 5; ++x) {
      if (y == 2 && (x == 1 || x == 2)) continue;
      cage.add_face({id(x, y), id(x + 1, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  cage.add_face({id(2, 2), id(3, 2), id(3, 3), id(2, 3), id(1, 3)});
  ASSERT_EQ(cage.corner_count(), 4 * cage.face_count());
  for (const int depth : {1, 2, 3}) {
    const Comparison c = compare_with_osd(cage, depth, subdiv_options(cage));
    EXPECT_LT(c.max_position, 1e-5) << "depth " << depth << " " << c.worst;
  }
}

}  // namespace
}  // namespace limn

namespace limn {
namespace {

// Single-crease patches are exact: where the table has regular or single-crease patches, it
// agrees with the limit points of uniform level 6 (limn's refinement, which matches
// OpenSubdiv's semi-sharp rules), and the semi-sharp creases need no isolation.
TEST(Patches, SingleCreasePatchesAreExact) {
  std::vector<std::pair<std::string, Mesh>> cages = {{"cage", make_shape("cage")}};
  for (const char* name : {"osd/catmark_single_crease.obj", "osd/catmark_cubes_semisharp.obj",
                           "osd/catmark_tent_creases1.obj"}) {
    const std::filesystem::path p = std::filesystem::path(LIMN_SHARED_MODELS) / name;
    if (std::filesystem::exists(p)) cages.emplace_back(name, read_mesh(p));
  }
  size_t total_crease = 0;
  for (const auto& [name, cage] : cages) {
    const test::Reference ref = test::reference(cage, 6);
    for (const CreaseMethod method : {CreaseMethod::uniform, CreaseMethod::chaikin}) {
      Mesh m = cage;
      m.tags.crease_method = method;
      test::Reference r =
          method == subdiv_options(cage).crease_method ? ref : test::reference(m, 6);
      PatchOptions po;
      po.subdiv = subdiv_options(m);
      po.depth = 3;
      const PatchTable t = build_patches(m, po);
      PatchOptions no = po;
      no.single_crease_patches = false;
      const PatchTable without = build_patches(m, no);
      size_t crease = 0;
      for (const PatchParam& p : t.regular_params) crease += p.type == PatchType::single_crease;
      total_crease += crease;
      if (crease) {
        EXPECT_LT(t.patch_count(), without.patch_count()) << name;
      }
      const PatchMap map(t);
      std::vector<PatchCoord> coords;
      std::vector<uint32_t> at;
      test::reference_samples(r, map, coords, at);
      const std::vector<float> pts = t.points(m.positions);
      std::vector<float> got(3 * coords.size());
      evaluate_patches(t, pts, coords, got.data());
      const double diag = bounding_box(m).diagonal();
      double worst = 0;
      size_t checked = 0;
      for (size_t i = 0; i < coords.size(); ++i) {
        if (coords[i].patch >= t.regular_params.size()) continue;  // end caps approximate
        const float* q = &r.limit[3 * size_t(at[i])];
        worst = std::max(worst, double(std::hypot(got[3 * i] - q[0], got[3 * i + 1] - q[1],
                                                  got[3 * i + 2] - q[2])) /
                                    diag);
        ++checked;
      }
      EXPECT_GT(checked, 0u);
      EXPECT_LT(worst, 1e-5) << name << (method == CreaseMethod::chaikin ? " chaikin" : "");
    }
  }
  EXPECT_GT(total_crease, 0u);
}

}  // namespace
}  // namespace limn

namespace limn {
namespace {

// A view change selects from the hierarchy: the same patches (params, transition bits, points)
// as building the table for those depths from scratch, and the same surface.
TEST(Patches, HierarchySelectionEqualsADirectBuild) {
  std::vector<Mesh> cages = {make_shape("torus"), make_shape("cage"), make_shape("cube")};
  const std::filesystem::path big = std::filesystem::path(LIMN_SHARED_MODELS) / "quads/bigguy.obj";
  if (std::filesystem::exists(big)) cages.push_back(read_mesh(big));
  cages.push_back(test::random_cage(17));
  test::Rng rng(99);
  for (size_t ci = 0; ci < cages.size(); ++ci) {
    const Mesh& cage = cages[ci];
    PatchOptions po;
    po.subdiv = subdiv_options(cage);
    po.depth = 5;
    const PatchHierarchy h = build_patch_hierarchy(cage, po);
    const std::vector<float> hp = h.table.points(cage.positions);
    for (int trial = 0; trial < 3; ++trial) {
      std::vector<uint8_t> d(cage.vertex_count());
      for (uint8_t& x : d) x = uint8_t(rng.below(7));  // some above the hierarchy's depth
      const PatchTable sel = select_patches(h, d);
      const PatchTable direct = build_patches(cage, po, d);
      ASSERT_EQ(sel.regular_params.size(), direct.regular_params.size()) << ci;
      ASSERT_EQ(sel.gregory_params.size(), direct.gregory_params.size()) << ci;
      auto key = [](const PatchParam& p) {
        return std::tuple(p.ptex, p.depth, p.u, p.v, int(p.type), p.boundary, p.transition,
                          p.crease_edge, p.sharpness);
      };
      for (const auto which : {&PatchTable::regular_params, &PatchTable::gregory_params}) {
        std::vector<decltype(key(PatchParam{}))> a, b;
        for (const PatchParam& p : sel.*which) a.push_back(key(p));
        for (const PatchParam& p : direct.*which) b.push_back(key(p));
        std::sort(a.begin(), a.end()), std::sort(b.begin(), b.end());
        EXPECT_EQ(a, b) << "cage " << ci << " trial " << trial;
      }
      // The same surface on a grid of every ptex face.
      const PatchMap ms(sel), md(direct);
      const std::vector<float> dp = direct.points(cage.positions);
      double worst = 0;
      for (uint32_t p = 0; p < sel.ptex_count; ++p)
        for (double u : {0.1, 0.5, 0.85})
          for (double v : {0.2, 0.6, 0.95}) {
            PatchCoord a, b;
            try {
              a = ms.find(p, u, v), b = md.find(p, u, v);
            } catch (const InputError&) {
              continue;  // a hole
            }
            float x[3], y[3];
            evaluate_patches(sel, hp, std::span(&a, 1), x);
            evaluate_patches(direct, dp, std::span(&b, 1), y);
            worst = std::max(worst, double(std::hypot(x[0] - y[0], x[1] - y[1], x[2] - y[2])));
          }
      EXPECT_LT(worst, 1e-6 * bounding_box(cage).diagonal()) << ci;
      // A selection tessellates like any table, with the hierarchy's points.
      const Mesh tess = tessellate_patches(cage, sel, hp, TessellateOptions{});
      const MeshStats st = analyze(tess, build_topology(tess));
      EXPECT_EQ(st.non_manifold_edges, 0u) << ci;
      if (ci == 0 || ci == 2) {  // the closed ones: torus, cube
        EXPECT_EQ(st.boundary_edges, 0u) << ci;
      }
    }
    EXPECT_THROW((void)select_patches(h, {}), InputError);
    EXPECT_THROW(
        (void)select_patches(h, std::vector<uint8_t>(cage.vertex_count())).points(cage.positions),
        InputError);
  }
}

}  // namespace
}  // namespace limn
