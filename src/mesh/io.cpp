// Format dispatch, whole-file reads and atomic writes.
#include "limn/mesh/io.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace limn {

MeshFormat format_from_name(std::string_view n) {
  std::string s(n);
  for (char& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (!s.empty() && s[0] == '.') s.erase(0, 1);
  if (s == "obj") return MeshFormat::obj;
  if (s == "ply") return MeshFormat::ply;
  if (s == "off") return MeshFormat::off;
  if (s == "glb") return MeshFormat::glb;
  return MeshFormat::automatic;
}

MeshFormat format_from_path(const std::filesystem::path& path) {
  return format_from_name(path.extension().string());
}

const char* format_name(MeshFormat f) {
  switch (f) {
    case MeshFormat::obj:
      return "obj";
    case MeshFormat::ply:
      return "ply";
    case MeshFormat::off:
      return "off";
    case MeshFormat::glb:
      return "glb";
    default:
      return "auto";
  }
}

std::string read_file(const std::filesystem::path& path) {
  const std::string name = path.string();
  const int fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(fmt::format("{}: cannot open: {}", name, std::strerror(errno)));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    const bool dir = S_ISDIR(st.st_mode);
    ::close(fd);
    throw InputError(fmt::format(
        "{}: {}", name, dir ? "is a directory, not a mesh file" : "is not a regular file"));
  }
  // Meshes are read whole; past this a file is more likely hostile than a model (a 16 GB OBJ
  // would be ~500M triangles), and failing here beats failing in the allocator.
  constexpr off_t kMaxBytes = off_t(16) << 30;
  if (st.st_size > kMaxBytes) {
    ::close(fd);
    throw InputError(fmt::format("{}: file is {:.1f} GB; limn reads meshes up to 16 GB", name,
                                 double(st.st_size) / double(1 << 30)));
  }
  std::string data;
  data.resize(static_cast<size_t>(st.st_size));
  size_t got = 0;
  while (got < data.size()) {
    const ssize_t n = ::read(fd, data.data() + got, data.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = errno;
      ::close(fd);
      throw InputError(fmt::format("{}: read failed: {}", name,
                                   n == 0 ? "file shrank while reading" : std::strerror(e)));
    }
    got += static_cast<size_t>(n);
  }
  ::close(fd);
  return data;
}

namespace {

MeshFormat sniff(std::string_view d) {
  if (d.size() >= 3 && std::memcmp(d.data(), "\xEF\xBB\xBF", 3) == 0) d.remove_prefix(3);
  if (d.starts_with("ply") && d.size() > 3 && (d[3] == '\n' || d[3] == '\r'))
    return MeshFormat::ply;
  for (const char* m : {"OFF", "COFF", "NOFF", "CNOFF"})
    if (d.starts_with(m)) return MeshFormat::off;
  if (d.starts_with("glTF")) return MeshFormat::glb;
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

Mesh read_mesh_memory(std::string_view data, MeshFormat format, std::string_view name) {
  if (format == MeshFormat::automatic) format = sniff(data);
  switch (format) {
    case MeshFormat::obj:
      return read_obj(data, name);
    case MeshFormat::ply:
      return read_ply(data, name);
    case MeshFormat::off:
      return read_off(data, name);
    case MeshFormat::glb:
      throw InputError(
          fmt::format("{}: reading glTF is not supported (limn writes .glb only)", name));
    default:
      if (data.empty()) throw InputError(fmt::format("{}: empty file", name));
      throw InputError(fmt::format("{}: not a mesh file limn can read (OBJ, PLY or OFF)", name));
  }
}

Mesh read_mesh(const std::filesystem::path& path, MeshFormat format) {
  const std::string data = read_file(path);
  if (data.empty()) throw InputError(fmt::format("{}: empty file", path.string()));
  if (format == MeshFormat::automatic) format = format_from_path(path);
  if (format == MeshFormat::automatic) format = sniff(data);
  return read_mesh_memory(data, format, path.string());
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
    default:
      throw InputError("no output format given");
  }
  return out;
}

void write_file_atomic(const std::filesystem::path& path, std::string_view bytes) {
  const std::string target = path.string();
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  // Hidden temp name beside the target (same filesystem, so rename is atomic).
  // (fmt rather than string concatenation: GCC 12's -Wrestrict misfires on the latter at -O3.)
  std::string tmp = fmt::format("{}/.{}.limn-XXXXXX", dir.string(), path.filename().string());
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0)
    throw std::runtime_error(
        fmt::format("{}: cannot create a file there: {}", target, std::strerror(errno)));
  auto fail = [&](const char* what) {
    const int e = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    throw std::runtime_error(fmt::format("{}: {}: {}", target, what, std::strerror(e)));
  };
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail("write failed");
    done += static_cast<size_t>(n);
  }
  if (::fchmod(fd, 0644) != 0) fail("chmod failed");
  if (::fsync(fd) != 0) fail("fsync failed");
  if (::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error(fmt::format("{}: close failed: {}", target, std::strerror(e)));
  }
  if (::rename(tmp.c_str(), target.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error(fmt::format("{}: cannot replace: {}", target, std::strerror(e)));
  }
}

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& opt) {
  MeshFormat f = opt.format == MeshFormat::automatic ? format_from_path(path) : opt.format;
  if (f == MeshFormat::automatic)
    throw InputError(
        fmt::format("{}: cannot tell the output format from the extension (use .obj, "
                    ".ply, .off or .glb)",
                    path.string()));
  write_file_atomic(path, write_mesh_memory(mesh, f, opt.ascii));
}

}  // namespace limn
