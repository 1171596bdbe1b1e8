// Embree 3, loaded on first use. Its library is large (44 MB): mapping, relocating and
// initialising it at process start cost ~15 ms on the reference machine, more than a whole
// `limn simplify` of a 6k-face mesh; commands that cast no ray should not pay it. Callers use
// Embree's own names through the table: `const EmbreeApi& e = embree(); e.rtcNewDevice(...)`.
// Internal header.
#pragma once

#include <embree3/rtcore.h>

// The functions limn calls, each once: the table's members and what is bound to them.
#define LIMN_EMBREE_FUNCTIONS(X) \
  X(rtcNewDevice)                \
  X(rtcReleaseDevice)            \
  X(rtcGetDeviceProperty)        \
  X(rtcNewScene)                 \
  X(rtcReleaseScene)             \
  X(rtcSetSceneBuildQuality)     \
  X(rtcSetSceneFlags)            \
  X(rtcCommitScene)              \
  X(rtcNewGeometry)              \
  X(rtcSetNewGeometryBuffer)     \
  X(rtcCommitGeometry)           \
  X(rtcAttachGeometry)           \
  X(rtcReleaseGeometry)          \
  X(rtcPointQuery)               \
  X(rtcIntersect1)               \
  X(rtcOccluded1)                \
  X(rtcOccluded8)                \
  X(rtcOccluded16)

namespace limn {

struct EmbreeApi {
#define LIMN_EMBREE_MEMBER(name) decltype(&::name) name;
  LIMN_EMBREE_FUNCTIONS(LIMN_EMBREE_MEMBER)
#undef LIMN_EMBREE_MEMBER
};

/// Embree's functions, the library loaded on the first call (thread-safe). Throws
/// std::runtime_error naming the library when it cannot be loaded or lacks a function.
const EmbreeApi& embree();

}  // namespace limn
