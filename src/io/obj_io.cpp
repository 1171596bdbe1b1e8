// OBJ: tinyobjloader parses; limn validates first and reads OpenSubdiv `t` tags itself.
//
// tinyobjloader is lenient in ways a pipeline tool cannot be: "nan" and missing coordinates become
// 0, a UTF-8 BOM silently drops the first line, out-of-range indices only warn, and a tag header
// such as `t crease 999999999/1/0` is allocated as written. So a strict scan runs first: it checks
// every number and index with a line number, counts elements, and parses the tags (tinyobjloader
// attaches tags to groups and drops them with empty groups). Only then does tinyobjloader parse,
// and its arrays are copied into the Mesh with face arity and indices kept exactly.
#include <fmt/format.h>
#include <tbb/parallel_invoke.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <istream>
#include <streambuf>

#include "limn/io/mesh_io.hpp"
#include "text_number.hpp"

namespace limn {

using namespace text;  // the shared number helpers (text_number.hpp)
namespace {

struct Cursor {
  const char* p;
  const char* end;
  bool at_end() const { return p == end; }
  void skip_space() {
    while (p != end && (*p == ' ' || *p == '\t')) ++p;
  }
  // Next whitespace-delimited token on this line, or empty at end of line / comment.
  std::string_view token() {
    skip_space();
    if (p == end || *p == '#') return {};
    const char* b = p;
    while (p != end && *p != ' ' && *p != '\t' && *p != '#') ++p;
    return {b, size_t(p - b)};
  }
};

struct ScanResult {
  size_t v = 0, vt = 0, vn = 0, faces = 0, corners = 0;
  size_t face_corners_with_uv = 0, face_corners_with_normal = 0;
  bool colors = false;
  long long max_v = 0, max_vt = 0, max_vn = 0;  // largest positive (absolute) index seen
  size_t max_v_line = 0, max_vt_line = 0, max_vn_line = 0;
};

class ObjScanner {
 public:
  ObjScanner(std::string_view data, std::string_view name, Mesh& mesh, bool soup)
      : data_(data), name_(name), mesh_(mesh), soup_(soup) {}

  ScanResult run() {
    const char* p = data_.data();
    const char* end = p + data_.size();
    while (p < end) {
      ++line_;
      const char* e = p;
      while (e != end && *e != '\n' && *e != '\r') ++e;
      line(Cursor{p, e});
      // \n, \r\n and lone \r all end a line (tinyobjloader agrees), so line numbers match.
      p = e;
      if (p != end) p += (*p == '\r' && p + 1 != end && p[1] == '\n') ? 2 : 1;
    }
    check_forward(r_.max_v, r_.v, r_.max_v_line, "vertex");
    check_forward(r_.max_vt, r_.vt, r_.max_vt_line, "texture coordinate");
    check_forward(r_.max_vn, r_.vn, r_.max_vn_line, "normal");
    return r_;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(fmt::format("{}: line {}: {}", name_, line_, what));
  }

  void check_forward(long long max, size_t count, size_t at, const char* kind) {
    if (max > static_cast<long long>(count))
      throw InputError(fmt::format("{}: line {}: {} index {} out of range ({} defined)", name_, at,
                                   kind, max, count));
  }

  void numbers(Cursor& c, int min_n, int max_n, int& n, float* out, const char* what) {
    n = 0;
    for (std::string_view t = c.token(); !t.empty(); t = c.token()) {
      if (n == max_n) fail(fmt::format("too many values for {} (at most {})", what, max_n));
      if (!parse_finite(t, out[n]))
        fail(fmt::format("{} value '{}' is not a finite number", what, t.substr(0, 32)));
      ++n;
    }
    if (n < min_n) fail(fmt::format("{} needs at least {} values, found {}", what, min_n, n));
  }

  // Resolves one OBJ index (1-based, or negative relative to the elements defined so far).
  void index(std::string_view t, size_t defined, long long& max_abs, size_t& max_line,
             const char* kind) {
    int64_t i;
    if (!parse_int(t, i))
      fail(fmt::format("{} index '{}' is not an integer", kind, t.substr(0, 32)));
    if (i == 0) fail(fmt::format("{} index 0 (OBJ indices start at 1)", kind));
    if (i < 0) {
      if (-i > static_cast<long long>(defined))
        fail(fmt::format("relative {} index {} reaches before the first {} ({} defined)", kind, i,
                         kind, defined));
      last_ = defined + i;
    } else {
      if (i > max_abs) max_abs = i, max_line = line_;  // forward references are checked at the end
      last_ = i - 1;
    }
  }

