// Whole-file reads and atomic writes, for every layer's files (meshes, textures, images).
#include "limn/mesh/file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn {

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

// Writes bytes to a hidden temporary file beside `path` (same file system, so a rename is
// atomic), flushed; returns its name. Throws std::runtime_error naming the path.
std::string stage(const std::filesystem::path& path, std::string_view bytes) {
  const std::string target = path.string();
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
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
  return tmp;
}

void commit(const std::string& tmp, const std::filesystem::path& path) {
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error(
        fmt::format("{}: cannot replace: {}", path.string(), std::strerror(e)));
  }
}

}  // namespace

void write_file_atomic(const std::filesystem::path& path, std::string_view bytes) {
  commit(stage(path, bytes), path);
}

void write_files_atomic(std::span<const std::pair<std::filesystem::path, std::string>> files) {
  std::vector<std::string> staged;
  try {
    for (const auto& [path, bytes] : files) staged.push_back(stage(path, bytes));
  } catch (...) {
    for (const std::string& tmp : staged) ::unlink(tmp.c_str());
    throw;
  }
  for (size_t i = 0; i < files.size(); ++i) {
    try {
      commit(staged[i], files[i].first);
    } catch (...) {
      for (size_t j = i + 1; j < files.size(); ++j) ::unlink(staged[j].c_str());
      throw;
    }
  }
}

}  // namespace limn
