// PLY: a small strict reader (ascii, binary little and big endian) and writer.
//
// The reader works in three passes over the header's promises: parse the header, check every
// declared count against the bytes that follow it (so a hostile count fails before anything is
// allocated), then read the body. Binary bodies take fast paths for the layouts nearly every
// writer emits (scalar-only vertex records, one `list uchar int` face property); everything else
// goes through a generic reader shared by ascii and binary that converts value by value.
// Element numbers in messages are 0-based, like validate()'s.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_set>

#include "limn/io/mesh_io.hpp"
#include "split_seams.hpp"
#include "text_number.hpp"

namespace limn {

using namespace text;  // the shared number helpers (text_number.hpp)
namespace {

enum class Type : uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

struct TypeName {
  std::string_view name;
  Type type;
};

constexpr TypeName kTypeNames[] = {
    {"char", Type::i8},   {"int8", Type::i8},     {"uchar", Type::u8},   {"uint8", Type::u8},
    {"short", Type::i16}, {"int16", Type::i16},   {"ushort", Type::u16}, {"uint16", Type::u16},
    {"int", Type::i32},   {"int32", Type::i32},   {"uint", Type::u32},   {"uint32", Type::u32},
    {"float", Type::f32}, {"float32", Type::f32}, {"double", Type::f64}, {"float64", Type::f64}};

size_t size_of(Type t) {
  constexpr size_t kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSizes[static_cast<int>(t)];
}

bool is_integer(Type t) {
  return t < Type::f32;
}
bool is_signed(Type t) {
  return t == Type::i8 || t == Type::i16 || t == Type::i32;
}

const char* type_name(Type t) {
  constexpr const char* kNames[] = {"char", "uchar", "short", "ushort",
                                    "int",  "uint",  "float", "double"};
  return kNames[static_cast<int>(t)];
}

// Range of an integer type (ascii values are checked against their declared type).
int64_t type_min(Type t) {
  constexpr int64_t kMin[] = {INT8_MIN, 0, INT16_MIN, 0, INT32_MIN, 0};
  return kMin[static_cast<int>(t)];
}

int64_t type_max(Type t) {
  constexpr int64_t kMax[] = {INT8_MAX, UINT8_MAX, INT16_MAX, UINT16_MAX, INT32_MAX, UINT32_MAX};
  return kMax[static_cast<int>(t)];
}

// Vertex attributes the reader keeps; every other property is parsed and dropped.
enum Slot : int8_t { kNone = -1, kX, kY, kZ, kNx, kNy, kNz, kRed, kGreen, kBlue, kAlpha, kU, kV };
constexpr int kSlots = 12;
constexpr const char* kSlotNames[kSlots] = {"x",   "y",     "z",    "nx",    "ny", "nz",
                                            "red", "green", "blue", "alpha", "u",  "v"};

int8_t slot_for(std::string_view n) {
  struct Alias {
    std::string_view name;
    int8_t slot;
  };
  static constexpr Alias kAliases[] = {{"x", kX},
                                       {"y", kY},
                                       {"z", kZ},
                                       {"nx", kNx},
                                       {"ny", kNy},
                                       {"nz", kNz},
                                       {"red", kRed},
                                       {"green", kGreen},
                                       {"blue", kBlue},
                                       {"alpha", kAlpha},
                                       {"diffuse_red", kRed},
                                       {"diffuse_green", kGreen},
                                       {"diffuse_blue", kBlue},
                                       {"u", kU},
                                       {"v", kV},
                                       {"s", kU},
                                       {"t", kV},
                                       {"texture_u", kU},
                                       {"texture_v", kV},
                                       {"texture_s", kU},
                                       {"texture_t", kV}};
  for (const Alias& a : kAliases)
    if (a.name == n) return a.slot;
  return kNone;
}

struct Property {
  std::string name;
  Type type = Type::f32;  // the value type; for a list, the item type
  Type count_type = Type::u8;
  bool list = false;
  bool indices = false;  // the face / strip vertex index list
  int8_t slot = kNone;   // vertex attribute fed by this scalar
  float divisor = 0.0f;  // integer colours are scaled into [0,1]
};

enum class Kind : uint8_t { other, vertex, face, tristrips };

struct Element {
  std::string name;
  uint64_t count = 0;
  size_t line = 0;  // header line that declared it
  Kind kind = Kind::other;
  std::vector<Property> props;
};

enum class Encoding : uint8_t { ascii, binary_le, binary_be };

// Current position for error messages: "<file>: [line N: ]<element> <index>: <problem>".
struct Where {
  std::string_view file;
  std::string_view element;
  uint64_t index = 0;
  size_t line = 0;  // 0 in binary bodies, where lines mean nothing
};

std::string message(const Where& w, std::string_view msg) {
  if (w.line != 0)
    return fmt::format("{}: line {}: {} {}: {}", w.file, w.line, w.element, w.index, msg);
  return fmt::format("{}: {} {}: {}", w.file, w.element, w.index, msg);
}

[[noreturn]] void fail(const Where& w, std::string_view msg) {
  throw InputError(message(w, msg));
}

// Narrows without the undefined behaviour of converting an out-of-range double to float.
float to_float(double d) {
  if (std::fabs(d) > std::numeric_limits<float>::max())
    return d > 0 ? INFINITY : -INFINITY;  // NaN falls through: fabs(NaN) > x is false
  return static_cast<float>(d);
}

// ---- number parsing (ascii) ----

// ---- binary loads ----

inline uint16_t load16(const char* p, bool swap) {
  uint16_t v;
  std::memcpy(&v, p, 2);
  return swap ? __builtin_bswap16(v) : v;
}
inline uint32_t load32(const char* p, bool swap) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return swap ? __builtin_bswap32(v) : v;
}
inline uint64_t load64(const char* p, bool swap) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return swap ? __builtin_bswap64(v) : v;
}

