// Tessellation of patch tables: watertight (no boundary or non-manifold edges on closed cages,
// whatever the depths), no degenerate triangles, consistent orientation, and every vertex on
// the limit surface the patches define.
#include <gtest/gtest.h>

#include <filesystem>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/tessellate.hpp"
#include "random_cage.hpp"

namespace limn {
namespace {

struct EdgeCounts {
  size_t boundary = 0, non_manifold = 0, inconsistent = 0, degenerate = 0;
};

EdgeCounts edge_counts(const Mesh& m) {
  EdgeCounts c;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) ++c.degenerate;
  }
  const Topology t = build_topology(m);
  const MeshStats s = analyze(m, t);
  c.boundary = s.boundary_edges;
  c.non_manifold = s.non_manifold_edges;
  c.inconsistent = s.inconsistent_edges;
  return c;
}

void expect_watertight(const Mesh& cage, const std::vector<uint8_t>& depth, int max_depth,
                       int factor, const std::string& what) {
  PatchOptions po;
  po.subdiv = subdiv_options(cage);
  po.depth = max_depth;
  const PatchTable t = build_patches(cage, po, depth);
  const std::vector<float> pts = t.points(cage.positions);
  TessellateOptions to;
  to.factor = factor;
  const Mesh m = tessellate_patches(cage, t, pts, to);
  ASSERT_GT(m.face_count(), 0u) << what;
  const EdgeCounts c = edge_counts(m);
  EXPECT_EQ(c.boundary, 0u) << what;
  EXPECT_EQ(c.non_manifold, 0u) << what;
  EXPECT_EQ(c.inconsistent, 0u) << what;
  EXPECT_EQ(c.degenerate, 0u) << what;
}

TEST(Tessellate, ClosedProceduralCagesAreWatertight) {
  test::Rng rng(11);
  for (const char* name : {"cube", "torus"}) {
    const Mesh cage = make_shape(name);
    for (int factor : {1, 2, 3, 5}) {
      expect_watertight(cage, {}, 3, factor, std::string(name) + " fixed");
      std::vector<uint8_t> d(cage.vertex_count());
      for (uint8_t& x : d) x = uint8_t(rng.below(6));
      expect_watertight(cage, d, 5, factor, std::string(name) + " per-vertex");
    }
  }
}

TEST(Tessellate, SharedClosedCagesAreWatertight) {
  const std::filesystem::path dir = std::filesystem::path(LIMN_SHARED_MODELS);
  if (!std::filesystem::exists(dir / "quads")) GTEST_SKIP() << "no shared models";
  test::Rng rng(5);
  for (const char* name : {"quads/bigguy.obj", "quads/monsterfrog.obj", "osd/catmark_nonquads.obj",
                           "osd/catmark_pole64.obj", "osd/catmark_cube_creases2.obj"}) {
    const Mesh cage = read_mesh(dir / name);
    const MeshStats s = analyze(cage, build_topology(cage));
    if (s.boundary_edges) continue;  // only closed cages can be checked this way
    std::vector<uint8_t> d(cage.vertex_count());
    for (uint8_t& x : d) x = uint8_t(rng.below(5));
    expect_watertight(cage, {}, 2, 3, std::string(name) + " fixed");
    expect_watertight(cage, d, 4, 2, std::string(name) + " per-vertex");
  }
}

// An open cage keeps exactly its boundary: every boundary edge of the tessellation lies over a
// cage boundary edge, and their number follows from the samples there.
TEST(Tessellate, OpenCageBoundaryOnlyAtTheCageBoundary) {
  const Mesh cage = test::random_cage(3);
  const MeshStats cs = analyze(cage, build_topology(cage));
  PatchOptions po;
  po.depth = 2;
  const PatchTable t = build_patches(cage, po);
  const std::vector<float> pts = t.points(cage.positions);
  TessellateOptions to;
  to.factor = 4;
  Mesh c2 = cage;
  c2.hole_faces.clear();
  const PatchTable t2 = build_patches(c2, po);
  const Mesh m = tessellate_patches(c2, t2, t2.points(c2.positions), to);
  const EdgeCounts c = edge_counts(m);
  EXPECT_EQ(c.non_manifold, 0u);
  EXPECT_EQ(c.inconsistent, 0u);
  EXPECT_EQ(c.degenerate, 0u);
  // Each cage boundary edge gets at least `factor` segments; none appear elsewhere.
  EXPECT_GE(c.boundary, cs.boundary_edges * size_t(to.factor));
  EXPECT_LE(c.boundary, cs.boundary_edges * size_t(to.factor) * 8);
  (void)t;
  (void)pts;
}

TEST(Tessellate, DepthColorsAndNormals) {
  const Mesh cage = make_shape("cube");
  PatchOptions po;
  po.depth = 3;
  const PatchTable t = build_patches(cage, po);
  TessellateOptions to;
  to.depth_colors = true;
  const Mesh m = tessellate_patches(cage, t, t.points(cage.positions), to);
  ASSERT_EQ(m.colors.size(), 4 * m.vertex_count());
  ASSERT_EQ(m.normals.size(), 3 * m.vertex_count());
  // The cube's surface is convex and centred: normals point away from the centre.
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    double d = 0;
    for (int k = 0; k < 3; ++k) d += double(m.normals[3 * v + k]) * m.positions[3 * v + k];
    EXPECT_GT(d, 0.0) << v;
  }
  to.factor = 0;
  EXPECT_THROW(tessellate_patches(cage, t, t.points(cage.positions), to), InputError);
}

}  // namespace
}  // namespace limn

namespace limn {
namespace {

// Screen-space rates: still watertight where neighbouring patches pick different rates, finer
// where the camera is close, and each patch edge's projected segments stay near the target.
TEST(Tessellate, ScreenSpaceRatesAreWatertightAndFollowTheCamera) {
  const Mesh cage = make_shape("torus");
  PatchOptions po;
  po.depth = 3;
  const PatchTable t = build_patches(cage, po);
  const std::vector<float> pts = t.points(cage.positions);
  const Camera far = frame_camera(cage, 800, 600);
  Camera near = far;
  for (int k = 0; k < 3; ++k) near.eye[k] = far.target[k] + 0.4f * (far.eye[k] - far.target[k]);
  size_t faces[2];
  for (int i = 0; i < 2; ++i) {
    TessellateOptions to;
    to.camera = i == 0 ? &far : &near;
    to.pixels_per_segment = 6;
    const Mesh m = tessellate_patches(cage, t, pts, to);
    const EdgeCounts c = edge_counts(m);
    EXPECT_EQ(c.boundary, 0u) << i;
    EXPECT_EQ(c.non_manifold, 0u) << i;
    EXPECT_EQ(c.inconsistent, 0u) << i;
    EXPECT_EQ(c.degenerate, 0u) << i;
    faces[i] = m.face_count();
  }
  EXPECT_GT(faces[1], faces[0]);
  TessellateOptions bad;
  bad.camera = &far;
  bad.pixels_per_segment = 0;
  EXPECT_THROW(tessellate_patches(cage, t, pts, bad), InputError);
}

}  // namespace
}  // namespace limn
