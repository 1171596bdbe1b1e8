// glTF 2.0 input (.gltf and .glb) through tinygltf.
//
// tinygltf parses the JSON and the GLB container and loads buffers, but does not check that
// accessors fit their bufferViews, that indices are in range, nor that the node graph is a tree,
// so every read below is bounds-checked here first. Images are never decoded (a callback
// accepts them unread) and file access goes through callbacks of our own that only read regular
// files and never write. Attribute values are read with memcpy, so misaligned offsets are
// tolerated rather than trusted.
#include <fmt/format.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "limn/io/mesh_io.hpp"

namespace limn {

namespace {

// ---- tinygltf callbacks ----

bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                const unsigned char*, int, void*) {
  return true;  // limn reads geometry only; an image must neither be decoded nor fail the load
}

bool file_exists(const std::string& path, void*) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

std::string expand_path(const std::string& path, void*) {
  return path;  // no ~ or environment expansion: a URI is a relative path, nothing more
}

bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                     void*) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  const std::streamoff size = in ? std::streamoff(in.tellg()) : -1;
  if (size < 0 || size > (std::streamoff(1) << 34)) {
    if (err) *err += fmt::format("cannot read '{}'\n", path);
    return false;
  }
  out->resize(static_cast<size_t>(size));
  in.seekg(0);
  if (size > 0 && !in.read(reinterpret_cast<char*>(out->data()), size)) {
    if (err) *err += fmt::format("cannot read '{}'\n", path);
    return false;
  }
  return true;
}

bool refuse_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is not allowed while reading\n";
  return false;
}

// tinygltf's messages are several lines; ours are one printable line.
std::string one_line(const std::string& s) {
  std::string out;
  bool space = false;
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 32 || u >= 127) {
      space = !out.empty();
      continue;
    }
    if (space) out += "; ";
    space = false;
    out += c;
    if (out.size() > 400) {
      out += "...";
      break;
    }
  }
  return out;
}

// ---- small column-major 4x4 matrices (glTF's layout) ----

struct Mat4 {
  double m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  double at(int row, int col) const { return m[4 * col + row]; }
};

Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a.at(row, k) * b.at(k, c);
      r.m[4 * c + row] = s;
    }
  return r;
}

// Cofactor matrix of the upper 3x3 (= det * inverse transpose), row-major, and the determinant.
void normal_matrix(const Mat4& a, double out[9], double& det) {
  const auto e = [&](int r, int c) { return a.at(r, c); };
  out[0] = e(1, 1) * e(2, 2) - e(1, 2) * e(2, 1);
  out[1] = e(1, 2) * e(2, 0) - e(1, 0) * e(2, 2);
  out[2] = e(1, 0) * e(2, 1) - e(1, 1) * e(2, 0);
  out[3] = e(0, 2) * e(2, 1) - e(0, 1) * e(2, 2);
  out[4] = e(0, 0) * e(2, 2) - e(0, 2) * e(2, 0);
  out[5] = e(0, 1) * e(2, 0) - e(0, 0) * e(2, 1);
  out[6] = e(0, 1) * e(1, 2) - e(0, 2) * e(1, 1);
  out[7] = e(0, 2) * e(1, 0) - e(0, 0) * e(1, 2);
  out[8] = e(0, 0) * e(1, 1) - e(0, 1) * e(1, 0);
  det = e(0, 0) * out[0] + e(0, 1) * out[1] + e(0, 2) * out[2];
  // Dividing by |det| only rescales (normals are renormalised); the sign turns the cofactors
  // into the inverse transpose's direction. A singular transform keeps the cofactors, which
  // still point along the surviving normal direction.
  if (det < 0)
    for (int i = 0; i < 9; ++i) out[i] = -out[i];
}

// ---- accessors ----

const char* type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return "SCALAR";
    case TINYGLTF_TYPE_VEC2:
      return "VEC2";
    case TINYGLTF_TYPE_VEC3:
      return "VEC3";
    case TINYGLTF_TYPE_VEC4:
      return "VEC4";
    case TINYGLTF_TYPE_MAT2:
      return "MAT2";
    case TINYGLTF_TYPE_MAT3:
      return "MAT3";
    case TINYGLTF_TYPE_MAT4:
      return "MAT4";
    default:
      return "an unknown type";
  }
}

