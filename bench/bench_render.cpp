// Frame time at equal screen error: the patches limn selects with a depth per vertex (measured
// errors, tolerance 0.5 px) vs classic FAS, the fixed depth (OpenSubdiv's isolation level) whose
// measured error is no larger, both drawn by limn's tessellation shaders with the same
// screen-space rates (8 px per segment), over a camera path (near, mid, far) on the FAS cages.
// Frame time = draw + glFinish, median of --frames frames after one warm-up (timer queries on a
// software driver see only the submission). The error is measured as limn_bench_adaptive_depth
// does (screen_error.hpp). On llvmpipe only the ratios mean something.
//   limn_bench_render [--tolerance PX] [--resolution WxH] [--frames N]
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <vector>

#include "limn/mesh/io.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"
#include "screen_error.hpp"

using namespace limn;
namespace fs = std::filesystem;

namespace {

struct Frame {
  double ms = 0;
  uint64_t triangles = 0;
};

Frame time_frames(const Mesh& cage, const PatchTable& t, std::span<const float> points,
                  const Camera& cam, RenderTarget& target, int frames) {
  PatchDrawer drawer(cage, t, points);
  DrawOptions o;
  const float white[4] = {1, 1, 1, 1};
  std::vector<double> ms;
  Frame f;
  for (int i = 0; i <= frames; ++i) {
    target.begin(white);
    target.finish();
    const auto t0 = std::chrono::steady_clock::now();
    f.triangles = drawer.draw(cam, o).triangles;
    target.finish();
    const double m =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (i > 0) ms.push_back(m);  // the first frame compiles and uploads
  }
  std::sort(ms.begin(), ms.end());
  f.ms = ms[ms.size() / 2];
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  float tolerance = 0.5f;
  int w = 1280, h = 720, frames = 5;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--tolerance") && i + 1 < argc)
      tolerance = float(std::atof(argv[++i]));
    if (!std::strcmp(argv[i], "--resolution") && i + 1 < argc)
      std::sscanf(argv[++i], "%dx%d", &w, &h);
    if (!std::strcmp(argv[i], "--frames") && i + 1 < argc)
      frames = std::max(1, std::atoi(argv[++i]));
  }
  GlContext gl;
  RenderTarget target(w, h, 1);
  fmt::print("renderer: {}, {}x{}, tolerance {} px, median of {} frames\n\n", gl.renderer(), w, h,
             tolerance, frames);
  fmt::print(
      "| model | camera | dynamic patches | dynamic err px | dynamic triangles | dynamic ms | "
      "fixed L | fixed patches | fixed err px | fixed triangles | fixed ms | fixed / dynamic |\n");
  fmt::print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  const fs::path models = LIMN_SHARED_MODELS;
  for (const char* name : {"quads/bigguy.obj", "quads/monsterfrog.obj"}) {
    const Mesh cage = read_mesh(models / name);
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
    for (const auto& [label, zoom] : bench::kCameraPath) {
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
      const Frame fd = time_frames(cage, dyn, hpoints, cam, target, frames);
      const Frame ff = time_frames(cage, fixed, fixed.points(cage.positions), cam, target, frames);
      fmt::print(
          "| {} | {} | {} | {:.3f} | {} | {:.1f} | {} | {} | {:.3f} | {} | {:.1f} | {:.2f}x |\n",
          fs::path(name).stem().string(), label, dyn.patch_count(), dyn_err, fd.triangles, fd.ms, L,
          fixed.patch_count(), fixed_err, ff.triangles, ff.ms, ff.ms / fd.ms);
      std::fflush(stdout);
    }
  }
}
