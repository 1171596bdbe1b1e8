#include "render_job.hpp"

#include <fmt/format.h>

#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"

namespace limn::jobs {

nlohmann::json camera_json(const Camera& c) {
  return {{"eye", {c.eye[0], c.eye[1], c.eye[2]}},
          {"target", {c.target[0], c.target[1], c.target[2]}},
          {"fovy_deg", c.fovy_deg}};
}

RenderedImage render_mesh(const Mesh& mesh, const MeshRender& o, std::string_view name,
                          Names names) {
  if (o.uv_checker > 0 && mesh.uv_indices.empty())
    throw InputError(
        fmt::format("{}: {}: the mesh has no UVs", name, option_name(names, "uv-checker")));
  GlContext gl;
  std::optional<GpuOctreeTexture> gpu_texture;
  if (o.texture) gpu_texture.emplace(*o.texture);
  RenderTarget target(o.width, o.height, o.samples);
  DrawOptions d;
  d.outline = o.wireframe;
  d.texture = gpu_texture ? &*gpu_texture : nullptr;
  d.texture_nearest = o.nearest;
  d.uv_checker = o.uv_checker;
  RenderedImage out;
  out.camera = frame_camera(mesh, o.width, o.height);
  if (o.camera) {
    for (int k = 0; k < 3; ++k) out.camera.eye[k] = o.camera->eye[k];
    for (int k = 0; k < 3; ++k) out.camera.target[k] = o.camera->target[k];
    out.camera.fovy_deg = o.camera->fovy_deg;
  }
  MeshDrawer drawer(mesh, {}, o.flat);
  target.begin(o.background);
  const DrawStats st = drawer.draw(out.camera, d);
  out.rgba = target.read_rgba();
  out.report = {{"renderer", gl.renderer()},         {"resolution", {o.width, o.height}},
                {"camera", camera_json(out.camera)}, {"drawn", st.patches},
                {"triangles", st.triangles},         {"gpu_ms", st.gpu_ms},
                {"cpu_draw_ms", st.cpu_ms}};
  return out;
}

}  // namespace limn::jobs
