// Patches at equal screen error: view-dependent depth per vertex (limn select_depths, tolerance
// 0.5 px) vs the fixed depth (classic FAS / OpenSubdiv's isolation level) needed for the same
// measured error, over a camera path (near, mid, far) on the FAS cages. Two rows per view: the
// depths from the per-valence estimate ("model"), and from the errors measured on the hierarchy
// (measure_vertex_errors, "measured"). sel_ms: what a view
// change costs (select_depths + select_patches from a hierarchy built once). The error is measured:
// 3 x 3 samples on every patch, against a reference table of depth 10 (regular patches are
// exact, its end caps are 2^-10 of a face), in pixels at the sample (visible samples only).
//   limn_bench_adaptive_depth [--tolerance PX] [--resolution WxH]
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "limn/io/mesh_io.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"
#include "screen_error.hpp"

using namespace limn;
using limn::bench::measured_error;
using limn::bench::Reference;
namespace fs = std::filesystem;

int main(int argc, char** argv) {
  float tolerance = 0.5f;
  int w = 1920, h = 1080;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--tolerance") && i + 1 < argc)
      tolerance = float(std::atof(argv[++i]));
    if (!std::strcmp(argv[i], "--resolution") && i + 1 < argc)
      std::sscanf(argv[++i], "%dx%d", &w, &h);
  }
  const fs::path models = LIMN_SHARED_MODELS;
  fmt::print("{:<16} {:>6} {:>9} {:>10} {:>11} {:>9} {:>11} {:>11} {:>9} {:>8}\n", "model",
             "camera", "errors", "dyn_patch", "dyn_err_px", "fixed_L", "fixed_patch", "fixed_err",
             "fewer", "sel_ms");
  for (const char* name : {"quads/bigguy.obj", "quads/monsterfrog.obj"}) {
    const Mesh cage = read_mesh(models / name);
    PatchOptions po;
    po.subdiv = subdiv_options(cage);
    po.depth = 10;
    Reference ref{build_patches(cage, po), {}};
    ref.points = ref.table.points(cage.positions);
    const VertexErrorModel model = vertex_error_model(cage, po.subdiv);
    VertexErrorModel measured = model;
    // The hierarchy to depth 10: built once; every view only selects from it.
    const auto th = std::chrono::steady_clock::now();
    const PatchHierarchy hierarchy = build_patch_hierarchy(cage, po);
    const double hier_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - th).count();
    const auto tm = std::chrono::steady_clock::now();
    measure_vertex_errors(cage, hierarchy, measured);
    const double measure_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tm).count();
    fmt::print(
        "{:<16} hierarchy to depth 10: {} nodes, {} patches, built in {:.1f} ms, errors "
        "measured in {:.1f} ms\n",
        fs::path(name).filename().string(), hierarchy.node_count(), hierarchy.table.patch_count(),
        hier_ms, measure_ms);
    const Camera framed = frame_camera(cage, w, h);
    for (const auto& [label, zoom] : bench::kCameraPath)
      for (const bool measure : {false, true}) {
        const Camera cam = bench::path_camera(framed, zoom);
        DepthOptions d;
        d.tolerance_px = tolerance;
        d.max_depth = 10;
        const auto t0 = std::chrono::steady_clock::now();
        const std::vector<uint8_t> depth = select_depths(cage, measure ? measured : model, cam, d);
        const PatchTable chosen = select_patches(hierarchy, depth);
        const double sel_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count();
        if (chosen.patch_count() == 0) return 1;
        po.depth = 10;
        const PatchTable dyn = build_patches(cage, po, depth);
        const double dyn_err = measured_error(cage, dyn, ref, cam);
        // The shallowest fixed depth whose measured error is no larger.
        int L = 0;
        size_t fixed_patches = 0;
        double fixed_err = 0;
        for (L = 0; L <= 10; ++L) {
          po.depth = L;
          const PatchTable f = build_patches(cage, po);
          fixed_err = measured_error(cage, f, ref, cam);
          fixed_patches = f.patch_count();
          if (fixed_err <= dyn_err) break;
        }
        fmt::print(
            "{:<16} {:>6} {:>9} {:>10} {:>11.3f} {:>9} {:>11} {:>11.3f} {:>8.0f}% {:>8.3f}\n",
            fs::path(name).filename().string(), label, measure ? "measured" : "model",
            dyn.patch_count(), dyn_err, L, fixed_patches, fixed_err,
            100.0 * (1.0 - double(dyn.patch_count()) / double(fixed_patches)), sel_ms);
        std::fflush(stdout);
      }
  }
}
