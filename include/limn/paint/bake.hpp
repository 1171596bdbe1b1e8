// limn paint: baking an octree texture into per-vertex colours or into a UV texture image.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/paint/texture.hpp"

namespace limn {

struct BakeOptions {
  bool filtered = true;  ///< trilinear at leaf level (OctreeSampler::filtered), else nearest
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

/// Bakes into the mesh's UVs (OpenGL convention: v = 0 is the bottom row). Every texel whose
/// centre lies in a face's UV triangle (faces fanned) takes the lookup at the matching surface
/// point, seen along that triangle's normal; texels outside every triangle stay transparent
/// except for `gutter` rings of dilation around the charts (each new texel the mean of its filled
/// 8-neighbours), so bilinear filtering and mips do not bleed the background into seams. Throws
/// InputError when the mesh has no UVs or the size is outside 1-16384. Parallel.
/// O(W H + texels covered * depth).
Image bake_uv_texture(const OctreeTexture& t, const Mesh& mesh, int width, int height,
                      int gutter = 8, const BakeOptions& opt = {});

/// PNG bytes of an image (stb_image_write).
std::string encode_png(const Image& image);

}  // namespace limn
