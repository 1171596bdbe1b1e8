// OBJ reading and writing: exact arity and indices, OpenSubdiv tags, line endings, and every
// kind of bad input rejected with a message naming the file and the line.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <iterator>

#include "limn/io/mesh_io.hpp"

namespace limn {
namespace {

using ::testing::HasSubstr;

const char* kQuadAndTri =
    "# two faces\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0.5 0\n"
    "f 1 2 3 4\n"
    "f 2 5 3\n";

// Expect an InputError whose message contains every fragment.
template <class... S>
void expect_bad(std::string_view data, S... fragments) {
  try {
    read_obj(data, "bad.obj");
    FAIL() << "accepted bad input:\n" << data;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_THAT(msg, HasSubstr("bad.obj"));
    for (const std::string_view f : {std::string_view(fragments)...})
      EXPECT_THAT(msg, HasSubstr(std::string(f)));
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
  }
}

TEST(Obj, KeepsArityAndIndices) {
  const Mesh m = read_obj(kQuadAndTri, "t.obj");
  ASSERT_EQ(m.vertex_count(), 5u);
  ASSERT_EQ(m.face_count(), 2u);
  EXPECT_EQ(m.face_offsets, (std::vector<uint32_t>{0, 4, 7}));
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2, 3, 1, 4, 2}));
  EXPECT_FLOAT_EQ(m.positions[13], 0.5f);
  EXPECT_TRUE(m.uv_indices.empty());
  EXPECT_TRUE(m.normal_indices.empty());
}

TEST(Obj, TextureAndNormalIndicesKeepTheirOwnSpaces) {
  const Mesh m = read_obj(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\nvn 0 0 1\n"
      "f 1/4/1 2/2/1 3/3/1\n",
      "t.obj");
  EXPECT_EQ(m.uv_indices, (std::vector<uint32_t>{3, 1, 2}));
  EXPECT_EQ(m.normal_indices, (std::vector<uint32_t>{0, 0, 0}));
  EXPECT_EQ(m.uvs.size(), 8u);
  EXPECT_EQ(m.normals.size(), 3u);
}

TEST(Obj, RelativeIndices) {
  const Mesh m = read_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", "t.obj");
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(Obj, GroupsKeepFileOrder) {
  const Mesh m = read_obj(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\ng a\nf 1 2 3\ng b\nf 2 4 3\ng a\nf 1 2 4\n", "t.obj");
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2, 1, 3, 2, 0, 1, 3}));
}

TEST(Obj, OpenSubdivTags) {
  const Mesh m = read_obj(std::string(kQuadAndTri) +
                              "t crease 2/1/0 0 1 2.5\n"
                              "t crease 3/2/0 1 2 3 1.0 10\n"
                              "t corner 2/1/0 3 4 4.0\n"
                              "t hole 1/0/0 1\n"
                              "t interpolateboundary 1/0/0 1\n"
                              "t creasemethod 0/0/1 chaikin\n"
                              "t facevaryinginterpolateboundary 1/0/0 1\n"
                              "t smoothtriangles 0/0/1 smooth\n",
                          "t.obj");
  EXPECT_EQ(m.crease_edges, (std::vector<uint32_t>{0, 1, 1, 2, 2, 3}));
  EXPECT_EQ(m.crease_sharpness, (std::vector<float>{2.5f, 1.0f, 10.0f}));
  EXPECT_EQ(m.corner_vertices, (std::vector<uint32_t>{3, 4}));
  EXPECT_EQ(m.corner_sharpness, (std::vector<float>{4.0f, 4.0f}));
  EXPECT_EQ(m.hole_faces, (std::vector<uint32_t>{1}));
  EXPECT_EQ(m.tags.boundary, BoundaryInterpolation::edge_and_corner);  // RenderMan: 1
  EXPECT_EQ(m.tags.crease_method, CreaseMethod::chaikin);
  EXPECT_EQ(m.tags.fvar_boundary, 1);
  EXPECT_TRUE(m.tags.smooth_triangles);
}

