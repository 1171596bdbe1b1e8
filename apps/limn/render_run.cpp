// limn render's work, in the GL module (gl_commands.hpp): a PNG of a mesh, or of its adaptive
// limit surface drawn with tessellation shaders, rendered headless (EGL; Mesa's llvmpipe without
// a GPU).
#include <fmt/format.h>

#include <optional>

#include "gl_commands.hpp"
#include "limn/paint/file.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"

namespace limn::cli {

LIMN_GL_ENTRY void limn_cli_render(const RenderJob& job) {
  const int w = job.width, h = job.height;
  const float* bg = job.clear_color;
  Stopwatch sw;
  const Mesh mesh = read_input(job.mesh, job.format, job.weld);
  std::optional<OctreeTexture> texture;
  if (!job.texture.empty()) texture = load_lot(job.texture);
  nlohmann::json timings = {{"read", sw.lap()}};
  GlContext gl;
  timings["context"] = sw.lap();
  std::optional<GpuOctreeTexture> gpu_texture;
  if (texture) gpu_texture.emplace(*texture);
  RenderTarget target(w, h, job.samples);
  DrawOptions d;
  d.outline = job.wireframe;
  d.depth_colors = job.a.depth_colors;
  d.pixels_per_segment = job.pps;
  d.factor = job.fixed_tess ? job.a.tess : 0;
  d.texture = gpu_texture ? &*gpu_texture : nullptr;
  d.texture_nearest = job.nearest;
  d.uv_checker = job.uv_checker;
  if (d.uv_checker > 0 && mesh.uv_indices.empty())
    throw InputError(fmt::format("{}: --uv-checker: the mesh has no UVs", job.mesh));
  DrawStats st;
  nlohmann::json patches = nullptr;
  Camera cam;
  if (job.adaptive) {
    const AdaptiveSurface surf = build_adaptive(mesh, job.a, w, h, sw, timings);
    cam = surf.cam;
    PatchDrawer drawer(mesh, surf.table, surf.points);
    timings["upload"] = sw.lap();
    target.begin(bg);
    st = drawer.draw(cam, d);
    patches = {{"regular", surf.table.regular_params.size()},
               {"gregory", surf.table.gregory_params.size()}};
  } else {
    cam = frame_camera(mesh, w, h);
    if (!job.a.camera.empty()) cam = parse_camera(job.a.camera, cam);
    MeshDrawer drawer(mesh, {}, job.flat);
    timings["upload"] = sw.lap();
    target.begin(bg);
    st = drawer.draw(cam, d);
  }
  timings["draw"] = sw.lap();
  write_png(job.out, w, h, target.read_rgba());
  timings["write"] = sw.lap();
  if (job.json) {
    nlohmann::json j = {{"input", job.mesh},
                        {"output", job.out},
                        {"renderer", gl.renderer()},
                        {"texture", texture ? nlohmann::json(job.texture) : nlohmann::json()},
                        {"resolution", {w, h}},
                        {"camera",
                         {{"eye", {cam.eye[0], cam.eye[1], cam.eye[2]}},
                          {"target", {cam.target[0], cam.target[1], cam.target[2]}},
                          {"fovy_deg", cam.fovy_deg}}},
                        {"drawn", st.patches},
                        {"patches", patches},
                        {"triangles", st.triangles},
                        {"gpu_ms", st.gpu_ms},
                        {"cpu_draw_ms", st.cpu_ms},
                        {"timings_ms", timings}};
    fmt::print("{}\n", j.dump(2));
  } else {
    fmt::print("{} -> {}: {} {} drawn, {} triangles, {}x{} ({:.1f} ms)\n", job.mesh, job.out,
               st.patches, job.adaptive ? "patches" : "polygons", st.triangles, w, h, sw.ms());
  }
}

}  // namespace limn::cli
