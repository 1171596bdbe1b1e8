// STL: a strict reader (ascii and binary) that welds the triangle soup into an indexed mesh, and
// a binary writer.
//
// Binary and ascii are told apart by size first: many binary writers start their 80-byte header
// with "solid", so only a file whose size disagrees with 84 + 50 * count, starts with "solid" and
// holds no NUL byte is read as ascii. Facet numbers in messages are 0-based, like validate()'s.
#include <fmt/format.h>

#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/weld.hpp"
#include "text_number.hpp"

namespace limn {

using namespace text;
namespace {

constexpr size_t kHeader = 84, kRecord = 50;

inline uint32_t load_u32le(const char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  if constexpr (std::endian::native == std::endian::big) v = __builtin_bswap32(v);
  return v;
}

inline float load_f32le(const char* p) {
  return std::bit_cast<float>(load_u32le(p));
}

bool starts_with_solid(std::string_view d) {
  size_t i = 0;
  while (i < d.size() && (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' || d[i] == '\n')) ++i;
  if (d.size() - i < 5) return false;
  for (size_t k = 0; k < 5; ++k)
    if (std::tolower(static_cast<unsigned char>(d[i + k])) != "solid"[k]) return false;
  return d.size() - i == 5 || std::isspace(static_cast<unsigned char>(d[i + 5]));
}

// Welds a triangle soup (9 floats per triangle), drops the triangles that repeat a vertex and
// keeps only the vertices of the remaining ones, numbered in order of first use.
Mesh weld_soup(const std::vector<float>& soup, std::string_view name, size_t* dropped) {
  const std::vector<uint32_t> group = weld_map(soup);
  const size_t nt = soup.size() / 9;
  std::vector<uint32_t> renumber(nt * 3, 0xFFFFFFFFu);
  Mesh m;
  m.face_offsets.reserve(nt + 1);
  m.face_vertices.reserve(3 * nt);
  size_t degenerate = 0;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t a = group[3 * t], b = group[3 * t + 1], c = group[3 * t + 2];
    if (a == b || b == c || a == c) {
      ++degenerate;
      continue;
    }
    for (size_t k = 0; k < 3; ++k) {
      uint32_t& r = renumber[group[3 * t + k]];
      if (r == 0xFFFFFFFFu) {
        r = static_cast<uint32_t>(m.vertex_count());
        m.positions.insert(m.positions.end(), &soup[9 * t + 3 * k], &soup[9 * t + 3 * k] + 3);
      }
      m.face_vertices.push_back(r);
    }
    m.face_offsets.push_back(static_cast<uint32_t>(m.face_vertices.size()));
  }
  if (dropped) *dropped = degenerate;
  validate(m, std::string(name));
  return m;
}

Mesh read_binary(std::string_view d, std::string_view name, size_t* dropped) {
  const uint64_t count = load_u32le(d.data() + 80);
  if (count > UINT32_MAX / 3)  // weld_map numbers points with 32 bits
    throw InputError(fmt::format("{}: {} triangles are more than limn can weld", name, count));
  std::vector<float> soup(9 * count);
  const char* p = d.data() + kHeader;
  for (uint64_t t = 0; t < count; ++t, p += kRecord) {
    for (size_t k = 0; k < 9; ++k) {
      const float x = load_f32le(p + 12 + 4 * k);
      if (!std::isfinite(x))
        throw InputError(fmt::format("{}: triangle {}: vertex {} has a non-finite coordinate ({})",
                                     name, t, k / 3, x));
      soup[9 * t + k] = x;
    }
  }
  return weld_soup(soup, name, dropped);
}

// Ascii STL as a stream of whitespace-separated tokens with line numbers; keywords are matched
// case-insensitively since some CAD exporters write them in capitals.
class AsciiStl {
 public:
  AsciiStl(std::string_view data, std::string_view name) : d_(data), name_(name) {}

  Mesh read(size_t* dropped) {
    bool any_solid = false;
    for (;;) {
      const std::string_view t = token();
      if (t.empty()) {
        if (!any_solid) fail("no 'solid' line");
        break;
      }
      if (!is(t, "solid")) {
        if (any_solid)
          fail(fmt::format("expected 'solid' or the end of the file, got '{}'", printable(t)));
        fail(fmt::format("expected 'solid', got '{}'", printable(t)));
      }
      any_solid = true;
      skip_line();  // the solid's name, which may contain spaces
      read_solid();
    }
    return weld_soup(soup_, name_, dropped);
  }

 private:
  void read_solid() {
    for (;;) {
      const std::string_view t = token();
      if (t.empty()) fail("truncated: the file ends before 'endsolid'");
      if (is(t, "endsolid")) {
        skip_line();
        return;
      }
      if (!is(t, "facet"))
        fail(fmt::format("facet {}: expected 'facet' or 'endsolid', got '{}'", facet_,
                         printable(t)));
      read_facet();
      ++facet_;
    }
  }

  void read_facet() {
    expect("normal");
    for (int k = 0; k < 3; ++k) {
      float n;
      const std::string_view t = need("a normal component");
      if (!parse_float(t, n))
        bad(fmt::format("normal component '{}' is not a number", printable(t)));
    }
    expect("outer");
    expect("loop");
    int vertices = 0;
    for (;;) {
      const std::string_view t = need("'vertex' or 'endloop'");
      if (is(t, "endloop")) break;
      if (!is(t, "vertex"))
        bad(fmt::format("expected 'vertex' or 'endloop', got '{}'", printable(t)));
      if (++vertices > 3) bad("has more than 3 vertices");
      for (int k = 0; k < 3; ++k) {
        const std::string_view x = need("a coordinate");
        float f;
        if (!parse_float(x, f)) bad(fmt::format("coordinate '{}' is not a number", printable(x)));
        if (!std::isfinite(f))
          bad(fmt::format("coordinate '{}' is not a finite float", printable(x)));
        soup_.push_back(f);
      }
    }
    if (vertices != 3) bad(fmt::format("has {} vertices (3 needed)", vertices));
    expect("endfacet");
  }

  [[noreturn]] void fail(std::string_view msg) const {
    throw InputError(fmt::format("{}: line {}: {}", name_, line_, msg));
  }
  [[noreturn]] void bad(std::string_view msg) const {
    fail(fmt::format("facet {}: {}", facet_, msg));
  }

  static bool is(std::string_view t, std::string_view keyword) {
    if (t.size() != keyword.size()) return false;
    for (size_t i = 0; i < t.size(); ++i)
      if (std::tolower(static_cast<unsigned char>(t[i])) != keyword[i]) return false;
    return true;
  }

  void expect(std::string_view keyword) {
    const std::string_view t = need(fmt::format("'{}'", keyword));
    if (!is(t, keyword)) bad(fmt::format("expected '{}', got '{}'", keyword, printable(t)));
  }

  std::string_view need(std::string_view what) {
    const std::string_view t = token();
    if (t.empty()) bad(fmt::format("truncated: the file ends before {}", what));
    return t;
  }

  // Next token; empty at the end of the data. Tracks line numbers (\n, \r\n and lone \r).
  std::string_view token() {
    while (p_ < d_.size()) {
      const char c = d_[p_];
      if (c == '\n' || (c == '\r' && (p_ + 1 == d_.size() || d_[p_ + 1] != '\n'))) ++line_;
      if (c != ' ' && c != '\t' && c != '\r' && c != '\n' && c != '\f' && c != '\v') break;
      ++p_;
    }
    const size_t b = p_;
    while (p_ < d_.size() && !std::isspace(static_cast<unsigned char>(d_[p_]))) ++p_;
    return d_.substr(b, p_ - b);
  }

  void skip_line() {
    while (p_ < d_.size() && d_[p_] != '\n' && d_[p_] != '\r') ++p_;
  }

  std::string_view d_, name_;
  size_t p_ = 0, line_ = 1, facet_ = 0;
  std::vector<float> soup_;
};

}  // namespace

Mesh read_stl(std::string_view d, std::string_view name, size_t* dropped_degenerate) {
  if (dropped_degenerate) *dropped_degenerate = 0;
  if (d.empty()) throw InputError(fmt::format("{}: empty file", name));
  const bool size_fits = d.size() >= kHeader && (d.size() - kHeader) % kRecord == 0 &&
                         (d.size() - kHeader) / kRecord == load_u32le(d.data() + 80);
  if (size_fits) return read_binary(d, name, dropped_degenerate);
  const bool text = std::memchr(d.data(), '\0', d.size()) == nullptr;
  if (starts_with_solid(d) && (text || d.size() < kHeader))
    return AsciiStl(d, name).read(dropped_degenerate);
  if (text)
    throw InputError(fmt::format(
        "{}: not an STL file (text, but not ascii STL: it does not start with 'solid')", name));
  if (d.size() < kHeader)
    throw InputError(
        fmt::format("{}: truncated: {} bytes, shorter than the 84-byte header of a binary STL",
                    name, d.size()));
  const uint64_t count = load_u32le(d.data() + 80);
  const uint64_t complete = (d.size() - kHeader) / kRecord;
  if (count > complete)
    throw InputError(fmt::format(
        "{}: triangle {}: truncated: the header declares {} triangles ({} bytes) but the file "
        "has {} bytes",
        name, complete, count, kHeader + kRecord * count, d.size()));
  throw InputError(fmt::format(
      "{}: the header declares {} triangles ({} bytes) but the file has {} bytes (trailing data)",
      name, count, kHeader + kRecord * count, d.size()));
}

void write_stl(const Mesh& m, std::string& out) {
  size_t nt = 0;
  for (size_t f = 0; f < m.face_count(); ++f) nt += m.face_size(f) - 2;
  if (nt > UINT32_MAX)
    throw InputError(fmt::format("cannot write STL: {} triangles exceed its 32-bit count", nt));
  char header[kHeader] = {};
  const std::string_view title = "binary STL written by limn";
  std::memcpy(header, title.data(), title.size());
  const auto put32 = [](char* p, uint32_t v) {
    if constexpr (std::endian::native == std::endian::big) v = __builtin_bswap32(v);
    std::memcpy(p, &v, 4);
  };
  put32(header + 80, static_cast<uint32_t>(nt));
  const size_t start = out.size();
  out.resize(start + kHeader + kRecord * nt);
  char* p = out.data() + start;
  std::memcpy(p, header, kHeader);
  p += kHeader;
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    for (size_t i = 1; i + 1 < fv.size(); ++i, p += kRecord) {
      const float* v[3] = {&m.positions[3 * size_t(fv[0])], &m.positions[3 * size_t(fv[i])],
                           &m.positions[3 * size_t(fv[i + 1])]};
      const double e1[3] = {double(v[1][0]) - v[0][0], double(v[1][1]) - v[0][1],
                            double(v[1][2]) - v[0][2]};
      const double e2[3] = {double(v[2][0]) - v[0][0], double(v[2][1]) - v[0][1],
                            double(v[2][2]) - v[0][2]};
      double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                     e1[0] * e2[1] - e1[1] * e2[0]};
      const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (double& x : n) x = len > 0 ? x / len : 0.0;
      for (int k = 0; k < 3; ++k) put32(p + 4 * k, std::bit_cast<uint32_t>(float(n[k])));
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k)
          put32(p + 12 + 12 * j + 4 * k, std::bit_cast<uint32_t>(v[j][k]));
      p[48] = p[49] = 0;
    }
  }
}

}  // namespace limn
