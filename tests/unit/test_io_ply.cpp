// PLY reading and writing: exact round trips, every encoding and line ending, tristrips, skipped
// elements, and bad input rejected with a one-line message naming the file and the place.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bad_input.hpp"
#include "limn/io/mesh_io.hpp"

#ifndef LIMN_TEST_DATA
#define LIMN_TEST_DATA "tests/data"
#endif

namespace limn {
namespace {

using ::testing::HasSubstr;
using namespace std::string_literals;

// Expect an InputError whose message is one line and contains every fragment.
template <class... S>
void expect_bad(std::string_view data, S... fragments) {
  test::expect_bad_input([](std::string_view d, std::string_view n) { return read_ply(d, n); },
                         data, "bad.ply", fragments...);
}

void expect_same(const Mesh& a, const Mesh& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.face_offsets, b.face_offsets);
  EXPECT_EQ(a.face_vertices, b.face_vertices);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.normal_indices, b.normal_indices);
  EXPECT_EQ(a.uvs, b.uvs);
  EXPECT_EQ(a.uv_indices, b.uv_indices);
  EXPECT_EQ(a.colors, b.colors);
}

// Binary PLY bytes in either byte order, written field by field.
class Bytes {
 public:
  explicit Bytes(bool big_endian) : big_(big_endian) {}
  template <class T>
  Bytes& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof v);
    if (big_ != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof b);
    s.append(b, sizeof b);
    return *this;
  }
  std::string s;

 private:
  bool big_;
};

std::string ply_header(const char* format, const std::string& body) {
  return std::string("ply\nformat ") + format + " 1.0\n" + body + "end_header\n";
}

const char* kAsciiQuadTri =
    "ply\n"
    "format ascii 1.0\n"
    "comment made by hand\n"
    "obj_info nothing useful\n"
    "element vertex 5\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "property uchar red\n"
    "property uchar green\n"
    "property uchar blue\n"
    "element face 2\n"
    "property list uchar int vertex_indices\n"
    "property uchar flags\n"
    "end_header\n"
    "0 0 0 255 0 0\n"
    "1 0 0 0 255 0\n"
    "1 1 0 0 0 255\n"
    "0 1 0 10 20 30\n"
    "2 0.5 -1.5e-3 0 0 0\n"
    "4 0 1 2 3 7\n"
    "3 1 4 2 0\n";

TEST(Ply, HandWrittenAscii) {
  const Mesh m = read_ply(kAsciiQuadTri, "t.ply");
  EXPECT_EQ(m.positions,
            (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0.5f, -1.5e-3f}));
  EXPECT_EQ(m.face_offsets, (std::vector<uint32_t>{0, 4, 7}));
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2, 3, 1, 4, 2}));
  const float k = 255.0f;
  EXPECT_EQ(m.colors, (std::vector<float>{1, 0, 0,      1,      0,      1, 0, 1, 0, 0,
                                          1, 1, 10 / k, 20 / k, 30 / k, 1, 0, 0, 0, 1}));
  EXPECT_TRUE(m.normals.empty());
  EXPECT_TRUE(m.normal_indices.empty());
  EXPECT_TRUE(m.uv_indices.empty());
}

TEST(Ply, NormalsUvsAndFloatColours) {
  const Mesh m = read_ply(
      "ply\nformat ascii 1.0\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "property float red\nproperty float green\nproperty float blue\n"
      "property float s\nproperty float t\n"
      "element face 1\nproperty list uchar uint vertex_index\nend_header\n"
      "0 0 0 0 0 1 0.25 0.5 0.75 0 0\n"
      "1 0 0 0 0 1 1 1 1 1 0\n"
      "0 1 0 0 0 -1 0 0 0 0 1\n"
      "3 2 0 1\n",
      "t.ply");
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{2, 0, 1}));
  EXPECT_EQ(m.normals, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, -1}));
  EXPECT_EQ(m.normal_indices, m.face_vertices);
  EXPECT_EQ(m.uvs, (std::vector<float>{0, 0, 1, 0, 0, 1}));
  EXPECT_EQ(m.uv_indices, m.face_vertices);
  EXPECT_EQ(m.colors, (std::vector<float>{0.25f, 0.5f, 0.75f, 1, 1, 1, 1, 1, 0, 0, 0, 1}));
}