  void face(Cursor& c) {
    face_.clear();
    bool any_uv = false, any_n = false, all_uv = true, all_n = true;
    for (std::string_view t = c.token(); !t.empty(); t = c.token()) {
      const size_t s1 = t.find('/');
      index(t.substr(0, s1), r_.v, r_.max_v, r_.max_v_line, "vertex");
      // No mesh limn holds has 2^32 vertices: a larger index is out of range, not a repeat.
      if (last_ >= kNoRepeat) fail(fmt::format("vertex index {} out of range", last_ + 1));
      face_.push_back(static_cast<uint32_t>(last_));
      bool has_uv = false, has_n = false;
      if (s1 != std::string_view::npos) {
        std::string_view rest = t.substr(s1 + 1);
        const size_t s2 = rest.find('/');
        const std::string_view vt = rest.substr(0, s2);
        if (!vt.empty())
          index(vt, r_.vt, r_.max_vt, r_.max_vt_line, "texture coordinate"), has_uv = true;
        if (s2 != std::string_view::npos) {
          const std::string_view vn = rest.substr(s2 + 1);
          if (vn.empty()) fail(fmt::format("face corner '{}' has an empty normal index", t));
          index(vn, r_.vn, r_.max_vn, r_.max_vn_line, "normal");
          has_n = true;
        } else if (vt.empty()) {
          fail(fmt::format("face corner '{}' is malformed", t));
        }
      }
      any_uv |= has_uv, all_uv &= has_uv, any_n |= has_n, all_n &= has_n;
    }
    if (face_.size() < 3)
      fail(fmt::format("face has {} vertices (at least 3 needed)", face_.size()));
    if (!soup_)
      if (const uint32_t r = repeated_vertex(face_, sorted_); r != kNoRepeat)
        throw RepairableError(
            fmt::format("{}: line {}: face repeats vertex {}", name_, line_, r + 1));
    if (any_uv != all_uv) fail("face mixes corners with and without texture coordinates");
    if (any_n != all_n) fail("face mixes corners with and without normals");
    ++r_.faces;
    r_.corners += face_.size();
    // tinyobjloader keeps arity in an unsigned char; the scan is the authority on face sizes.
    mesh_.face_offsets.push_back(static_cast<uint32_t>(r_.corners));
    if (all_uv) r_.face_corners_with_uv += face_.size();
    if (all_n) r_.face_corners_with_normal += face_.size();
  }

  // OpenSubdiv tag: `t name nint/nfloat/nstring ints... floats... strings...`.
  void tag(Cursor& c) {
    const std::string_view name = c.token();
    if (name.empty()) fail("tag without a name");
    const std::string_view counts = c.token();
    int64_t n[3] = {0, 0, 0};
    {
      std::string_view s = counts;
      for (int k = 0; k < 3; ++k) {
        const size_t slash = s.find('/');
        if (!parse_int(s.substr(0, slash), n[k]) || n[k] < 0 || (k < 2) == (slash == s.npos))
          fail(fmt::format("tag '{}' has malformed counts '{}' (expected ints/floats/strings)",
                           name, counts.substr(0, 32)));
        s = slash == s.npos ? std::string_view() : s.substr(slash + 1);
      }
    }
    // Bounded by the line length before anything is stored: hostile counts cannot allocate.
    ints_.clear(), floats_.clear(), strings_.clear();
    for (std::string_view t = c.token(); !t.empty(); t = c.token()) {
      if (static_cast<long long>(ints_.size()) < n[0]) {
        int64_t i;
        if (!parse_int(t, i) || i < 0 || i > 0xFFFFFFF0LL)
          fail(fmt::format("tag '{}' integer '{}' is not a valid index", name, t.substr(0, 32)));
        ints_.push_back(static_cast<uint32_t>(i));
      } else if (static_cast<long long>(floats_.size()) < n[1]) {
        float f;
        if (!parse_finite(t, f))
          fail(fmt::format("tag '{}' value '{}' is not a finite number", name, t.substr(0, 32)));
        floats_.push_back(f);
      } else if (static_cast<long long>(strings_.size()) < n[2]) {
        strings_.push_back(t);
      } else {
        fail(fmt::format("tag '{}' has more arguments than its counts {} say", name, counts));
      }
    }
    if (static_cast<long long>(ints_.size()) != n[0] ||
        static_cast<long long>(floats_.size()) != n[1] ||
        static_cast<long long>(strings_.size()) != n[2])
      fail(fmt::format("tag '{}' has fewer arguments than its counts {} say", name, counts));
    apply_tag(name);
  }

