// STL reading and writing: ascii and binary (also a binary header that starts with "solid"),
// welding into a closed indexed mesh, degenerate triangles, round trips through write_stl, and
// bad input rejected with one line naming the file and the facet or line.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "bad_input.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/mesh/weld.hpp"

#ifndef LIMN_TEST_DATA
#define LIMN_TEST_DATA "tests/data"
#endif

namespace limn {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

using Tri = std::array<std::array<float, 3>, 3>;

// The unit cube's 12 outward triangles, each listing its own copies of the corners.
std::vector<Tri> cube_triangles() {
  const Mesh cube = make_cube();
  std::vector<Tri> out;
  for (size_t f = 0; f < cube.face_count(); ++f) {
    const auto fv = cube.face(f);
    for (size_t i = 1; i + 1 < fv.size(); ++i) {
      Tri t;
      const uint32_t c[3] = {fv[0], fv[i], fv[i + 1]};
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) t[k][j] = cube.positions[3 * c[k] + j];
      out.push_back(t);
    }
  }
  return out;
}

std::string ascii_stl(const std::vector<Tri>& tris, const char* eol = "\n") {
  std::string s = std::string("solid cube") + eol;
  for (const Tri& t : tris) {
    s += std::string("  facet normal 0 0 0") + eol + "    outer loop" + eol;
    for (const auto& v : t) s += fmt::format("      vertex {} {} {}{}", v[0], v[1], v[2], eol);
    s += std::string("    endloop") + eol + "  endfacet" + eol;
  }
  return s + "endsolid cube" + eol;
}

template <class T>
void put(std::string& s, T v) {
  char b[sizeof v];
  std::memcpy(b, &v, sizeof v);
  s.append(b, sizeof v);
}

std::string binary_stl(const std::vector<Tri>& tris, std::string header = "binary") {
  header.resize(80, '\0');
  std::string s = header;
  put(s, static_cast<uint32_t>(tris.size()));
  for (const Tri& t : tris) {
    for (int k = 0; k < 3; ++k) put(s, 0.0f);
    for (const auto& v : t)
      for (const float x : v) put(s, x);
    put(s, uint16_t{0});
  }
  return s;
}

void expect_closed_cube(const Mesh& m) {
  EXPECT_EQ(m.vertex_count(), 8u);
  EXPECT_EQ(m.face_count(), 12u);
  const Topology topo = build_topology(m);
  const MeshStats s = analyze(m, topo);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.inconsistent_edges, 0u);
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.euler_characteristic, 2);
}

template <class... S>
void expect_bad(std::string_view data, S... fragments) {
  test::expect_bad_input([](std::string_view d, std::string_view n) { return read_stl(d, n); },
                         data, "bad.stl", fragments...);
}

TEST(Stl, AsciiCubeWeldsIntoAClosedMesh) {
  expect_closed_cube(read_stl(ascii_stl(cube_triangles()), "cube.stl"));
  expect_closed_cube(read_stl(ascii_stl(cube_triangles(), "\r\n"), "crlf.stl"));
}

TEST(Stl, BinaryCubeWeldsIntoAClosedMesh) {
  const Mesh m = read_stl(binary_stl(cube_triangles()), "cube.stl");
  expect_closed_cube(m);
  // Positions are exactly the cube's; vertices are numbered in order of first use.
  const Mesh cube = make_cube();
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    bool found = false;
    for (size_t w = 0; w < cube.vertex_count(); ++w)
      found |= std::equal(&m.positions[3 * v], &m.positions[3 * v] + 3, &cube.positions[3 * w]);
    EXPECT_TRUE(found) << v;
  }
}

TEST(Stl, BinaryHeaderStartingWithSolidIsStillBinary) {
  const std::string bin = binary_stl(cube_triangles(), "solid cube exported by a CAD program");
  ASSERT_TRUE(bin.starts_with("solid"));
  expect_closed_cube(read_stl(bin, "solid.stl"));
  // Dispatch by content (no extension) finds it too.
  expect_closed_cube(read_mesh_memory(bin, MeshFormat::automatic, "solid"));
  expect_closed_cube(read_mesh_memory(ascii_stl(cube_triangles()), MeshFormat::automatic, "a"));
}

TEST(Stl, KeywordsAnyCaseAndSeveralSolids) {
  std::string s = ascii_stl(cube_triangles());
  std::string upper = s;
  for (char& c : upper)
    if (std::isalpha(static_cast<unsigned char>(c))) c = char(std::toupper(c));
  expect_closed_cube(read_stl(upper, "upper.stl"));
  const auto tris = cube_triangles();
  const std::vector<Tri> a(tris.begin(), tris.begin() + 5), b(tris.begin() + 5, tris.end());
  expect_closed_cube(read_stl(ascii_stl(a) + ascii_stl(b), "two_solids.stl"));
}

