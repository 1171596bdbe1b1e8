// Limit-surface evaluation throughput: points per second on a 9 x 9 grid of every face, limn
// (evaluate_grids on its patch table, 1 and 2 threads; and the lookup path, PatchMap +
// evaluate_patches, 1 thread) beside OpenSubdiv 3.5's two
// CPU paths in one run: Far (adaptive PatchTable with Gregory-basis end caps: PatchMap +
// EvaluateBasis + the weighted sums) and Bfr (RefinerSurfaceFactory: one Surface per face,
// PreparePatchPoints, Evaluate). Positions and first derivatives; each side's point preparation
// (refined and end-cap points) is timed with it. Cages of quads only, isolation depth 3 for limn
// and Far, Bfr at its defaults. Medians of 3.
//   limn_bench_patch_eval [--grid N]
#include <fmt/format.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <memory>

#include "osd_bench.hpp"

#include "limn/mesh/io.hpp"
#include "limn/subdiv/patches.hpp"

using namespace OpenSubdiv;
using limn::bench::now_ms;
namespace fs = std::filesystem;

namespace {

template <class F>
double median_ms(F&& f) {
  std::vector<double> t;
  for (int i = 0; i < 3; ++i) {
    const double t0 = now_ms();
    f();
    t.push_back(now_ms() - t0);
  }
  return limn::bench::median(t);
}

struct P3 {
  float x = 0, y = 0, z = 0;
  void Clear(void* = nullptr) { x = y = z = 0; }
  void AddWithWeight(const P3& p, float w) { x += w * p.x, y += w * p.y, z += w * p.z; }
};

}  // namespace

int main(int argc, char** argv) {
  int grid = 9;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--grid") && i + 1 < argc) grid = std::max(2, std::atoi(argv[++i]));
  const int depth = 3;
  const fs::path models = LIMN_SHARED_MODELS;
  fmt::print("{:<16} {:>9} {:>10} {:>10} {:>10} {:>10} {:>10} {:>9} {:>9} {:>9} {:>9}\n", "model",
             "points", "limn1t_ms", "limn2t_ms", "lookup1t", "far_ms", "bfr_ms", "far/limn",
             "bfr/limn", "bfr/l2t", "far/look");
  for (const char* name : {"quads/bigguy.obj", "quads/monsterfrog.obj"}) {
    const limn::Mesh cage = limn::read_mesh(models / name);
    std::vector<float> uv;
    for (int j = 0; j < grid; ++j)
      for (int i = 0; i < grid; ++i)
        uv.push_back(float(i) / float(grid - 1)), uv.push_back(float(j) / float(grid - 1));
    const size_t nf = cage.face_count(), per = uv.size() / 2, total = nf * per;
    std::vector<float> out(3 * total), du(3 * total), dv(3 * total);

    // limn: the table is built once (preprocessing is benchmarked elsewhere).
    limn::PatchOptions po;
    po.subdiv = limn::subdiv_options(cage);
    po.depth = depth;
    const limn::PatchTable table = limn::build_patches(cage, po);
    const limn::PatchMap map(table);
    std::vector<limn::PatchCoord> coords(total);
    auto limn_run = [&] {
      const std::vector<float> pts = table.points(cage.positions);
      for (size_t f = 0; f < nf; ++f)
        for (size_t k = 0; k < per; ++k)
          coords[f * per + k] = map.find(uint32_t(f), uv[2 * k], uv[2 * k + 1]);
      limn::evaluate_patches(table, pts, coords, out.data(), du.data(), dv.data());
    };
    // The same points, in the same order (face by face, row by row), without lookups.
    auto limn_grid = [&] {
      const std::vector<float> pts = table.points(cage.positions);
      limn::evaluate_grids(table, pts, grid, out.data(), du.data(), dv.data());
    };
    double limn1, limn2, lookup1;
    {
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      limn1 = median_ms(limn_grid);
      lookup1 = median_ms(limn_run);
    }
    limn2 = median_ms(limn_grid);

    // Far.
    const limn::bench::OsdAdaptive far = limn::bench::osd_adaptive(cage, depth, false, false);
    const Far::PatchTable* pt = far.table.get();
    const Far::PatchMap far_map(*pt);
    std::vector<P3> verts;
    limn::bench::osd_points(far, cage, verts);  // sized (and touched) outside the timing
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const double far_ms = median_ms([&] {
      limn::bench::osd_points(far, cage, verts);
      float wp[20], wu[20], wv[20];
      for (size_t f = 0; f < nf; ++f)
        for (size_t k = 0; k < per; ++k) {
          const auto* h = far_map.FindPatch(int(f), uv[2 * k], uv[2 * k + 1]);
          pt->EvaluateBasis(*h, uv[2 * k], uv[2 * k + 1], wp, wu, wv);
          const auto cvs = pt->GetPatchVertices(*h);
          P3 p, a, b;
          for (int i = 0; i < cvs.size(); ++i) {
            p.AddWithWeight(verts[size_t(cvs[i])], wp[i]);
            a.AddWithWeight(verts[size_t(cvs[i])], wu[i]);
            b.AddWithWeight(verts[size_t(cvs[i])], wv[i]);
          }
          const size_t o = 3 * (f * per + k);
          out[o] = p.x, out[o + 1] = p.y, out[o + 2] = p.z;
          du[o] = a.x, dv[o] = b.x;
        }
    });

    // Bfr.
    auto bfr_refiner = limn::bench::osd_refiner(cage);
    const Bfr::RefinerSurfaceFactory<> factory(*bfr_refiner);
    const double bfr_ms = median_ms([&] {
      Bfr::Surface<float> surface;
      std::vector<float> patch_points;
      const Bfr::Surface<float>::PointDescriptor desc(3);
      for (size_t f = 0; f < nf; ++f) {
        if (!factory.InitVertexSurface(int(f), &surface)) continue;
        patch_points.resize(3 * size_t(surface.GetNumPatchPoints()));
        surface.PreparePatchPoints(cage.positions.data(), desc, patch_points.data(), desc);
        for (size_t k = 0; k < per; ++k) {
          const size_t o = 3 * (f * per + k);
          surface.Evaluate(&uv[2 * k], patch_points.data(), desc, &out[o], &du[o], &dv[o]);
        }
      }
    });
    fmt::print(
        "{:<16} {:>9} {:>10.2f} {:>10.2f} {:>10.2f} {:>10.2f} {:>10.2f} {:>8.2f}x {:>8.2f}x "
        "{:>8.2f}x {:>8.2f}x\n",
        fs::path(name).filename().string(), total, limn1, limn2, lookup1, far_ms, bfr_ms,
        far_ms / limn1, bfr_ms / limn1, bfr_ms / limn2, far_ms / lookup1);
    std::fflush(stdout);
  }
}
