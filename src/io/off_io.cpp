// OFF (Geomview object file format): a strict line-based reader and a plain writer.
//
// OFF is nominally free-form whitespace, but optional trailing values (face colours, the colour
// width of COFF vertices) can only be told apart line by line, and every writer in practice puts
// one vertex or face per line. So the reader requires that, and in exchange can report precise
// line numbers and reject lines with stray values. Element numbers in messages are 0-based.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>

#include "limn/io/mesh_io.hpp"
#include "text_number.hpp"

namespace limn {

using namespace text;  // the shared number helpers (text_number.hpp)
namespace {

bool is_integer_token(std::string_view t) {
  t = strip_plus(t);
  if (!t.empty() && t[0] == '-') t.remove_prefix(1);
  return !t.empty() && std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; });
}

class OffReader {
 public:
  OffReader(std::string_view data, std::string_view name, bool soup)
      : data_(data), name_(name), soup_(soup) {}

  Mesh read() {
    if (data_.size() >= 3 && std::memcmp(data_.data(), "\xEF\xBB\xBF", 3) == 0)
      data_.remove_prefix(3);
    if (data_.empty()) throw InputError(fmt::format("{}: empty file", name_));
    header();
    read_vertices();
    read_faces();
    if (next_line())
      fail(fmt::format("unexpected data after the last face ('{}')", printable(token())));
    if (normals_) mesh_.normal_indices = mesh_.face_vertices;
    if (uvs_) mesh_.uv_indices = mesh_.face_vertices;
    (soup_ ? validate_soup : validate)(mesh_, std::string(name_));
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void fail(std::string_view msg) const {
    throw InputError(fmt::format("{}: line {}: {}", name_, line_, msg));
  }
  [[noreturn]] void fail(const char* kind, uint64_t i, std::string_view msg) const {
    throw InputError(fmt::format("{}: line {}: {} {}: {}", name_, line_, kind, i, msg));
  }

  // Moves to the next line with content ('#' starts a comment anywhere); false at end of file.
  bool next_line() {
    for (;;) {
      if (pos_ >= data_.size()) return false;
      size_t e = pos_;
      while (e < data_.size() && data_[e] != '\n' && data_[e] != '\r') ++e;
      cur_ = data_.data() + pos_;
      lend_ = data_.data() + e;
      pos_ = e;
      if (pos_ < data_.size())
        pos_ += (data_[pos_] == '\r' && pos_ + 1 < data_.size() && data_[pos_ + 1] == '\n') ? 2 : 1;
      ++line_;
      if (const void* hash = std::memchr(cur_, '#', size_t(lend_ - cur_)))
        lend_ = static_cast<const char*>(hash);
      while (cur_ != lend_ && (*cur_ == ' ' || *cur_ == '\t')) ++cur_;
      if (cur_ != lend_) return true;
    }
  }

  std::string_view token() {
    while (cur_ != lend_ && (*cur_ == ' ' || *cur_ == '\t')) ++cur_;
    const char* b = cur_;
    while (cur_ != lend_ && *cur_ != ' ' && *cur_ != '\t') ++cur_;
    return {b, size_t(cur_ - b)};
  }

  uint64_t count(std::string_view t, const char* what) {
    int64_t v;
    if (!parse_int(t, v) || v < 0)
      fail(fmt::format("{} count '{}' is not a non-negative integer", what, printable(t)));
    return static_cast<uint64_t>(v);
  }

  void header() {
    if (!next_line()) fail("no OFF header (only comments or blank lines)");
    std::string_view key = token();
    const std::string_view full = key;
    // Geomview's prefixes, in its order: [ST][C][N][4][n]OFF.
    if (key.starts_with("ST")) uvs_ = true, key.remove_prefix(2);
    if (key.starts_with("C")) colors_ = true, key.remove_prefix(1);
    if (key.starts_with("N")) normals_ = true, key.remove_prefix(1);
    if (key != "OFF") {
      if (key.ends_with("OFF") && (key.starts_with("4") || key.starts_with("n")))
        fail(fmt::format("'{}': only 3-dimensional OFF is supported", printable(full)));
      fail(fmt::format("not an OFF file (expected an OFF header keyword, found '{}')",
                       printable(full)));
    }
    std::string_view t = token();
    if (t == "BINARY") fail("binary OFF is not supported");
    if (t.empty()) {
      if (!next_line()) fail("truncated: no vertex and face counts after the header");
      t = token();
    }
    nv_ = count(t, "vertex");
    const std::string_view tf = token();
    if (tf.empty()) fail("the counts line needs the vertex and face counts");
    nf_ = count(tf, "face");
    const std::string_view te = token();
    if (!te.empty()) count(te, "edge");  // unused, but it must still be a count
    if (const std::string_view x = token(); !x.empty())
      fail(fmt::format("unexpected value '{}' after the counts", printable(x)));

    // Every vertex and face takes a line of at least two bytes: counts that cannot fit in the
    // rest of the file are rejected before anything is allocated. (A tighter bound would turn a
    // short face line into a vague "bad count" instead of its own message.)
    const uint64_t room = data_.size() - pos_ + 1;  // the last line may lack its newline
    if (nv_ > room / 2 || nf_ > (room - nv_ * 2) / 2)
      fail(
          fmt::format("{} vertices and {} faces cannot fit in the {} bytes that follow "
                      "(truncated file or bad count)",
                      nv_, nf_, room - 1));
    // Valid vertices ("0 0 0\n") and faces ("3 0 1 2\n") are longer; reserving by that bound
    // keeps memory proportional to the file even when the counts lie.
    reserve_v_ = std::min<uint64_t>(nv_, room / 6);
    reserve_f_ = std::min<uint64_t>(nf_, room / 8);
    if (nv_ > UINT32_MAX) fail(fmt::format("{} vertices exceed the 32-bit index range", nv_));
  }

  void read_vertices() {
    const size_t base = 3 + (normals_ ? 3 : 0);
    const size_t want = base + (uvs_ ? 2 : 0);
    mesh_.positions.reserve(3 * reserve_v_);
    if (normals_) mesh_.normals.reserve(3 * reserve_v_);
    if (colors_) mesh_.colors.reserve(4 * reserve_v_);
    if (uvs_) mesh_.uvs.reserve(2 * reserve_v_);
    std::string_view tok[16];
    float val[16];
    for (uint64_t i = 0; i < nv_; ++i) {
      if (!next_line()) {
        ++line_;
        fail("vertex", i,
             fmt::format("truncated: the file ends before this vertex ({} declared)", nv_));
      }
      size_t n = 0;
      for (std::string_view t = token(); !t.empty(); t = token()) {
        if (n == 16) fail("vertex", i, "too many values on the line");
        tok[n] = t;
        if (!parse_finite(t, val[n]))
          fail("vertex", i, fmt::format("'{}' is not a finite number", printable(t)));
        ++n;
      }
      // COFF colours are RGB or RGBA; whatever sits between the normal and the uv is colour.
      const size_t ncolor = n >= want ? n - want : 0;
      if (n < want || (colors_ && ncolor != 3 && ncolor != 4) || (!colors_ && n != want)) {
        fail("vertex", i,
             colors_ ? fmt::format("has {} values (expected {} or {})", n, want + 3, want + 4)
                     : fmt::format("has {} values (expected {})", n, want));
      }
      mesh_.positions.insert(mesh_.positions.end(), val, val + 3);
      if (normals_) mesh_.normals.insert(mesh_.normals.end(), val + 3, val + 6);
      if (colors_) {
        // Integer colours are 0-255 (MeshLab and most tools); fractional ones are already 0-1.
        const bool bytes = std::all_of(tok + base, tok + base + ncolor, is_integer_token);
        float c[4] = {0, 0, 0, 1};
        for (size_t k = 0; k < ncolor; ++k) {
          c[k] = val[base + k];
          if (bytes) {
            if (c[k] < 0.0f || c[k] > 255.0f)
              fail("vertex", i, fmt::format("colour value {} is out of range 0-255", c[k]));
            c[k] /= 255.0f;
          }
        }
        mesh_.colors.insert(mesh_.colors.end(), c, c + 4);
      }
      if (uvs_) mesh_.uvs.insert(mesh_.uvs.end(), val + n - 2, val + n);
    }
  }

  void read_faces() {
    mesh_.face_offsets.reserve(reserve_f_ + 1);
    mesh_.face_vertices.reserve(3 * reserve_f_);
    std::vector<uint32_t> face, sorted;
    for (uint64_t i = 0; i < nf_; ++i) {
      if (!next_line()) {
        ++line_;
        fail("face", i,
             fmt::format("truncated: the file ends before this face ({} declared)", nf_));
      }
      const std::string_view tn = token();
      int64_t n;
      if (!parse_int(tn, n) || n < 0)
        fail("face", i,
             fmt::format("vertex count '{}' is not a non-negative integer", printable(tn)));
      if (n < 3) fail("face", i, fmt::format("has {} vertices (at least 3 needed)", n));
      face.clear();
      for (int64_t k = 0; k < n; ++k) {
        const std::string_view t = token();
        if (t.empty())
          fail("face", i, fmt::format("declares {} vertices but the line has {}", n, k));
        int64_t v;
        if (!parse_int(t, v))
          fail("face", i, fmt::format("vertex index '{}' is not an integer", printable(t)));
        if (v < 0) fail("face", i, fmt::format("vertex index {} is negative", v));
        if (static_cast<uint64_t>(v) >= nv_)
          fail("face", i, fmt::format("vertex index {} out of range ({} vertices)", v, nv_));
        face.push_back(static_cast<uint32_t>(v));
      }
      // A face may end with a colour: a colormap index, RGB or RGBA. It is checked, not kept.
      int extra = 0;
      for (std::string_view t = token(); !t.empty(); t = token(), ++extra) {
        float x;
        if (extra == 4 || !parse_finite(t, x))
          fail("face", i,
               fmt::format("unexpected value '{}' after the vertex indices", printable(t)));
      }
      if (!soup_)
        if (const uint32_t r = repeated_vertex(face, sorted); r != kNoRepeat)
          throw RepairableError(
              fmt::format("{}: line {}: face {}: repeats vertex {}", name_, line_, i, r));
      if (mesh_.face_vertices.size() + face.size() > UINT32_MAX)
        fail("face", i, "more face corners than 32-bit offsets can address");
      mesh_.add_face(face);
    }
  }

  std::string_view data_, name_;
  bool soup_;
  size_t pos_ = 0, line_ = 0;
  const char* cur_ = nullptr;
  const char* lend_ = nullptr;
  bool colors_ = false, normals_ = false, uvs_ = false;
  uint64_t nv_ = 0, nf_ = 0, reserve_v_ = 0, reserve_f_ = 0;
  Mesh mesh_;
};

}  // namespace

Mesh read_off(std::string_view data, std::string_view name, bool soup) {
  return OffReader(data, name, soup).read();
}

void write_off(const Mesh& m, std::string& out) {
  out.reserve(out.size() + m.vertex_count() * 36 + m.corner_count() * 8 + m.face_count() * 4);
  out += fmt::format("OFF\n{} {} 0\n", m.vertex_count(), m.face_count());
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    for (int k = 0; k < 3; ++k) {
      if (k) out += ' ';
      put_float(out, m.positions[3 * v + k]);
    }
    out += '\n';
  }
  for (size_t f = 0; f < m.face_count(); ++f) {
    put_uint(out, m.face_size(f));
    for (const uint32_t v : m.face(f)) out += ' ', put_uint(out, v);
    out += '\n';
  }
}

}  // namespace limn
