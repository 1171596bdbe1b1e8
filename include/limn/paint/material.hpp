// limn paint: material channels. A painted material is the base-colour octree texture (RGBA8,
// straight alpha, as texture.hpp describes) plus, once any of them is painted, a second octree
// texture over the same cube holding roughness, metallic and height in the R, G and B bytes of
// its samples (the "RMH" texture). A texture painted in colour only has no RMH texture and
// costs exactly what it did before materials existed.
//
// RMH samples use alpha as coverage: the RMH texture's background holds the channels' defaults
// with alpha 0, a texel a brush touched has alpha 255, and a lookup's value is its RGB over the
// defaults by its alpha (`material_value`), so filtering and mip averages (premultiplied, as
// for colour) blend painted values with the defaults of the texels around them.
//
// Height is a fraction in [0, 1] of `height_scale` model units along the surface normal, 0.5 the
// surface itself (so a brush can raise and lower it); stored in 8 bits like the other channels,
// looked up (and baked) in float, so filtering between texels does not band.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "limn/paint/texture.hpp"

namespace limn {

/// The scalar channels of the RMH texture, in the order of its bytes.
enum class MaterialChannel : uint8_t { roughness = 0, metallic = 1, height = 2 };
inline constexpr int kMaterialChannels = 3;
/// "roughness", "metallic", "height". O(1).
const char* channel_name(MaterialChannel c);

/// The height scale of a material made from a colour texture, as a fraction of its cube's size.
inline constexpr float kDefaultHeightScale = 0.02f;

/// Values where a channel was never painted.
struct MaterialDefaults {
  float roughness = 0.5f, metallic = 0.0f, height = 0.5f;
};

struct MaterialTexture {
  OctreeTexture color;  ///< base colour
  /// Roughness, metallic, height (R, G, B; alpha is coverage), over color's cube; absent until
  /// one of them is painted.
  std::optional<OctreeTexture> rmh;
  /// Model units that height 1 stands for above height 0 (bump shading, normal maps). > 0.
  float height_scale = 0;

  /// A material whose base colour is `color` (no RMH texture), height_scale kDefaultHeightScale of
  /// its cube.
  static MaterialTexture from_color(OctreeTexture color);
  /// The RMH texture, made (the same start tree as OctreeTexture::create over `surface`, every
  /// texel at `defaults`) when absent. Precondition: `surface` is the painted mesh's.
  OctreeTexture& ensure_rmh(const class PaintSurface& surface, const MaterialDefaults& defaults);
  /// The defaults stored in the RMH texture's background (MaterialDefaults{} without one).
  MaterialDefaults defaults() const;
  /// Pool bytes of both textures.
  size_t bytes() const;
  bool operator==(const MaterialTexture& o) const = default;
};

/// The RMH background for these defaults: channels in RGB, alpha 0. Throws InputError naming the
/// channel when a value is outside [0, 1] or not finite. O(1).
Rgba8 rmh_background(const MaterialDefaults& d);
/// Channel values (roughness, metallic, height) of an RMH lookup `rgba` (straight, [0,1]) over the
/// defaults in `background`: rgb * a + default * (1 - a). O(1).
std::array<float, 3> material_value(const float rgba[4], Rgba8 background);

}  // namespace limn