TEST(Ply, PartialAttributeSetsAreIgnored) {
  // nx without nz, red without blue: no usable normal or colour.
  const Mesh m = read_ply(
      "ply\nformat ascii 1.0\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\nproperty float nx\n"
      "property uchar red\nproperty uchar green\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 1 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n",
      "t.ply");
  EXPECT_TRUE(m.normals.empty());
  EXPECT_TRUE(m.colors.empty());
  EXPECT_EQ(m.vertex_count(), 3u);
}

Mesh awkward_mesh() {
  Mesh m;
  const float coords[] = {0.1f, -2.5e-7f, 3.14159274f, 1e10f,   7.0f, -0.3333333f, 1e-45f, 6, 7,
                          8,    9,        10,          -1e-38f, 0.3f, 123456.789f, 2,      2, 2};
  for (int i = 0; i < 6; ++i) m.add_vertex(coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]);
  m.add_face({0, 1, 2, 3});
  m.add_face({3, 2, 1});
  m.add_face({0, 1, 5, 4, 3});
  for (int i = 0; i < 6; ++i)
    m.colors.insert(m.colors.end(), {float(i * 40) / 255.0f, float(255 - i) / 255.0f,
                                     float(i * i) / 255.0f, float(200 + i) / 255.0f});
  for (int i = 0; i < 6; ++i) m.normals.insert(m.normals.end(), {0.6f, -0.8f, float(i) * 1e-3f});
  m.normal_indices = m.face_vertices;
  for (int i = 0; i < 6; ++i) m.uvs.insert(m.uvs.end(), {float(i) / 7.0f, 1.0f - float(i) / 3.0f});
  m.uv_indices = m.face_vertices;
  return m;
}

TEST(Ply, RoundTripBinaryIsExact) {
  const Mesh m = awkward_mesh();
  std::string out;
  write_ply(m, out, /*ascii=*/false);
  EXPECT_THAT(out, HasSubstr("format binary_little_endian 1.0\ncomment limn\n"));
  EXPECT_THAT(out, HasSubstr("property list uchar int vertex_indices\n"));
  expect_same(read_ply(out, "rt.ply"), m);
}

TEST(Ply, RoundTripAsciiIsExact) {
  const Mesh m = awkward_mesh();
  std::string out;
  write_ply(m, out, /*ascii=*/true);
  EXPECT_THAT(out, HasSubstr("format ascii 1.0\ncomment limn\n"));
  expect_same(read_ply(out, "rt.ply"), m);
}

TEST(Ply, SplitsVerticesWhereACornerHasItsOwnNormal) {
  Mesh m = awkward_mesh();
  m.colors.clear();
  m.uvs.clear();
  m.uv_indices.clear();
  m.normal_indices[0] = 1;  // corner 0 disagrees with its vertex's other corners: a seam
  std::string out;
  write_ply(m, out, false);
  EXPECT_THAT(out, HasSubstr("property float nx"));
  EXPECT_THAT(out, ::testing::Not(HasSubstr("red")));
  const Mesh r = read_ply(out, "rt.ply");
  ASSERT_EQ(r.corner_count(), m.corner_count());
  EXPECT_EQ(r.face_offsets, m.face_offsets);
  // Every corner keeps its position and its own normal.
  for (size_t c = 0; c < m.corner_count(); ++c)
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(r.positions[3 * r.face_vertices[c] + k], m.positions[3 * m.face_vertices[c] + k]);
      EXPECT_EQ(r.normals[3 * r.face_vertices[c] + k], m.normals[3 * m.normal_indices[c] + k]);
    }
  // Only the vertex with two normals is split.
  EXPECT_EQ(r.vertex_count(), m.vertex_count() + 1);
}

TEST(Ply, LargeFacesUseAWideListCount) {
  Mesh m;
  std::vector<uint32_t> big;
  for (uint32_t i = 0; i < 300; ++i) {
    const float a = float(i) * 0.0209f;
    m.add_vertex(std::cos(a), std::sin(a), 0);
    big.push_back(i);
  }
  m.add_face(big);
  m.add_face({0, 1, 2});
  for (const bool ascii : {false, true}) {
    std::string out;
    write_ply(m, out, ascii);
    EXPECT_THAT(out, HasSubstr("property list uint int vertex_indices\n"));
    const Mesh r = read_ply(out, "rt.ply");
    EXPECT_EQ(r.face_offsets, m.face_offsets);
    EXPECT_EQ(r.face_vertices, m.face_vertices);
    EXPECT_EQ(r.positions, m.positions);
  }
}

