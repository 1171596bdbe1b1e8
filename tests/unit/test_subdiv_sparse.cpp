// Sparse (feature-adaptive) refinement against OpenSubdiv 3.5's uniform refinement.
//
// Every local point of every sparse level is matched to OpenSubdiv's point of the same
// provenance (face / edge / vertex point of a matched parent), every local face to OpenSubdiv's
// child face of the matched parent face, every local edge to OpenSubdiv's edge between the
// matched ends; then positions, winding, holes and sharpness must agree, the completeness flags
// must be true where limn sets them, and every requested ring or face must be present and whole.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/subdiv/refine.hpp"
#include "osd_oracle.hpp"
#include "random_cage.hpp"

#ifndef LIMN_SHARED_MODELS
#define LIMN_SHARED_MODELS "/work/shared/models"
#endif

namespace limn {
namespace {

namespace fs = std::filesystem;
namespace osd = test::osd;
using OsdIndex = osd::Far::Index;
constexpr OsdIndex kInvalid = osd::Far::INDEX_INVALID;

struct Maps {
  std::vector<OsdIndex> vertex, edge, face;
};

// Faces around each local vertex, counted from the local faces.
std::vector<uint32_t> local_face_counts(const RefinedLevel& L) {
  std::vector<uint32_t> n(L.vertex_count(), 0);
  for (uint32_t v : L.face_vertices) ++n[v];
  return n;
}

struct Requests {
  std::vector<uint8_t> vertex, face;
};

void expect_sparse_matches_osd(const Mesh& cage, const Requests& req, const SubdivOptions& o) {
  const SparseRefinement sr = refine_sparse(cage, req.vertex, req.face, o);
  int want = 0;
  for (uint8_t d : req.vertex) want = std::max(want, int(d));
  for (uint8_t d : req.face) want = std::max(want, int(d));
  ASSERT_EQ(sr.levels.size(), size_t(want) + 1) << "levels: one per requested depth";
  ASSERT_EQ(sr.stencils.size(), size_t(want));
  const test::OsdRefinement orf = test::osd_refine(cage, want, o);
  const double tolerance = 1e-6 * bounding_box(cage).diagonal();

  std::vector<Maps> maps(sr.levels.size());
  for (size_t k = 0; k < sr.levels.size(); ++k) {
    SCOPED_TRACE(fmt::format("level {}", k));
    const SparseLevel& S = sr.levels[k];
    const RefinedLevel& L = S.level;
    const osd::Far::TopologyLevel& T = *orf.levels[k].topology;
    Maps& m = maps[k];
    const size_t nv = L.vertex_count(), nf = L.face_count(), ne = L.edge_count();
    ASSERT_EQ(S.vertex_complete.size(), nv);
    ASSERT_EQ(S.vertex_depth.size(), nv);
    ASSERT_EQ(S.face_depth.size(), nf);
    ASSERT_EQ(L.face_hole.size(), nf);

    // Vertices through their parents.
    m.vertex.assign(nv, kInvalid);
    if (k == 0) {
      ASSERT_EQ(nv, cage.vertex_count());
      for (size_t v = 0; v < nv; ++v) m.vertex[v] = OsdIndex(v);
    } else {
      const Maps& pm = maps[k - 1];
      const osd::Far::TopologyLevel& PT = *orf.levels[k - 1].topology;
      const size_t a = S.parent_faces.size(), b = a + S.parent_edges.size();
      ASSERT_EQ(b + S.parent_vertices.size(), nv) << "vertex blocks";
      for (size_t i = 0; i < a; ++i)
        m.vertex[i] = PT.GetFaceChildVertex(pm.face[S.parent_faces[i]]);
      for (size_t i = a; i < b; ++i)
        m.vertex[i] = PT.GetEdgeChildVertex(pm.edge[S.parent_edges[i - a]]);
      for (size_t i = b; i < nv; ++i)
        m.vertex[i] = PT.GetVertexChildVertex(pm.vertex[S.parent_vertices[i - b]]);
    }
    std::vector<char> seen(size_t(T.GetNumVertices()), 0);
    for (size_t v = 0; v < nv; ++v) {
      ASSERT_TRUE(m.vertex[v] >= 0 && m.vertex[v] < T.GetNumVertices()) << "vertex " << v;
      ASSERT_FALSE(seen[size_t(m.vertex[v])]) << "two local vertices match one OSD vertex";
      seen[size_t(m.vertex[v])] = 1;
    }

    // Faces through their parent face and corner; the winding must be OpenSubdiv's.
    m.face.assign(nf, kInvalid);
    if (k == 0) {
      ASSERT_EQ(nf, cage.face_count());
      for (size_t f = 0; f < nf; ++f) m.face[f] = OsdIndex(f);
    } else {
      ASSERT_EQ(S.face_parent.size(), nf);
      const osd::Far::TopologyLevel& PT = *orf.levels[k - 1].topology;
      // OpenSubdiv rotates a quad's children so the corner's vertex point sits at the corner's
      // position; limn starts every child at its vertex point. So find the child by that point.
      for (size_t f = 0; f < nf; ++f) {
        const OsdIndex corner_point = m.vertex[L.face_vertices[L.face_offsets[f]]];
        for (OsdIndex c : PT.GetFaceChildFaces(maps[k - 1].face[S.face_parent[f]]))
          if (T.GetFaceVertices(c).FindIndex(corner_point) >= 0) m.face[f] = c;
        ASSERT_NE(m.face[f], kInvalid) << "face " << f << " matches no child of its parent";
      }
    }
    for (size_t f = 0; f < nf; ++f) {
      const auto fv = T.GetFaceVertices(m.face[f]);
      const uint32_t b = L.face_offsets[f], n = L.face_offsets[f + 1] - b;
      ASSERT_EQ(size_t(fv.size()), size_t(n)) << "face " << f;
      int shift = 0;
      while (shift < fv.size() && fv[shift] != m.vertex[L.face_vertices[b]]) ++shift;
      for (uint32_t i = 0; i < n; ++i)
        ASSERT_EQ(fv[(shift + int(i)) % fv.size()], m.vertex[L.face_vertices[b + i]])
            << "face " << f << " winding or vertices differ from OpenSubdiv's";
      EXPECT_EQ(L.face_hole[f] != 0, T.IsFaceHole(m.face[f])) << "hole tag of face " << f;
    }

    // Edges by their ends; sharpness as OpenSubdiv's.
    m.edge.assign(ne, kInvalid);
    for (size_t e = 0; e < ne; ++e) {
      m.edge[e] =
          T.FindEdge(m.vertex[L.edge_vertices[2 * e]], m.vertex[L.edge_vertices[2 * e + 1]]);
      ASSERT_NE(m.edge[e], kInvalid) << "edge " << e << " has no OpenSubdiv edge";
      EXPECT_NEAR(L.edge_sharpness[e], T.GetEdgeSharpness(m.edge[e]), 1e-6) << "edge " << e;
    }
    for (size_t v = 0; v < nv; ++v)
      EXPECT_NEAR(L.vertex_sharpness[v], T.GetVertexSharpness(m.vertex[v]), 1e-6) << "vertex " << v;

    // Completeness is never claimed where a face is missing.
    const std::vector<uint32_t> local = local_face_counts(L);
    for (size_t v = 0; v < nv; ++v) {
      if (!S.vertex_complete[v]) continue;
      ASSERT_EQ(local[v], uint32_t(T.GetVertexFaces(m.vertex[v]).size()))
          << "vertex " << v << " claims a whole ring";
    }

    // Positions: every local point is OpenSubdiv's.
    const std::vector<float> mine = sr.positions(cage, int(k));
    ASSERT_EQ(mine.size(), 3 * nv);
    const std::vector<double>& theirs = orf.levels[k].positions;
    double worst = 0;
    size_t bad = 0;
    for (size_t v = 0; v < nv; ++v) {
      const size_t ov = 3 * size_t(m.vertex[v]);
      double d = 0;
      for (size_t c = 0; c < 3; ++c)
        d = std::max(d, std::abs(double(mine[3 * v + c]) - theirs[ov + c]));
      worst = std::max(worst, d);
      bad += !(d <= tolerance);
    }
    EXPECT_EQ(bad, 0u) << "positions off by up to " << worst << " (tolerance " << tolerance << ")";
  }

  // Every request is honoured. A vertex request of depth d: at each level k <= d, every child of
  // the faces around the level-(k-1) descendant (the ring around the level-k descendant and its
  // siblings, which FAS turns into regular and transition patches) is present with whole
  // vertices. A face request: its descendants are present with whole vertices.
  auto expect_whole = [&](size_t k, OsdIndex of, const std::string& what) {
    const Maps& m = maps[k];
    const SparseLevel& S = sr.levels[k];
    const auto it = std::find(m.face.begin(), m.face.end(), of);
    ASSERT_NE(it, m.face.end()) << "level " << k << ": " << what << " is missing";
    const size_t f = size_t(it - m.face.begin());
    for (uint32_t c = S.level.face_offsets[f]; c < S.level.face_offsets[f + 1]; ++c)
      ASSERT_TRUE(S.vertex_complete[S.level.face_vertices[c]])
          << "level " << k << ": a vertex of " << what << " is not whole";
  };
  for (size_t v0 = 0; v0 < req.vertex.size(); ++v0) {
    OsdIndex ov = OsdIndex(v0);
    for (size_t k = 1; k <= req.vertex[v0]; ++k) {
      const osd::Far::TopologyLevel& PT = *orf.levels[k - 1].topology;
      for (OsdIndex pf : PT.GetVertexFaces(ov))
        for (OsdIndex of : PT.GetFaceChildFaces(pf))
          ASSERT_NO_FATAL_FAILURE(
              expect_whole(k, of, fmt::format("a face near cage vertex {}'s descendant", v0)));
      ov = PT.GetVertexChildVertex(ov);
    }
  }
  for (size_t f0 = 0; f0 < req.face.size(); ++f0) {
    std::vector<OsdIndex> faces = {OsdIndex(f0)};
    for (size_t k = 1; k <= req.face[f0]; ++k) {
      std::vector<OsdIndex> kids;
      for (OsdIndex f : faces)
        for (OsdIndex c : orf.levels[k - 1].topology->GetFaceChildFaces(f)) kids.push_back(c);
      faces.swap(kids);
      for (OsdIndex of : faces)
        ASSERT_NO_FATAL_FAILURE(
            expect_whole(k, of, fmt::format("a descendant of cage face {}", f0)));
    }
  }
}

// Deterministic requests: extraordinary and tagged vertices, a few faces, non-quads once.
Requests pick_requests(const Mesh& cage, uint64_t seed, int max_depth) {
  test::Rng rng(seed);
  const Topology t = build_topology(cage);
  Requests r;
  r.vertex.assign(cage.vertex_count(), 0);
  r.face.assign(cage.face_count(), 0);
  std::vector<uint8_t> tagged(cage.vertex_count(), 0);
  for (uint32_t v : cage.crease_edges) tagged[v] = 1;
  for (uint32_t v : cage.corner_vertices) tagged[v] = 1;
  size_t picked = 0;
  for (uint32_t v = 0; v < cage.vertex_count(); ++v) {
    const bool special = t.vertex_face_count(v) != 4 || tagged[v];
    // Not every special vertex, so that sparse regions have borders inside the surface.
    if (special && rng.below(3) != 0 && picked < 40) {
      r.vertex[v] = uint8_t(1 + rng.below(uint32_t(max_depth)));
      ++picked;
    }
  }
  for (size_t n = 0; n < 2; ++n)
    r.face[rng.below(uint32_t(cage.face_count()))] = uint8_t(1 + rng.below(2));
  for (size_t f = 0; f < cage.face_count(); ++f)
    if (cage.face_size(f) != 4 && r.face[f] == 0 && rng.below(2)) r.face[f] = 1;
  r.vertex[rng.below(uint32_t(cage.vertex_count()))] = uint8_t(max_depth);  // the deepest
  return r;
}

std::vector<fs::path> shared_cages() {
  return test::shared_cages(LIMN_SHARED_MODELS);
}

class SparseModel : public ::testing::TestWithParam<fs::path> {};

TEST_P(SparseModel, MatchesOpenSubdiv) {
  const Mesh cage = read_mesh(GetParam());
  for (CreaseMethod method : {CreaseMethod::uniform, CreaseMethod::chaikin}) {
    SubdivOptions o = subdiv_options(cage);
    o.crease_method = method;
    SCOPED_TRACE(method == CreaseMethod::chaikin ? "chaikin" : "uniform");
    expect_sparse_matches_osd(cage, pick_requests(cage, 17, cage.face_count() > 1000 ? 3 : 4), o);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, SparseModel, ::testing::ValuesIn(shared_cages()),
                         [](const auto& p) {
                           std::string s = p.param.stem().string();
                           for (char& c : s)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return s;
                         });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(SparseModel);

TEST(Sparse, SharedCagesPresent) {
  EXPECT_GE(shared_cages().size(), 20u) << "expected the cages in " << LIMN_SHARED_MODELS;
}

TEST(Sparse, RandomCagesEveryBoundaryAndCreaseRule) {
  for (uint64_t seed = 1; seed <= 10; ++seed)
    for (BoundaryInterpolation b : {BoundaryInterpolation::none, BoundaryInterpolation::edge_only,
                                    BoundaryInterpolation::edge_and_corner})
      for (CreaseMethod m : {CreaseMethod::uniform, CreaseMethod::chaikin}) {
        SCOPED_TRACE(fmt::format("seed {} boundary {} chaikin {}", seed, int(b), int(m)));
        const Mesh cage = test::random_cage(seed);
        SubdivOptions o;
        o.boundary = b;
        o.crease_method = m;
        o.smooth_triangles = seed % 2 == 1;
        expect_sparse_matches_osd(cage, pick_requests(cage, seed, 4), o);
        if (HasFatalFailure()) return;
      }
}

TEST(Sparse, DeepVertexOnACubeAndATorus) {
  // Depth 7 around one vertex; OpenSubdiv refines the whole cage uniformly as the reference.
  const Mesh cube = make_shape("cube");
  Requests r;
  r.vertex.assign(cube.vertex_count(), 0);
  r.vertex[0] = 7;
  expect_sparse_matches_osd(cube, r, subdiv_options(cube));
  const Mesh torus = make_shape("torus");
  Requests t;
  t.face.assign(torus.face_count(), 0);
  t.vertex.assign(torus.vertex_count(), 0);
  const Topology topo = build_topology(torus);
  for (uint32_t v = 0; v < torus.vertex_count(); ++v)
    if (topo.vertex_face_count(v) != 4) t.vertex[v] = 5;
  t.face[3] = 3;
  expect_sparse_matches_osd(torus, t, subdiv_options(torus));
}

TEST(Sparse, NothingRequestedIsTheCage) {
  const Mesh cube = make_shape("cube");
  const SparseRefinement sr = refine_sparse(cube, {}, {}, subdiv_options(cube));
  ASSERT_EQ(sr.levels.size(), 1u);
  EXPECT_EQ(sr.levels[0].level.face_vertices, cube.face_vertices);
  EXPECT_TRUE(sr.stencils.empty());
}

TEST(Sparse, LevelDoneFollowsEachRequestWithTheSameLevel) {
  // A lean run (levels dropped as it goes) refining everything twice: level_done(k) comes after
  // request(k) and before request(k + 1), once per level, the last one included, with the
  // level request(k) saw and that level's own adjacency; the last level's comes with corner
  // twins instead of edge -> corner lists, equal to the mesh layer's own corner table.
  const Mesh cage = make_shape("cage");
  std::vector<std::string> events;
  std::vector<size_t> faces_seen;
  const SparseRefinement sr = refine_sparse(
      cage, subdiv_options(cage),
      [&](size_t k, const SparseLevel& S, const LevelAdjacency&, std::vector<uint8_t>& req) {
        events.push_back("request " + std::to_string(k));
        faces_seen.push_back(S.level.face_count());
        if (k < 2) std::fill(req.begin(), req.end(), uint8_t(1));
      },
      false,
      [&](size_t k, const SparseLevel& S, const LevelAdjacency& a) {
        events.push_back("done " + std::to_string(k));
        ASSERT_LT(k, faces_seen.size());
        EXPECT_EQ(S.level.face_count(), faces_seen[k]);
        EXPECT_EQ(a.vertex_corner_offsets.size(), S.level.vertex_count() + 1);
        EXPECT_EQ(a.corner_edge.size(), S.level.face_vertices.size());
        if (k < 2) {
          EXPECT_EQ(a.edge_corner_offsets.size(), S.level.edge_count() + 1);
          EXPECT_TRUE(a.corner_twin.empty());
          return;
        }
        EXPECT_TRUE(a.edge_corner_offsets.empty() && a.edge_corners.empty());
        ASSERT_EQ(a.corner_twin.size(), S.level.face_vertices.size());
        Mesh m;
        m.face_offsets = S.level.face_offsets, m.face_vertices = S.level.face_vertices;
        m.positions.assign(3 * S.level.vertex_count(), 0.0f);
        const Topology t = build_topology(m);
        ASSERT_EQ(t.corner_twin.size(), a.corner_twin.size());
        size_t inner = 0;
        for (size_t c = 0; c < a.corner_twin.size(); ++c) {
          EXPECT_EQ(a.corner_twin[c], t.corner_twin[c]) << c;
          inner += a.corner_twin[c] < kNonManifold;
        }
        EXPECT_GT(inner, a.corner_twin.size() / 2);  // a closed cage: almost every edge has two
      });
  const std::vector<std::string> want = {"request 0", "done 0",    "request 1",
                                         "done 1",    "request 2", "done 2"};
  EXPECT_EQ(events, want);
  EXPECT_EQ(sr.stencils.size(), 2u);
  const UniformRefinement ur = refine_uniform(cage, 2, subdiv_options(cage));
  ASSERT_EQ(faces_seen.size(), 3u);
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(faces_seen[k], ur.levels[k].face_count()) << k;
}

TEST(Sparse, EverythingRequestedIsUniform) {
  // Local numbering may differ from the uniform levels' (edges come from another table), so
  // compare the point sets: the same points, as many faces.
  const Mesh cage = make_shape("cage");
  const std::vector<uint8_t> all(cage.face_count(), 3);
  const SparseRefinement sr = refine_sparse(cage, {}, all, subdiv_options(cage));
  const UniformRefinement ur = refine_uniform(cage, 3, subdiv_options(cage));
  ASSERT_EQ(sr.levels.size(), 4u);
  auto sorted_points = [](const std::vector<float>& p) {
    std::vector<std::array<float, 3>> q(p.size() / 3);
    for (size_t i = 0; i < q.size(); ++i) q[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    std::sort(q.begin(), q.end());
    return q;
  };
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(sr.levels[k].level.face_count(), ur.levels[k].face_count()) << "level " << k;
    EXPECT_EQ(sr.levels[k].level.edge_count(), ur.levels[k].edge_count()) << "level " << k;
    const auto a = sorted_points(sr.positions(cage, int(k)));
    const auto b = sorted_points(ur.positions(cage, int(k)));
    ASSERT_EQ(a.size(), b.size()) << "level " << k;
    for (size_t i = 0; i < a.size(); ++i)
      for (size_t c = 0; c < 3; ++c) ASSERT_NEAR(a[i][c], b[i][c], 1e-5f) << "level " << k;
    for (uint8_t w : sr.levels[k].vertex_complete) EXPECT_EQ(w, 1) << "level " << k;
  }
}

TEST(Sparse, WorkIsLinearInDepthNotExponential) {
  // One extraordinary vertex of BigGuy refined 8 deep: uniform level 8 would be 95M faces.
  const fs::path path = fs::path(LIMN_SHARED_MODELS) / "quads" / "bigguy.obj";
  ASSERT_TRUE(fs::exists(path)) << path;
  const Mesh cage = read_mesh(path);
  const Topology t = build_topology(cage);
  uint32_t ev = 0;
  while (t.vertex_face_count(ev) == 4) ++ev;
  std::vector<uint8_t> depth(cage.vertex_count(), 0);
  depth[ev] = 8;
  const SparseRefinement sr = refine_sparse(cage, depth, {}, subdiv_options(cage));
  ASSERT_EQ(sr.levels.size(), 9u);
  const size_t first = sr.levels[1].level.face_count();
  size_t total = 0;
  for (size_t k = 1; k <= 8; ++k) {
    const size_t n = sr.levels[k].level.face_count();
    EXPECT_LE(n, 2 * first) << "level " << k << " grew: the region must shrink with the level";
    total += n;
  }
  EXPECT_LT(total, 16 * first);
  // The vertex's descendant is whole at the deepest level and its limit stencil is usable.
  const SparseLevel& last = sr.levels.back();
  size_t desc = ev;
  for (size_t k = 1; k <= 8; ++k) {
    const SparseLevel& S = sr.levels[k];
    const auto it = std::find(S.parent_vertices.begin(), S.parent_vertices.end(), desc);
    ASSERT_NE(it, S.parent_vertices.end()) << "level " << k;
    desc = S.parent_faces.size() + S.parent_edges.size() + size_t(it - S.parent_vertices.begin());
  }
  EXPECT_TRUE(last.vertex_complete[desc]);
  EXPECT_EQ(last.vertex_depth[desc], 0);
  // A vertex's limit point does not move under refinement: the limit stencil of the deepest
  // descendant must land where the cage vertex's own limit stencil does.
  auto limit_at = [&](const RefinedLevel& L, const std::vector<float>& pts, size_t v) {
    const LimitStencils ls = limit_stencils(L);
    std::array<double, 3> q{0, 0, 0};
    const float* w = ls.position.row_weights(v);
    for (uint32_t j = ls.position.offsets[v]; j < ls.position.offsets[v + 1]; ++j)
      for (size_t c = 0; c < 3; ++c)
        q[c] += double(w[j - ls.position.offsets[v]]) * pts[3 * size_t(ls.position.indices[j]) + c];
    return q;
  };
  const auto deep = limit_at(last.level, sr.positions(cage, 8), desc);
  const auto cage_limit = limit_at(sr.levels[0].level, cage.positions, ev);
  for (size_t c = 0; c < 3; ++c)
    EXPECT_NEAR(deep[c], cage_limit[c], 1e-5 * bounding_box(cage).diagonal());
}

TEST(Sparse, CageStencilsMatchLevelByLevel) {
  // The flattened tables turn the cage straight into each sparse level's points.
  const Mesh cage = test::random_cage(3);
  const Requests req = pick_requests(cage, 3, 4);
  const SparseRefinement sr = refine_sparse(cage, req.vertex, req.face, subdiv_options(cage));
  const float tol = 1e-6f * bounding_box(cage).diagonal();
  for (int k = 1; k < int(sr.levels.size()); ++k) {
    const StencilTable flat = cage_stencils(sr, k);
    const std::vector<float> chained = sr.positions(cage, k);
    ASSERT_EQ(3 * flat.size(), chained.size()) << "level " << k;
    std::vector<float> direct(chained.size());
    apply_stencils(flat, cage.positions.data(), direct.data(), 3);
    for (size_t i = 0; i < direct.size(); ++i)
      ASSERT_NEAR(direct[i], chained[i], tol) << "level " << k << " value " << i;
  }
  EXPECT_THROW(cage_stencils(sr, 0), InputError);
}

TEST(Sparse, BadRequestsAreInputErrors) {
  const Mesh cube = make_shape("cube");
  const std::vector<uint8_t> short_list(3, 1), too_deep(cube.vertex_count(), 17);
  EXPECT_THROW(refine_sparse(cube, short_list, {}, {}), InputError);
  EXPECT_THROW(refine_sparse(cube, {}, short_list, {}), InputError);
  EXPECT_THROW(refine_sparse(cube, too_deep, {}, {}), InputError);
}

}  // namespace
}  // namespace limn