int64_t load_integer(const char* p, Type t, bool swap) {
  switch (t) {
    case Type::i8:
      return static_cast<int8_t>(*p);
    case Type::u8:
      return static_cast<uint8_t>(*p);
    case Type::i16:
      return static_cast<int16_t>(load16(p, swap));
    case Type::u16:
      return load16(p, swap);
    case Type::i32:
      return static_cast<int32_t>(load32(p, swap));
    default:
      return load32(p, swap);
  }
}

double load_number(const char* p, Type t, bool swap) {
  if (t == Type::f32) return std::bit_cast<float>(load32(p, swap));
  if (t == Type::f64) return std::bit_cast<double>(load64(p, swap));
  return static_cast<double>(load_integer(p, t, swap));
}

// ---- body sources: one element instance at a time, ascii or binary ----

class AsciiSource {
 public:
  AsciiSource(const char* p, const char* end, size_t line, Where& w)
      : p_(p), end_(end), line_(line), w_(w) {}

  void begin(const Element& e, uint64_t i) {
    w_.index = i;
    if (!next_line()) {
      w_.line = line_ + 1;
      fail(w_, fmt::format("truncated: the file ends before this element ({} declared)", e.count));
    }
  }

  void finish() {
    const std::string_view t = token();
    if (!t.empty()) fail(w_, fmt::format("unexpected extra value '{}' on the line", printable(t)));
  }

  float scalar(const Property& p) {
    const std::string_view t = need_token(p);
    float f;
    if (p.type == Type::f32) {
      if (!parse_float(t, f)) bad_value(t, p);
    } else if (p.type == Type::f64) {
      double d;
      if (!parse_double(t, d)) bad_value(t, p);
      f = to_float(d);
    } else {
      f = static_cast<float>(checked_integer(t, p.type, p));
    }
    return f;
  }

  int64_t integer(const Property& p, Type t) { return checked_integer(need_token(p), t, p); }

  uint64_t list_size(const Property& p) {
    const int64_t n = checked_integer(need_token(p), p.count_type, p);
    if (n < 0) fail(w_, fmt::format("'{}' has negative list length {}", p.name, n));
    return static_cast<uint64_t>(n);
  }

  void skip(const Property& p) {
    const uint64_t n = p.list ? list_size(p) : 1;
    for (uint64_t k = 0; k < n; ++k) {
      const std::string_view t = need_token(p);
      double d;
      if (is_integer(p.type) ? (checked_integer(t, p.type, p), true) : parse_double(t, d)) continue;
      bad_value(t, p);
    }
  }

  // Anything but blank lines after the last element means the header's counts are wrong.
  void expect_end() {
    if (next_line())
      throw InputError(fmt::format("{}: line {}: unexpected data after the last element ('{}')",
                                   w_.file, line_, printable(token())));
  }

 private:
  bool next_line() {
    for (;;) {
      if (p_ == end_) return false;
      const char* e = p_;
      while (e != end_ && *e != '\n' && *e != '\r') ++e;
      cur_ = p_;
      lend_ = e;
      p_ = e;
      if (p_ != end_) p_ += (*p_ == '\r' && p_ + 1 != end_ && p_[1] == '\n') ? 2 : 1;
      w_.line = ++line_;
      skip_space();
      if (cur_ != lend_) return true;
    }
  }

  void skip_space() {
    while (cur_ != lend_ && (*cur_ == ' ' || *cur_ == '\t')) ++cur_;
  }

  std::string_view token() {
    skip_space();
    const char* b = cur_;
    while (cur_ != lend_ && *cur_ != ' ' && *cur_ != '\t') ++cur_;
    return {b, size_t(cur_ - b)};
  }

  std::string_view need_token(const Property& p) {
    const std::string_view t = token();
    if (t.empty()) fail(w_, fmt::format("line ends before the value of '{}'", p.name));
    return t;
  }

  [[noreturn]] void bad_value(std::string_view t, const Property& p) {
    fail(w_,
         fmt::format("'{}' is not a valid {} for '{}'", printable(t), type_name(p.type), p.name));
  }