TEST(Ply, EmptyMeshRoundTrips) {
  for (const bool ascii : {false, true}) {
    std::string out;
    write_ply(Mesh{}, out, ascii);
    const Mesh r = read_ply(out, "empty.ply");
    EXPECT_EQ(r.vertex_count(), 0u);
    EXPECT_EQ(r.face_count(), 0u);
  }
}

// The common layout (float xyz, list uchar int) in both byte orders; big endian exercises the
// byte-swapping fast path, little endian the memcpy one.
std::string quad_tri_binary(bool big) {
  Bytes b(big);
  const float pos[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0.5f, -1.5e-3f};
  for (const float x : pos) b.put(x);
  b.put(uint8_t(4)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2)).put(int32_t(3));
  b.put(uint8_t(3)).put(int32_t(1)).put(int32_t(4)).put(int32_t(2));
  return ply_header(big ? "binary_big_endian" : "binary_little_endian",
                    "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 2\nproperty list uchar int vertex_indices\n") +
         b.s;
}

TEST(Ply, BigAndLittleEndianParseIdentically) {
  const Mesh le = read_ply(quad_tri_binary(false), "le.ply");
  const Mesh be = read_ply(quad_tri_binary(true), "be.ply");
  expect_same(le, be);
  const Mesh ascii = read_ply(kAsciiQuadTri, "a.ply");
  EXPECT_EQ(le.positions, ascii.positions);
  EXPECT_EQ(le.face_offsets, ascii.face_offsets);
  EXPECT_EQ(le.face_vertices, ascii.face_vertices);
}

// Every scalar type, lists with unusual count types, and elements limn does not use, in both
// byte orders: this takes the generic (value by value) binary path.
std::string mixed_types_binary(bool big) {
  Bytes b(big);
  for (int i = 0; i < 3; ++i) {
    b.put(double(i) + 0.5).put(float(i == 1)).put(int16_t(-i));
    b.put(int8_t(-1)).put(uint16_t(65535)).put(uint32_t(7));  // skipped scalars
    b.put(uint8_t(2)).put(float(1)).put(float(2));            // skipped list
    b.put(uint8_t(i * 100)).put(uint8_t(255)).put(uint8_t(0)).put(uint16_t(65535));
  }
  b.put(int32_t(-5));                                                     // flags (skipped)
  b.put(uint16_t(3)).put(uint32_t(2)).put(uint32_t(0)).put(uint32_t(1));  // the face
  b.put(uint32_t(2)).put(int8_t(0)).put(int8_t(1));                       // edge 0: list
  b.put(double(9.5));                                                     // edge 0: scalar
  b.put(uint32_t(0)).put(double(1.5));                                    // edge 1: empty list
  return ply_header(big ? "binary_big_endian" : "binary_little_endian",
                    "comment every type\n"
                    "element vertex 3\nproperty float64 x\nproperty float32 y\nproperty int16 z\n"
                    "property char a\nproperty ushort b\nproperty uint32 c\n"
                    "property list uint8 float d\n"
                    "property uchar red\nproperty uint8 green\nproperty uchar blue\n"
                    "property ushort alpha\n"
                    "element face 1\nproperty int flags\n"
                    "property list ushort uint vertex_indices\n"
                    "element edge 2\nproperty list uint int8 ends\nproperty double weight\n") +
         b.s;
}

TEST(Ply, EveryTypeInBothByteOrders) {
  const Mesh le = read_ply(mixed_types_binary(false), "le.ply");
  const Mesh be = read_ply(mixed_types_binary(true), "be.ply");
  expect_same(le, be);
  EXPECT_EQ(le.positions, (std::vector<float>{0.5f, 0, 0, 1.5f, 1, -1, 2.5f, 0, -2}));
  EXPECT_EQ(le.face_vertices, (std::vector<uint32_t>{2, 0, 1}));
  EXPECT_EQ(le.colors,
            (std::vector<float>{0, 1, 0, 1, 100 / 255.0f, 1, 0, 1, 200 / 255.0f, 1, 0, 1}));
}

