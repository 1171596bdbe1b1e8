// OFF reading and writing: header variants (COFF, NOFF, CNOFF, STOFF), comments and line
// endings, exact round trips, the shared CGAL models, and bad input rejected line by line.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "limn/io/mesh_io.hpp"

#ifndef LIMN_TEST_DATA
#define LIMN_TEST_DATA "tests/data"
#endif
#ifndef LIMN_SHARED_MODELS
#define LIMN_SHARED_MODELS "/work/shared/models"
#endif

namespace limn {
namespace {

using ::testing::HasSubstr;

template <class... S>
void expect_bad(std::string_view data, S... fragments) {
  try {
    read_off(data, "bad.off");
    FAIL() << "accepted bad input:\n" << data;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_THAT(msg, HasSubstr("bad.off: "));
    for (const std::string_view f : {std::string_view(fragments)...})
      EXPECT_THAT(msg, HasSubstr(std::string(f)));
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
  }
}

const char* kQuadTri =
    "# made by hand\n"
    "OFF # the header may carry a comment\n"
    "# so may any line\n"
    "5 2 0\n"
    "\n"
    "0 0 0\n"
    "1 0 0   # a vertex with a comment\n"
    "1 1 0\n"
    "\t0 1 0\n"
    "2 0.5 -1.5e-3\n"
    "4 0 1 2 3\n"
    "3 1 4 2 255 0 0\n";

TEST(Off, HandWritten) {
  const Mesh m = read_off(kQuadTri, "t.off");
  EXPECT_EQ(m.positions,
            (std::vector<float>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0.5f, -1.5e-3f}));
  EXPECT_EQ(m.face_offsets, (std::vector<uint32_t>{0, 4, 7}));
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2, 3, 1, 4, 2}));
  EXPECT_TRUE(m.colors.empty());
  EXPECT_TRUE(m.normals.empty());
}

TEST(Off, CountsOnTheHeaderLineWithoutEdgeCount) {
  const Mesh m = read_off("OFF 3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 0.5 0.5 0.5 1\n", "t.off");
  EXPECT_EQ(m.vertex_count(), 3u);
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(Off, ColourVertices) {
  // RGBA bytes, RGB bytes, RGB fractions; alpha defaults to 1.
  const Mesh m = read_off(
      "COFF\n3 1 0\n0 0 0 255 0 51 102\n1 0 0 0 255 0\n0 1 0 0.25 0.5 1\n"
      "3 0 1 2\n",
      "t.off");
  EXPECT_EQ(m.positions, (std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0}));
  EXPECT_EQ(m.colors,
            (std::vector<float>{1, 0, 51 / 255.0f, 102 / 255.0f, 0, 1, 0, 1, 0.25f, 0.5f, 1, 1}));
}

TEST(Off, NormalVertices) {
  const Mesh m =
      read_off("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0.6 0.8\n3 2 1 0\n", "t.off");
  EXPECT_EQ(m.normals, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0.6f, 0.8f}));
  EXPECT_EQ(m.normal_indices, m.face_vertices);
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{2, 1, 0}));
}

TEST(Off, NormalsBeforeColoursBeforeTextureCoordinates) {
  const Mesh m = read_off(
      "STCNOFF\n3 1 0\n"
      "0 0 0  0 0 1  1.0 0 0 1  0.5 0.25\n"
      "1 0 0  0 0 1  0 255 0  1 0\n"
      "0 1 0  0 0 1  0 0 1 0.5  0 1\n"
      "3 0 1 2\n",
      "t.off");
  EXPECT_EQ(m.normals, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}));
  EXPECT_EQ(m.colors, (std::vector<float>{1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 0.5f}));
  EXPECT_EQ(m.uvs, (std::vector<float>{0.5f, 0.25f, 1, 0, 0, 1}));
  EXPECT_EQ(m.uv_indices, m.face_vertices);
}

TEST(Off, CnoffReadsNormalThenColour) {
  const Mesh m = read_off(
      "CNOFF\n3 1\n0 0 0 0 0 1 255 0 0 255\n1 0 0 0 0 1 0 255 0 255\n"
      "0 1 0 0 0 1 0 0 255 255\n3 0 1 2\n",
      "t.off");
  EXPECT_EQ(m.normals.size(), 9u);
  EXPECT_EQ(m.colors, (std::vector<float>{1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1}));
}