int components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return 1;
    case TINYGLTF_TYPE_VEC2:
      return 2;
    case TINYGLTF_TYPE_VEC3:
      return 3;
    case TINYGLTF_TYPE_VEC4:
    case TINYGLTF_TYPE_MAT2:
      return 4;
    case TINYGLTF_TYPE_MAT3:
      return 9;
    case TINYGLTF_TYPE_MAT4:
      return 16;
    default:
      return 0;
  }
}

const char* component_name(int c) {
  switch (c) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
      return "byte";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return "unsigned byte";
    case TINYGLTF_COMPONENT_TYPE_SHORT:
      return "short";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return "unsigned short";
    case TINYGLTF_COMPONENT_TYPE_INT:
      return "int";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return "unsigned int";
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return "float";
    default:
      return "an unknown component type";
  }
}

size_t component_size(int c) {
  switch (c) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

template <class T>
T load(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  if constexpr (std::endian::native == std::endian::big && sizeof(T) > 1) {
    if constexpr (sizeof(T) == 2)
      v = std::bit_cast<T>(__builtin_bswap16(std::bit_cast<uint16_t>(v)));
    else
      v = std::bit_cast<T>(__builtin_bswap32(std::bit_cast<uint32_t>(v)));
  }
  return v;
}

// One component as a float: normalized integers map to [0,1] or [-1,1] as the spec says.
float load_component(const unsigned char* p, int comp, bool normalized) {
  switch (comp) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const float x = static_cast<float>(load<int8_t>(p));
      return normalized ? std::max(x / 127.0f, -1.0f) : x;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      const float x = static_cast<float>(load<uint8_t>(p));
      return normalized ? x / 255.0f : x;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      const float x = static_cast<float>(load<int16_t>(p));
      return normalized ? std::max(x / 32767.0f, -1.0f) : x;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      const float x = static_cast<float>(load<uint16_t>(p));
      return normalized ? x / 65535.0f : x;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      return static_cast<float>(load<uint32_t>(p));
    default:
      return load<float>(p);
  }
}

// A checked accessor: `count` elements of `ncomp` components, element i at base + i * stride.
struct View {
  const unsigned char* base = nullptr;
  size_t stride = 0, count = 0;
  int comp = 0, ncomp = 0;
  bool normalized = false;
  int index = -1;
};

// Which (type, componentType, normalized) combinations an attribute accepts.
struct Rule {
  unsigned types;     // bit (1 << ncomp) per accepted VEC/SCALAR width
  unsigned floats;    // 1: float accepted
  unsigned norm_int;  // bit (comp - 5120) per integer type accepted when normalized
  unsigned raw_int;   // bit (comp - 5120) per integer type accepted when not normalized
};

constexpr unsigned kB = 1u << 0, kUB = 1u << 1, kS = 1u << 2, kUS = 1u << 3, kUI = 1u << 5;

class GltfReader {
 public:
  GltfReader(const tinygltf::Model& model, std::string_view name) : g_(model), name_(name) {
    for (const std::string& e : g_.extensionsUsed)
      if (e == "KHR_mesh_quantization") quantized_ = true;
  }

