#include "core/embree.hpp"

#include <dlfcn.h>

#include <stdexcept>
#include <string>

// The build names the library by its soname; builds without CMake (scripts/cross-check) get
// Embree 3's.
#ifndef LIMN_EMBREE_LIBRARY
#define LIMN_EMBREE_LIBRARY "libembree3.so.3"
#endif

namespace limn {

namespace {

EmbreeApi load() {
  void* lib = dlopen(LIMN_EMBREE_LIBRARY, RTLD_NOW | RTLD_LOCAL);
  if (!lib) throw std::runtime_error(std::string("cannot load Embree: ") + dlerror());
  EmbreeApi api{};
  auto bind = [lib](auto& fn, const char* name) {
    void* sym = dlsym(lib, name);
    if (!sym)
      throw std::runtime_error(std::string(LIMN_EMBREE_LIBRARY) + " has no function " + name);
    fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(sym);
  };
#define LIMN_BIND(name) bind(api.name, #name)
  LIMN_BIND(rtcNewDevice);
  LIMN_BIND(rtcReleaseDevice);
  LIMN_BIND(rtcGetDeviceProperty);
  LIMN_BIND(rtcNewScene);
  LIMN_BIND(rtcReleaseScene);
  LIMN_BIND(rtcSetSceneBuildQuality);
  LIMN_BIND(rtcSetSceneFlags);
  LIMN_BIND(rtcCommitScene);
  LIMN_BIND(rtcNewGeometry);
  LIMN_BIND(rtcSetNewGeometryBuffer);
  LIMN_BIND(rtcCommitGeometry);
  LIMN_BIND(rtcAttachGeometry);
  LIMN_BIND(rtcReleaseGeometry);
  LIMN_BIND(rtcPointQuery);
  LIMN_BIND(rtcIntersect1);
  LIMN_BIND(rtcOccluded1);
  LIMN_BIND(rtcOccluded8);
  LIMN_BIND(rtcOccluded16);
#undef LIMN_BIND
  return api;  // the library stays loaded for the process's life
}

}  // namespace

const EmbreeApi& embree() {
  static const EmbreeApi api = load();
  return api;
}

}  // namespace limn
