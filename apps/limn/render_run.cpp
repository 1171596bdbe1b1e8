// limn render's work, in the GL module (gl_commands.hpp): a PNG of a mesh, or of its adaptive
// limit surface drawn with tessellation shaders, rendered headless (EGL; Mesa's llvmpipe without
// a GPU).
#include <fmt/format.h>

#include <optional>

#include "../common/render_job.hpp"
#include "gl_commands.hpp"
#include "limn/paint/file.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"

namespace limn::cli {

LIMN_GL_ENTRY void limn_cli_render(const RenderJob& job) {
  const int w = job.width, h = job.height;
  Stopwatch sw;
  const Mesh mesh = read_input(job.mesh, job.format, job.weld);
  std::optional<OctreeTexture> texture;
  if (!job.texture.empty()) texture = load_lot(job.texture);
  nlohmann::json timings = {{"read", sw.lap()}};
  nlohmann::json report;
  std::vector<uint8_t> rgba;
  if (job.adaptive) {
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
    const AdaptiveSurface surf = build_adaptive(mesh, job.a, w, h, sw, timings);
    PatchDrawer drawer(mesh, surf.table, surf.points);
    timings["upload"] = sw.lap();
    target.begin(job.clear_color);
    const DrawStats st = drawer.draw(surf.cam, d);
    rgba = target.read_rgba();
    report = {{"renderer", gl.renderer()},
              {"resolution", {w, h}},
              {"camera", jobs::camera_json(surf.cam)},
              {"drawn", st.patches},
              {"patches",
               {{"regular", surf.table.regular_params.size()},
                {"gregory", surf.table.gregory_params.size()}}},
              {"triangles", st.triangles},
              {"gpu_ms", st.gpu_ms},
              {"cpu_draw_ms", st.cpu_ms}};
  } else {
    jobs::MeshRender r;
    r.width = w, r.height = h, r.samples = job.samples;
    std::copy(job.clear_color, job.clear_color + 4, r.background);
    if (!job.a.camera.empty()) r.camera = parse_camera(job.a.camera, Camera{});
    r.flat = job.flat, r.wireframe = job.wireframe, r.uv_checker = job.uv_checker;
    r.texture = texture ? &*texture : nullptr;
    r.nearest = job.nearest;
    jobs::RenderedImage image = jobs::render_mesh(mesh, r, job.mesh, jobs::Names::cli);
    rgba = std::move(image.rgba);
    report = std::move(image.report);
    report["patches"] = nullptr;
  }
  timings["draw"] = sw.lap();
  write_png(job.out, w, h, rgba);
  timings["write"] = sw.lap();
  if (job.json) {
    report["input"] = job.mesh;
    report["output"] = job.out;
    report["texture"] = texture ? nlohmann::json(job.texture) : nlohmann::json();
    report["timings_ms"] = timings;
    fmt::print("{}\n", report.dump(2));
  } else {
    fmt::print("{} -> {}: {} {} drawn, {} triangles, {}x{} ({:.1f} ms)\n", job.mesh, job.out,
               report["drawn"].get<size_t>(), job.adaptive ? "patches" : "polygons",
               report["triangles"].get<uint64_t>(), w, h, sw.ms());
  }
}

}  // namespace limn::cli