  Mesh read(size_t* dropped) {
    for (const std::string& e : g_.extensionsRequired)
      if (e.find("compression") != std::string::npos)
        throw InputError(fmt::format(
            "{}: the file requires extension {} (compressed geometry), which limn does not read",
            name_, one_line(e)));
    if (g_.scenes.empty()) {
      // No scene to follow: every mesh once, untransformed.
      for (size_t i = 0; i < g_.meshes.size(); ++i) read_mesh(static_cast<int>(i), Mat4());
    } else {
      const int s = g_.defaultScene >= 0 ? g_.defaultScene : 0;
      if (size_t(s) >= g_.scenes.size())
        fail(
            fmt::format("scene {} is the default but the file has {} scenes", s, g_.scenes.size()));
      walk(g_.scenes[size_t(s)], s);
    }
    if (!all_normals_) mesh_.normals.clear();
    if (!all_uvs_) mesh_.uvs.clear();
    if (!any_colors_) mesh_.colors.clear();
    if (!mesh_.normals.empty()) mesh_.normal_indices = mesh_.face_vertices;
    if (!mesh_.uvs.empty()) mesh_.uv_indices = mesh_.face_vertices;
    if (dropped) *dropped = degenerate_;
    validate(mesh_, std::string(name_));
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void fail(std::string_view msg) const {
    throw InputError(fmt::format("{}: {}", name_, msg));
  }

  // Depth-first over the scene's trees; glTF requires disjoint strict trees, so a node reached
  // twice is a cycle or a shared child and is rejected rather than followed.
  void walk(const tinygltf::Scene& scene, int s) {
    std::vector<char> seen(g_.nodes.size(), 0);
    std::vector<std::pair<int, Mat4>> stack;
    for (const int n : scene.nodes) {
      if (n < 0 || size_t(n) >= g_.nodes.size())
        fail(
            fmt::format("scene {} lists node {} but the file has {} nodes", s, n, g_.nodes.size()));
      stack.emplace_back(n, Mat4());
    }
    std::reverse(stack.begin(), stack.end());
    while (!stack.empty()) {
      const auto [n, parent] = stack.back();
      stack.pop_back();
      if (seen[size_t(n)])
        fail(fmt::format("node {} is reached twice (the node hierarchy must be a tree)", n));
      seen[size_t(n)] = 1;
      const tinygltf::Node& node = g_.nodes[size_t(n)];
      const Mat4 global = parent * local(node, n);
      if (node.mesh >= 0) read_mesh(node.mesh, global, n);
      for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) {
        if (*it < 0 || size_t(*it) >= g_.nodes.size())
          fail(fmt::format("node {} has child {} but the file has {} nodes", n, *it,
                           g_.nodes.size()));
        stack.emplace_back(*it, global);
      }
    }
  }

  Mat4 local(const tinygltf::Node& node, int n) const {
    const auto finite = [&](const std::vector<double>& v, const char* what, size_t size) {
      if (v.empty()) return false;
      if (v.size() != size)
        fail(fmt::format("node {}: {} has {} numbers ({} needed)", n, what, v.size(), size));
      for (const double x : v)
        if (!std::isfinite(x)) fail(fmt::format("node {}: {} is not finite", n, what));
      return true;
    };
    Mat4 m;
    if (finite(node.matrix, "matrix", 16)) {
      std::copy(node.matrix.begin(), node.matrix.end(), m.m);
      return m;
    }
    // T * R * S: the columns of R scaled by S, then the translation column.
    double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
    if (finite(node.rotation, "rotation", 4)) {
      double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2], w = node.rotation[3];
      const double len = std::sqrt(x * x + y * y + z * z + w * w);
      if (!(len > 0)) fail(fmt::format("node {}: rotation is a zero quaternion", n));
      x /= len, y /= len, z /= len, w /= len;
      const double q[9] = {
          1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
          2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
          2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
      std::copy(q, q + 9, r);
    }
    double s[3] = {1, 1, 1}, t[3] = {0, 0, 0};
    if (finite(node.scale, "scale", 3)) std::copy(node.scale.begin(), node.scale.end(), s);
    if (finite(node.translation, "translation", 3))
      std::copy(node.translation.begin(), node.translation.end(), t);
    for (int c = 0; c < 3; ++c)
      for (int row = 0; row < 3; ++row) m.m[4 * c + row] = r[3 * row + c] * s[c];
    for (int row = 0; row < 3; ++row) m.m[12 + row] = t[row];
    return m;
  }

  void read_mesh(int index, const Mat4& xf, int node = -1) {
    if (size_t(index) >= g_.meshes.size())
      fail(fmt::format("node {} refers to mesh {} but the file has {} meshes", node, index,
                       g_.meshes.size()));
    const tinygltf::Mesh& gm = g_.meshes[size_t(index)];
    for (size_t p = 0; p < gm.primitives.size(); ++p) {
      where_ = fmt::format("mesh {} primitive {}", index, p);
      read_primitive(gm.primitives[p], xf);
    }
  }