TEST(Ply, FastAndGenericFacePathsAgree) {
  // An extra face property moves the same faces off the fast path.
  Bytes fast(false), slow(false);
  for (const float x : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 1.f, 0.f}) {
    fast.put(x);
    slow.put(x);
  }
  const std::vector<std::vector<int32_t>> faces = {{0, 1, 2}, {0, 2, 3}, {3, 2, 1, 0}, {1, 3, 0}};
  for (const auto& f : faces) {
    fast.put(uint8_t(f.size()));
    slow.put(uint8_t(f.size()));
    for (const int32_t v : f) fast.put(v), slow.put(v);
    slow.put(uint8_t(9));
  }
  const std::string head =
      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\n";
  const Mesh a = read_ply(ply_header("binary_little_endian", head) + fast.s, "fast.ply");
  const Mesh b = read_ply(
      ply_header("binary_little_endian", head + "property uchar flag\n") + slow.s, "s.ply");
  expect_same(a, b);
  EXPECT_EQ(a.face_offsets, (std::vector<uint32_t>{0, 3, 6, 10, 13}));
  EXPECT_EQ(a.face_vertices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 3, 2, 1, 0, 1, 3, 0}));
}

// Strip A stitches to a later part of itself with repeated indices (degenerate triangles);
// strip B follows a -1 restart, so its orientation parity starts over.
const char* kStripHeader =
    "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
    "element tristrips 1\nproperty list int int vertex_indices\n";
const int32_t kStrip[] = {0, 1, 2, 3, 3, 4, 4, 5, 6, -1, 7, 6, 5, 4};
const std::vector<uint32_t> kStripFaces = {0, 1, 2, 2, 1, 3, 4, 5, 6, 7, 6, 5, 5, 6, 4};

TEST(Ply, TristripsAscii) {
  std::string text = ply_header("ascii", kStripHeader);
  for (int v = 0; v < 8; ++v) text += fmt::format("{} {} 0\n", v % 4, v / 4);
  text += "14";
  for (const int32_t i : kStrip) text += fmt::format(" {}", i);
  text += "\n";
  const Mesh m = read_ply(text, "strip.ply");
  EXPECT_EQ(m.face_vertices, kStripFaces);
  EXPECT_EQ(m.face_count(), 5u);
}

TEST(Ply, TristripsBinary) {
  Bytes b(true);
  for (int v = 0; v < 8; ++v) b.put(float(v % 4)).put(float(v / 4)).put(0.0f);
  b.put(int32_t(14));
  for (const int32_t i : kStrip) b.put(i);
  const Mesh m = read_ply(ply_header("binary_big_endian", kStripHeader) + b.s, "strip.ply");
  EXPECT_EQ(m.face_vertices, kStripFaces);
}

TEST(Ply, UnknownElementsAndPropertiesAreSkippedInAscii) {
  const Mesh m = read_ply(
      "ply\nformat ascii 1.0\n"
      "element material 2\nproperty list uchar float rgb\nproperty int id\n"
      "element vertex 3\nproperty double confidence\nproperty float x\nproperty float y\n"
      "property list uchar int tags\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\n"
      "element edge 1\nproperty int a\nproperty int b\nend_header\n"
      "3 0.1 0.2 0.3 7\n0 8\n"
      "1e300 0 0 2 5 6 0\n0.5 1 0 0 0\n-1 0 1 3 1 2 3 0\n"
      "3 0 1 2\n"
      "0 1\n",
      "t.ply");
  EXPECT_EQ(m.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(Ply, LineEndingsAndBomParseLikeClean) {
  const Mesh clean = read_ply(kAsciiQuadTri, "t.ply");
  std::string crlf, cr;
  for (const char* p = kAsciiQuadTri; *p; ++p) {
    crlf += *p == '\n' ? std::string("\r\n") : std::string(1, *p);
    cr += *p == '\n' ? '\r' : *p;
  }
  expect_same(read_ply(crlf, "crlf.ply"), clean);
  expect_same(read_ply(cr, "cr.ply"), clean);
  expect_same(read_ply("\xEF\xBB\xBF" + crlf, "bom.ply"), clean);
  // No final newline, blank lines and tabs in the body.
  std::string loose = kAsciiQuadTri;
  loose.pop_back();
  loose.replace(loose.find("end_header\n") + 11, 0, "\n \t\n");
  loose.replace(loose.find("1 0 0 0 255 0"), 1, "\t+1");
  expect_same(read_ply(loose, "loose.ply"), clean);
}

TEST(Ply, BinaryBodyAfterCrLfAndLoneCrHeaders) {
  // x's first little-endian byte is 0x0A ('\n'): a lone-\r header must not eat it.
  const float x = std::bit_cast<float>(0x3F80000Au);
  Bytes b(false);
  for (const float v : {x, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) b.put(v);
  b.put(uint8_t(3)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2));
  const std::string header =
      ply_header("binary_little_endian",
                 "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\n");
  std::string crlf, cr;
  for (const char c : header) {
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    cr += c == '\n' ? '\r' : c;
  }
  for (const std::string& h : {header, crlf, cr}) {
    const Mesh m = read_ply(h + b.s, "t.ply");
    ASSERT_EQ(m.vertex_count(), 3u);
    EXPECT_EQ(m.positions[0], x);
    EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2}));
  }
}

