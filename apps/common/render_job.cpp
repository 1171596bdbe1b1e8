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

namespace {

DrawOptions draw_options(const MeshRender& o, const GpuOctreeTexture* texture,
                         const GpuOctreeTexture* rmh) {
  DrawOptions d;
  d.outline = o.wireframe;
  d.texture = texture;
  d.material = rmh;
  d.height_scale = o.height_scale;
  d.texture_nearest = o.nearest;
  d.uv_checker = o.uv_checker;
  d.depth_colors = o.depth_colors;
  d.pixels_per_segment = o.pixels_per_segment;
  d.factor = o.factor;
  return d;
}

// The steps every render shares: a context, the texture on the GPU, the target, the camera;
// `make_drawer` builds the drawer once the context is current.
template <class MakeDrawer>
RenderedImage render_with(const Mesh& mesh, const MeshRender& o, std::string_view name, Names names,
                          MakeDrawer make_drawer) {
  if (o.uv_checker > 0 && mesh.uv_indices.empty())
    throw InputError(
        fmt::format("{}: {}: the mesh has no UVs", name, option_name(names, "uv-checker")));
  GlContext gl;
  std::optional<GpuOctreeTexture> gpu_texture;
  if (o.texture) gpu_texture.emplace(*o.texture);
  std::optional<GpuOctreeTexture> gpu_rmh;
  if (o.rmh) gpu_rmh.emplace(*o.rmh);
  RenderTarget target(o.width, o.height, o.samples);
  RenderedImage out;
  out.camera = view_camera(mesh, o.width, o.height, o.camera);
  auto drawer = make_drawer();
  target.begin(o.background);
  const DrawStats st = drawer.draw(
      out.camera,
      draw_options(o, gpu_texture ? &*gpu_texture : nullptr, gpu_rmh ? &*gpu_rmh : nullptr));
  out.rgba = target.read_rgba();
  out.report = {{"renderer", gl.renderer()},         {"resolution", {o.width, o.height}},
                {"camera", camera_json(out.camera)}, {"drawn", st.patches},
                {"triangles", st.triangles},         {"gpu_ms", st.gpu_ms},
                {"cpu_draw_ms", st.cpu_ms}};
  return out;
}

}  // namespace

RenderedImage render_mesh(const Mesh& mesh, const MeshRender& o, std::string_view name,
                          Names names) {
  RenderedImage out =
      render_with(mesh, o, name, names, [&] { return MeshDrawer(mesh, {}, o.flat); });
  out.report["patches"] = nullptr;
  return out;
}

RenderedImage render_patches(const Mesh& cage, const PatchTable& table,
                             std::span<const float> points, const MeshRender& o,
                             std::string_view name, Names names) {
  RenderedImage out =
      render_with(cage, o, name, names, [&] { return PatchDrawer(cage, table, points); });
  out.report["patches"] = {{"regular", table.regular_params.size()},
                           {"gregory", table.gregory_params.size()}};
  return out;
}

}  // namespace limn::jobs