Mesh awkward_mesh() {
  Mesh m;
  const float coords[] = {0.1f, -2.5e-7f, 3.14159274f, 1e10f,   7.0f, -0.3333333f, 1e-45f, 6, 7,
                          8,    9,        10,          -1e-38f, 0.3f, 123456.789f, 2,      2, 2};
  for (int i = 0; i < 6; ++i) m.add_vertex(coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]);
  m.add_face({0, 1, 2, 3});
  m.add_face({3, 2, 1});
  m.add_face({0, 1, 5, 4, 3});
  return m;
}

TEST(Off, RoundTripIsExact) {
  const Mesh m = awkward_mesh();
  std::string out;
  write_off(m, out);
  EXPECT_EQ(out.rfind("OFF\n6 3 0\n", 0), 0u);
  const Mesh r = read_off(out, "rt.off");
  EXPECT_EQ(r.positions, m.positions);
  EXPECT_EQ(r.face_offsets, m.face_offsets);
  EXPECT_EQ(r.face_vertices, m.face_vertices);
}

TEST(Off, WriterOutputIsPlainOff) {
  Mesh m;
  m.add_vertex(0, 0, 0);
  m.add_vertex(1, 0, 0);
  m.add_vertex(0, 0.5f, 0);
  m.add_face({0, 1, 2});
  std::string out = "keep ";
  write_off(m, out);
  EXPECT_EQ(out, "keep OFF\n3 1 0\n0 0 0\n1 0 0\n0 0.5 0\n3 0 1 2\n");
}

TEST(Off, LargePolygonRoundTrips) {
  Mesh m;
  std::vector<uint32_t> big;
  for (uint32_t i = 0; i < 300; ++i) {
    const float a = float(i) * 0.0209f;
    m.add_vertex(std::cos(a), std::sin(a), 0);
    big.push_back(299 - i);
  }
  m.add_face(big);
  std::string out;
  write_off(m, out);
  const Mesh r = read_off(out, "rt.off");
  EXPECT_EQ(r.face_vertices, m.face_vertices);
  EXPECT_EQ(r.positions, m.positions);
}

TEST(Off, EmptyMesh) {
  const Mesh m = read_off("OFF\n0 0 0\n", "t.off");
  EXPECT_EQ(m.vertex_count(), 0u);
  EXPECT_EQ(m.face_count(), 0u);
  std::string out;
  write_off(m, out);
  EXPECT_EQ(read_off(out, "t.off").face_count(), 0u);
}

TEST(Off, LineEndingsAndBomParseLikeClean) {
  const Mesh clean = read_off(kQuadTri, "t.off");
  std::string crlf, cr;
  for (const char* p = kQuadTri; *p; ++p) {
    crlf += *p == '\n' ? std::string("\r\n") : std::string(1, *p);
    cr += *p == '\n' ? '\r' : *p;
  }
  for (const std::string& s : {crlf, cr, "\xEF\xBB\xBF" + crlf, crlf.substr(0, crlf.size() - 2)}) {
    const Mesh m = read_off(s, "t.off");
    EXPECT_EQ(m.positions, clean.positions);
    EXPECT_EQ(m.face_offsets, clean.face_offsets);
    EXPECT_EQ(m.face_vertices, clean.face_vertices);
  }
}

TEST(Off, LineNumbersCountLoneCarriageReturns) {
  expect_bad("OFF\r3 1 0\r\n0 0 0\r1 0 0\r0 1 0\r3 0 1 7\r", "line 6", "face 0");
}

TEST(Off, PlusSignsAndUnderflow) {
  const Mesh m = read_off("OFF\n+3 +1 +0\n+1 1e-50 -1e-400\n1 0 0\n0 1 0\n+3 +0 1 2\n", "t.off");
  EXPECT_EQ(m.positions[0], 1.0f);
  EXPECT_EQ(m.positions[1], 0.0f);
  EXPECT_EQ(m.positions[2], 0.0f);
  EXPECT_EQ(m.face_vertices, (std::vector<uint32_t>{0, 1, 2}));
}

// ---- the shared CGAL models ----

Mesh read_path(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return read_off(s.str(), p.string());
}