TEST(Stl, NegativeZeroWeldsWithZero) {
  const Tri t1 = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  const Tri t2 = {{{-0.0f, 0, 0}, {0, -1, 0}, {1, 0, -0.0f}}};
  const Mesh m = read_stl(binary_stl({t1, t2}), "zeros.stl");
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2, 0, 3, 1}));
}

TEST(Stl, DegenerateTrianglesAreDroppedAndCounted) {
  auto tris = cube_triangles();
  tris.push_back({{{0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {2, 2, 2}}});  // two equal corners
  tris.push_back({{{9, 9, 9}, {9, 9, 9}, {9, 9, 9}}});                    // a point
  size_t dropped = 99;
  const Mesh m = read_stl(binary_stl(tris), "degenerate.stl", &dropped);
  EXPECT_EQ(dropped, 2u);
  expect_closed_cube(m);  // and no vertex of the dropped triangles is kept
  size_t dropped_ascii = 0;
  read_stl(ascii_stl(tris), "degenerate.stl", &dropped_ascii);
  EXPECT_EQ(dropped_ascii, 2u);
}

TEST(Stl, EmptyBinaryIsAnEmptyMesh) {
  const Mesh m = read_stl(binary_stl({}), "empty.stl");
  EXPECT_EQ(m.vertex_count(), 0u);
  EXPECT_EQ(m.face_count(), 0u);
}

TEST(Stl, WriterRoundTripsThroughTheReader) {
  const Mesh cube = make_cube();
  std::string out;
  write_stl(cube, out);
  ASSERT_EQ(out.size(), 84u + 50u * 12u);
  EXPECT_FALSE(out.starts_with("solid"));
  const Mesh back = read_stl(out, "cube.stl");
  expect_closed_cube(back);
  // Facet normals are unit and point outwards.
  for (size_t t = 0; t < 12; ++t) {
    float n[3], v[3];
    std::memcpy(n, out.data() + 84 + 50 * t, 12);
    std::memcpy(v, out.data() + 84 + 50 * t + 12, 12);
    EXPECT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-6f);
    EXPECT_GT(n[0] * v[0] + n[1] * v[1] + n[2] * v[2], 0.0f);
  }
  // A torus through STL keeps its vertices (all distinct) and its triangulated faces.
  const int valences[] = {5};
  const Mesh torus = make_torus(24, 12, valences);
  const Mesh t2 = read_mesh_memory(write_mesh_memory(torus, MeshFormat::stl), MeshFormat::stl, "t");
  EXPECT_EQ(t2.vertex_count(), torus.vertex_count());
  EXPECT_EQ(t2.face_count(), torus.corner_count() - 2 * torus.face_count());
  EXPECT_EQ(format_from_name("STL"), MeshFormat::stl);
  EXPECT_EQ(format_from_path("x/y.stl"), MeshFormat::stl);
}

// ---- bad input ----

TEST(Stl, BadEmpty) {
  expect_bad("", "empty file");
}

TEST(Stl, BadTruncatedBinary) {
  const std::string bin = binary_stl(cube_triangles());
  expect_bad(bin.substr(0, bin.size() - 7), "triangle 11", "truncated", "declares 12 triangles");
  expect_bad(bin.substr(0, 60), "truncated");
}

TEST(Stl, BadTruncatedBinaryWithSolidHeader) {
  const std::string bin = binary_stl(cube_triangles(), "solid but binary");
  expect_bad(bin.substr(0, bin.size() - 60), "triangle 10", "truncated");
}

TEST(Stl, BadLyingCount) {
  std::string bin = binary_stl(cube_triangles());
  const uint32_t lie = 0xFFFFFFFFu;
  std::memcpy(bin.data() + 80, &lie, 4);
  expect_bad(bin, "declares 4294967295 triangles");
}

TEST(Stl, BadTrailingBytes) {
  expect_bad(binary_stl(cube_triangles()) + "xyz", "trailing data");
}

TEST(Stl, BadNonFiniteBinary) {
  auto tris = cube_triangles();
  tris[3][1][2] = std::nanf("");
  expect_bad(binary_stl(tris), "triangle 3", "vertex 1", "non-finite");
  tris[3][1][2] = INFINITY;
  expect_bad(binary_stl(tris), "triangle 3", "non-finite");
}

TEST(Stl, BadNonFiniteAscii) {
  const Tri t = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  std::string s = ascii_stl({t, t});
  const size_t at = s.rfind("vertex 1 0 0");
  expect_bad(s.substr(0, at) + "vertex nan 0 0" + s.substr(at + 12), "line 12", "facet 1", "'nan'");
  expect_bad(s.substr(0, at) + "vertex 1e999 0 0" + s.substr(at + 12), "facet 1", "finite");
  expect_bad(s.substr(0, at) + "vertex one 0 0" + s.substr(at + 12), "facet 1",
             "'one' is not a number");
}

