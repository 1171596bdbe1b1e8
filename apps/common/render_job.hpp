// `limn render MESH` (without --adaptive) on a mesh in memory: the image as RGBA8 pixels, shared
// by the CLI's GL module and the Python module so both draw the same pixels.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "jobs.hpp"
#include "limn/mesh/mesh.hpp"
#include "limn/paint/texture.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"

namespace limn::jobs {

struct MeshRender {
  int width = 1280, height = 720, samples = 4;
  float background[4] = {1, 1, 1, 1};
  std::optional<Camera> camera;  ///< eye, target, fovy (view_camera); none: the mesh framed
  bool flat = false, wireframe = false;
  float uv_checker = 0;                    ///< squares per UV unit; 0: off
  const OctreeTexture* texture = nullptr;  ///< colour from a painted texture
  bool nearest = false;                    ///< texture: nearest texel, not filtered
  /// The painted material's RMH texture (null: none) and height scale: PBR shading and bumps.
  const OctreeTexture* rmh = nullptr;
  float height_scale = 0;
  // Patches only (render_patches):
  bool depth_colors = false;        ///< colour by refinement level
  float pixels_per_segment = 8.0f;  ///< screen-space tessellation, unless factor > 0
  int factor = 0;                   ///< segments per patch edge (1-32); 0: screen-space
};

struct RenderedImage {
  std::vector<uint8_t> rgba;  ///< rows top to bottom
  Camera camera;              ///< the camera drawn from
  nlohmann::json report;      ///< renderer, polygons drawn, triangles, GPU and CPU ms, camera
};

/// Draws `mesh` headless (EGL; llvmpipe without a GPU). InputError for the UV checker on a mesh
/// without UVs; std::runtime_error when no OpenGL 4.5 context can be made.
RenderedImage render_mesh(const Mesh& mesh, const MeshRender& options, std::string_view name,
                          Names names);

/// `limn render --adaptive`: a patch table (its points from `points`, as PatchTable::points or
/// a hierarchy's for a selection) drawn with tessellation shaders. The report counts patches
/// (regular, gregory) instead of polygons.
RenderedImage render_patches(const Mesh& cage, const PatchTable& table,
                             std::span<const float> points, const MeshRender& options,
                             std::string_view name, Names names);

/// A camera's report: eye, target, fovy_deg.
nlohmann::json camera_json(const Camera& c);

}  // namespace limn::jobs