  [[noreturn]] void fail_prim(std::string_view msg) const {
    fail(where_ + ": " + std::string(msg));
  }

  View accessor(int index, std::string_view role, const Rule& rule) const {
    const auto bad = [&](std::string_view msg) {
      fail_prim(fmt::format("{} accessor {} {}", role, index, msg));
    };
    if (index < 0 || size_t(index) >= g_.accessors.size())
      fail_prim(fmt::format("{} refers to accessor {} but the file has {} accessors", role, index,
                            g_.accessors.size()));
    const tinygltf::Accessor& a = g_.accessors[size_t(index)];
    if (a.sparse.isSparse) bad("is sparse, which limn does not read");
    View v;
    v.index = index;
    v.comp = a.componentType;
    v.ncomp = components(a.type);
    v.normalized = a.normalized;
    v.count = a.count;
    const size_t csize = component_size(a.componentType);
    const bool is_float = a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
    const unsigned bit = csize && !is_float ? 1u << (a.componentType - 5120) : 0u;
    const bool type_ok =
        v.ncomp > 0 && v.ncomp <= 4 && a.type != TINYGLTF_TYPE_MAT2 && (rule.types >> v.ncomp & 1u);
    const bool comp_ok =
        is_float ? rule.floats != 0 : (bit & (a.normalized ? rule.norm_int : rule.raw_int)) != 0;
    if (!type_ok || !comp_ok)
      bad(fmt::format("is {} of {}{}, which {} does not allow", type_name(a.type),
                      a.normalized ? "normalized " : "", component_name(a.componentType), role));
    if (a.bufferView < 0)
      bad("has no bufferView (sparse or compressed data, which limn does not read)");
    if (size_t(a.bufferView) >= g_.bufferViews.size())
      bad(fmt::format("refers to bufferView {} but the file has {}", a.bufferView,
                      g_.bufferViews.size()));
    const tinygltf::BufferView& bv = g_.bufferViews[size_t(a.bufferView)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= g_.buffers.size())
      bad(fmt::format("uses bufferView {} whose buffer {} does not exist", a.bufferView,
                      bv.buffer));
    const std::vector<unsigned char>& data = g_.buffers[size_t(bv.buffer)].data;
    if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
      bad(fmt::format("uses bufferView {} (bytes {}..{}) past the end of buffer {} ({} bytes)",
                      a.bufferView, bv.byteOffset, bv.byteOffset + bv.byteLength, bv.buffer,
                      data.size()));
    const size_t elem = csize * size_t(v.ncomp);
    v.stride = bv.byteStride ? bv.byteStride : elem;
    if (v.stride < elem)
      bad(fmt::format("has elements of {} bytes but bufferView {} has byteStride {}", elem,
                      a.bufferView, bv.byteStride));
    if (v.count > 0) {
      const size_t len = bv.byteLength;
      if (a.byteOffset > len || elem > len - a.byteOffset ||
          (v.count - 1) > (len - a.byteOffset - elem) / v.stride)
        bad(
            fmt::format("({} elements of {} bytes, stride {}, offset {}) runs past the end of "
                        "bufferView {} ({} bytes)",
                        v.count, elem, v.stride, a.byteOffset, a.bufferView, len));
    }
    v.base = data.data() + bv.byteOffset + a.byteOffset;
    return v;
  }

  // Reads `width` floats per element (missing components of a VEC3 colour are 1), checking
  // that each is finite.
  std::vector<float> floats(const View& v, std::string_view role, int width) const {
    std::vector<float> out(v.count * size_t(width), 1.0f);
    const size_t csize = component_size(v.comp);
    for (size_t i = 0; i < v.count; ++i) {
      const unsigned char* p = v.base + i * v.stride;
      for (int k = 0; k < v.ncomp; ++k) {
        const float x = load_component(p + size_t(k) * csize, v.comp, v.normalized);
        if (!std::isfinite(x))
          fail_prim(
              fmt::format("{} accessor {} element {} is not finite ({})", role, v.index, i, x));
        out[i * size_t(width) + size_t(k)] = x;
      }
    }
    return out;
  }

  int attribute(const tinygltf::Primitive& prim, const char* semantic) const {
    const auto it = prim.attributes.find(semantic);
    return it == prim.attributes.end() ? -1 : it->second;
  }