TEST(Stl, BadFacetVertexCount) {
  const Tri t = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  const std::string s = ascii_stl({t});
  const size_t v = s.find("      vertex 0 1 0");
  expect_bad(s.substr(0, v) + s.substr(v + 19), "facet 0", "has 2 vertices");
  expect_bad(s.substr(0, v) + "      vertex 0 1 0\n" + s.substr(v), "facet 0",
             "more than 3 vertices");
}

TEST(Stl, BadTruncatedAscii) {
  const Tri t = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  const std::string s = ascii_stl({t, t});
  expect_bad(s.substr(0, s.find("endsolid")), "truncated", "endsolid");
  expect_bad(s.substr(0, s.rfind("vertex") + 10), "facet 1", "truncated");
  expect_bad(s.substr(0, s.rfind("endloop")), "facet 1", "truncated");
}

TEST(Stl, BadGarbage) {
  expect_bad("hello world\n", "not ascii STL");
  expect_bad("solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n banana\n", "facet 0",
             "'banana'");
  const Tri t = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  expect_bad(ascii_stl({t}) + "trailing words\n", "expected 'solid'", "'trailing'");
}

TEST(Stl, BadFilesInTestData) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(LIMN_TEST_DATA) / "bad")) {
    if (e.path().extension() != ".stl") continue;
    SCOPED_TRACE(e.path().string());
    try {
      read_mesh(e.path());
      ADD_FAILURE() << "accepted";
    } catch (const InputError& err) {
      const std::string msg = err.what();
      EXPECT_THAT(msg, HasSubstr(e.path().filename().string()));
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    ++n;
  }
  EXPECT_GE(n, 4u);
}

// ---- weld_vertices on a plain mesh ----

TEST(Weld, SplitCubeBecomesTheCubeWithPerCornerAttributes) {
  // The cube with every face given its own four vertices, a per-corner UV and a colour.
  const Mesh cube = make_cube();
  Mesh split;
  for (size_t f = 0; f < cube.face_count(); ++f) {
    std::vector<uint32_t> face;
    for (const uint32_t v : cube.face(f)) {
      face.push_back(split.add_vertex(cube.positions[3 * v], cube.positions[3 * v + 1],
                                      cube.positions[3 * v + 2]));
      split.uvs.insert(split.uvs.end(), {float(f), float(v)});
      split.colors.insert(split.colors.end(), {float(f) / 8, 0, 0, 1});
    }
    split.add_face(face);
  }
  split.uv_indices = split.face_vertices;
  size_t dropped = 9;
  const Mesh w = weld_vertices(split, &dropped);
  validate(w);
  EXPECT_EQ(dropped, 0u);
  EXPECT_EQ(w.vertex_count(), 8u);
  EXPECT_EQ(w.face_count(), 6u);
  EXPECT_EQ(w.uvs.size() / 2, 24u);
  for (size_t c = 0; c < w.corner_count(); ++c) {
    EXPECT_EQ(w.uvs[2 * w.uv_indices[c]], split.uvs[2 * split.uv_indices[c]]);
    EXPECT_EQ(w.uvs[2 * w.uv_indices[c] + 1], split.uvs[2 * split.uv_indices[c] + 1]);
  }
  // The first original vertex of each group gives the colour.
  EXPECT_EQ(w.colors[0], 0.0f);
  const MeshStats s = analyze(w, build_topology(w));
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
}

TEST(Weld, FacesThatCollapseAreDroppedWithTheirHoleTags) {
  Mesh m;
  for (int i = 0; i < 5; ++i) m.add_vertex(float(i % 4), 0, float(i / 4));
  m.positions[3 * 4] = 0;  // vertex 4 now sits on vertex 0
  m.positions[3 * 4 + 2] = 0;
  m.add_face({0, 1, 2});
  m.add_face({1, 2, 4, 0});  // repeats vertex 0 once welded
  m.add_face({1, 3, 2});
  m.hole_faces = {1, 2};
  m.crease_edges = {0, 4, 1, 2};
  m.crease_sharpness = {1.0f, 2.0f};
  size_t dropped = 0;
  const Mesh w = weld_vertices(m, &dropped);
  validate(w);
  EXPECT_EQ(dropped, 1u);
  EXPECT_EQ(w.vertex_count(), 4u);
  EXPECT_EQ(w.face_count(), 2u);
  EXPECT_EQ(w.hole_faces, std::vector<uint32_t>{1});
  EXPECT_EQ(w.crease_edges, (std::vector<uint32_t>{1, 2}));
  EXPECT_EQ(w.crease_sharpness, std::vector<float>{2.0f});
}

TEST(Weld, MapGroupsBitEqualPointsInOrderOfFirstAppearance) {
  const float xyz[] = {1, 2, 3, 0, 0, 0, 1, 2, 3, -0.0f, 0, -0.0f, 1, 2, 3.0000002f};
  uint32_t groups = 0;
  EXPECT_EQ(weld_map(xyz, &groups), (std::vector<uint32_t>{0, 1, 0, 1, 2}));
  EXPECT_EQ(groups, 3u);
}

}  // namespace
}  // namespace limn