// OpenSubdiv's shape files name the triangle rule: "catmark" is TRI_SUB_CATMARK (its default),
// "smooth" TRI_SUB_SMOOTH (regression/common/shape_utils.cpp); anything else is refused.
TEST(Obj, SmoothTrianglesTagNamesTheRule) {
  const std::string base = std::string(kQuadAndTri) + "t smoothtriangles 0/0/1 ";
  EXPECT_FALSE(read_obj(base + "catmark\n", "t.obj").tags.smooth_triangles);
  EXPECT_TRUE(read_obj(base + "smooth\n", "t.obj").tags.smooth_triangles);
  EXPECT_FALSE(read_obj(std::string(kQuadAndTri), "t.obj").tags.smooth_triangles);
  EXPECT_THROW(read_obj(base + "loop\n", "t.obj"), InputError);
  Mesh m = read_obj(base + "smooth\n", "t.obj");
  for (bool smooth : {true, false}) {
    m.tags.smooth_triangles = smooth;
    std::string text;
    write_obj(m, text);
    EXPECT_EQ(read_obj(text, "again.obj").tags.smooth_triangles, smooth);
  }
}

TEST(Obj, TagsAfterAnEmptyGroupAreKept) {
  const Mesh m = read_obj(std::string(kQuadAndTri) + "g empty\nt crease 2/1/0 0 1 3\n", "t.obj");
  EXPECT_EQ(m.crease_sharpness.size(), 1u);
}

TEST(Obj, VertexColours) {
  const Mesh m = read_obj("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n", "t.obj");
  ASSERT_EQ(m.colors.size(), 12u);
  EXPECT_EQ(m.colors[0], 1.0f);
  EXPECT_EQ(m.colors[5], 1.0f);
  EXPECT_EQ(m.colors[10], 1.0f);
  EXPECT_EQ(m.colors[3], 1.0f);  // alpha
}

TEST(Obj, BomAndMixedLineEndingsParseLikeCleanText) {
  const Mesh clean = read_obj(kQuadAndTri, "t.obj");
  const std::string messy =
      "\xEF\xBB\xBF# two faces\r\nv 0 0 0\rv 1 0 0\nv 1 1 0\r\nv 0 1 0\rv 2 0.5 0\r\n"
      "f 1 2 3 4\r"
      "f 2 5 3";  // no final newline
  const Mesh m = read_obj(messy, "t.obj");
  EXPECT_EQ(m.positions, clean.positions);
  EXPECT_EQ(m.face_offsets, clean.face_offsets);
  EXPECT_EQ(m.face_vertices, clean.face_vertices);
}

TEST(Obj, LineNumbersCountLoneCarriageReturns) {
  expect_bad("v 0 0 0\rv 1 0 0\r\nv 0 1 0\rf 1 2 7\r", "line 4");
}

TEST(Obj, RoundTripIsExact) {
  Mesh m;
  const float coords[] = {0.1f, -2.5e-7f, 3.14159274f, 1e10f, 7.0f, -0.3333333f, 5, 6, 7, 8, 9, 10};
  for (int i = 0; i < 4; ++i) m.add_vertex(coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]);
  m.add_face({0, 1, 2, 3});
  m.add_face({3, 2, 1});
  m.uvs = {0.25f, 0.75f, 0.1f, 0.9f};
  m.uv_indices = {0, 1, 0, 1, 1, 0, 1};
  m.normals = {0, 0, 1, 0.6f, 0.8f, 0};
  m.normal_indices = {0, 0, 1, 1, 0, 1, 0};
  m.colors = {0.2f, 0.4f, 0.6f, 1, 1, 0, 0, 1, 0, 1, 0, 1, 0.5f, 0.5f, 0.5f, 1};
  m.crease_edges = {0, 1};
  m.crease_sharpness = {1.5f};
  m.corner_vertices = {2};
  m.corner_sharpness = {10.0f};
  m.hole_faces = {1};
  m.tags.boundary = BoundaryInterpolation::edge_only;
  m.tags.crease_method = CreaseMethod::chaikin;
  std::string text;
  write_obj(m, text);
  const Mesh r = read_obj(text, "rt.obj");
  EXPECT_EQ(r.positions, m.positions);
  EXPECT_EQ(r.face_offsets, m.face_offsets);
  EXPECT_EQ(r.face_vertices, m.face_vertices);
  EXPECT_EQ(r.uvs, m.uvs);
  EXPECT_EQ(r.uv_indices, m.uv_indices);
  EXPECT_EQ(r.normals, m.normals);
  EXPECT_EQ(r.normal_indices, m.normal_indices);
  EXPECT_EQ(r.colors, m.colors);
  EXPECT_EQ(r.crease_edges, m.crease_edges);
  EXPECT_EQ(r.crease_sharpness, m.crease_sharpness);
  EXPECT_EQ(r.corner_vertices, m.corner_vertices);
  EXPECT_EQ(r.corner_sharpness, m.corner_sharpness);
  EXPECT_EQ(r.hole_faces, m.hole_faces);
  EXPECT_EQ(r.tags.boundary, m.tags.boundary);
  EXPECT_EQ(r.tags.crease_method, m.tags.crease_method);
}

