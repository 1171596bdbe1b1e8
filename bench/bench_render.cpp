// Frame time at equal screen error: the patches limn selects with a depth per vertex (measured
// errors, tolerance 0.5 px) vs classic FAS, the fixed depth (OpenSubdiv's isolation level) whose
// measured error is no larger, drawn by limn's tessellation shaders with the same screen-space
// rates (8 px per segment), and vs OpenSubdiv's own GLSL patch drawing (osdGPU: Far's adaptive
// table at that same isolation level, Gregory-basis end caps, OpenSubdiv's screen-space
// tessellation at 8 px per segment; osd_draw.hpp), over a camera path (near, mid, far). Frame
// time = draw + glFinish, median of --frames frames after one warm-up (timer queries on a
// software driver see only the submission). The error is measured as limn_bench_adaptive_depth
// does (screen_error.hpp). OpenSubdiv's image is checked against limn's fixed-depth frame at the
// same camera: their coverage masks agree on this share of the pixels either covers ("osd
// agree"). On llvmpipe only the ratios mean something. The last column: each draw's GPU time (a
// timer query, median): on a real GPU what the frame costs the GPU alone; on llvmpipe little
// more than the submission.
//   limn_bench_render [--tolerance PX] [--resolution WxH] [--frames N] [--mesh FILE]...
//                     [--shape NAME]... [--cameras near,mid,far] [--no-osd] [--profile]
//                     [--fastest] [--osd-chunk N] [--zoom Z]... [--json FILE]
// --zoom adds a camera at Z times the framing distance (label xZ; --cameras none: only those).
// --mesh / --shape replace the default models (BigGuy, MonsterFrog); --shape takes limn's
// procedural shapes (limn shape --help: terrain is the 801k-quad terrain). --profile adds, per
// view, the regular patches and the end caps of both limn tables drawn apart, with and without
// rasterisation (GL_RASTERIZER_DISCARD), and their triangles. --fastest reports each draw's
// fastest frame instead of the median (on a machine shared with other work, the least disturbed).
// --osd-chunk: patches per OpenSubdiv draw call (default: 32 on llvmpipe, as limn's drawer, else
// whole patch arrays). --json: the table's rows and the renderer, also as JSON (scripts/gpu-bench).
#include <epoxy/gl.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"
#include "osd_draw.hpp"
#include "screen_error.hpp"

using namespace limn;
namespace fs = std::filesystem;

namespace {

struct Frame {
  double ms = 0;
  double gpu_ms = 0;  ///< the draw's GPU time (timer query; on llvmpipe only the submission)
  uint64_t triangles = 0;
  std::vector<uint8_t> mask;  ///< covered pixels of the last frame
};

std::vector<uint8_t> coverage(RenderTarget& target) {
  const std::vector<uint8_t> rgba = target.read_rgba();
  std::vector<uint8_t> m(rgba.size() / 4);
  for (size_t i = 0; i < m.size(); ++i)
    m[i] = rgba[4 * i] != 255 || rgba[4 * i + 1] != 255 || rgba[4 * i + 2] != 255;
  return m;
}

// The share of the pixels either mask covers on which both agree (as the render tests count).
double agreement(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  size_t differ = 0, covered = 0;
  for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i], covered += a[i] || b[i];
  return covered ? 1.0 - double(differ) / double(covered) : 1.0;
}

struct Drawn {
  uint64_t triangles = 0;
  double gpu_ms = 0;
};
using Draw = std::function<Drawn()>;  // draws one frame

// Frame time of each draw (the median, or the fastest frame with `fastest`) after one warm-up
// round (compiles and uploads). The draws take turns frame by frame, so that load from other
// processes falls on all of them alike. With `masks`, one more untimed round records each draw's
// coverage.
bool fastest = false;  // --fastest

