// A material whose height is known everywhere: a flat sheet facing +z with a height ramp along
// x, for the tests of normal maps and bump shading to hold against its slope.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "limn/paint/brush.hpp"
#include "paint/octree_blocks.hpp"
#include "paint_oracle.hpp"

namespace limn::test {

/// test::sheet over [x0, x1] x [x0, x1] at z = 0 (n x n quads, UVs (x, y) over [0, 1]) and a tiny
/// triangle at z = lift, UVs outside every tile, that moves the texture's cube so the sheet
/// runs through the middle of a layer of cells rather than along a face between two.
inline Mesh lifted_sheet(double x0, double x1, int n, float lift) {
  Mesh m = sheet(x0, x1, x0, x1, 0, n, true);
  const uint32_t v0 = uint32_t(m.vertex_count());
  const float c = float(0.5 * (x0 + x1));
  m.add_vertex(c, c, lift), m.add_vertex(c + 0.01f, c, lift), m.add_vertex(c, c + 0.01f, lift);
  m.add_face({v0, v0 + 1, v0 + 2});
  const uint32_t t0 = uint32_t(m.uvs.size() / 2);
  m.uvs.insert(m.uvs.end(), {20, 20, 20.1f, 20, 20, 20.1f});
  m.uv_indices.insert(m.uv_indices.end(), {t0, t0 + 1, t0 + 2});
  return m;
}

inline constexpr int kRampDepth = 6;

/// The material's RMH texture refined to kRampDepth over the surface, every sample's height byte
/// 64 + 2 i in the cells of column i (x): a ramp of 2/255 per cell width. Returns the ramp's
/// slope, height units per model unit.
inline double paint_height_ramp(MaterialTexture& mat, const PaintSurface& s) {
  OctreeTexture& rmh = mat.ensure_rmh(s, {});
  refine_surface(rmh, s, kRampDepth);
  detail::OctreeEditor ed(rmh);
  std::vector<std::pair<size_t, Rgba8>> writes;
  rmh.for_each_sample([&](const OctreeSample& x) {
    writes.push_back({x.word, pack_rgba8(128, 0, 64 + 2 * x.x, 255)});
  });
  for (auto [w, c] : writes) ed.set(uint32_t(w), c);
  recompute_averages(rmh);
  return (2.0 / 255) / (double(rmh.size()) / (1 << kRampDepth));
}

}  // namespace limn::test
