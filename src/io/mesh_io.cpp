// Format dispatch: by name, extension or the file's first bytes.
#include "limn/io/mesh_io.hpp"

#include <fmt/format.h>

#include <cstring>

#include "limn/mesh/file.hpp"
#include "limn/mesh/weld.hpp"

namespace limn {

MeshFormat format_from_name(std::string_view n) {
  std::string s(n);
  for (char& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (!s.empty() && s[0] == '.') s.erase(0, 1);
  if (s == "obj") return MeshFormat::obj;
  if (s == "ply") return MeshFormat::ply;
  if (s == "off") return MeshFormat::off;
  if (s == "glb") return MeshFormat::glb;
  if (s == "gltf") return MeshFormat::gltf;
  if (s == "stl") return MeshFormat::stl;
  return MeshFormat::automatic;
}

MeshFormat format_from_path(const std::filesystem::path& path) {
  return format_from_name(path.extension().string());
}

namespace {

MeshFormat sniff(std::string_view d) {
  // Binary STL has no magic, but its size is exact; checked first because its free-form header
  // may start with "solid", "OFF" or anything else. Text cannot match by chance: four text bytes
  // read as a count of over 150 million triangles, which the size would have to equal exactly.
  if (d.size() >= 84) {
    uint32_t count;
    std::memcpy(&count, d.data() + 80, 4);
    if ((d.size() - 84) % 50 == 0 && (d.size() - 84) / 50 == count) return MeshFormat::stl;
  }
  if (d.size() >= 3 && std::memcmp(d.data(), "\xEF\xBB\xBF", 3) == 0) d.remove_prefix(3);
  if (d.starts_with("ply") && d.size() > 3 && (d[3] == '\n' || d[3] == '\r'))
    return MeshFormat::ply;
  for (const char* m : {"OFF", "COFF", "NOFF", "CNOFF"})
    if (d.starts_with(m)) return MeshFormat::off;
  if (d.starts_with("glTF")) return MeshFormat::glb;
  const size_t text = d.find_first_not_of(" \t\r\n");
  // glTF JSON: an object with an "asset" member, which writers may put after large arrays.
  if (text != std::string_view::npos && d[text] == '{' &&
      d.find("\"asset\"") != std::string_view::npos)
    return MeshFormat::gltf;
  if (text != std::string_view::npos && d.substr(text).starts_with("solid") &&
      d.substr(0, 4096).find("facet") != std::string_view::npos)
    return MeshFormat::stl;
  // OBJ has no magic: accept text whose first statement is an OBJ keyword.
  size_t i = 0;
  while (i < d.size()) {
    while (i < d.size() && (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' || d[i] == '\n')) ++i;
    if (i < d.size() && d[i] == '#') {
      while (i < d.size() && d[i] != '\n' && d[i] != '\r') ++i;
      continue;
    }
    break;
  }
  const std::string_view rest = d.substr(i);
  for (const char* k : {"v ", "vt ", "vn ", "f ", "o ", "g ", "mtllib ", "s ", "usemtl ", "v\t"})
    if (rest.starts_with(k)) return MeshFormat::obj;
  return MeshFormat::automatic;
}

}  // namespace

Mesh read_mesh_memory(std::string_view data, const ReadOptions& opt, std::string_view name) {
  MeshFormat format = opt.format;
  if (format == MeshFormat::automatic) format = sniff(data);
  if (opt.dropped_degenerate) *opt.dropped_degenerate = 0;
  switch (format) {
    case MeshFormat::obj:
      return read_obj(data, name, opt.soup);
    case MeshFormat::ply:
      return read_ply(data, name, opt.soup);
    case MeshFormat::off:
      return read_off(data, name, opt.soup);
    case MeshFormat::stl:
      return read_stl(data, name, opt.dropped_degenerate);
    case MeshFormat::glb:
    case MeshFormat::gltf: {
      size_t dropped = 0, dropped_by_weld = 0;
      Mesh m = read_gltf(data, name, opt.base_dir, &dropped);
      if (opt.weld) m = weld_vertices(m, &dropped_by_weld);
      if (opt.dropped_degenerate) *opt.dropped_degenerate = dropped + dropped_by_weld;
      return m;
    }
    default:
      if (data.empty()) throw InputError(fmt::format("{}: empty file", name));
      throw InputError(
          fmt::format("{}: not a mesh file limn can read (OBJ, PLY, OFF, STL, glTF or GLB)", name));
  }
}

Mesh read_mesh_memory(std::string_view data, MeshFormat format, std::string_view name) {
  ReadOptions opt;
  opt.format = format;
  return read_mesh_memory(data, opt, name);
}

Mesh read_mesh(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string data = read_file(path);
  if (data.empty()) throw InputError(fmt::format("{}: empty file", path.string()));
  ReadOptions opt = options;
  if (opt.format == MeshFormat::automatic) opt.format = format_from_path(path);
  if (opt.format == MeshFormat::automatic) opt.format = sniff(data);
  if (opt.base_dir.empty()) opt.base_dir = path.parent_path();
  return read_mesh_memory(data, opt, path.string());
}

Mesh read_mesh(const std::filesystem::path& path, MeshFormat format) {
  ReadOptions opt;
  opt.format = format;
  return read_mesh(path, opt);
}

std::vector<std::string> dropped_attributes(const Mesh& m, MeshFormat format) {
  const bool geometry_only = format == MeshFormat::off || format == MeshFormat::stl;
  const bool keeps_tags = format == MeshFormat::obj;
  std::vector<std::string> out;
  if (geometry_only && !m.uv_indices.empty()) out.emplace_back("uv");
  if (geometry_only && !m.normal_indices.empty()) out.emplace_back("normals");
  if (geometry_only && !m.colors.empty()) out.emplace_back("colors");
  if (format == MeshFormat::obj) {
    bool alpha = false;
    for (size_t i = 3; i < m.colors.size() && !alpha; i += 4) alpha = m.colors[i] != 1.0f;
    if (alpha) out.emplace_back("alpha");
  }
  if (!keeps_tags) {
    if (!m.crease_sharpness.empty()) out.emplace_back("creases");
    if (!m.corner_sharpness.empty()) out.emplace_back("corners");
    if (!m.hole_faces.empty()) out.emplace_back("holes");
    const SubdivTags none;
    if (m.tags.boundary != none.boundary || m.tags.fvar_boundary != none.fvar_boundary ||
        m.tags.crease_method != none.crease_method ||
        m.tags.smooth_triangles != none.smooth_triangles)
      out.emplace_back("tags");
  }
  return out;
}

std::string write_mesh_memory(const Mesh& mesh, MeshFormat format, bool ascii_ply) {
  std::string out;
  switch (format) {
    case MeshFormat::obj:
      write_obj(mesh, out);
      break;
    case MeshFormat::ply:
      write_ply(mesh, out, ascii_ply);
      break;
    case MeshFormat::off:
      write_off(mesh, out);
      break;
    case MeshFormat::glb:
      write_glb(mesh, out);
      break;
    case MeshFormat::stl:
      write_stl(mesh, out);
      break;
    case MeshFormat::gltf:
      throw InputError("writing .gltf is not supported (limn writes binary glTF: use .glb)");
    default:
      throw InputError("no output format given");
  }
  return out;
}

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& opt) {
  MeshFormat f = opt.format == MeshFormat::automatic ? format_from_path(path) : opt.format;
  if (f == MeshFormat::automatic)
    throw InputError(
        fmt::format("{}: cannot tell the output format from the extension (use .obj, "
                    ".ply, .off, .stl or .glb)",
                    path.string()));
  write_file_atomic(path, write_mesh_memory(mesh, f, opt.ascii));
}

}  // namespace limn
