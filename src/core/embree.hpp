// Embree 3, loaded on first use. Its library is large (44 MB): mapping, relocating and
// initialising it at process start cost ~15 ms on the reference machine, more than a whole
// `limn simplify` of a 6k-face mesh; commands that cast no ray should not pay it. Callers use
// Embree's own names through the table: `const EmbreeApi& e = embree(); e.rtcNewDevice(...)`.
// Internal header.
#pragma once

#include <embree3/rtcore.h>

namespace limn {

struct EmbreeApi {
  decltype(&::rtcNewDevice) rtcNewDevice;
  decltype(&::rtcReleaseDevice) rtcReleaseDevice;
  decltype(&::rtcGetDeviceProperty) rtcGetDeviceProperty;
  decltype(&::rtcNewScene) rtcNewScene;
  decltype(&::rtcReleaseScene) rtcReleaseScene;
  decltype(&::rtcSetSceneBuildQuality) rtcSetSceneBuildQuality;
  decltype(&::rtcSetSceneFlags) rtcSetSceneFlags;
  decltype(&::rtcCommitScene) rtcCommitScene;
  decltype(&::rtcNewGeometry) rtcNewGeometry;
  decltype(&::rtcSetNewGeometryBuffer) rtcSetNewGeometryBuffer;
  decltype(&::rtcCommitGeometry) rtcCommitGeometry;
  decltype(&::rtcAttachGeometry) rtcAttachGeometry;
  decltype(&::rtcReleaseGeometry) rtcReleaseGeometry;
  decltype(&::rtcPointQuery) rtcPointQuery;
  decltype(&::rtcIntersect1) rtcIntersect1;
  decltype(&::rtcOccluded1) rtcOccluded1;
  decltype(&::rtcOccluded8) rtcOccluded8;
  decltype(&::rtcOccluded16) rtcOccluded16;
};

/// Embree's functions, the library loaded on the first call (thread-safe). Throws
/// std::runtime_error naming the library when it cannot be loaded or lacks a function.
const EmbreeApi& embree();

}  // namespace limn
