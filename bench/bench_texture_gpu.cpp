// Octree-texture lookups on the GPU beside the CPU's, in one run: the same texture (the whole
// surface filled at depth D, then 12 painted strokes of other colours), the same points (random
// surface points with their face normals, in random order), looked up by
// GpuOctreeTexture::lookup (the drawers' GLSL in a compute shader: points up, nearest and
// filtered results down, one call) and by OctreeSampler::nearest_batch + filtered_batch on all of
// TBB's threads (a sampler per chunk of points, an OctreeIndex for the random walks). Before
// timing, every GPU result is checked against the CPU's (nearest equal, filtered within 1e-4):
// a mismatch is printed and makes the exit status 1. Reported: lookups per second (each point
// both lookups) for the GPU's whole call ("call": transfers included), its dispatch alone
// ("shader": a GL timer query) and the CPU, with the ratios. On a software driver (llvmpipe)
// the "GPU" is this CPU too: only a real GPU's figures mean anything (scripts/gpu-bench).
//   limn_bench_texture_gpu [--mesh FILE]... [--depth D] [--points N] [--reps N] [--json FILE]
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "clock.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/texture.hpp"
#include "paint_scene.hpp"

namespace fs = std::filesystem;
using namespace limn;

namespace {

using bench::median;
using bench::now_ms;

struct CpuResults {
  std::vector<Rgba8> nearest;
  std::vector<uint8_t> nearest_found;
  std::vector<float> filtered;
  std::vector<uint8_t> filtered_found;
};

// Both lookups of every point on TBB's threads, a sampler per chunk of 4096 points.
void cpu_lookups(const OctreeTexture& t, const OctreeIndex& index, const std::vector<float>& p,
                 const std::vector<float>& n, CpuResults& r) {
  const size_t count = p.size() / 3;
  r.nearest.resize(count), r.nearest_found.resize(count);
  r.filtered.resize(4 * count), r.filtered_found.resize(count);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, count, 4096), [&](const tbb::blocked_range<size_t>& b) {
        OctreeSampler s(t, &index);
        const size_t i = b.begin(), m = b.size();
        s.nearest_batch(&p[3 * i], &n[3 * i], m, &r.nearest[i], &r.nearest_found[i]);
        s.filtered_batch(&p[3 * i], &n[3 * i], m, 0.0f, &r.filtered[4 * i], &r.filtered_found[i]);
      });
}

struct Row {
  std::string model;
  size_t triangles = 0, points = 0, pool_bytes = 0, mismatches = 0;
  double gpu_call_ms = 0, gpu_shader_ms = 0, cpu_ms = 0;
};

}  // namespace

