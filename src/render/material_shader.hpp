// Material shading's GLSL: octree.glsl a second time, every name prefixed rmh_ and its pool at
// its own binding, so a fragment reads the colour texture and the RMH texture with the same walk;
// then material.glsl. Render layer internal.
#pragma once

#include <string>

namespace limn::detail {

/// The storage-buffer binding of the RMH texture's pool.
inline constexpr unsigned kRmhBinding = 9;

/// The source, made once.
const std::string& material_glsl();

}  // namespace limn::detail
