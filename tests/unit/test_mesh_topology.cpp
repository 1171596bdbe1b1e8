// Corner table and analysis against brute-force references on small meshes and procedural shapes.
#include <gtest/gtest.h>

#include <array>

#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "oracle.hpp"

namespace limn {
namespace {

Mesh grid(int n) {  // n x n quads, open
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.add_vertex(float(i), float(j), 0.0f);
  auto id = [&](int i, int j) { return uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      m.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  return m;
}

void expect_topology_consistent(const Mesh& m) {
  const Topology t = build_topology(m);
  const test::BruteStats b = test::brute_stats(m);
  ASSERT_EQ(t.edge_count(), b.edges);
  for (size_t c = 0; c < m.corner_count(); ++c) {
    const uint32_t e = t.corner_edge[c];
    const uint32_t a = m.face_vertices[c], bb = m.face_vertices[t.corner_next[c]];
    ASSERT_EQ(t.edge_vertices[2 * e], std::min(a, bb));
    ASSERT_EQ(t.edge_vertices[2 * e + 1], std::max(a, bb));
    const uint32_t tw = t.corner_twin[c];
    if (tw < kNonManifold) {
      EXPECT_EQ(t.corner_edge[tw], e);
      EXPECT_EQ(t.corner_twin[tw], c);
      EXPECT_NE(t.corner_face[tw], t.corner_face[c]);
    }
    EXPECT_EQ(t.edge_faces[e] == 1, tw == kNone);
    EXPECT_EQ(t.edge_faces[e] > 2, tw == kNonManifold);
  }
  const MeshStats s = analyze(m, t);
  EXPECT_EQ(s.boundary_edges, b.boundary_edges);
  EXPECT_EQ(s.non_manifold_edges, b.non_manifold_edges);
  EXPECT_EQ(s.inconsistent_edges, b.inconsistent_edges);
  EXPECT_EQ(s.components, b.components);
  if (s.non_manifold_vertices == 0) {
    EXPECT_EQ(s.boundary_loops, b.boundary_loops);
  }
  EXPECT_EQ(s.referenced_vertices, b.referenced);
}

TEST(Topology, CubeIsClosedGenusZero) {
  const Mesh m = make_cube();
  const MeshStats s = analyze(m, build_topology(m));
  EXPECT_EQ(s.edges, 12u);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_EQ(s.genus, 0);
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.extraordinary_vertices, 8u);  // valence 3 corners
  EXPECT_EQ(s.inconsistent_edges, 0u);
  expect_topology_consistent(m);
}

TEST(Topology, GridBoundaryAndValences) {
  const Mesh m = grid(4);
  const MeshStats s = analyze(m, build_topology(m));
  EXPECT_EQ(s.edges, 40u);
  EXPECT_EQ(s.boundary_edges, 16u);
  EXPECT_EQ(s.boundary_loops, 1u);
  EXPECT_EQ(s.genus, 0);
  EXPECT_EQ(s.extraordinary_vertices, 0u);  // interior valence 4, boundary 1 or 2 faces
  expect_topology_consistent(m);
}

TEST(Topology, NonManifoldEdgeIsReportedNotRejected) {
  Mesh m;  // three triangles sharing edge 0-1: a "book" with three pages
  for (auto p : {std::array<float, 3>{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}})
    m.add_vertex(p[0], p[1], p[2]);
  m.add_face({0, 1, 2});
  m.add_face({1, 0, 3});
  m.add_face({0, 1, 4});
  const MeshStats s = analyze(m, build_topology(m));
  EXPECT_EQ(s.non_manifold_edges, 1u);
  EXPECT_GE(s.non_manifold_vertices, 2u);
  EXPECT_EQ(s.genus, -1);
  expect_topology_consistent(m);
}

TEST(Topology, BowtieVertexIsNonManifold) {
  Mesh m;  // two triangles touching at vertex 0 only
  for (auto p : {std::array<float, 3>{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}})
    m.add_vertex(p[0], p[1], p[2]);
  m.add_face({0, 1, 2});
  m.add_face({0, 3, 4});
  const MeshStats s = analyze(m, build_topology(m));
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.non_manifold_vertices, 1u);
  EXPECT_EQ(s.components, 1u);
  expect_topology_consistent(m);
}

TEST(Topology, FlippedFaceIsInconsistent) {
  Mesh m = grid(2);
  std::swap(m.face_vertices[1], m.face_vertices[3]);  // reverse face 0
  const MeshStats s = analyze(m, build_topology(m));
  EXPECT_EQ(s.inconsistent_edges, 2u);
  expect_topology_consistent(m);
}

TEST(Topology, UnreferencedAndDegenerate) {
  Mesh m = grid(1);
  m.add_vertex(5, 5, 5);  // unreferenced
  const uint32_t a = m.add_vertex(2, 0, 0), b = m.add_vertex(3, 0, 0), c = m.add_vertex(4, 0, 0);
  m.add_face({a, b, c});  // collinear: zero area
  const MeshStats s = analyze(m, build_topology(m));
  EXPECT_EQ(s.unreferenced_vertices, 1u);
  EXPECT_EQ(s.degenerate_faces, 1u);
  EXPECT_EQ(s.components, 2u);
}

TEST(Topology, ProceduralShapesAgreeWithBruteForce) {
  for (const char* name : {"cube", "torus", "cage", "terrain-small", "torus-dense-small"}) {
    SCOPED_TRACE(name);
    expect_topology_consistent(make_shape(name));
  }
}

TEST(Topology, LargeMeshUsesThreadsAndStaysDeterministic) {
  const Mesh m = grid(300);  // 90k quads: above the parallel threshold
  const Topology a = build_topology(m), b = build_topology(m);
  EXPECT_EQ(a.corner_edge, b.corner_edge);
  EXPECT_EQ(a.corner_twin, b.corner_twin);
  const MeshStats s = analyze(m, a);
  EXPECT_EQ(s.edges, 2u * 300 * 301);
  EXPECT_EQ(s.boundary_loops, 1u);
}

}  // namespace
}  // namespace limn