TEST(Ply, LargePolygonWithoutRepeatsIsAccepted) {
  std::string text = ply_header("ascii",
                                "element vertex 40\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 1\n"
                                "property list uchar int vertex_indices\n");
  for (int i = 0; i < 40; ++i)
    text += fmt::format("{} {} 0\n", std::cos(i * 0.157), std::sin(i * 0.157));
  text += "40";
  for (int i = 39; i >= 0; --i) text += fmt::format(" {}", i);
  const Mesh m = read_ply(text + "\n", "big.ply");
  EXPECT_EQ(m.face_size(0), 40u);
  EXPECT_EQ(m.face_vertices.front(), 39u);
}

TEST(Ply, UnderflowReadsAsZero) {
  const Mesh m = read_ply(
      ply_header("ascii",
                 "element vertex 3\nproperty float x\nproperty double y\nproperty float z\n") +
          "1e-50 -1e-400 0.0000000000000000000000000000000000000000000000000001\n"
          "1 0 0\n0 1 0\n",
      "t.ply");
  EXPECT_EQ(m.positions[0], 0.0f);
  EXPECT_EQ(m.positions[1], 0.0f);
  EXPECT_EQ(m.positions[2], 0.0f);
  EXPECT_EQ(m.face_count(), 0u);
}

// ---- bad input: one test per case ----

const char* kVertexHeader =
    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\n";

std::string ascii_ply(const std::string& body) {
  return ply_header("ascii", kVertexHeader) + body;
}

