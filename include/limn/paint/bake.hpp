// limn paint: baking an octree texture into per-vertex colours or into a UV texture image.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/paint/material.hpp"

namespace limn {

struct BakeOptions {
  bool filtered = true;  ///< trilinear at leaf level (OctreeSampler::filtered), else nearest
  /// bake_uv_texture: the UDIM tile to bake (u in [tile % 10, +1], v in [tile / 10, +1]; UDIM
  /// number 1001 + tile); triangles in other tiles are left out.
  int tile = 0;
};

/// RGBA (floats in [0,1]) per vertex: the lookup at the vertex with its area-weighted normal
/// (`vertex_normals`); the background where nothing is stored. Parallel. O(V depth).
std::vector<float> bake_vertex_colors(const OctreeTexture& t, const Mesh& mesh,
                                      const BakeOptions& opt = {});

/// An RGBA8 image, rows top to bottom.
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
};

/// Bakes into the mesh's UVs (OpenGL convention: v = 0 is the bottom row of tile opt.tile). Every
/// texel whose
/// centre lies in a face's UV triangle (faces fanned) takes the lookup at the matching surface
/// point, seen along that triangle's normal; texels outside every triangle stay transparent
/// except for `gutter` rings of dilation around the charts (each new texel the mean of its filled
/// 8-neighbours), so bilinear filtering and mips do not bleed the background into seams. Throws
/// InputError when the mesh has no UVs, the size is outside 1-16384 or the tile outside 0-99.
/// Parallel.
/// O(W H + texels covered * depth).
Image bake_uv_texture(const OctreeTexture& t, const Mesh& mesh, int width, int height,
                      int gutter = 8, const BakeOptions& opt = {});

/// A one-channel 16-bit image (0-65535 over [0, 1]), rows top to bottom.
struct Image16 {
  int width = 0, height = 0;
  std::vector<uint16_t> values;
};

/// A material baked into one UV tile (empty images for what was not baked).
struct MaterialImages {
  Image base_color;  ///< as bake_uv_texture of the colour texture
  /// glTF's packing: roughness in green, metalness in blue (red and alpha 255); RMH only.
  Image metallic_roughness;
  Image16 height;  ///< RMH only
  /// Tangent-space normals of the height field (height * height_scale model units): x along +u,
  /// y along +v (glTF's and OpenGL's convention), RGB = n * 0.5 + 0.5; only when asked.
  Image normal;
};

/// Bakes every channel of a material into the mesh's UVs, as bake_uv_texture does (the same
/// texels, lookups and gutter): the channels' values over their defaults, height in float before
/// it is rounded to 16 bits (so filtering between texels does not band), and with `normal_map`
/// a normal map whose slopes are the height field's per model unit on each texel's triangle (a
/// flat one without RMH). Throws as bake_uv_texture. Parallel. O(W H + texels covered * depth).
MaterialImages bake_material(const MaterialTexture& m, const Mesh& mesh, int width, int height,
                             int gutter = 8, const BakeOptions& opt = {}, bool normal_map = false);

/// Throws InputError "TEXTURE_NAME: painted on another mesh ..." when under half of the mesh's
/// vertices (up to 4096 of them, evenly spread) fall in a leaf of the texture: the texture's
/// cells follow the surface it was made for, so another mesh mostly misses them. A subdivided,
/// simplified or unwrapped version of the painted mesh passes. O(min(V, 4096) depth).
void check_texture_fits(const OctreeTexture& t, const Mesh& mesh, const std::string& texture_name,
                        const std::string& mesh_name);

/// The UDIM tiles (0-99; UDIM number 1001 + tile) that hold the centres of the mesh's UV
/// triangles, ascending: the images bake_uv_texture makes for them hold every triangle (a
/// triangle reaching past its tile is cut at the tile's edge). `outside` (may be null) receives
/// the triangles whose centre lies outside u, v in [0, 10) (or is not a number), which no tile
/// holds. Throws InputError when the mesh has no UVs. O(corners).
std::vector<int> uv_tiles(const Mesh& mesh, size_t* outside = nullptr);

/// PNG bytes of an image (stb_image_write).
std::string encode_png(const Image& image);
/// PNG bytes of a 16-bit greyscale image. Throws std::runtime_error for an empty image.
std::string encode_png16(const Image16& image);

}  // namespace limn