void convert_and_compare(const char* rel, size_t faces, size_t vertices) {
  const std::filesystem::path p = std::filesystem::path(LIMN_SHARED_MODELS) / rel;
  // ../shared/models is part of the test environment: a missing model is a failure.
  ASSERT_TRUE(std::filesystem::exists(p)) << p << " is missing";
  const Mesh m = read_path(p);
  EXPECT_EQ(m.face_count(), faces);
  EXPECT_EQ(m.vertex_count(), vertices);
  std::string off, ply_bin, ply_txt;
  write_off(m, off);
  write_ply(m, ply_bin, false);
  write_ply(m, ply_txt, true);
  for (const Mesh& r :
       {read_off(off, "c.off"), read_ply(ply_bin, "c.ply"), read_ply(ply_txt, "c.ply")}) {
    EXPECT_EQ(r.positions, m.positions);
    EXPECT_EQ(r.face_offsets, m.face_offsets);
    EXPECT_EQ(r.face_vertices, m.face_vertices);
  }
}

TEST(Off, SharedBladeConverts) {
  convert_and_compare("tri/blade.off", 16222, 8231);
}
TEST(Off, SharedArmadilloConverts) {
  convert_and_compare("tri/armadillo-cgal-52k.off", 52000, 26002);
}

// ---- bad input: one test per case ----

const char* kHead = "OFF\n3 1 0\n";

TEST(OffBad, EmptyFile) {
  expect_bad("", "empty file");
}
TEST(OffBad, OnlyComments) {
  expect_bad("# nothing\n\n", "line 2", "no OFF header");
}
TEST(OffBad, NotOff) {
  expect_bad("ply\nformat ascii 1.0\n", "line 1", "not an OFF file", "'ply'");
}
TEST(OffBad, OffMustBeAWholeToken) {
  expect_bad("OFFSET\n3 1 0\n", "line 1", "'OFFSET'");
}
TEST(OffBad, BinaryOff) {
  expect_bad("OFF BINARY\n", "line 1", "binary OFF");
}
TEST(OffBad, FourDimensional) {
  expect_bad("4OFF\n1 0 0\n0 0 0 0\n", "line 1", "3-dimensional");
}
TEST(OffBad, MissingCounts) {
  expect_bad("OFF\n", "line 1", "truncated");
}
TEST(OffBad, OneCount) {
  expect_bad("OFF\n3\n", "line 2", "vertex and face counts");
}
TEST(OffBad, NegativeCount) {
  expect_bad("OFF\n-3 1 0\n", "line 2", "vertex count '-3'");
}
TEST(OffBad, FractionalCount) {
  expect_bad("OFF\n3 1.5 0\n", "line 2", "face count '1.5'");
}
TEST(OffBad, ExtraValueAfterCounts) {
  expect_bad("OFF\n3 1 0 7\n", "line 2", "unexpected value '7'");
}
TEST(OffBad, HugeVertexCount) {
  expect_bad("OFF\n4000000000 1 0\n0 0 0\n", "line 2", "4000000000 vertices");
}
TEST(OffBad, HugeFaceCount) {
  expect_bad("OFF\n3 99999999999999 0\n0 0 0\n1 0 0\n0 1 0\n", "line 2", "99999999999999 faces");
}
TEST(OffBad, CountBeyondInt64) {
  expect_bad("OFF\n99999999999999999999 1 0\n", "line 2");
}
TEST(OffBad, TruncatedVertices) {
  expect_bad("OFF\n3 1 0\n0.00000000 0.00000000 0.00000000\n1.00000000 0.00000000 0.00000000\n",
             "line 5", "vertex 2", "truncated");
}
TEST(OffBad, TruncatedFaces) {
  expect_bad(
      "OFF\n3 2 0\n0.000000 0.000000 0.000000\n1.000000 0.000000 0.000000\n"
      "0.000000 1.000000 0.000000\n3 0 1 2\n",
      "line 7", "face 1", "truncated");
}
TEST(OffBad, NonNumericCoordinate) {
  expect_bad(std::string(kHead) + "0 0 0\n1x 0 0\n0 1 0\n3 0 1 2\n", "line 4", "vertex 1", "'1x'");
}
TEST(OffBad, NanCoordinate) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 nan 0\n3 0 1 2\n", "line 5", "vertex 2",
             "'nan'");
}
TEST(OffBad, InfCoordinate) {
  expect_bad(std::string(kHead) + "-inf 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "line 3", "vertex 0");
}
TEST(OffBad, OverflowCoordinate) {
  expect_bad(std::string(kHead) + "0 0 1e39\n1 0 0\n0 1 0\n3 0 1 2\n", "line 3", "'1e39'");
}
TEST(OffBad, TooFewVertexValues) {
  expect_bad(std::string(kHead) + "0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "line 3",
             "2 values (expected 3)");
}
TEST(OffBad, TooManyVertexValues) {
  expect_bad(std::string(kHead) + "0 0 0 1\n1 0 0\n0 1 0\n3 0 1 2\n", "line 3",
             "4 values (expected 3)");
}
TEST(OffBad, CoffWithTwoColourValues) {
  expect_bad("COFF\n3 1 0\n0 0 0 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n", "line 3",
             "expected 6 or 7");
}
TEST(OffBad, CoffByteColourOutOfRange) {
  expect_bad("COFF\n3 1 0\n0 0 0 1 1 1\n1 0 0 300 1 1\n0 1 0 1 1 1\n3 0 1 2\n", "line 4",
             "vertex 1", "out of range 0-255");
}
TEST(OffBad, IndexPastEnd) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "line 6", "face 0",
             "vertex index 3 out of range (3 vertices)");
}
TEST(OffBad, NegativeIndex) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "line 6",
             "index -1 is negative");
}
TEST(OffBad, NonNumericIndex) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n3 0 b 2\n", "line 6", "'b'");
}
TEST(OffBad, FaceWithTwoVertices) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "line 6", "2 vertices");
}
TEST(OffBad, RepeatedIndex) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n", "line 6", "repeats vertex 1");
}
TEST(OffBad, RepeatedIndexInLargeFace) {
  std::string s = "OFF\n30 1 0\n";
  for (int i = 0; i < 30; ++i) s += fmt::format("{} 0 0\n", i);
  s += "25";
  for (int i = 0; i < 25; ++i) s += fmt::format(" {}", i == 20 ? 3 : i);
  expect_bad(s + "\n", "line 33", "repeats vertex 3");
}
TEST(OffBad, FaceShortOfItsCount) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "line 6",
             "declares 4 vertices but the line has 3");
}
TEST(OffBad, HugeFaceArity) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n", "line 6",
             "declares 4000000000 vertices");
}
TEST(OffBad, TooManyFaceColourValues) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 1 1 1 1 1\n", "line 6",
             "unexpected value '1'");
}
TEST(OffBad, NonNumericFaceColour) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 red\n", "line 6", "'red'");
}
TEST(OffBad, DataAfterTheLastFace) {
  expect_bad(std::string(kHead) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n", "line 7",
             "after the last face");
}
TEST(OffBad, BinaryGarbage) {
  std::string g = "OFF\n";
  for (int i = 0; i < 512; ++i) g += static_cast<char>((i * 151 + 7) & 0xFF);
  expect_bad(g, "line ");
}