  void read_primitive(const tinygltf::Primitive& prim, const Mat4& xf) {
    static constexpr const char* kModes[] = {"points", "lines", "line loop", "line strip"};
    const int mode = prim.mode;
    if (mode >= 0 && mode <= 3)
      fail_prim(fmt::format("has mode {} ({}), limn reads triangles", mode, kModes[mode]));
    if (mode < 4 || mode > 6) fail_prim(fmt::format("has unknown mode {}", mode));

    const int pos_index = attribute(prim, "POSITION");
    if (pos_index < 0) fail_prim("has no POSITION attribute");
    const unsigned any_int = kB | kUB | kS | kUS;
    const View pv = accessor(pos_index, "POSITION",
                             {1u << 3, 1, quantized_ ? any_int : 0u, quantized_ ? any_int : 0u});
    const size_t n = pv.count;
    const size_t base = mesh_.vertex_count();
    if (n > size_t(UINT32_MAX) - base)
      fail_prim(fmt::format("brings the vertex count past 2^32 ({} + {})", base, n));
    const auto same_count = [&](const View& v, const char* role) {
      if (v.count != n)
        fail_prim(fmt::format("{} accessor {} has {} elements but POSITION has {}", role, v.index,
                              v.count, n));
    };

    const std::vector<float> pos = floats(pv, "POSITION", 3);
    for (size_t i = 0; i < n; ++i) {
      const double p[3] = {pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]};
      for (int r = 0; r < 3; ++r) {
        const double x = xf.at(r, 0) * p[0] + xf.at(r, 1) * p[1] + xf.at(r, 2) * p[2] + xf.at(r, 3);
        if (!(std::fabs(x) <= std::numeric_limits<float>::max()))
          fail_prim(fmt::format("vertex {} is not finite after the node transforms", i));
        mesh_.positions.push_back(static_cast<float>(x));
      }
    }

    double nm[9], det;
    normal_matrix(xf, nm, det);
    const int nrm_index = attribute(prim, "NORMAL");
    mesh_.normals.resize(3 * (base + n), 0.0f);
    if (nrm_index >= 0) {
      const View v = accessor(nrm_index, "NORMAL", {1u << 3, 1, quantized_ ? kB | kS : 0u, 0});
      same_count(v, "NORMAL");
      const std::vector<float> nrm = floats(v, "NORMAL", 3);
      for (size_t i = 0; i < n; ++i) {
        double o[3];
        for (int r = 0; r < 3; ++r)
          o[r] = nm[3 * r] * nrm[3 * i] + nm[3 * r + 1] * nrm[3 * i + 1] +
                 nm[3 * r + 2] * nrm[3 * i + 2];
        const double len = std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
        for (int r = 0; r < 3; ++r)
          mesh_.normals[3 * (base + i) + size_t(r)] =
              len > 0 && std::isfinite(len) ? static_cast<float>(o[r] / len) : 0.0f;
      }
    } else {
      all_normals_ = false;
    }

    const int uv_index = attribute(prim, "TEXCOORD_0");
    mesh_.uvs.resize(2 * (base + n), 0.0f);
    if (uv_index >= 0) {
      const View v = accessor(
          uv_index, "TEXCOORD_0",
          {1u << 2, 1, kUB | kUS | (quantized_ ? kB | kS : 0u), quantized_ ? any_int : 0u});
      same_count(v, "TEXCOORD_0");
      const std::vector<float> uv = floats(v, "TEXCOORD_0", 2);
      for (size_t i = 0; i < n; ++i) {
        mesh_.uvs[2 * (base + i)] = uv[2 * i];
        mesh_.uvs[2 * (base + i) + 1] = 1.0f - uv[2 * i + 1];  // glTF's v points down
      }
    } else {
      all_uvs_ = false;
    }

    const int col_index = attribute(prim, "COLOR_0");
    mesh_.colors.resize(4 * (base + n), 1.0f);
    if (col_index >= 0) {
      const View v = accessor(col_index, "COLOR_0", {1u << 3 | 1u << 4, 1, kUB | kUS, 0});
      same_count(v, "COLOR_0");
      const std::vector<float> col = floats(v, "COLOR_0", 4);
      for (size_t i = 0; i < 4 * n; ++i) mesh_.colors[4 * base + i] = std::clamp(col[i], 0.f, 1.f);
      any_colors_ = true;
    }