// ---- bad input: one test per case ----
TEST(ObjBad, EmptyFile) {
  expect_bad("", "no vertices");
}
TEST(ObjBad, OnlyComments) {
  expect_bad("# nothing here\n\n", "no vertices");
}
TEST(ObjBad, TruncatedVertex) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1", "line 3", "at least 3");
}
TEST(ObjBad, TruncatedFace) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2", "line 4", "at least 3");
}
TEST(ObjBad, FaceIndexZero) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4", "index 0");
}
TEST(ObjBad, NegativeIndexBeforeStart) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", "line 4", "-4");
}
TEST(ObjBad, IndexPastEnd) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4", "out of range");
}
TEST(ObjBad, HugeIndex) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", "line 4");
}
TEST(ObjBad, TexcoordIndexPastEnd) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/2\n", "texture coordinate");
}
TEST(ObjBad, NaNCoordinate) {
  expect_bad("v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 1", "nan");
}
TEST(ObjBad, InfCoordinate) {
  expect_bad("v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n", "line 2");
}
TEST(ObjBad, OverflowCoordinate) {
  expect_bad("v 0 0 1e999\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 1");
}
TEST(ObjBad, NonNumericCoordinate) {
  expect_bad("v 0 0x 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 1");
}
TEST(ObjBad, FaceWithTwoVertices) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "2 vertices");
}
TEST(ObjBad, RepeatedVertexInFace) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2 3\n", "line 4", "repeats vertex 2");
}
TEST(ObjBad, RepeatedVertexViaRelativeIndex) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -3\n", "repeats vertex 1");
}
TEST(ObjBad, BinaryGarbage) {
  std::string g = "v 0 0 0\n";
  for (int i = 0; i < 256; ++i) g += static_cast<char>((i * 37) & 0xFF);
  expect_bad(g, "bad.obj");
}
TEST(ObjBad, HostileTagCount) {
  expect_bad(std::string(kQuadAndTri) + "t crease 999999999/1/0 0 1 2\n", "crease",
             "fewer arguments");
}
TEST(ObjBad, MalformedTagCounts) {
  expect_bad(std::string(kQuadAndTri) + "t crease 2/x 0 1 2\n", "counts");
}
TEST(ObjBad, TagVertexOutOfRange) {
  expect_bad(std::string(kQuadAndTri) + "t crease 2/1/0 0 77 2\n", "crease", "77");
}
TEST(ObjBad, HoleFaceOutOfRange) {
  expect_bad(std::string(kQuadAndTri) + "t hole 1/0/0 5\n", "hole");
}
TEST(ObjBad, NegativeSharpness) {
  expect_bad(std::string(kQuadAndTri) + "t crease 2/1/0 0 1 -2\n", "negative sharpness");
}
TEST(ObjBad, MixedTexcoordCorners) {
  expect_bad("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3\n", "mixes");
}

TEST(ObjBad, RepeatedVertexInAHugeFace) {
  // 200k-gon with one repeat at the end: must be found without a quadratic scan.
  std::string t;
  const int n = 200000;
  for (int i = 0; i < n; ++i) fmt::format_to(std::back_inserter(t), "v {} 0 0\n", i);
  t += "f";
  for (int i = 1; i <= n; ++i) fmt::format_to(std::back_inserter(t), " {}", i);
  t += " 5\n";
  expect_bad(t, "repeats vertex 5");
}

TEST(Obj, HugeFaceIsRead) {
  std::string t;
  const int n = 200000;
  for (int i = 0; i < n; ++i)
    fmt::format_to(std::back_inserter(t), "v {} {} 0\n", i % 1000, i / 1000);
  t += "f";
  for (int i = 1; i <= n; ++i) fmt::format_to(std::back_inserter(t), " {}", i);
  t += "\n";
  const Mesh m = read_obj(t, "big.obj");
  EXPECT_EQ(m.face_size(0), uint32_t(n));
}

}  // namespace
}  // namespace limn