// ---- the bad-input files ----

std::vector<std::string> bad_files() {
  std::vector<std::string> out;
  const std::filesystem::path dir = std::filesystem::path(LIMN_TEST_DATA) / "bad";
  if (std::filesystem::is_directory(dir))
    for (const auto& e : std::filesystem::directory_iterator(dir))
      if (e.path().extension() == ".off") out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(OffBadFiles, Present) {
  EXPECT_GE(bad_files().size(), 12u) << LIMN_TEST_DATA;
}

class OffBadFile : public ::testing::TestWithParam<std::string> {};

TEST_P(OffBadFile, ThrowsNamingTheFileAndTheLine) {
  const std::string path = (std::filesystem::path(LIMN_TEST_DATA) / "bad" / GetParam()).string();
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  try {
    read_off(s.str(), path);
    FAIL() << path << " was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;
    const std::string rest = msg.substr(path.size());
    EXPECT_TRUE(rest == ": empty file" || (rest.rfind(": line ", 0) == 0 &&
                                           std::isdigit(static_cast<unsigned char>(rest[7]))))
        << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

INSTANTIATE_TEST_SUITE_P(Data, OffBadFile, ::testing::ValuesIn(bad_files()), [](const auto& tp) {
  std::string n = tp.param.substr(0, tp.param.size() - 4);
  std::replace_if(
      n.begin(), n.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); }, '_');
  return n;
});
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(OffBadFile);

}  // namespace
}  // namespace limn
