#include "core/embree.hpp"

#include <dlfcn.h>

#include <stdexcept>
#include <string>
#include <type_traits>

// The build names the library by its soname; builds without CMake (scripts/cross-check) get
// Embree 3's.
#ifndef LIMN_EMBREE_LIBRARY
#define LIMN_EMBREE_LIBRARY "libembree3.so.3"
#endif

namespace limn {

namespace {

#ifdef LIMN_EMBREE_LINKED
// Sanitizer builds link Embree instead: LeakSanitizer cannot scan the dynamic TLS that a
// dlopen'd Embree gives TBB's threads (its stop-the-world tracer crashes at exit), while a
// library loaded at start has static TLS.
EmbreeApi load() {
  EmbreeApi api{};
#define LIMN_EMBREE_TAKE(name) api.name = &::name;
  LIMN_EMBREE_FUNCTIONS(LIMN_EMBREE_TAKE)
#undef LIMN_EMBREE_TAKE
  return api;
}
#else
EmbreeApi load() {
  void* lib = dlopen(LIMN_EMBREE_LIBRARY, RTLD_NOW | RTLD_LOCAL);
  if (!lib) throw std::runtime_error(std::string("cannot load Embree: ") + dlerror());
  EmbreeApi api{};
  auto bind = [lib](auto& fn, const char* name) {
    void* sym = dlsym(lib, name);
    if (!sym)
      throw std::runtime_error(std::string(LIMN_EMBREE_LIBRARY) + " has no function " + name);
    fn = reinterpret_cast<std::remove_reference_t<decltype(fn)> >(sym);
  };
#define LIMN_EMBREE_BIND(name) bind(api.name, #name);
  LIMN_EMBREE_FUNCTIONS(LIMN_EMBREE_BIND)
#undef LIMN_EMBREE_BIND
  return api;  // the library stays loaded for the process's life
}
#endif

}  // namespace

const EmbreeApi& embree() {
  static const EmbreeApi api = load();
  return api;
}

}  // namespace limn
