// limn render's work, in the GL module (gl_commands.hpp): a PNG of a mesh, or of its adaptive
// limit surface drawn with tessellation shaders, rendered headless (EGL; Mesa's llvmpipe without
// a GPU).
#include <fmt/format.h>

#include <optional>

#include "../common/render_job.hpp"
#include "gl_commands.hpp"
#include "limn/paint/file.hpp"
#include "limn/render/image.hpp"

namespace limn::cli {

LIMN_GL_ENTRY void limn_cli_render(const RenderJob& job) {
  const int w = job.width, h = job.height;
  Stopwatch sw;
  const Mesh mesh = read_input(job.mesh, job.format, job.weld);
  std::optional<MaterialTexture> texture;
  if (!job.texture.empty()) texture = load_lot(job.texture);
  nlohmann::json timings = {{"read", sw.lap()}};
  jobs::MeshRender r;
  r.width = w, r.height = h, r.samples = job.samples;
  std::copy(job.clear_color, job.clear_color + 4, r.background);
  r.flat = job.flat, r.wireframe = job.wireframe, r.uv_checker = job.uv_checker;
  r.texture = texture ? &texture->color : nullptr;
  r.rmh = texture && texture->rmh ? &*texture->rmh : nullptr;
  r.height_scale = texture ? texture->height_scale : 0.0f;
  r.nearest = job.nearest;
  jobs::RenderedImage image;
  if (job.adaptive) {
    const AdaptiveSurface surf = build_adaptive(mesh, job.a, w, h, sw, timings);
    r.camera = surf.cam;
    r.depth_colors = job.a.depth_colors;
    r.pixels_per_segment = job.pps;
    r.factor = job.fixed_tess ? job.a.tess : 0;
    image = jobs::render_patches(mesh, surf.table, surf.points, r, job.mesh, jobs::Names::cli);
  } else {
    if (!job.a.camera.empty()) r.camera = parse_camera(job.a.camera, Camera{});
    image = jobs::render_mesh(mesh, r, job.mesh, jobs::Names::cli);
  }
  std::vector<uint8_t> rgba = std::move(image.rgba);
  nlohmann::json report = std::move(image.report);
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