std::string triangle_le(float x0, int32_t i0, uint8_t n = 3) {
  Bytes b(false);
  for (const float v : {x0, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) b.put(v);
  b.put(n).put(i0).put(int32_t(1)).put(int32_t(2));
  return ply_header("binary_little_endian", kVertexHeader) + b.s;
}

TEST(PlyBad, EmptyFile) {
  expect_bad("", "empty file");
}
TEST(PlyBad, OnlyABom) {
  expect_bad("\xEF\xBB\xBF", "empty file");
}
TEST(PlyBad, NotPly) {
  expect_bad("solid cube\nfacet normal 0 0 1\n", "line 1", "not a PLY file");
}
TEST(PlyBad, MagicWithTrailingText) {
  expect_bad("ply junk\nformat ascii 1.0\n", "line 1");
}
TEST(PlyBad, MissingEndHeader) {
  expect_bad("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n", "line 4", "end_header");
}
TEST(PlyBad, UnknownFormat) {
  expect_bad("ply\nformat binary_middle_endian 1.0\nend_header\n", "line 2",
             "unknown format 'binary_middle_endian'");
}
TEST(PlyBad, UnsupportedVersion) {
  expect_bad("ply\nformat ascii 2.0\nend_header\n", "line 2", "2.0");
}
TEST(PlyBad, NoFormatLine) {
  expect_bad("ply\nelement vertex 0\nend_header\n", "line 3", "format");
}
TEST(PlyBad, UnknownKeyword) {
  expect_bad("ply\nformat ascii 1.0\nelemnt vertex 3\nend_header\n", "line 3", "'elemnt'");
}
TEST(PlyBad, UnknownPropertyType) {
  expect_bad("ply\nformat ascii 1.0\nelement vertex 1\nproperty float3 x\nend_header\n", "line 4",
             "unknown property type 'float3'");
}
TEST(PlyBad, FloatListCount) {
  expect_bad("ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\n",
             "line 4", "not an integer type");
}
TEST(PlyBad, PropertyBeforeElement) {
  expect_bad("ply\nformat ascii 1.0\nproperty float x\nend_header\n", "line 3",
             "before any element");
}
TEST(PlyBad, ElementCountNotANumber) {
  expect_bad("ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "line 3", "'-3'");
}
TEST(PlyBad, DuplicateElement) {
  expect_bad("ply\nformat ascii 1.0\nelement vertex 0\nelement vertex 0\nend_header\n", "line 4",
             "twice");
}
TEST(PlyBad, DuplicateProperty) {
  expect_bad("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty int x\n",
             "line 5", "'x' declared twice");
}
TEST(PlyBad, NoVertexElement) {
  expect_bad(
      "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\n"
      "end_header\n",
      "no vertex element");
}
TEST(PlyBad, VertexWithoutZ) {
  expect_bad(
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "end_header\n0 0\n",
      "line 3", "no 'z' property");
}
TEST(PlyBad, FaceWithoutIndexList) {
  expect_bad(
      "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
      "property float z\nelement face 0\nproperty list uchar int corners\nend_header\n",
      "line 7", "no vertex_indices list");
}
TEST(PlyBad, FloatIndexList) {
  expect_bad(
      "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
      "property float z\nelement face 0\nproperty list uchar float vertex_indices\n"
      "end_header\n",
      "line 7", "non-integer");
}
TEST(PlyBad, IntColour) {
  expect_bad(
      "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
      "property float z\nproperty int red\nproperty int green\nproperty int blue\n"
      "end_header\n",
      "line 3", "colour property 'red'");
}
TEST(PlyBad, BinaryDataInHeader) {
  expect_bad("ply\nformat ascii 1.0\nelement vertex 3\0\x01\x02\n"s, "line 3",
             "binary data in the header");
}
TEST(PlyBad, HugeVertexCountAscii) {
  expect_bad(
      "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n0 0 0\n",
      "line 3", "4000000000 'vertex' elements");
}
TEST(PlyBad, HugeVertexCountBinary) {
  // 2^64 - 1 elements: the byte estimate must not overflow into a small number.
  expect_bad(ply_header("binary_little_endian",
                        "element vertex 18446744073709551615\nproperty float x\nproperty float y\n"
                        "property float z\n") +
                 std::string(12, '\0'),
             "line 3", "18446744073709551615 'vertex' elements");
}
TEST(PlyBad, HugeFaceCountBinary) {
  expect_bad(ply_header("binary_big_endian",
                        "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 3000000000\nproperty list uchar int vertex_indices\n"),
             "line 7", "3000000000 'face' elements");
}
TEST(PlyBad, HugeCountOfAnUnknownElement) {
  expect_bad(ply_header("binary_little_endian",
                        "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
                        "element junk 999999999999\nproperty list uint uchar stuff\n") +
                 "abcd",
             "line 7", "999999999999 'junk' elements");
}
TEST(PlyBad, HugeListCountBinary) {
  Bytes b(false);
  for (int i = 0; i < 9; ++i) b.put(0.0f);
  b.put(uint32_t(4000000000u)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2));
  expect_bad(ply_header("binary_little_endian",
                        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 1\nproperty list uint int vertex_indices\n") +
                 b.s,
             "face 0", "4000000000 values runs past the end");
}
TEST(PlyBad, HugeListCountFastPath) {
  std::string data = triangle_le(0, 0, 255);
  expect_bad(data, "face 0", "255 values runs past the end");
}
TEST(PlyBad, TruncatedBinaryVertices) {
  std::string data = triangle_le(0, 0);
  data.resize(data.size() - 20);
  expect_bad(data, "line 3", "truncated");
}
TEST(PlyBad, TruncatedBinaryFace) {
  // Long enough for the header's minimum (3 indices a face), but the second face is cut short.
  Bytes b(false);
  for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 1.f, 1.f, 0.f}) b.put(v);
  b.put(uint8_t(4)).put(int32_t(0)).put(int32_t(1)).put(int32_t(3)).put(int32_t(2));
  b.put(uint8_t(3)).put(int32_t(0)).put(int32_t(1)).put(int16_t(2));
  expect_bad(ply_header("binary_little_endian",
                        "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 2\nproperty list uchar int vertex_indices\n") +
                 b.s,
             "face 1", "truncated");
}
// The header check assumes lists are empty; fixed-size rows after a long list can still be cut
// short and must be caught when they are read (found by the fuzzer as a heap overflow).
TEST(PlyBad, TruncatedFixedRowsAfterALongList) {
  Bytes b(false);
  for (int i = 0; i < 9; ++i) b.put(float(i % 4 == 0));
  b.put(uint8_t(3)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2));
  b.put(int32_t(7));  // junk 0; junk 1 is missing
  expect_bad(ply_header("binary_little_endian",
                        std::string(kVertexHeader) + "element junk 2\nproperty int a\n") +
                 b.s,
             "junk 1", "truncated");
}
TEST(PlyBad, TruncatedVerticesAfterALongList) {
  Bytes b(true);
  b.put(uint8_t(3)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2));
  for (int i = 0; i < 7; ++i) b.put(1.0f);  // vertex 2 is cut short
  expect_bad(
      ply_header("binary_big_endian",
                 "element face 1\nproperty list uchar int vertex_indices\n"
                 "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n") +
          b.s,
      "vertex 2", "truncated");
}
TEST(PlyBad, TruncatedAsciiFaces) {
  expect_bad(ascii_ply("0.0000 0.0000 0.0000\n1.0000 0.0000 0.0000\n0.0000 1.0000 0.0000\n"),
             "line 13", "face 0", "truncated");
}
TEST(PlyBad, NonNumericToken) {
  expect_bad(ascii_ply("0 0 0\n1 0x 0\n0 1 0\n3 0 1 2\n"), "line 11", "vertex 1", "'0x'");
}
TEST(PlyBad, NanCoordinateAscii) {
  expect_bad(ascii_ply("0 0 0\n1 0 0\n0 nan 0\n3 0 1 2\n"), "line 12", "vertex 2", "not a finite");
}
TEST(PlyBad, InfCoordinateBinary) {
  expect_bad(triangle_le(INFINITY, 0), "vertex 0", "x is not a finite float (inf)");
}
TEST(PlyBad, NanCoordinateBigEndian) {
  Bytes b(true);
  for (const float v : {0.f, 0.f, 0.f, 1.f, NAN, 0.f, 0.f, 1.f, 0.f}) b.put(v);
  b.put(uint8_t(3)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2));
  expect_bad(ply_header("binary_big_endian", kVertexHeader) + b.s, "vertex 1",
             "y is not a finite float");
}
TEST(PlyBad, DoubleOverflowsFloat) {
  expect_bad(
      ply_header("ascii",
                 "element vertex 1\nproperty double x\nproperty float y\nproperty float z\n") +
          "1e300 0 0\n",
      "line 8", "vertex 0", "not a finite");
}
TEST(PlyBad, FloatTokenOverflows) {
  expect_bad(ascii_ply("0 0 0\n1 0 0\n0 1e39 0\n3 0 1 2\n"), "line 12", "vertex 2");
}
TEST(PlyBad, IndexPastEndAscii) {
  expect_bad(ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), "line 13", "face 0",
             "vertex index 3 out of range (3 vertices)");
}
TEST(PlyBad, IndexPastEndBinary) {
  expect_bad(triangle_le(0, 40000), "face 0", "vertex index 40000 out of range (3 vertices)");
}
TEST(PlyBad, NegativeIndexBinary) {
  expect_bad(triangle_le(0, -1), "face 0", "vertex index -1 is negative");
}
TEST(PlyBad, FaceWithTwoVertices) {
  expect_bad(ascii_ply("0 0 0\n1 0 0\n0 1 0\n2 0 1\n"), "face 0", "2 vertices (at least 3");
}
TEST(PlyBad, FaceWithTwoVerticesBinary) {
  expect_bad(triangle_le(0, 0, 2), "face 0", "2 vertices");
}
TEST(PlyBad, RepeatedVertexBinary) {
  expect_bad(triangle_le(0, 2), "face 0", "repeats vertex 2");
}
TEST(PlyBad, RepeatedVertexInLargeFace) {
  std::string text = ply_header("ascii",
                                "element vertex 40\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 1\n"
                                "property list uchar int vertex_indices\n");
  for (int i = 0; i < 40; ++i) text += fmt::format("{} 0 0\n", i);
  text += "30";
  for (int i = 0; i < 30; ++i) text += fmt::format(" {}", i == 29 ? 7 : i);
  expect_bad(text + "\n", "face 0", "repeats vertex 7");
}
TEST(PlyBad, ExtraValueOnAsciiLine) {
  expect_bad(ascii_ply("0 0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n"), "line 11", "vertex 1",
             "extra value '5'");
}
TEST(PlyBad, MissingValueOnAsciiLine) {
  expect_bad(ascii_ply("0 0 0\n1 0\n0 1 0\n3 0 1 2\n"), "line 11", "before the value of 'z'");
}
TEST(PlyBad, ShortFaceListOnAsciiLine) {
  expect_bad(ascii_ply("0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n"), "line 13", "face 0");
}
TEST(PlyBad, DataAfterTheLastElement) {
  expect_bad(ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n"), "line 14",
             "after the last element");
}
TEST(PlyBad, ListCountOutOfRangeForItsType) {
  expect_bad(ascii_ply("0 0 0\n1 0 0\n0 1 0\n256 0 1 2\n"), "line 13", "out of range for uchar");
}
TEST(PlyBad, FractionalIndex) {
  expect_bad(ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n"), "line 13", "'1.5'");
}
TEST(PlyBad, NegativeListCountBinary) {
  Bytes b(false);
  for (int i = 0; i < 9; ++i) b.put(0.0f);
  b.put(int8_t(-3)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2));
  expect_bad(ply_header("binary_little_endian",
                        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 1\nproperty list char int vertex_indices\n") +
                 b.s,
             "face 0", "negative list length -3");
}
TEST(PlyBad, TristripIndexOutOfRange) {
  expect_bad(ply_header("ascii", kStripHeader) +
                 "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n5 0 1 2 -1 8\n",
             "tristrips 0", "vertex index 8 out of range");
}
TEST(PlyBad, TristripNegativeIndexOtherThanRestart) {
  expect_bad(ply_header("ascii", kStripHeader) +
                 "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n4 0 1 2 -2\n",
             "tristrips 0", "-2 is negative");
}
TEST(PlyBad, BinaryGarbage) {
  std::string g;
  for (int i = 0; i < 512; ++i) g += static_cast<char>((i * 151 + 7) & 0xFF);
  expect_bad(g, "line 1", "not a PLY file");
}
TEST(PlyBad, GarbageAfterMagic) {
  std::string g = "ply\n";
  for (int i = 0; i < 512; ++i) g += static_cast<char>((i * 151 + 7) & 0xFF);
  expect_bad(g, "line ");
}

// ---- the bad-input files: every one fails with a one-line message naming it and the place ----

std::vector<std::string> bad_files(const char* ext) {
  std::vector<std::string> out;
  const std::filesystem::path dir = std::filesystem::path(LIMN_TEST_DATA) / "bad";
  if (std::filesystem::is_directory(dir))
    for (const auto& e : std::filesystem::directory_iterator(dir))
      if (e.path().extension() == ext) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// ": line N: ...", ": <element> N: ..." or ": empty file".
bool names_a_place(const std::string& rest) {
  if (rest == ": empty file") return true;
  std::istringstream in(rest.substr(2));
  std::string word;
  unsigned long n;
  char colon;
  return rest.rfind(": ", 0) == 0 && (in >> word >> n >> colon) && colon == ':';
}

TEST(PlyBadFiles, Present) {
  EXPECT_GE(bad_files(".ply").size(), 15u) << LIMN_TEST_DATA;
}

class PlyBadFile : public ::testing::TestWithParam<std::string> {};

TEST_P(PlyBadFile, ThrowsNamingTheFileAndThePlace) {
  const std::string path = (std::filesystem::path(LIMN_TEST_DATA) / "bad" / GetParam()).string();
  const std::string data = slurp(path);
  try {
    read_ply(data, path);
    FAIL() << path << " was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;
    EXPECT_TRUE(names_a_place(msg.substr(path.size()))) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

INSTANTIATE_TEST_SUITE_P(Data, PlyBadFile, ::testing::ValuesIn(bad_files(".ply")),
                         [](const auto& tp) {
                           std::string n = tp.param.substr(0, tp.param.size() - 4);
                           std::replace_if(
                               n.begin(), n.end(),
                               [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); },
                               '_');
                           return n;
                         });
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(PlyBadFile);

}  // namespace
}  // namespace limn
