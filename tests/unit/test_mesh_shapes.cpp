// Procedural shapes checked against brute-force edge counting written here (std::map over
// directed and undirected edges, no limn topology code), plus geometry and determinism checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "limn/mesh/shapes.hpp"

namespace limn {
namespace {

/// What a brute-force pass over all face edges finds.
struct Census {
  size_t vertices = 0, faces = 0, edges = 0;
  size_t boundary_edges = 0;      ///< undirected edges with one face
  size_t non_manifold_edges = 0;  ///< undirected edges with more than two faces
  size_t repeated_directed = 0;   ///< directed edges used by more than one face (misoriented)
  size_t unpaired_interior = 0;   ///< two-face edges not used once in each direction
  size_t unreferenced = 0;
  long boundary_loops = 0;  ///< -1 when a vertex has two outgoing boundary edges
  bool all_quads = true;
  std::vector<int> valence;  ///< undirected edges at each vertex
  std::vector<char> on_boundary;
  long euler() const { return long(vertices) - long(edges) + long(faces); }
};

Census census(const Mesh& m) {
  Census c;
  c.vertices = m.vertex_count();
  c.faces = m.face_count();
  std::map<std::pair<uint32_t, uint32_t>, int> directed, undirected;
  std::vector<char> used(c.vertices, 0);
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    if (fv.size() != 4) c.all_quads = false;
    for (size_t i = 0; i < fv.size(); ++i) {
      const uint32_t a = fv[i], b = fv[(i + 1) % fv.size()];
      ++directed[{a, b}];
      ++undirected[{std::min(a, b), std::max(a, b)}];
      used[a] = 1;
    }
  }
  c.edges = undirected.size();
  c.valence.assign(c.vertices, 0);
  c.on_boundary.assign(c.vertices, 0);
  for (char u : used) c.unreferenced += u == 0;
  for (const auto& [d, n] : directed) c.repeated_directed += n > 1;
  std::map<uint32_t, uint32_t> boundary_next;
  for (const auto& [e, n] : undirected) {
    ++c.valence[e.first];
    ++c.valence[e.second];
    if (n > 2) ++c.non_manifold_edges;
    const auto fwd = directed.find(e), rev = directed.find({e.second, e.first});
    const int nf = fwd == directed.end() ? 0 : fwd->second;
    const int nr = rev == directed.end() ? 0 : rev->second;
    if (n == 2 && !(nf == 1 && nr == 1)) ++c.unpaired_interior;
    if (n == 1) {
      ++c.boundary_edges;
      c.on_boundary[e.first] = c.on_boundary[e.second] = 1;
      const uint32_t from = nf ? e.first : e.second, to = nf ? e.second : e.first;
      if (!boundary_next.emplace(from, to).second) c.boundary_loops = -1;
    }
  }
  if (c.boundary_loops == 0) {
    // Every boundary vertex has one outgoing boundary edge: follow them and count the cycles.
    std::map<uint32_t, char> seen;
    for (const auto& [start, unused] : boundary_next) {
      if (seen[start]) continue;
      ++c.boundary_loops;
      for (uint32_t v = start; !seen[v]; v = boundary_next.count(v) ? boundary_next[v] : v)
        seen[v] = 1;
    }
  }
  return c;
}

/// Closed (or bounded), two faces per interior edge, each used once in each direction.
void expect_manifold_oriented(const Census& c) {
  EXPECT_EQ(c.non_manifold_edges, 0u);
  EXPECT_EQ(c.repeated_directed, 0u);
  EXPECT_EQ(c.unpaired_interior, 0u);
  EXPECT_EQ(c.unreferenced, 0u);
  EXPECT_TRUE(c.all_quads);
}

/// Newell normal of face f and its centroid, computed here rather than with limn's helpers.
void normal_and_centroid(const Mesh& m, size_t f, double n[3], double ctr[3]) {
  const auto fv = m.face(f);
  n[0] = n[1] = n[2] = ctr[0] = ctr[1] = ctr[2] = 0;
  for (size_t i = 0; i < fv.size(); ++i) {
    const float* a = &m.positions[3 * size_t(fv[i])];
    const float* b = &m.positions[3 * size_t(fv[(i + 1) % fv.size()])];
    n[0] += (double(a[1]) - b[1]) * (double(a[2]) + b[2]);
    n[1] += (double(a[2]) - b[2]) * (double(a[0]) + b[0]);
    n[2] += (double(a[0]) - b[0]) * (double(a[1]) + b[1]);
    for (int k = 0; k < 3; ++k) ctr[k] += a[k] / double(fv.size());
  }
}

/// Counts faces whose normal points towards `inside(centroid)` (the point they should face away
/// from) or is zero.
template <class Inside>
size_t inward_faces(const Mesh& m, Inside inside) {
  size_t bad = 0;
  for (size_t f = 0; f < m.face_count(); ++f) {
    double n[3], c[3], o[3];
    normal_and_centroid(m, f, n, c);
    inside(c, o);
    const double d = n[0] * (c[0] - o[0]) + n[1] * (c[1] - o[1]) + n[2] * (c[2] - o[2]);
    bad += !(d > 0);
  }
  return bad;
}

/// Nearest point of the torus's core circle (radius 1 in the xy plane).
void torus_core(const double c[3], double o[3]) {
  const double r = std::hypot(c[0], c[1]);
  o[0] = c[0] / r, o[1] = c[1] / r, o[2] = 0;
}

size_t count_valence(const Census& c, int n, bool interior_only = false) {
  size_t k = 0;
  for (size_t v = 0; v < c.valence.size(); ++v)
    k += c.valence[v] == n && !(interior_only && c.on_boundary[v]);
  return k;
}

TEST(Shapes, NamesAreListedAndUnknownNameThrows) {
  const std::vector<std::string> expected = {
      "cube", "torus", "cage", "terrain", "torus-dense", "terrain-small", "torus-dense-small"};
  auto names = shape_names();
  std::sort(names.begin(), names.end());
  auto want = expected;
  std::sort(want.begin(), want.end());
  EXPECT_EQ(names, want);
  EXPECT_THROW(make_shape("teapot"), InputError);
  try {
    make_shape("teapot");
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("'teapot'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("torus-dense-small"), std::string::npos) << msg;
  }
}

TEST(Shapes, SmallShapesValidateAndReferenceEveryVertex) {
  for (const char* name : {"cube", "torus", "cage", "terrain-small", "torus-dense-small"}) {
    SCOPED_TRACE(name);
    const Mesh m = make_shape(name);
    EXPECT_NO_THROW(validate(m, name));
    EXPECT_GT(m.face_count(), 0u);
    EXPECT_EQ(census(m).unreferenced, 0u);
  }
}

TEST(Shapes, CubeIsClosedOutwardGenusZero) {
  const Mesh m = make_cube();
  EXPECT_NO_THROW(validate(m));
  const Census c = census(m);
  EXPECT_EQ(c.vertices, 8u);
  EXPECT_EQ(c.faces, 6u);
  EXPECT_EQ(c.edges, 12u);
  EXPECT_EQ(c.euler(), 2);
  EXPECT_EQ(c.boundary_edges, 0u);
  expect_manifold_oriented(c);
  EXPECT_EQ(count_valence(c, 3), 8u);
  EXPECT_EQ(inward_faces(m, [](const double*, double* o) { o[0] = o[1] = o[2] = 0; }), 0u);
  for (float x : m.positions) EXPECT_EQ(std::fabs(x), 0.5f);
}

void check_torus(int major, int minor, const std::vector<int>& valences) {
  SCOPED_TRACE(::testing::Message()
               << major << "x" << minor << " valences " << ::testing::PrintToString(valences));
  const Mesh m = make_torus(major, minor, valences);
  EXPECT_NO_THROW(validate(m));
  const Census c = census(m);
  EXPECT_EQ(c.boundary_edges, 0u);
  EXPECT_EQ(c.boundary_loops, 0);
  expect_manifold_oriented(c);
  EXPECT_EQ(c.euler(), 0);
  // Each requested valence appears at least as often as requested. Valences above 5 come only
  // from block centres (rims get 3, 4 or 5), so those counts are exact.
  std::map<int, size_t> want;
  for (int n : valences) ++want[n];
  for (auto [n, k] : want) {
    if (n > 5)
      EXPECT_EQ(count_valence(c, n), k) << "valence " << n;
    else
      EXPECT_GE(count_valence(c, n), k) << "valence " << n;
  }
  for (int v : c.valence) {
    EXPECT_GE(v, 3);
    EXPECT_LE(v, 12);
  }
  // Every vertex, block centres included, lies on the torus (R = 1, r = 0.4), faces point away
  // from the core circle.
  double worst = 0;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const float* p = &m.positions[3 * v];
    const double d = std::hypot(std::hypot(double(p[0]), double(p[1])) - 1.0, double(p[2]));
    worst = std::max(worst, std::fabs(d - 0.4));
  }
  EXPECT_LT(worst, 1e-5);
  EXPECT_EQ(inward_faces(m, torus_core), 0u);
}

TEST(Shapes, TorusWithRequestedValences) {
  check_torus(48, 24, {3, 5, 6, 8});
  check_torus(48, 24, {7});
  check_torus(48, 24, {12});
  check_torus(16, 8, {12});  // 6 x 6 block: tight but fits with the wrap-around gap
  check_torus(40, 30, {3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  check_torus(6, 9, {3, 3, 3, 3, 3, 3});  // two rows of three blocks
  check_torus(6, 3, {});
}

TEST(Shapes, TorusSingleBlockValenceHistogram) {
  // One block of valence n on a regular torus. Even n uses an even x even block whose corners
  // get no spoke: the centre, n - 4 spoke-less rim vertices of valence 3, everything else 4.
  // Odd n cannot avoid spoking two corners (valence 5), leaving n - 2 rim vertices of valence 3.
  for (int n = 3; n <= 12; ++n) {
    SCOPED_TRACE(n);
    const Census c = census(make_torus(30, 20, std::vector<int>{n}));
    std::map<int, size_t> hist, want;
    for (int v : c.valence) ++hist[v];
    ++want[n];
    if (n % 2 == 0) {
      want[3] += size_t(n - 4);
    } else {
      want[5] += 2;
      want[3] += size_t(n - 2);
    }
    size_t rest = c.vertices;
    for (auto& [k, cnt] : want) rest -= cnt;
    want[4] += rest;
    std::erase_if(want, [](const auto& kv) { return kv.second == 0; });
    EXPECT_EQ(hist, want);
  }
}

TEST(Shapes, TorusBlockCentreSitsInTheMiddleOfItsRing) {
  // A block's rim is symmetric about the block's mean parameter, so on a fine grid (little
  // curvature across a block) the centre vertex must be close to the mean of its ring vertices,
  // compared with the ring's radius. A centre evaluated off the mean parameter is not.
  const Mesh m = make_torus(240, 160, std::vector<int>{6, 8, 10, 12});
  const Census c = census(m);
  size_t checked = 0;
  for (uint32_t v = 0; v < c.vertices; ++v) {
    if (c.valence[v] < 6) continue;  // rims only have valences 3 to 5
    std::map<uint32_t, int> ring;    // vertices of the faces around v
    for (size_t f = 0; f < m.face_count(); ++f) {
      const auto fv = m.face(f);
      if (std::find(fv.begin(), fv.end(), v) == fv.end()) continue;
      for (uint32_t w : fv)
        if (w != v) ring[w] = 1;
    }
    ASSERT_EQ(ring.size(), 2 * size_t(c.valence[v]));  // the block's boundary
    double mean[3] = {0, 0, 0}, radius = 0, off = 0;
    for (auto [w, unused] : ring)
      for (int k = 0; k < 3; ++k) mean[k] += m.positions[3 * w + k] / double(ring.size());
    for (auto [w, unused] : ring) {
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(m.positions[3 * w + k] - mean[k], 2);
      radius += std::sqrt(d2) / double(ring.size());
    }
    for (int k = 0; k < 3; ++k) off += std::pow(m.positions[3 * v + k] - mean[k], 2);
    EXPECT_LT(std::sqrt(off), 0.15 * radius) << "valence " << c.valence[v];
    ++checked;
  }
  EXPECT_EQ(checked, 4u);
}

TEST(Shapes, DefaultTorusMatchesDocumentedParameters) {
  const Mesh m = make_shape("torus");
  const Census c = census(m);
  for (int n : {3, 5, 6, 8}) EXPECT_GE(count_valence(c, n), 1u) << n;
  // 48 x 24 quads changed by 1 - (a-1)(b-1) per block: 1x2 +1, 2x3 -1, 2x4 -2, 4x4 -8.
  EXPECT_EQ(m.face_count(), 48u * 24u + 1 - 1 - 2 - 8);
  EXPECT_EQ(c.euler(), 0);
}

TEST(Shapes, TorusRejectsWhatDoesNotFit) {
  EXPECT_THROW(make_torus(48, 24, std::vector<int>{2}), std::invalid_argument);
  EXPECT_THROW(make_torus(48, 24, std::vector<int>{13}), std::invalid_argument);
  EXPECT_THROW(make_torus(6, 6, std::vector<int>{12}), std::invalid_argument);  // 6x6 block
  EXPECT_THROW(make_torus(16, 6, std::vector<int>{12}), std::invalid_argument);
  EXPECT_THROW(make_torus(8, 8, std::vector<int>{8, 8}), std::invalid_argument);
  EXPECT_THROW(make_torus(2, 8, std::vector<int>{}), std::invalid_argument);
  EXPECT_NO_THROW(make_torus(10, 5, std::vector<int>{8, 8}));  // 4x4 blocks side by side
}

TEST(Shapes, CreaseCageTags) {
  const Mesh m = make_crease_cage();
  EXPECT_NO_THROW(validate(m));
  const Census c = census(m);
  EXPECT_EQ(c.faces, 45u);  // 5 sides of 3 x 3
  expect_manifold_oriented(c);
  EXPECT_EQ(c.boundary_loops, 1);
  EXPECT_EQ(c.boundary_edges, 12u);  // the open top rim
  EXPECT_EQ(c.euler(), 1);           // a disc
  EXPECT_EQ(inward_faces(m, [](const double*, double* o) { o[0] = o[1] = o[2] = 0; }), 0u);
  // The open rim is at the top: every boundary vertex has z = 1.
  for (size_t v = 0; v < c.vertices; ++v)
    if (c.on_boundary[v]) {
      EXPECT_FLOAT_EQ(m.positions[3 * v + 2], 1.0f);
    }

  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    for (size_t i = 0; i < fv.size(); ++i) {
      const uint32_t a = fv[i], b = fv[(i + 1) % fv.size()];
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  }
  ASSERT_EQ(m.crease_edges.size(), 2 * m.crease_sharpness.size());
  size_t infinite = 0, semi = 0;
  for (size_t e = 0; e < m.crease_sharpness.size(); ++e) {
    const uint32_t a = m.crease_edges[2 * e], b = m.crease_edges[2 * e + 1];
    EXPECT_TRUE(edges.count({std::min(a, b), std::max(a, b)})) << "crease " << e;
    const float s = m.crease_sharpness[e];
    if (s == kInfiniteSharpness) {
      ++infinite;  // bottom rim: both ends at z = -1
      EXPECT_FLOAT_EQ(m.positions[3 * a + 2], -1.0f);
      EXPECT_FLOAT_EQ(m.positions[3 * b + 2], -1.0f);
    } else if (s == 2.5f) {
      ++semi;  // vertical: same x and y at both ends
      EXPECT_FLOAT_EQ(m.positions[3 * a], m.positions[3 * b]);
      EXPECT_FLOAT_EQ(m.positions[3 * a + 1], m.positions[3 * b + 1]);
    }
  }
  EXPECT_EQ(infinite, 12u);
  EXPECT_EQ(semi, 6u);
  ASSERT_EQ(m.corner_vertices.size(), 2u);
  ASSERT_EQ(m.corner_sharpness.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const uint32_t v = m.corner_vertices[i];
    ASSERT_LT(v, c.vertices);
    EXPECT_EQ(c.valence[v], 3);  // a box corner
    EXPECT_FLOAT_EQ(m.positions[3 * v + 2], -1.0f);
    EXPECT_EQ(m.corner_sharpness[i], kInfiniteSharpness);
  }
  ASSERT_EQ(m.hole_faces.size(), 1u);
  EXPECT_LT(m.hole_faces[0], m.face_count());
  EXPECT_EQ(m.tags.boundary, BoundaryInterpolation::edge_and_corner);
  EXPECT_EQ(m.tags.crease_method, CreaseMethod::uniform);
}

TEST(Shapes, TerrainSmall) {
  const Mesh m = make_shape("terrain-small");
  const Census c = census(m);
  expect_manifold_oriented(c);
  EXPECT_EQ(c.boundary_loops, 1);
  EXPECT_EQ(c.boundary_edges, 4u * 64u);  // blocks stay off the boundary
  EXPECT_EQ(c.euler(), 1);
  // 64 / 12 = 5 lattice sites per side, one block each, valences 3, 5 or 6.
  size_t centres = 0;
  for (int n : {3, 5, 6}) centres += count_valence(c, n, true) > 0;
  EXPECT_EQ(centres, 3u) << "some of valences 3, 5, 6 missing";
  for (size_t v = 0; v < c.vertices; ++v)
    if (!c.on_boundary[v]) {
      EXPECT_GE(c.valence[v], 3);
      EXPECT_LE(c.valence[v], 6);
    }
  EXPECT_NEAR(double(m.face_count()), 64.0 * 64.0, 25 * 2);
  EXPECT_EQ(
      inward_faces(m, [](const double* p, double* o) { o[0] = p[0], o[1] = p[1], o[2] = -1; }), 0u);
  for (size_t v = 0; v < c.vertices; ++v) {
    EXPECT_LE(std::fabs(m.positions[3 * v]), 1.0f);
    EXPECT_LE(std::fabs(m.positions[3 * v + 1]), 1.0f);
    EXPECT_LE(std::fabs(m.positions[3 * v + 2]), 0.1501f);
  }
}

TEST(Shapes, TerrainIsDeterministicPerSeed) {
  const Mesh a = make_shape("terrain-small", 7), b = make_shape("terrain-small", 7);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.face_offsets, b.face_offsets);
  EXPECT_EQ(a.face_vertices, b.face_vertices);
  const Mesh d = make_shape("terrain-small", 8);
  EXPECT_NE(a.positions, d.positions);
  EXPECT_NE(a.face_vertices, d.face_vertices);  // different block sites
  const Mesh t1 = make_shape("torus-dense-small", 3), t2 = make_shape("torus-dense-small", 3);
  EXPECT_EQ(t1.positions, t2.positions);
  EXPECT_EQ(t1.face_vertices, t2.face_vertices);
  EXPECT_NE(t1.face_vertices, make_shape("torus-dense-small", 4).face_vertices);
}

TEST(Shapes, TerrainSmallGridsAndBadArguments) {
  for (int n : {1, 5, 6, 13}) {
    SCOPED_TRACE(n);
    const Mesh m = make_terrain(n, 1, 6);
    const Census c = census(m);
    expect_manifold_oriented(c);
    EXPECT_EQ(c.boundary_loops, 1);
    EXPECT_EQ(c.euler(), 1);
  }
  EXPECT_THROW(make_terrain(0, 1), std::invalid_argument);
  EXPECT_THROW(make_terrain(64, 1, 5), std::invalid_argument);
}

TEST(Shapes, DenseTorusSmall) {
  const Mesh m = make_shape("torus-dense-small");
  EXPECT_NO_THROW(validate(m));
  const Census c = census(m);
  expect_manifold_oriented(c);
  EXPECT_EQ(c.boundary_edges, 0u);
  EXPECT_EQ(c.euler(), 0);
  size_t ev = 0;
  for (int v : c.valence) ev += v != 4;
  const double frac = double(ev) / double(c.vertices);
  EXPECT_GE(frac, 0.05);
  EXPECT_LE(frac, 0.20);
  for (int n : {3, 5, 6, 8}) EXPECT_GT(count_valence(c, n), 0u) << n;
  EXPECT_EQ(inward_faces(m, torus_core), 0u);
  for (int seed : {2, 3}) {  // other seeds and odd sizes are just as well formed
    const Census o = census(make_dense_torus(37, 19, uint64_t(seed)));
    expect_manifold_oriented(o);
    EXPECT_EQ(o.boundary_edges, 0u);
    EXPECT_EQ(o.euler(), 0);
  }
  for (auto [w, h] : {std::pair{3, 3}, std::pair{5, 9}}) {  // tiles too small for blocks
    const Census o = census(make_dense_torus(w, h, 1));
    expect_manifold_oriented(o);
    EXPECT_EQ(o.euler(), 0);
  }
}

// The large shapes are checked with sorted directed-edge keys instead of std::map (1.6M edges);
// still independent of limn's topology code.
struct FastCheck {
  size_t repeated = 0, unpaired = 0, interior_ev = 0, vertices = 0;
};
FastCheck fast_check(const Mesh& m) {
  FastCheck r;
  std::vector<uint64_t> keys;
  keys.reserve(m.corner_count());
  std::vector<int> val(m.vertex_count(), 0);
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    for (size_t i = 0; i < fv.size(); ++i)
      keys.push_back(uint64_t(fv[i]) << 32 | fv[(i + 1) % fv.size()]);
  }
  std::sort(keys.begin(), keys.end());
  std::vector<char> boundary(m.vertex_count(), 0);
  for (size_t i = 0; i < keys.size(); ++i) {
    if (i > 0 && keys[i] == keys[i - 1]) ++r.repeated;
    const uint32_t a = uint32_t(keys[i] >> 32), b = uint32_t(keys[i]);
    ++val[a];  // outgoing half-edges: the valence in a closed mesh, one less on a boundary
    if (!std::binary_search(keys.begin(), keys.end(), uint64_t(b) << 32 | a)) {
      ++r.unpaired;
      boundary[a] = boundary[b] = 1;
    }
  }
  r.vertices = m.vertex_count();
  for (size_t v = 0; v < val.size(); ++v) r.interior_ev += !boundary[v] && val[v] != 4;
  return r;
}

TEST(Shapes, FullSizeTerrainAndDenseTorus) {
  for (const char* name : {"terrain", "torus-dense"}) {
    SCOPED_TRACE(name);
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh m = make_shape(name);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_NO_THROW(validate(m, name));
    EXPECT_GE(m.face_count(), 790000u);
    EXPECT_LE(m.face_count(), 810000u);
    const FastCheck r = fast_check(m);
    EXPECT_EQ(r.repeated, 0u);
    const bool closed = std::string(name) == "torus-dense";
    EXPECT_EQ(r.unpaired, closed ? 0u : 4u * 895u);
    const double frac = double(r.interior_ev) / double(r.vertices);
    if (closed) {
      EXPECT_GE(frac, 0.05);
      EXPECT_LE(frac, 0.20);
    } else {
      EXPECT_GT(r.interior_ev, 1000u);
    }
    std::printf(
        "[ shapes   ] %s: %zu vertices, %zu faces, %.2f%% extraordinary, built in %.0f ms\n", name,
        m.vertex_count(), m.face_count(), 100.0 * frac, ms);
  }
}

}  // namespace
}  // namespace limn
