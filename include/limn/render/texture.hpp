// limn render: an octree texture (limn paint) on the GPU.
//
// The pool is uploaded as is, one shader storage buffer of uint32 words, and read by a GLSL port
// of OctreeSampler's walk: the same descriptors, brick masks, tags and sides, the same nearest
// and filtered lookups (trilinear over the leaf level with weights renormalised over the taps
// that have a sample facing the normal; node averages when the footprint is wider than a leaf).
// Texture coordinates are computed in double precision, as on the CPU, so a point falls in the
// same cell on both. Drawers take it through DrawOptions::texture and colour each fragment by
// the lookup at its position and normal, with a footprint of one pixel.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "limn/paint/texture.hpp"

namespace limn {

class GpuOctreeTexture {
 public:
  /// Uploads the texture's pool (a current OpenGL 4.5 context is needed). Throws
  /// std::runtime_error when the pool exceeds the driver's largest storage buffer. O(pool).
  explicit GpuOctreeTexture(const OctreeTexture& t);
  ~GpuOctreeTexture();
  GpuOctreeTexture(const GpuOctreeTexture&) = delete;
  GpuOctreeTexture& operator=(const GpuOctreeTexture&) = delete;

  /// Uploads `t` again (after painting): only the words from the first one that differs from
  /// the last upload to the last one that differs, the whole pool when its size changed.
  /// O(pool) on the CPU, O(changed range) transferred.
  void update(const OctreeTexture& t);
  /// Words sent by the last upload or update (what a paint stroke costs the bus).
  size_t last_upload_words() const;

  /// Looks points up on the GPU with a compute shader running the drawers' GLSL: what tests
  /// hold to OctreeSampler. p and n: 3 floats per point (n may be empty: front samples).
  /// `footprint` as OctreeSampler::filtered (world units, 0: leaf level).
  struct Lookups {
    std::vector<uint32_t> nearest;  ///< OctreeSampler::nearest's colour (background if none)
    std::vector<uint8_t> nearest_found;
    std::vector<float> filtered;  ///< 4 floats per point, OctreeSampler::filtered's rgba
    std::vector<uint8_t> filtered_found;
    /// The compute dispatch's time on the GPU (a timer query), without the transfers; on a
    /// software driver it covers little more than the submission.
    double shader_ms = 0;
  };
  Lookups lookup(std::span<const float> p, std::span<const float> n, float footprint) const;

  /// Binds the pool and sets the lookup uniforms of `program` (render layer internal): those of
  /// octree.glsl, or of a copy whose names start with `prefix` and whose pool is at `binding`.
  void bind(unsigned program, int mode) const;
  void bind(unsigned program, int mode, const std::string& prefix, unsigned binding) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace limn
