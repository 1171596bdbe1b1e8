// subdivide_uniform (lean: stencils built, applied and dropped chunk by chunk) must produce
// exactly the last level of refine_uniform, which the OpenSubdiv conformance tests check: the
// same points bit for bit, the same faces less the holes, the same remaining sharpness.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <tuple>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/refine.hpp"
#include "random_cage.hpp"

#ifndef LIMN_SHARED_MODELS
#define LIMN_SHARED_MODELS "/work/shared/models"
#endif

namespace limn {
namespace {

namespace fs = std::filesystem;

using Crease = std::tuple<uint32_t, uint32_t, float>;

void expect_lean_matches_full(const Mesh& cage, int depth, const SubdivOptions& o) {
  SCOPED_TRACE(fmt::format("depth {}", depth));
  const UniformRefinement ur = refine_uniform(cage, depth, o);
  SubdivideStats st;
  const Mesh m = subdivide_uniform(cage, depth, o, &st);
  const RefinedLevel& L = ur.levels.back();

  ASSERT_EQ(st.levels.size(), ur.levels.size());
  for (size_t k = 0; k < ur.levels.size(); ++k) {
    EXPECT_EQ(st.levels[k].vertices, ur.levels[k].vertex_count()) << "level " << k;
    EXPECT_EQ(st.levels[k].faces, ur.levels[k].face_count()) << "level " << k;
    EXPECT_EQ(st.levels[k].edges, ur.levels[k].edge_count()) << "level " << k;
    if (k > 0) {
      EXPECT_EQ(st.levels[k].stencil_entries, ur.stencils[k - 1].indices.size());
    }
  }
  EXPECT_GE(st.topology_ms, 0.0);

  EXPECT_EQ(m.positions, ur.positions(cage, depth)) << "points differ";
  Mesh faces;
  for (size_t f = 0; f < L.face_count(); ++f)
    if (!L.face_hole[f])
      faces.add_face(std::span<const uint32_t>(L.face_vertices.data() + L.face_offsets[f],
                                               L.face_offsets[f + 1] - L.face_offsets[f]));
  EXPECT_EQ(m.face_offsets, faces.face_offsets);
  EXPECT_EQ(m.face_vertices, faces.face_vertices);
  if (depth == 0) return;  // the cage keeps its own tags

  std::set<Crease> want, got;
  for (size_t e = 0; e < L.edge_count(); ++e)
    if (L.edge_sharpness[e] > 0)
      want.emplace(L.edge_vertices[2 * e], L.edge_vertices[2 * e + 1], L.edge_sharpness[e]);
  for (size_t i = 0; i < m.crease_sharpness.size(); ++i) {
    const uint32_t a = m.crease_edges[2 * i], b = m.crease_edges[2 * i + 1];
    got.emplace(std::min(a, b), std::max(a, b), m.crease_sharpness[i]);
  }
  EXPECT_EQ(got, want) << "remaining creases";
  std::set<std::pair<uint32_t, float>> want_c, got_c;
  for (size_t v = 0; v < L.vertex_count(); ++v)
    if (L.vertex_sharpness[v] > 0) want_c.emplace(uint32_t(v), L.vertex_sharpness[v]);
  for (size_t i = 0; i < m.corner_vertices.size(); ++i)
    got_c.emplace(m.corner_vertices[i], m.corner_sharpness[i]);
  EXPECT_EQ(got_c, want_c) << "remaining corners";
  EXPECT_EQ(m.tags.boundary, cage.tags.boundary);
}

TEST(SubdivideLean, ShapesEveryDepth) {
  for (const char* name : {"cage", "torus", "cube"}) {
    SCOPED_TRACE(name);
    const Mesh cage = make_shape(name);
    for (int d = 0; d <= 3; ++d) expect_lean_matches_full(cage, d, subdiv_options(cage));
  }
}

TEST(SubdivideLean, HolesCreasesAndChaikin) {
  for (const char* f : {"osd/catmark_hole_test1.obj", "osd/catmark_cubes_semisharp.obj",
                        "osd/catmark_chaikin0.obj", "osd/catmark_nonquads.obj"}) {
    SCOPED_TRACE(f);
    const fs::path p = fs::path(LIMN_SHARED_MODELS) / f;
    ASSERT_TRUE(fs::exists(p)) << p;
    const Mesh cage = read_mesh(p);
    expect_lean_matches_full(cage, 3, subdiv_options(cage));
  }
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(fmt::format("random cage {}", seed));
    const Mesh cage = test::random_cage(seed);
    SubdivOptions o;
    o.crease_method = seed % 2 ? CreaseMethod::chaikin : CreaseMethod::uniform;
    expect_lean_matches_full(cage, 3, o);
  }
}

TEST(SubdivideLean, LargeEnoughForParallelChunks) {
  // terrain-small at level 2 has more points than one stencil chunk, so chunks run in parallel.
  const Mesh cage = make_shape("terrain-small");
  expect_lean_matches_full(cage, 2, subdiv_options(cage));
}

TEST(SubdivideLean, BadDepthIsAnInputError) {
  const Mesh cube = make_shape("cube");
  EXPECT_THROW(subdivide_uniform(cube, 9, {}), InputError);
  EXPECT_THROW(subdivide_uniform(cube, -1, {}), InputError);
}

}  // namespace
}  // namespace limn