  int64_t checked_integer(std::string_view t, Type type, const Property& p) {
    int64_t v;
    if (!parse_int(t, v))
      fail(w_,
           fmt::format("'{}' is not a valid {} for '{}'", printable(t), type_name(type), p.name));
    if (v < type_min(type) || v > type_max(type))
      fail(w_, fmt::format("value {} of '{}' is out of range for {}", v, p.name, type_name(type)));
    return v;
  }

  const char* p_;
  const char* end_;
  size_t line_;
  Where& w_;
  const char* cur_ = nullptr;
  const char* lend_ = nullptr;
};

class BinarySource {
 public:
  BinarySource(const char* p, const char* end, bool swap, Where& w)
      : p_(p), end_(end), swap_(swap), w_(w) {}

  void begin(const Element&, uint64_t i) { w_.index = i; }
  void finish() {}

  float scalar(const Property& p) {
    need(size_of(p.type));
    const double d = load_number(p_, p.type, swap_);
    p_ += size_of(p.type);
    return to_float(d);
  }

  int64_t integer(const Property&, Type t) {
    need(size_of(t));
    const int64_t v = load_integer(p_, t, swap_);
    p_ += size_of(t);
    return v;
  }

  uint64_t list_size(const Property& p) {
    const int64_t n = integer(p, p.count_type);
    if (n < 0) fail(w_, fmt::format("'{}' has negative list length {}", p.name, n));
    // Checked before the items are touched: a corrupt count must not drive a huge loop.
    if (static_cast<uint64_t>(n) > left() / size_of(p.type))
      fail(w_, fmt::format("truncated: list '{}' of {} values runs past the end of the file",
                           p.name, n));
    return static_cast<uint64_t>(n);
  }

  void skip(const Property& p) {
    const size_t n = p.list ? list_size(p) : 1;
    need(n * size_of(p.type));
    p_ += n * size_of(p.type);
  }

  const char* pos() const { return p_; }
  void advance(size_t n) { p_ += n; }
  size_t left() const { return size_t(end_ - p_); }
  bool swap() const { return swap_; }

  void need(size_t n) {
    if (left() < n)
      fail(w_,
           fmt::format("truncated: the file ends inside this element ({} bytes left, {} needed)",
                       left(), n));
  }

 private:
  const char* p_;
  const char* end_;
  bool swap_;
  Where& w_;
};

// ---- the reader ----

class PlyReader {
 public:
  PlyReader(std::string_view data, std::string_view name, bool soup)
      : data_(data), name_(name), soup_(soup) {
    where_.file = name_;
  }