  void apply_tag(std::string_view name) {
    auto sharp = [&](float s) {
      if (s < 0) fail(fmt::format("tag '{}' has negative sharpness {}", name, s));
      return s;
    };
    if (name == "crease") {
      // A chain of vertices; one sharpness for all its edges or one per edge.
      if (ints_.size() < 2) fail("crease tag needs at least 2 vertices");
      const size_t edges = ints_.size() - 1;
      if (floats_.size() != 1 && floats_.size() != edges)
        fail(fmt::format("crease tag has {} sharpness values for {} edges", floats_.size(), edges));
      for (size_t i = 0; i < edges; ++i) {
        mesh_.crease_edges.push_back(ints_[i]);
        mesh_.crease_edges.push_back(ints_[i + 1]);
        mesh_.crease_sharpness.push_back(sharp(floats_[floats_.size() == 1 ? 0 : i]));
      }
    } else if (name == "corner") {
      if (ints_.empty()) fail("corner tag needs at least one vertex");
      if (floats_.size() != 1 && floats_.size() != ints_.size())
        fail(fmt::format("corner tag has {} sharpness values for {} vertices", floats_.size(),
                         ints_.size()));
      for (size_t i = 0; i < ints_.size(); ++i) {
        mesh_.corner_vertices.push_back(ints_[i]);
        mesh_.corner_sharpness.push_back(sharp(floats_[floats_.size() == 1 ? 0 : i]));
      }
    } else if (name == "hole") {
      mesh_.hole_faces.insert(mesh_.hole_faces.end(), ints_.begin(), ints_.end());
    } else if (name == "interpolateboundary") {
      // RenderMan's convention, which OpenSubdiv's shapes follow: 1 sharpens edges and corners,
      // 2 edges only.
      if (ints_.size() != 1 || ints_[0] > 2)
        fail("interpolateboundary tag needs one value 0, 1 or 2");
      mesh_.tags.boundary = ints_[0] == 0   ? BoundaryInterpolation::none
                            : ints_[0] == 1 ? BoundaryInterpolation::edge_and_corner
                                            : BoundaryInterpolation::edge_only;
    } else if (name == "facevaryinginterpolateboundary") {
      if (ints_.size() != 1 || ints_[0] > 5)
        fail("facevaryinginterpolateboundary needs one value 0-5");
      mesh_.tags.fvar_boundary = static_cast<int8_t>(ints_[0]);
    } else if (name == "creasemethod") {
      if (strings_.size() != 1 || (strings_[0] != "normal" && strings_[0] != "chaikin"))
        fail("creasemethod tag needs 'normal' or 'chaikin'");
      mesh_.tags.crease_method =
          strings_[0] == "chaikin" ? CreaseMethod::chaikin : CreaseMethod::uniform;
    } else if (name == "smoothtriangles") {
      // As OpenSubdiv's shape files read it: the value names the triangle rule, "catmark"
      // (Sdc TRI_SUB_CATMARK, the default) or "smooth" (TRI_SUB_SMOOTH).
      if (strings_.size() != 1 || (strings_[0] != "catmark" && strings_[0] != "smooth"))
        fail("smoothtriangles tag needs 'catmark' or 'smooth'");
      mesh_.tags.smooth_triangles = strings_[0] == "smooth";
    }
    // Other tags are OpenSubdiv extensions limn does not use; they are skipped.
  }

  void line(Cursor c) {
    const std::string_view key = c.token();
    if (key.empty()) return;
    float vals[7];
    int n;
    if (key == "v") {
      numbers(c, 3, 7, n, vals, "vertex");
      if (n == 5 || n == 7) fail(fmt::format("vertex has {} values (expected 3, 4 or 6)", n));
      r_.colors |= n == 6;
      ++r_.v;
    } else if (key == "vt") {
      numbers(c, 1, 3, n, vals, "texture coordinate");
      ++r_.vt;
    } else if (key == "vn") {
      numbers(c, 3, 3, n, vals, "normal");
      ++r_.vn;
    } else if (key == "f") {
      face(c);
    } else if (key == "t") {
      tag(c);
    } else if (key.size() > 1 && key[0] == 'v' && key != "vp") {
      fail(fmt::format("unknown statement '{}'", key.substr(0, 16)));
    } else if (static_cast<unsigned char>(key[0]) < 32 ||
               static_cast<unsigned char>(key[0]) > 126) {
      fail("binary data in a text file");
    }
    // o, g, s, usemtl, mtllib, l, p, vp...: grouping and materials do not change the surface.
  }