std::vector<Frame> time_frames(RenderTarget& target, int frames, const std::vector<Draw>& draws,
                               bool masks = false) {
  const float white[4] = {1, 1, 1, 1};
  std::vector<std::vector<double>> ms(draws.size()), gpu(draws.size());
  std::vector<Frame> out(draws.size());
  for (int i = 0; i <= frames; ++i)
    for (size_t j = 0; j < draws.size(); ++j) {
      target.begin(white);
      target.finish();
      const auto t0 = std::chrono::steady_clock::now();
      const Drawn d = draws[j]();
      target.finish();
      out[j].triangles = d.triangles;
      if (i > 0) {
        ms[j].push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count());
        gpu[j].push_back(d.gpu_ms);
      }
    }
  for (size_t j = 0; j < draws.size(); ++j) {
    std::sort(ms[j].begin(), ms[j].end());
    std::sort(gpu[j].begin(), gpu[j].end());
    out[j].ms = fastest ? ms[j][0] : ms[j][ms[j].size() / 2];
    out[j].gpu_ms = fastest ? gpu[j][0] : gpu[j][gpu[j].size() / 2];
    if (masks) {
      target.begin(white);
      draws[j]();
      out[j].mask = coverage(target);
    }
  }
  return out;
}

// A draw of a limn table by its own drawer.
Draw limn_draw(std::vector<std::unique_ptr<PatchDrawer>>& keep, const Mesh& cage,
               const PatchTable& t, std::span<const float> points, const Camera& cam,
               bool discard = false) {
  keep.push_back(std::make_unique<PatchDrawer>(cage, t, points));
  PatchDrawer* d = keep.back().get();
  return [d, cam, discard] {
    if (discard) glEnable(GL_RASTERIZER_DISCARD);
    const DrawStats st = d->draw(cam, DrawOptions{});
    if (discard) glDisable(GL_RASTERIZER_DISCARD);
    return Drawn{st.triangles, st.gpu_ms};
  };
}

// The table with only its regular patches (gregory = false) or only its end caps.
PatchTable only(const PatchTable& t, bool gregory) {
  PatchTable o = t;
  if (gregory)
    o.regular_params.clear(), o.regular_points.clear();
  else
    o.gregory_params.clear(), o.gregory_points.clear();
  return o;
}

// Per patch type and together, with and without rasterisation: where the time of a limn table
// goes.
void profile(const char* what, const Mesh& cage, const PatchTable& t, std::span<const float> pts,
             const Camera& cam, RenderTarget& target, int frames) {
  const PatchTable parts[3] = {only(t, false), only(t, true), t};
  const char* names[3] = {"regular", "end caps", "all"};
  std::vector<std::unique_ptr<PatchDrawer>> keep;
  std::vector<Draw> draws;
  for (const PatchTable& part : parts)
    for (bool discard : {false, true})
      draws.push_back(limn_draw(keep, cage, part, pts, cam, discard));
  const std::vector<Frame> f = time_frames(target, frames, draws);
  for (int k = 0; k < 3; ++k) {
    const size_t n = parts[k].patch_count();
    if (!n) continue;
    const Frame& full = f[size_t(2 * k)];
    const Frame& geo = f[size_t(2 * k + 1)];
    fmt::print(
        "  {} {}: {} patches, {} triangles ({:.1f} per patch), {:.1f} ms drawn, {:.1f} ms "
        "without rasterisation ({:.2f} us per patch, {:.3f} us per triangle)\n",
        what, names[k], n, full.triangles, double(full.triangles) / double(n), full.ms, geo.ms,
        1e3 * geo.ms / double(n), 1e3 * geo.ms / double(std::max<uint64_t>(full.triangles, 1)));
  }
  std::fflush(stdout);
}

struct Model {
  std::string name;
  Mesh cage;
};

}  // namespace

