#include "adaptive.hpp"

#include <fmt/format.h>

#include <cmath>
#include <sstream>

#include "../common/image_size.hpp"

namespace limn::cli {

void add_adaptive_options(CLI::App& cmd, AdaptiveOpts& a, bool render) {
  cmd.add_option("--depth", a.depth,
                 "--adaptive: isolation depth of every irregular vertex (0-12; default 3)");
  cmd.add_option("--tolerance", a.tolerance,
                 "--adaptive: screen error in pixels; picks a depth per vertex from the camera");
  cmd.add_option("--max-depth", a.max_depth, "--adaptive --tolerance: deepest level (0-12)");
  cmd.add_option("--errors", a.errors,
                 "--adaptive --tolerance: 'measured' (every end cap down to --max-depth "
                 "compared with the deepest surface), 'estimated' (per-valence constants, no "
                 "hierarchy) or 'auto' (default: measured up to 32768 cage faces)");
  cmd.add_option("--camera", a.camera,
                 "ex,ey,ez,tx,ty,tz,fovy_deg (default: frames the model from the front)");
  cmd.add_option(
      "--resolution", a.resolution,
      render ? "Image size WxH (default 1280x720)" : "Image size WxH for --tolerance (1280x720)");
  cmd.add_option("--tess", a.tess,
                 render ? "--adaptive: segments per patch edge (1-32); default: screen-space rates"
                        : "--adaptive: segments per patch edge (1-64, default 4)");
  cmd.add_option("--tess-px", a.tess_px,
                 render ? "--adaptive: about one segment per PX pixels of cage edge (default 8)"
                        : "--adaptive: screen-space tessellation, one segment per PX pixels "
                          "(camera)");
  cmd.add_flag("--depth-colors", a.depth_colors,
               render ? "--adaptive: colour each patch by its refinement level"
                      : "--adaptive: colour vertices by the level of their patch");
}

Camera parse_camera(const std::string& s, Camera c) {
  std::vector<float> v = parse_numbers(s, "--camera");
  if (v.size() != 7 || !(v[6] > 0 && v[6] < 180))
    throw InputError(
        fmt::format("--camera {}: expected ex,ey,ez,tx,ty,tz,fovy_deg (0 < fovy < 180)", s));
  for (int k = 0; k < 3; ++k) c.eye[k] = v[size_t(k)], c.target[k] = v[size_t(k) + 3];
  c.fovy_deg = v[6];
  for (float x : v)
    if (!std::isfinite(x)) throw InputError(fmt::format("--camera {}: not finite", s));
  return c;
}

void parse_resolution(const std::string& s, int& w, int& h) {
  app::parse_image_size(s, "--resolution", "1280x720", 1, 32768, w, h);
}

void check_adaptive(const AdaptiveOpts& a, int& w, int& h) {
  if (a.dynamic && a.depth >= 0) throw InputError("--depth and --tolerance exclude each other");
  if (a.errors != "auto" && a.errors != "measured" && a.errors != "estimated")
    throw InputError(
        fmt::format("--errors {}: expected 'auto', 'measured' or 'estimated'", a.errors));
  if (a.dynamic && !(a.tolerance > 0 && std::isfinite(a.tolerance)))
    throw InputError(
        fmt::format("--tolerance {}: must be a positive number of pixels", a.tolerance));
  if (a.depth > 12) throw InputError(fmt::format("--depth {}: must be 0-12", a.depth));
  if (a.max_depth < 0 || a.max_depth > 12)
    throw InputError(fmt::format("--max-depth {}: must be 0-12", a.max_depth));
  if (a.tess < 1 || a.tess > 64) throw InputError(fmt::format("--tess {}: must be 1-64", a.tess));
  w = 1280, h = 720;
  if (!a.resolution.empty()) parse_resolution(a.resolution, w, h);
}

AdaptiveSurface build_adaptive(const Mesh& cage, const AdaptiveOpts& a, int w, int h, Stopwatch& sw,
                               nlohmann::json& timings) {
  AdaptiveSurface out;
  const bool dynamic = a.dynamic;
  const int depth = a.depth >= 0 ? a.depth : 3;
  out.depth = depth, out.width = w, out.height = h;
  const SubdivOptions options = subdiv_options(cage);
  Camera& cam = out.cam;
  cam = frame_camera(cage, w, h);
  if (!a.camera.empty()) cam = parse_camera(a.camera, cam);
  VertexErrorModel& model = out.model;
  model = vertex_error_model(cage, options);
  PatchOptions po;
  po.subdiv = options;
  po.depth = dynamic ? a.max_depth : depth;
  // Measured errors: every patch down to --max-depth once, its end caps' errors measured, and
  // the view's patches selected from it (no second isolation).
  // auto: measured up to kMeasuredFaces cage faces (the hierarchy is built whole, level by level,
  // so its memory grows with the cage), estimated above.
  constexpr size_t kMeasuredFaces = 32768;
  const bool measured = dynamic && (a.errors == "measured" ||
                                    (a.errors == "auto" && cage.face_count() <= kMeasuredFaces));
  out.measured = measured;
  PatchHierarchy& hierarchy = out.hierarchy;
  if (measured) {
    hierarchy = build_patch_hierarchy(cage, po);
    timings["hierarchy"] = sw.lap();
    measure_vertex_errors(cage, hierarchy, model);
    timings["measure"] = sw.lap();
  }
  if (dynamic) {
    DepthOptions d;
    d.tolerance_px = a.tolerance;
    d.max_depth = a.max_depth;
    out.vdepth = select_depths(cage, model, cam, d, {}, {}, &out.estimate);
  } else {
    // The error the fixed depth leaves, as the same model estimates it for this camera.
    DepthOptions d;
    std::vector<uint8_t> pin(cage.vertex_count(), uint8_t(depth));
    select_depths(cage, model, cam, d, {}, pin, &out.estimate);
  }
  timings["select"] = sw.lap();
  PatchStats& ps = out.stats;
  PatchTable& table = out.table;
  if (measured) {
    table = select_patches(hierarchy, out.vdepth);
    timings["select_patches"] = sw.lap();
    for (const auto* params : {&table.regular_params, &table.gregory_params})
      for (const PatchParam& p : *params) {
        if (ps.regular_by_level.size() <= p.level) {
          ps.regular_by_level.resize(p.level + 1u, 0);
          ps.gregory_by_level.resize(p.level + 1u, 0);
        }
        ++(p.type == PatchType::gregory ? ps.gregory_by_level : ps.regular_by_level)[p.level];
      }
  } else {
    table = build_patches(cage, po, out.vdepth, &ps);
    timings["isolate"] = ps.refine_ms;
    timings["patches"] = ps.patches_ms;
    sw.lap();
  }
  out.points = (measured ? hierarchy.table : table).points(cage.positions);
  timings["points"] = sw.lap();
  return out;
}

}  // namespace limn::cli