  std::string_view data_, name_;
  Mesh& mesh_;
  bool soup_;
  ScanResult r_;
  size_t line_ = 0;
  size_t last_ = 0;
  std::vector<uint32_t> face_, sorted_;
  std::vector<uint32_t> ints_;
  std::vector<float> floats_;
  std::vector<std::string_view> strings_;
};

// tinyobjloader sizes tag arrays by the counts a tag line declares (up to 8192 strings each), so
// a small hostile file could ask for gigabytes. Lines starting with `t` are rare: find them with
// memchr and check their counts against their token counts before tinyobjloader sees the data.
bool tag_lines_plausible(std::string_view data) {
  const char* const begin = data.data();
  const char* const end = begin + data.size();
  for (const char* p = begin; (p = static_cast<const char*>(std::memchr(p, 't', size_t(end - p))));
       ++p) {
    const char* b = p;
    while (b > begin && (b[-1] == ' ' || b[-1] == '\t')) --b;
    if ((b != begin && b[-1] != '\n' && b[-1] != '\r') || p + 1 == end ||
        (p[1] != ' ' && p[1] != '\t'))
      continue;
    const char* e = p;
    while (e != end && *e != '\n' && *e != '\r') ++e;
    Cursor c{p + 1, e};
    c.token();  // name
    const std::string_view counts = c.token();
    long long total = 0;
    size_t start = 0;
    for (int k = 0; k < 3; ++k) {
      const size_t slash = counts.find('/', start);
      int64_t n;
      if (!parse_int(counts.substr(start, slash == counts.npos ? counts.npos : slash - start), n) ||
          n < 0)
        return false;
      total += n;
      if (slash == counts.npos) break;
      start = slash + 1;
    }
    long long tokens = 0;
    while (!c.token().empty()) ++tokens;
    if (total > tokens) return false;
  }
  return true;
}

// A read-only streambuf over memory, so tinyobjloader reads without a copy.
struct MemoryBuffer : std::streambuf {
  MemoryBuffer(const char* b, size_t n) {
    char* p = const_cast<char*>(b);  // never written: the buffer is only read through
    setg(p, p, p + n);
  }
};

}  // namespace

// Below this size both reads take a few milliseconds: starting TBB's threads for them would
// cost more than the second core saves (~25 ms on the reference machine, at a process's start).
constexpr size_t kParallelBytes = size_t(4) << 20;

Mesh read_obj(std::string_view data, std::string_view name, bool soup) {
  if (data.size() >= 3 && std::memcmp(data.data(), "\xEF\xBB\xBF", 3) == 0) data.remove_prefix(3);
  if (std::memchr(data.data(), '\0', data.size()) != nullptr)
    throw InputError(fmt::format("{}: contains NUL bytes (binary data, not an OBJ file)", name));
  Mesh mesh;
  ScanResult scan;
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  bool parsed = false;
  auto parse = [&] {
    MemoryBuffer buf(data.data(), data.size());
    std::istream in(&buf);
    // No material reader: an OBJ must not make limn open other files it names.
    parsed = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, nullptr,
                              /*triangulate=*/false, /*default_vcols_fallback=*/false);
  };
  auto scan_all = [&] { scan = ObjScanner(data, name, mesh, soup).run(); };
  if (!tag_lines_plausible(data)) {
    scan_all();  // throws with the offending line; tinyobjloader never sees the data
  } else if (data.size() >= kParallelBytes) {
    // The strict scan and tinyobjloader's parse read the same bytes independently: run them
    // side by side, so validation costs a second core rather than wall time.
    tbb::parallel_invoke(scan_all, parse);
  } else {
    scan_all();
    parse();
  }
  if (scan.v == 0)
    throw InputError(fmt::format("{}: no vertices (empty or not an OBJ file)", name));
  if (!parsed) {
    std::string msg = err.substr(0, err.find('\n'));
    throw InputError(fmt::format("{}: {}", name, msg.empty() ? "tinyobjloader failed" : msg));
  }
  if (attrib.vertices.size() != 3 * scan.v)
    throw InputError(fmt::format("{}: parser disagreement: {} vertices scanned, {} parsed", name,
                                 scan.v, attrib.vertices.size() / 3));

  mesh.positions = std::move(attrib.vertices);
  if (scan.colors && attrib.colors.size() == 3 * scan.v) {
    mesh.colors.resize(4 * scan.v);
    for (size_t i = 0; i < scan.v; ++i) {
      for (int k = 0; k < 3; ++k) mesh.colors[4 * i + k] = attrib.colors[3 * i + k];
      mesh.colors[4 * i + 3] = 1.0f;
    }
  }
  const bool uv = scan.corners > 0 && scan.face_corners_with_uv == scan.corners;
  const bool nrm = scan.corners > 0 && scan.face_corners_with_normal == scan.corners;
  if (uv) mesh.uvs = std::move(attrib.texcoords);
  if (nrm) mesh.normals = std::move(attrib.normals);