  Mesh read() {
    if (data_.size() >= 3 && std::memcmp(data_.data(), "\xEF\xBB\xBF", 3) == 0)
      data_.remove_prefix(3);
    if (data_.empty()) throw InputError(fmt::format("{}: empty file", name_));
    parse_header();
    assign_roles();
    check_sizes();
    allocate();
    const char* p = data_.data() + body_;
    const char* end = data_.data() + data_.size();
    if (encoding_ == Encoding::ascii) {
      AsciiSource src(p, end, header_lines_, where_);
      for (const Element& e : elements_) read_element(src, e);
      src.expect_end();
    } else {
      // Trailing bytes after the last element are ignored, as other binary readers do.
      BinarySource src(
          p, end, (encoding_ == Encoding::binary_be) != (std::endian::native == std::endian::big),
          where_);
      for (const Element& e : elements_) read_binary_element(src, e);
    }
    if (has_normals_) mesh_.normal_indices = mesh_.face_vertices;
    if (has_uvs_) mesh_.uv_indices = mesh_.face_vertices;
    (soup_ ? validate_soup : validate)(mesh_, std::string(name_));
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void fail_line(size_t line, std::string_view msg) const {
    throw InputError(fmt::format("{}: line {}: {}", name_, line, msg));
  }

  void parse_header() {
    size_t pos = 0, line = 0;
    bool lone_cr = false;  // the magic line's terminator, to find where a binary body starts
    std::vector<std::string_view> tok;
    bool have_format = false;
    std::unordered_set<std::string> element_names, property_names;
    for (;;) {
      if (pos >= data_.size()) {
        if (line == 0 || !have_magic_)
          fail_line(1, "not a PLY file (it does not start with 'ply')");
        fail_line(line, "the header has no end_header line (truncated or not a PLY file)");
      }
      size_t e = pos;
      while (e < data_.size() && data_[e] != '\n' && data_[e] != '\r') ++e;
      const std::string_view text = data_.substr(pos, e - pos);
      ++line;
      size_t next = e;
      if (e < data_.size())
        next += (data_[e] == '\r' && e + 1 < data_.size() && data_[e + 1] == '\n') ? 2 : 1;
      tok.clear();
      for (size_t i = 0; i < text.size();) {
        while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
        const size_t b = i;
        while (i < text.size() && text[i] != ' ' && text[i] != '\t') ++i;
        if (i > b) tok.push_back(text.substr(b, i - b));
      }
      if (!have_magic_) {
        if (tok.size() != 1 || tok[0] != "ply")
          fail_line(1, "not a PLY file (it does not start with 'ply')");
        have_magic_ = true;
        lone_cr = e < data_.size() && data_[e] == '\r' && next == e + 1;
        pos = next;
        continue;
      }
      const bool is_comment = !tok.empty() && (tok[0] == "comment" || tok[0] == "obj_info");
      if (!is_comment)
        for (const char c : text)
          if ((static_cast<unsigned char>(c) < 32 && c != '\t') || c == 127)
            fail_line(line, "binary data in the header (missing end_header?)");
      pos = next;
      if (tok.empty() || is_comment) continue;
      const std::string_view key = tok[0];
      if (key == "format") {
        if (have_format) fail_line(line, "second format line");
        if (tok.size() != 3) fail_line(line, "format line must be 'format <encoding> 1.0'");
        if (tok[1] == "ascii")
          encoding_ = Encoding::ascii;
        else if (tok[1] == "binary_little_endian")
          encoding_ = Encoding::binary_le;
        else if (tok[1] == "binary_big_endian")
          encoding_ = Encoding::binary_be;
        else
          fail_line(line, fmt::format("unknown format '{}'", printable(tok[1])));
        if (tok[2] != "1.0" && tok[2] != "1")
          fail_line(line, fmt::format("unsupported PLY version '{}'", printable(tok[2])));
        have_format = true;
      } else if (key == "element") {
        if (tok.size() != 3) fail_line(line, "element line must be 'element <name> <count>'");
        Element el;
        el.name = tok[1];
        el.line = line;
        const auto [ptr, ec] =
            std::from_chars(tok[2].data(), tok[2].data() + tok[2].size(), el.count);
        if (ec != std::errc() || ptr != tok[2].data() + tok[2].size())
          fail_line(line, fmt::format("element count '{}' is not a non-negative integer",
                                      printable(tok[2])));
        // Sets, not scans: a hostile header with millions of names must stay linear.
        if (!element_names.insert(el.name).second)
          fail_line(line, fmt::format("element '{}' declared twice", printable(el.name)));
        property_names.clear();
        if (el.name == "vertex") el.kind = Kind::vertex;
        if (el.name == "face") el.kind = Kind::face;
        if (el.name == "tristrips") el.kind = Kind::tristrips;
        elements_.push_back(std::move(el));
      } else if (key == "property") {
        if (elements_.empty()) fail_line(line, "property before any element");
        Property p;
        const bool list = tok.size() >= 2 && tok[1] == "list";
        if (tok.size() != (list ? 5u : 3u))
          fail_line(line, list ? "list property must be 'property list <count type> <item type> "
                                 "<name>'"
                               : "property must be 'property <type> <name>'");
        p.list = list;
        if (list) {
          p.count_type = parse_type(tok[2], line);
          if (!is_integer(p.count_type))
            fail_line(line, fmt::format("list count type '{}' is not an integer type", tok[2]));
        }
        p.type = parse_type(tok[list ? 3 : 1], line);
        p.name = tok.back();
        if (!property_names.insert(p.name).second)
          fail_line(line, fmt::format("property '{}' declared twice", printable(p.name)));
        elements_.back().props.push_back(std::move(p));
      } else if (key == "end_header") {
        if (tok.size() != 1) fail_line(line, "unexpected text after end_header");
        if (!have_format) fail_line(line, "the header has no format line");
        header_lines_ = line;
        body_ = pos;
        if (encoding_ != Encoding::ascii && e < data_.size() && lone_cr && data_[e] == '\r')
          body_ = e + 1;  // a \n right after a lone-\r header belongs to the binary body
        return;
      } else {
        const bool data = key[0] == '-' || (key[0] >= '0' && key[0] <= '9');
        fail_line(line, fmt::format("unknown header keyword '{}'{}", printable(key),
                                    data ? " (data before end_header?)" : ""));
      }
    }
  }

  Type parse_type(std::string_view s, size_t line) const {
    for (const TypeName& t : kTypeNames)
      if (t.name == s) return t.type;
    fail_line(line, fmt::format("unknown property type '{}'", printable(s)));
  }

  void assign_roles() {
    const Element* vertex = nullptr;
    for (Element& e : elements_) {
      if (e.kind == Kind::vertex) {
        vertex = &e;
        bool seen[kSlots] = {};
        for (Property& p : e.props) {
          const int8_t s = slot_for(p.name);
          if (s == kNone || seen[s]) continue;  // u and s both present: the first one wins
          if (p.list) {
            if (s <= kZ) fail_line(e.line, fmt::format("vertex property '{}' is a list", p.name));
            continue;
          }
          if (s >= kRed && s <= kAlpha) {
            if (p.type == Type::u8)
              p.divisor = 255.0f;
            else if (p.type == Type::u16)
              p.divisor = 65535.0f;
            else if (!(p.type == Type::f32 || p.type == Type::f64))
              fail_line(e.line, fmt::format("colour property '{}' has type {} (expected uchar, "
                                            "ushort, float or double)",
                                            p.name, type_name(p.type)));
          }
          p.slot = s;
          seen[s] = true;
        }
        for (int s = kX; s <= kZ; ++s)
          if (!seen[s])
            fail_line(e.line, fmt::format("vertex element has no '{}' property", kSlotNames[s]));
        // Partial attribute sets (nx without nz, red without blue) carry no usable attribute.
        has_normals_ = seen[kNx] && seen[kNy] && seen[kNz];
        has_colors_ = seen[kRed] && seen[kGreen] && seen[kBlue];
        has_alpha_ = has_colors_ && seen[kAlpha];
        has_uvs_ = seen[kU] && seen[kV];
        for (Property& p : e.props) {
          if ((p.slot >= kNx && p.slot <= kNz && !has_normals_) ||
              (p.slot >= kRed && p.slot <= kAlpha && !has_colors_) || (p.slot >= kU && !has_uvs_))
            p.slot = kNone;
        }
      } else if (e.kind == Kind::face || e.kind == Kind::tristrips) {
        Property* idx = nullptr;
        for (Property& p : e.props)
          if (p.name == "vertex_indices" || p.name == "vertex_index") {
            if (!p.list)
              fail_line(e.line, fmt::format("{} property '{}' is not a list", e.name, p.name));
            if (!is_integer(p.type))
              fail_line(e.line, fmt::format("{} property '{}' has non-integer items ({})", e.name,
                                            p.name, type_name(p.type)));
            if (!idx) idx = &p;
          }
        if (!idx) fail_line(e.line, fmt::format("{} element has no vertex_indices list", e.name));
        idx->indices = true;
      }
    }
    if (!vertex) {
      const size_t line = elements_.empty() ? header_lines_ : elements_.back().line;
      fail_line(line, "the header declares no vertex element");
    }
    nv_ = vertex->count;
  }

  // Every element instance needs some minimum number of bytes; a count that cannot fit in what
  // follows the header is rejected here, before any allocation. Lists count as empty, so a short
  // face still gets its own precise message.
  void check_sizes() {
    const bool ascii = encoding_ == Encoding::ascii;
    const uint64_t avail = data_.size() - body_;
    uint64_t need = 0;
    for (const Element& e : elements_) {
      uint64_t min = 0;
      for (const Property& p : e.props) min += ascii ? 1 : size_of(p.list ? p.count_type : p.type);
      if (ascii) min *= 2;  // a value and a separator
      if (min == 0) continue;
      // An ascii file's last line may lack its newline: one byte of slack.
      const uint64_t room = avail + (ascii ? 1 : 0) - need;
      if (e.count > room / min)
        fail_line(e.line, fmt::format("{} '{}' elements need at least {} bytes each but only {} "
                                      "bytes remain (truncated file or bad count)",
                                      e.count, printable(e.name), min, room));
      need += e.count * min;
      if (e.kind == Kind::vertex && e.count > UINT32_MAX)
        fail_line(e.line, fmt::format("{} vertices exceed the 32-bit index range", e.count));
      if (e.kind == Kind::face && e.count >= UINT32_MAX)
        fail_line(e.line, fmt::format("{} faces exceed the 32-bit offset range", e.count));
    }
  }

  void allocate() {
    mesh_.positions.resize(3 * nv_);
    if (has_normals_) mesh_.normals.resize(3 * nv_);
    if (has_colors_) mesh_.colors.resize(4 * nv_);
    if (has_uvs_) mesh_.uvs.resize(2 * nv_);
    for (const Element& e : elements_)
      if (e.kind == Kind::face) {
        // Corners are bounded by the bytes left, so hostile counts cannot inflate the reserve.
        const uint64_t left = data_.size() - body_;
        const uint64_t corners = encoding_ == Encoding::ascii ? left / 2 : left / 4;
        mesh_.face_offsets.reserve(e.count + 1);
        mesh_.face_vertices.reserve(std::min<uint64_t>(3 * e.count, corners));
      }
  }

  // ---- elements, generic path ----

  template <class Src>
  void read_element(Src& src, const Element& e) {
    where_.element = e.name;
    if (e.props.empty()) return;  // nothing to read, whatever the count says
    switch (e.kind) {
      case Kind::vertex: {
        float val[kSlots] = {};
        for (uint64_t i = 0; i < e.count; ++i) {
          src.begin(e, i);
          for (const Property& p : e.props) {
            if (p.slot == kNone) {
              src.skip(p);
              continue;
            }
            const float f = src.scalar(p);
            val[p.slot] = p.divisor != 0.0f ? f / p.divisor : f;
          }
          src.finish();
          store_vertex(i, val);
        }
        break;
      }
      case Kind::face:
      case Kind::tristrips:
        for (uint64_t i = 0; i < e.count; ++i) {
          src.begin(e, i);
          for (const Property& p : e.props) {
            if (!p.indices) {
              src.skip(p);
              continue;
            }
            const uint64_t n = src.list_size(p);
            scratch_.clear();
            for (uint64_t k = 0; k < n; ++k) scratch_.push_back(src.integer(p, p.type));
            restart_ = is_signed(p.type) ? -1 : type_max(p.type);  // -1 as an unsigned item
          }
          src.finish();
          if (e.kind == Kind::face)
            add_face(scratch_);
          else
            add_strips(scratch_);
        }
        break;
      case Kind::other:
        for (uint64_t i = 0; i < e.count; ++i) {
          src.begin(e, i);
          for (const Property& p : e.props) src.skip(p);
          src.finish();
        }
        break;
    }
  }

  void store_vertex(uint64_t i, const float* val) {
    for (int s = 0; s < kSlots; ++s)
      if (!std::isfinite(val[s]) &&
          (s <= kZ || (s <= kNz && has_normals_) || (s <= kAlpha && s >= kRed && has_colors_) ||
           (s >= kU && has_uvs_)))
        fail(where_, fmt::format("{} is not a finite float ({})", kSlotNames[s], val[s]));
    std::copy(val, val + 3, &mesh_.positions[3 * i]);
    if (has_normals_) std::copy(val + kNx, val + kNx + 3, &mesh_.normals[3 * i]);
    if (has_colors_) {
      std::copy(val + kRed, val + kRed + 4, &mesh_.colors[4 * i]);
      if (!has_alpha_) mesh_.colors[4 * i + 3] = 1.0f;
    }
    if (has_uvs_) std::copy(val + kU, val + kU + 2, &mesh_.uvs[2 * i]);
  }

  void check_index(int64_t v) const {
    if (v < 0) fail(where_, fmt::format("vertex index {} is negative", v));
    if (static_cast<uint64_t>(v) >= nv_)
      fail(where_, fmt::format("vertex index {} out of range ({} vertices)", v, nv_));
  }

  void append_face(const uint32_t* idx, size_t n) {
    if (mesh_.face_vertices.size() + n > UINT32_MAX)
      fail(where_, "more face corners than 32-bit offsets can address");
    mesh_.face_vertices.insert(mesh_.face_vertices.end(), idx, idx + n);
    mesh_.face_offsets.push_back(static_cast<uint32_t>(mesh_.face_vertices.size()));
  }

  void add_face(const std::vector<int64_t>& f) {
    if (f.size() < 3) fail(where_, fmt::format("has {} vertices (at least 3 needed)", f.size()));
    face_.resize(f.size());
    for (size_t k = 0; k < f.size(); ++k) {
      check_index(f[k]);
      face_[k] = static_cast<uint32_t>(f[k]);
    }
    if (!soup_)
      if (const uint32_t r = repeated_vertex(face_, sorted_); r != kNoRepeat)
        throw RepairableError(message(where_, fmt::format("repeats vertex {}", r)));
    append_face(face_.data(), face_.size());
  }

  // Strips alternate orientation; a triangle that repeats an index is one of the degenerate
  // triangles writers use to stitch strips together, not a face.
  void add_strips(const std::vector<int64_t>& s) {
    size_t start = 0;
    for (size_t k = 0; k <= s.size(); ++k) {
      if (k < s.size() && s[k] != restart_) {
        check_index(s[k]);
        continue;
      }
      for (size_t j = start; j + 2 < k; ++j) {
        uint32_t t[3] = {uint32_t(s[j]), uint32_t(s[j + 1]), uint32_t(s[j + 2])};
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        if ((j - start) % 2 == 1) std::swap(t[0], t[1]);
        append_face(t, 3);
      }
      start = k + 1;
    }
  }

  // ---- elements, binary fast paths ----

  void read_binary_element(BinarySource& src, const Element& e) {
    where_.element = e.name;
    where_.line = 0;
    if (e.props.empty()) return;
    bool fixed = true;
    size_t stride = 0;
    for (const Property& p : e.props) {
      fixed &= !p.list;
      stride += size_of(p.type);
    }
    if (fixed && e.kind == Kind::vertex) return read_fixed_vertices(src, e, stride);
    if (fixed && e.kind == Kind::other) {
      check_rows(src, e.count, stride);
      src.advance(e.count * stride);
      return;
    }
    if (e.kind == Kind::face && e.props.size() == 1 && size_of(e.props[0].count_type) == 1 &&
        size_of(e.props[0].type) == 4)
      return src.swap() ? read_fast_faces<true>(src, e) : read_fast_faces<false>(src, e);
    read_element(src, e);
  }

  // The header check is only a lower bound (earlier lists may have used more bytes than their
  // minimum), so fixed-size rows are checked again here, naming the first incomplete one.
  void check_rows(BinarySource& src, uint64_t count, size_t stride) {
    if (count <= src.left() / stride) return;
    where_.index = src.left() / stride;
    src.advance(where_.index * stride);
    src.need(stride);  // throws: fewer than stride bytes are left
  }

  void read_fixed_vertices(BinarySource& src, const Element& e, size_t stride) {
    check_rows(src, e.count, stride);
    struct Field {
      size_t offset;
      Type type;
      int8_t slot;
      float divisor;
    };
    Field fields[kSlots];
    int nfields = 0;
    size_t off = 0;
    for (const Property& p : e.props) {
      if (p.slot != kNone) fields[nfields++] = {off, p.type, p.slot, p.divisor};
      off += size_of(p.type);
    }
    const char* row = src.pos();
    const bool swap = src.swap();
    const bool plain_xyz = nfields == 3 && !swap && fields[0].type == Type::f32 &&
                           fields[1].type == Type::f32 && fields[2].type == Type::f32 &&
                           fields[0].offset == 0 && fields[1].offset == 4 && fields[2].offset == 8;
    float* out = mesh_.positions.data();
    if (plain_xyz) {
      // The common case: rows start with float x y z; copy them and check afterwards.
      if (stride == 12) {
        if (e.count) std::memcpy(out, row, 12 * e.count);
      } else {
        for (uint64_t i = 0; i < e.count; ++i) std::memcpy(out + 3 * i, row + i * stride, 12);
      }
      for (uint64_t i = 0; i < 3 * e.count; ++i)
        if (!std::isfinite(out[i])) {
          where_.index = i / 3;
          fail(where_, fmt::format("{} is not a finite float ({})", kSlotNames[i % 3], out[i]));
        }
    } else {
      float val[kSlots] = {};
      for (uint64_t i = 0; i < e.count; ++i, row += stride) {
        for (int k = 0; k < nfields; ++k) {
          const Field& f = fields[k];
          const float x = to_float(load_number(row + f.offset, f.type, swap));
          val[f.slot] = f.divisor != 0.0f ? x / f.divisor : x;
        }
        where_.index = i;
        store_vertex(i, val);
      }
    }
    src.advance(e.count * stride);
  }

  template <bool kSwap>
  void read_fast_faces(BinarySource& src, const Element& e) {
    const Property& p = e.props[0];
    const bool signed_count = p.count_type == Type::i8;
    const bool signed_index = p.type == Type::i32;
    const char* q = src.pos();
    const char* const end = q + src.left();
    const uint32_t nv = static_cast<uint32_t>(nv_);
    auto& fv = mesh_.face_vertices;
    auto& offsets = mesh_.face_offsets;
    const size_t first_face = mesh_.face_count();
    for (uint64_t f = 0; f < e.count; ++f) {
      if (q == end || static_cast<size_t>(end - q - 1) < 4u * static_cast<uint8_t>(*q) ||
          (signed_count && static_cast<int8_t>(*q) < 0) || static_cast<uint8_t>(*q) < 3) {
        break;  // the generic path below reports it
      }
      const unsigned n = static_cast<uint8_t>(*q);
      if (n == 3 && fv.size() + 3 <= UINT32_MAX) {
        const uint32_t a = load32(q + 1, kSwap), b = load32(q + 5, kSwap), c = load32(q + 9, kSwap);
        if (a < nv && b < nv && c < nv && a != b && b != c && a != c) {
          fv.push_back(a);
          fv.push_back(b);
          fv.push_back(c);
          offsets.push_back(static_cast<uint32_t>(fv.size()));
          q += 13;
          continue;
        }
      }
      scratch_.resize(n);
      for (unsigned k = 0; k < n; ++k) {
        const uint32_t v = load32(q + 1 + 4 * k, kSwap);
        scratch_[k] = signed_index ? static_cast<int32_t>(v) : static_cast<int64_t>(v);
      }
      where_.index = f;
      add_face(scratch_);
      q += 1 + 4 * n;
    }
    const uint64_t done = mesh_.face_count() - first_face;
    src.advance(size_t(q - src.pos()));
    if (done == e.count) return;
    // Finish with the generic reader from the failing face so errors read the same everywhere.
    for (uint64_t f = done; f < e.count; ++f) {
      where_.index = f;
      read_one_face(src, e);
    }
  }

  void read_one_face(BinarySource& src, const Element& e) {
    const Property& p = e.props[0];
    const uint64_t n = src.list_size(p);
    scratch_.clear();
    for (uint64_t k = 0; k < n; ++k) scratch_.push_back(src.integer(p, p.type));
    add_face(scratch_);
  }

  std::string_view data_, name_;
  Where where_;
  bool have_magic_ = false;
  Encoding encoding_ = Encoding::ascii;
  std::vector<Element> elements_;
  size_t header_lines_ = 0;
  size_t body_ = 0;
  uint64_t nv_ = 0;
  bool has_normals_ = false, has_colors_ = false, has_alpha_ = false, has_uvs_ = false;
  int64_t restart_ = -1;
  Mesh mesh_;
  std::vector<int64_t> scratch_;
  std::vector<uint32_t> face_, sorted_;
  bool soup_;
};

}  // namespace

