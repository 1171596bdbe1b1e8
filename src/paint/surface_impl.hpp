// PaintSurface's private part: its Embree scene, and what the paint layer derives from the
// surface once and keeps with it. Internal header.
#pragma once

#include "core/embree.hpp"

#include <memory>
#include <mutex>

#include "limn/paint/surface.hpp"

namespace limn {

struct PaintSurface::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  bool ray16 = false;  // 16-ray packets native (AVX-512): a little faster than 8 there
  // The refiner's triangle lists of a texture cube's start cells (StartLists, kept_lists.hpp): made
  // once, under the lock, and read by every dab that refines one of them.
  mutable std::mutex derived_mutex;
  mutable std::shared_ptr<const void> derived;

  ~Impl() {
    if (scene) embree().rtcReleaseScene(scene);
    if (device) embree().rtcReleaseDevice(device);
  }
};

}  // namespace limn