int main(int argc, char** argv) {
  std::vector<fs::path> meshes;
  int depth = 10, reps = 5;
  size_t points = 1000000;
  std::string json_path;
  for (int i = 1; i < argc; ++i) {
    const bool more = i + 1 < argc;
    if (!std::strcmp(argv[i], "--mesh") && more)
      meshes.emplace_back(argv[++i]);
    else if (!std::strcmp(argv[i], "--depth") && more)
      depth = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--points") && more)
      points = size_t(std::atoll(argv[++i]));
    else if (!std::strcmp(argv[i], "--reps") && more)
      reps = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--json") && more)
      json_path = argv[++i];
    else {
      fmt::print(stderr,
                 "usage: limn_bench_texture_gpu [--mesh FILE]... [--depth D] [--points N] "
                 "[--reps N] [--json FILE]\n");
      return 2;
    }
  }
  if (meshes.empty())
    for (const char* name : {"tri/stanford-bunny.obj", "tri/armadillo-100k.obj"})
      meshes.push_back(fs::path(LIMN_SHARED_MODELS) / name);

  GlContext gl;
  const int threads = tbb::this_task_arena::max_concurrency();
  fmt::print("renderer: {}; CPU: {} threads; depth {}, {} points, median of {}\n\n", gl.renderer(),
             threads, depth, points, reps);
  fmt::print(
      "| model | triangles | pool MiB | GPU call ms | GPU shader ms | CPU ms | GPU call M/s | GPU "
      "shader M/s | CPU M/s | call / CPU | shader / CPU | mismatches |\n"
      "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  std::vector<Row> rows;
  bool ok = true;
  for (const fs::path& path : meshes) {
    const Mesh mesh = read_mesh(path);
    const PaintSurface surf(mesh);
    OctreeTexture t = OctreeTexture::create(surf, pack_rgba8(20, 20, 20, 255));
    const float base[4] = {0.8f, 0.5f, 0.2f, 1.0f};
    fill(t, surf, base, BlendMode::mix, 1.0f, depth);
    bench::paint_strokes(t, surf, depth, bench::surface_points(surf, 12, 99));
    t.compact();
    const OctreeIndex index(t);
    std::vector<float> p, n;
    p.reserve(3 * points), n.reserve(3 * points);
    for (const bench::Sample& s : bench::surface_points(surf, points, 7))
      p.insert(p.end(), s.p, s.p + 3), n.insert(n.end(), s.n, s.n + 3);

    Row row{path.stem().string(), surf.triangle_count(), points, t.stats().bytes};
    const GpuOctreeTexture gpu(t);
    CpuResults cpu;
    cpu_lookups(t, index, p, n, cpu);
    const GpuOctreeTexture::Lookups g = gpu.lookup(p, n, 0.0f);
    for (size_t i = 0; i < points; ++i) {
      bool same = g.nearest_found[i] == cpu.nearest_found[i] &&
                  g.filtered_found[i] == cpu.filtered_found[i] &&
                  (!cpu.nearest_found[i] || g.nearest[i] == cpu.nearest[i]);
      for (int k = 0; k < 4 && same && cpu.filtered_found[i]; ++k)
        same = std::fabs(g.filtered[4 * i + k] - cpu.filtered[4 * i + k]) <= 1e-4f;
      if (!same && row.mismatches++ < 5)
        fmt::print(stderr, "{}: point {} ({}, {}, {}): GPU and CPU lookups differ\n", row.model, i,
                   p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    }
    ok = ok && row.mismatches == 0;

    // Turns, so that other load on the machine falls on both alike.
    std::vector<double> call, shader, cpu_t;
    for (int r = 0; r < reps; ++r) {
      double t0 = now_ms();
      const GpuOctreeTexture::Lookups l = gpu.lookup(p, n, 0.0f);
      call.push_back(now_ms() - t0);
      shader.push_back(l.shader_ms);
      t0 = now_ms();
      cpu_lookups(t, index, p, n, cpu);
      cpu_t.push_back(now_ms() - t0);
    }
    row.gpu_call_ms = median(call), row.gpu_shader_ms = median(shader), row.cpu_ms = median(cpu_t);
    const double mp = double(points) * 1e-3;  // M points per ms -> M/s
    // A software driver's timer query sees only the submission: no shader figures then.
    const bool timed = row.gpu_shader_ms > 1e-3;
    fmt::print(
        "| {} | {} | {:.1f} | {:.2f} | {} | {:.2f} | {:.1f} | {} | {:.1f} | {:.2f}x | {} | {} |\n",
        row.model, row.triangles, double(row.pool_bytes) / (1 << 20), row.gpu_call_ms,
        timed ? fmt::format("{:.3f}", row.gpu_shader_ms) : "-", row.cpu_ms, mp / row.gpu_call_ms,
        timed ? fmt::format("{:.1f}", mp / row.gpu_shader_ms) : "-", mp / row.cpu_ms,
        row.cpu_ms / row.gpu_call_ms,
        timed ? fmt::format("{:.2f}x", row.cpu_ms / row.gpu_shader_ms) : "-", row.mismatches);
    std::fflush(stdout);
    rows.push_back(row);
  }
  if (!json_path.empty()) {
    nlohmann::json j = {{"renderer", gl.renderer()}, {"cpu_threads", threads}, {"depth", depth}};
    for (const Row& r : rows)
      j["rows"].push_back({{"model", r.model},
                           {"triangles", r.triangles},
                           {"points", r.points},
                           {"pool_bytes", r.pool_bytes},
                           {"gpu_call_ms", r.gpu_call_ms},
                           {"gpu_shader_ms", r.gpu_shader_ms},
                           {"cpu_ms", r.cpu_ms},
                           {"mismatches", r.mismatches}});
    std::ofstream(json_path) << j.dump(2) << "\n";
  }
  return ok ? 0 : 1;
}
