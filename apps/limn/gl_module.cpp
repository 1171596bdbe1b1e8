#include <dlfcn.h>
#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "gl_commands.hpp"

namespace limn::cli {

void* gl_entry(const char* name) {
  // The module's path relative to the executable is the same in the build tree and once
  // installed (LIMN_GL_MODULE: bindir -> libdir/limn, set by CMake).
  static void* module = [] {
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    const std::filesystem::path path = (exe.parent_path() / LIMN_GL_MODULE).lexically_normal();
    void* m = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (m == nullptr)
      throw std::runtime_error(
          fmt::format("cannot open limn's OpenGL module {}: {}", path.string(), dlerror()));
    return m;
  }();
  void* entry = dlsym(module, name);
  if (entry == nullptr)
    throw std::runtime_error(fmt::format("limn's OpenGL module has no {}", name));
  return entry;
}

}  // namespace limn::cli