    // Indices, then triangles by mode.
    std::vector<uint32_t> idx;
    if (prim.indices >= 0) {
      const View v = accessor(prim.indices, "indices", {1u << 1, 0, 0, kUB | kUS | kUI});
      idx.resize(v.count);
      const size_t csize = component_size(v.comp);
      for (size_t i = 0; i < v.count; ++i) {
        const unsigned char* p = v.base + i * v.stride;
        const uint32_t x = csize == 1   ? load<uint8_t>(p)
                           : csize == 2 ? load<uint16_t>(p)
                                        : load<uint32_t>(p);
        if (x >= n)
          fail_prim(fmt::format("indices accessor {} element {} is {}, past the vertex count {}",
                                v.index, i, x, n));
        idx[i] = x;
      }
    } else {
      idx.resize(n);
      for (size_t i = 0; i < n; ++i) idx[i] = static_cast<uint32_t>(i);
    }
    const size_t m = idx.size();
    if (mode == TINYGLTF_MODE_TRIANGLES && m % 3 != 0)
      fail_prim(fmt::format("has {} {} for triangles (not a multiple of 3)", m,
                            prim.indices >= 0 ? "indices" : "vertices"));
    const bool flip = det < 0;  // a mirroring transform reverses the winding (glTF 3.7.2.1)
    const auto emit = [&](uint32_t a, uint32_t b, uint32_t c) {
      if (a == b || b == c || a == c) {
        ++degenerate_;
        return;
      }
      if (flip) std::swap(b, c);
      const uint32_t o = static_cast<uint32_t>(base);
      mesh_.face_vertices.insert(mesh_.face_vertices.end(), {o + a, o + b, o + c});
      mesh_.face_offsets.push_back(static_cast<uint32_t>(mesh_.face_vertices.size()));
    };
    if (mesh_.face_vertices.size() + 3 * m > UINT32_MAX)
      fail_prim("brings the corner count past 2^32");
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      for (size_t i = 0; i + 2 < m; i += 3) emit(idx[i], idx[i + 1], idx[i + 2]);
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      // Odd triangles swap their last two vertices to keep the strip's orientation.
      for (size_t i = 0; i + 2 < m; ++i) emit(idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]);
    } else {
      for (size_t i = 1; i + 1 < m; ++i) emit(idx[i], idx[i + 1], idx[0]);
    }
  }

  const tinygltf::Model& g_;
  std::string_view name_;
  std::string where_;
  bool quantized_ = false;
  bool all_normals_ = true, all_uvs_ = true, any_colors_ = false;
  size_t degenerate_ = 0;
  Mesh mesh_;
};

}  // namespace

Mesh read_gltf(std::string_view data, std::string_view name, const std::filesystem::path& base_dir,
               size_t* dropped_degenerate) {
  if (dropped_degenerate) *dropped_degenerate = 0;
  if (data.empty()) throw InputError(fmt::format("{}: empty file", name));
  if (data.size() > UINT32_MAX)
    throw InputError(
        fmt::format("{}: {} bytes, more than a glTF file can hold", name, data.size()));
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&skip_image, nullptr);
  loader.SetFsCallbacks({&file_exists, &expand_path, &read_whole_file, &refuse_write, nullptr});
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = data.starts_with("glTF");
  const auto len = static_cast<unsigned int>(data.size());
  const bool ok =
      binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                           reinterpret_cast<const unsigned char*>(data.data()), len,
                                           base_dir.string())
             : loader.LoadASCIIFromString(&model, &err, &warn, data.data(), len, base_dir.string());
  if (!ok) {
    const std::string why = one_line(err);
    throw InputError(fmt::format("{}: cannot read {}: {}", name, binary ? "GLB" : "glTF",
                                 why.empty() ? "tinygltf gave no reason" : why));
  }
  return GltfReader(model, name).read(dropped_degenerate);
}

}  // namespace limn