Mesh read_ply(std::string_view data, std::string_view name, bool soup) {
  return PlyReader(data, name, soup).read();
}

namespace {

// An attribute is per-vertex when it has one value per vertex and its corners index it exactly
// like the positions; only such attributes fit PLY's vertex records.
bool per_vertex(const Mesh& m, const std::vector<float>& values, size_t width,
                const std::vector<uint32_t>& indices) {
  return m.vertex_count() > 0 && values.size() == width * m.vertex_count() &&
         indices == m.face_vertices;
}

uint8_t quantize(float c) {
  if (!(c > 0.0f)) return 0;  // also NaN
  if (c >= 1.0f) return 255;
  return static_cast<uint8_t>(std::lround(c * 255.0f));
}

template <class T>
char* put_le(char* p, T v) {
  if constexpr (std::endian::native == std::endian::big) {
    if constexpr (sizeof(T) == 4)
      v = std::bit_cast<T>(__builtin_bswap32(std::bit_cast<uint32_t>(v)));
  }
  std::memcpy(p, &v, sizeof v);
  return p + sizeof v;
}

}  // namespace

void write_ply(const Mesh& m, std::string& out, bool ascii) {
  if ((!m.uv_indices.empty() && !per_vertex(m, m.uvs, 2, m.uv_indices)) ||
      (!m.normal_indices.empty() && !per_vertex(m, m.normals, 3, m.normal_indices)))
    return write_ply(split_at_seams(m), out, ascii);
  const size_t nv = m.vertex_count(), nf = m.face_count();
  const bool colors = m.vertex_count() > 0 && m.colors.size() == 4 * nv;
  const bool normals = per_vertex(m, m.normals, 3, m.normal_indices);
  const bool uvs = per_vertex(m, m.uvs, 2, m.uv_indices);
  size_t max_arity = 0;
  for (size_t f = 0; f < nf; ++f) max_arity = std::max<size_t>(max_arity, m.face_size(f));
  const bool wide_count = max_arity > 255;
  const bool wide_index = nv > static_cast<size_t>(INT32_MAX);

  out += "ply\n";
  out += ascii ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
  out += "comment limn\n";
  out += fmt::format("element vertex {}\n", nv);
  out += "property float x\nproperty float y\nproperty float z\n";
  if (normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors)
    out += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  if (uvs) out += "property float u\nproperty float v\n";
  out += fmt::format("element face {}\n", nf);
  out += fmt::format("property list {} {} vertex_indices\n", wide_count ? "uint" : "uchar",
                     wide_index ? "uint" : "int");
  out += "end_header\n";

  if (ascii) {
    out.reserve(out.size() + nv * 40 + m.corner_count() * 8 + nf * 4);
    for (size_t v = 0; v < nv; ++v) {
      for (int k = 0; k < 3; ++k) {
        if (k) out += ' ';
        put_float(out, m.positions[3 * v + k]);
      }
      if (normals)
        for (int k = 0; k < 3; ++k) out += ' ', put_float(out, m.normals[3 * v + k]);
      if (colors)
        for (int k = 0; k < 4; ++k) out += ' ', put_uint(out, quantize(m.colors[4 * v + k]));
      if (uvs)
        for (int k = 0; k < 2; ++k) out += ' ', put_float(out, m.uvs[2 * v + k]);
      out += '\n';
    }
    for (size_t f = 0; f < nf; ++f) {
      put_uint(out, m.face_size(f));
      for (const uint32_t v : m.face(f)) out += ' ', put_uint(out, v);
      out += '\n';
    }
    return;
  }

  const size_t stride = 12 + (normals ? 12 : 0) + (colors ? 4 : 0) + (uvs ? 8 : 0);
  const size_t start = out.size();
  out.resize(start + nv * stride + nf * (wide_count ? 4 : 1) + 4 * m.corner_count());
  char* p = out.data() + start;
  for (size_t v = 0; v < nv; ++v) {
    for (int k = 0; k < 3; ++k) p = put_le(p, m.positions[3 * v + k]);
    if (normals)
      for (int k = 0; k < 3; ++k) p = put_le(p, m.normals[3 * v + k]);
    if (colors)
      for (int k = 0; k < 4; ++k) *p++ = static_cast<char>(quantize(m.colors[4 * v + k]));
    if (uvs)
      for (int k = 0; k < 2; ++k) p = put_le(p, m.uvs[2 * v + k]);
  }
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t n = m.face_size(f);
    if (wide_count)
      p = put_le(p, n);
    else
      *p++ = static_cast<char>(n);
    for (const uint32_t v : m.face(f)) p = put_le(p, v);
  }
}

}  // namespace limn