int main(int argc, char** argv) {
  float tolerance = 0.5f;
  int w = 1280, h = 720, frames = 5;
  bool run_osd = true, run_profile = false;
  size_t osd_chunk = 0;  // patches per OpenSubdiv draw call; 0: as limn's drawer
  std::vector<Model> models;
  std::string cameras = "near,mid,far";
  std::vector<std::string> labels;  // extra camera stops (--zoom)
  std::vector<float> zooms;
  std::string json_path;
  for (int i = 1; i < argc; ++i) {
    const bool more = i + 1 < argc;
    if (!std::strcmp(argv[i], "--tolerance") && more) tolerance = float(std::atof(argv[++i]));
    if (!std::strcmp(argv[i], "--resolution") && more) std::sscanf(argv[++i], "%dx%d", &w, &h);
    if (!std::strcmp(argv[i], "--frames") && more) frames = std::max(1, std::atoi(argv[++i]));
    if (!std::strcmp(argv[i], "--cameras") && more) cameras = argv[++i];
    if (!std::strcmp(argv[i], "--zoom") && more) {
      labels.push_back(fmt::format("x{}", argv[++i]));
      zooms.push_back(float(std::atof(argv[i])));
    }
    if (!std::strcmp(argv[i], "--no-osd")) run_osd = false;
    if (!std::strcmp(argv[i], "--profile")) run_profile = true;
    if (!std::strcmp(argv[i], "--fastest")) fastest = true;
    if (!std::strcmp(argv[i], "--json") && more) json_path = argv[++i];
    if (!std::strcmp(argv[i], "--osd-chunk") && more) osd_chunk = size_t(std::atoll(argv[++i]));
    if (!std::strcmp(argv[i], "--mesh") && more) {
      const fs::path p = argv[++i];
      models.push_back({p.stem().string(), read_mesh(p)});
    }
    if (!std::strcmp(argv[i], "--shape") && more) {
      const std::string name = argv[++i];
      models.push_back({name, make_shape(name)});
    }
  }
  if (models.empty()) {
    const fs::path dir = LIMN_SHARED_MODELS;
    for (const char* name : {"quads/bigguy.obj", "quads/monsterfrog.obj"})
      models.push_back({fs::path(name).stem().string(), read_mesh(dir / name)});
  }
  GlContext gl;
  RenderTarget target(w, h, 1);
  // Patches per draw call, as limn's PatchDrawer picks it (llvmpipe mixes up per-patch data in
  // larger draws).
  const size_t chunk = osd_chunk                                             ? osd_chunk
                       : gl.renderer().find("llvmpipe") != std::string::npos ? 32
                                                                             : SIZE_MAX;
  fmt::print("renderer: {}, {}x{}, tolerance {} px, {} of {} frames\n\n", gl.renderer(), w, h,
             tolerance, fastest ? "fastest" : "median", frames);
  nlohmann::json json = {{"renderer", gl.renderer()},
                         {"resolution", {w, h}},
                         {"tolerance_px", tolerance},
                         {"frames", frames},
                         {"statistic", fastest ? "fastest" : "median"},
                         {"rows", nlohmann::json::array()}};
  fmt::print(
      "| model | camera | dynamic patches | dynamic err px | dynamic triangles | dynamic ms | "
      "fixed L | fixed patches | fixed err px | fixed triangles | fixed ms | osd patches | osd "
      "triangles | osd ms | osd agree | fixed / dynamic | osd / dynamic | GPU ms dynamic / fixed / "
      "osd |\n");
  fmt::print(
      "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
      "\n");
  for (const Model& model : models) {
    const Mesh& cage = model.cage;
    PatchOptions po;
    po.subdiv = subdiv_options(cage);
    po.depth = 10;
    bench::Reference ref{build_patches(cage, po), {}};
    ref.points = ref.table.points(cage.positions);
    VertexErrorModel errors = vertex_error_model(cage, po.subdiv);
    const PatchHierarchy hierarchy = build_patch_hierarchy(cage, po);
    measure_vertex_errors(cage, hierarchy, errors);
    const std::vector<float> hpoints = hierarchy.table.points(cage.positions);
    const Camera framed = frame_camera(cage, w, h);
    std::vector<bench::PathStop> stops;
    for (const bench::PathStop& stop : bench::kCameraPath)
      if (cameras.find(stop.label) != std::string::npos) stops.push_back(stop);
    for (size_t k = 0; k < zooms.size(); ++k) stops.push_back({labels[k].c_str(), zooms[k]});
    for (const auto& [label, zoom] : stops) {
      const Camera cam = bench::path_camera(framed, zoom);
      DepthOptions d;
      d.tolerance_px = tolerance;
      d.max_depth = 10;
      const std::vector<uint8_t> depth = select_depths(cage, errors, cam, d);
      const PatchTable dyn = select_patches(hierarchy, depth);
      po.depth = 10;
      const double dyn_err = bench::measured_error(cage, build_patches(cage, po, depth), ref, cam);
      int L = 0;
      PatchTable fixed;
      double fixed_err = 0;
      for (L = 0; L <= 10; ++L) {
        po.depth = L;
        fixed = build_patches(cage, po);
        fixed_err = bench::measured_error(cage, fixed, ref, cam);
        if (fixed_err <= dyn_err) break;
      }
      const std::vector<float> fpoints = fixed.points(cage.positions);
      std::vector<std::unique_ptr<PatchDrawer>> keep;
      std::vector<Draw> draws = {limn_draw(keep, cage, dyn, hpoints, cam),
                                 limn_draw(keep, cage, fixed, fpoints, cam)};
      std::unique_ptr<bench::OsdGlDrawer> osd;
      if (run_osd) {
        osd = std::make_unique<bench::OsdGlDrawer>(cage, L);
        draws.push_back([&] {
          const bench::OsdGlDrawer::Stats st =
              osd->draw(cam, DrawOptions{}.pixels_per_segment, chunk);
          return Drawn{st.triangles, st.gpu_ms};
        });
      }
      const std::vector<Frame> f = time_frames(target, frames, draws, run_osd);
      const Frame &fd = f[0], &ff = f[1];
      std::string osd_cols = "- | - | - | - | -";
      if (run_osd)
        osd_cols = fmt::format("{} | {} | {:.1f} | {:.2f}% | {:.2f}x", osd->stats().patches,
                               f[2].triangles, f[2].ms, 100.0 * agreement(f[2].mask, ff.mask),
                               f[2].ms / fd.ms);
      fmt::print(
          "| {} | {} | {} | {:.3f} | {} | {:.1f} | {} | {} | {:.3f} | {} | {:.1f} | {} | {:.2f}x "
          "| {} | {:.2f} / {:.2f} / {} |\n",
          model.name, label, dyn.patch_count(), dyn_err, fd.triangles, fd.ms, L,
          fixed.patch_count(), fixed_err, ff.triangles, ff.ms,
          osd_cols.substr(0, osd_cols.rfind(" | ")), ff.ms / fd.ms,
          osd_cols.substr(osd_cols.rfind(" | ") + 3), fd.gpu_ms, ff.gpu_ms,
          run_osd ? fmt::format("{:.2f}", f[2].gpu_ms) : "-");
      std::fflush(stdout);
      nlohmann::json row = {{"model", model.name},
                            {"camera", label},
                            {"dynamic",
                             {{"patches", dyn.patch_count()},
                              {"error_px", dyn_err},
                              {"triangles", fd.triangles},
                              {"ms", fd.ms},
                              {"gpu_ms", fd.gpu_ms}}},
                            {"fixed",
                             {{"level", L},
                              {"patches", fixed.patch_count()},
                              {"error_px", fixed_err},
                              {"triangles", ff.triangles},
                              {"ms", ff.ms},
                              {"gpu_ms", ff.gpu_ms}}}};
      if (run_osd)
        row["osd"] = {{"patches", osd->stats().patches},
                      {"triangles", f[2].triangles},
                      {"ms", f[2].ms},
                      {"gpu_ms", f[2].gpu_ms},
                      {"coverage_agreement", agreement(f[2].mask, ff.mask)}};
      json["rows"].push_back(row);
      if (!json_path.empty()) std::ofstream(json_path) << json.dump(2) << "\n";
      if (run_profile) {
        profile("dynamic", cage, dyn, hpoints, cam, target, frames);
        profile("fixed", cage, fixed, fpoints, cam, target, frames);
      }
    }
  }
}