  mesh.face_vertices.reserve(scan.corners);
  if (uv) mesh.uv_indices.reserve(scan.corners);
  if (nrm) mesh.normal_indices.reserve(scan.corners);
  for (const auto& shape : shapes) {  // shapes hold the faces in file order
    for (const tinyobj::index_t& i : shape.mesh.indices) {
      mesh.face_vertices.push_back(static_cast<uint32_t>(i.vertex_index));
      if (uv) mesh.uv_indices.push_back(static_cast<uint32_t>(i.texcoord_index));
      if (nrm) mesh.normal_indices.push_back(static_cast<uint32_t>(i.normal_index));
    }
  }
  if (mesh.face_count() != scan.faces || mesh.corner_count() != scan.corners)
    throw InputError(fmt::format("{}: parser disagreement: {} corners scanned, {} parsed", name,
                                 scan.corners, mesh.corner_count()));
  (soup ? validate_soup : validate)(mesh, std::string(name));
  return mesh;
}

void write_obj(const Mesh& m, std::string& out) {
  out.reserve(out.size() + m.vertex_count() * 36 + m.corner_count() * 8);
  out += "# limn\n";
  const bool colors = !m.colors.empty();
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    out += 'v';
    for (int k = 0; k < 3; ++k) out += ' ', put_float(out, m.positions[3 * v + k]);
    if (colors)
      for (int k = 0; k < 3; ++k) out += ' ', put_float(out, m.colors[4 * v + k]);
    out += '\n';
  }
  for (size_t i = 0; i < m.uvs.size() / 2; ++i) {
    out += "vt ";
    put_float(out, m.uvs[2 * i]);
    out += ' ';
    put_float(out, m.uvs[2 * i + 1]);
    out += '\n';
  }
  for (size_t i = 0; i < m.normals.size() / 3; ++i) {
    out += "vn";
    for (int k = 0; k < 3; ++k) out += ' ', put_float(out, m.normals[3 * i + k]);
    out += '\n';
  }
  const bool uv = !m.uv_indices.empty(), nrm = !m.normal_indices.empty();
  for (size_t f = 0; f < m.face_count(); ++f) {
    out += 'f';
    for (uint32_t c = m.face_offsets[f]; c < m.face_offsets[f + 1]; ++c) {
      out += ' ';
      put_uint(out, uint64_t(m.face_vertices[c]) + 1);
      if (uv || nrm) out += '/';
      if (uv) put_uint(out, uint64_t(m.uv_indices[c]) + 1);
      if (nrm) out += '/', put_uint(out, uint64_t(m.normal_indices[c]) + 1);
    }
    out += '\n';
  }
  // OpenSubdiv tags: vertex and face ids are 0-based there.
  for (size_t i = 0; i < m.crease_sharpness.size(); ++i) {
    out += "t crease 2/1/0 ";
    put_uint(out, m.crease_edges[2 * i]);
    out += ' ';
    put_uint(out, m.crease_edges[2 * i + 1]);
    out += ' ';
    put_float(out, m.crease_sharpness[i]);
    out += '\n';
  }
  for (size_t i = 0; i < m.corner_vertices.size(); ++i) {
    out += "t corner 1/1/0 ";
    put_uint(out, m.corner_vertices[i]);
    out += ' ';
    put_float(out, m.corner_sharpness[i]);
    out += '\n';
  }
  if (!m.hole_faces.empty()) {
    out += fmt::format("t hole {}/0/0", m.hole_faces.size());
    for (uint32_t f : m.hole_faces) out += ' ', put_uint(out, f);
    out += '\n';
  }
  if (m.tags.boundary != BoundaryInterpolation::unset)
    out += fmt::format("t interpolateboundary 1/0/0 {}\n",
                       m.tags.boundary == BoundaryInterpolation::none              ? 0
                       : m.tags.boundary == BoundaryInterpolation::edge_and_corner ? 1
                                                                                   : 2);
  if (m.tags.fvar_boundary >= 0)
    out += fmt::format("t facevaryinginterpolateboundary 1/0/0 {}\n", int(m.tags.fvar_boundary));
  if (m.tags.crease_method != CreaseMethod::unset)
    out += fmt::format("t creasemethod 0/0/1 {}\n",
                       m.tags.crease_method == CreaseMethod::chaikin ? "chaikin" : "normal");
  if (m.tags.smooth_triangles) out += "t smoothtriangles 0/0/1 smooth\n";
}

}  // namespace limn
