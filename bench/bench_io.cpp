// Load-time benchmark: limn's readers (+ adjacency) beside tinyobjloader's own raw parse, on the
// shared igea scan, a binary PLY of it, and the 800k-quad procedural terrain. Prints the ratios
// the foundation issue asks for after Google Benchmark's table.
//   limn_bench_io [--benchmark_repetitions=N ...]
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tiny_obj_loader.h>
#include <unistd.h>

#include <filesystem>
#include <map>

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"

namespace fs = std::filesystem;

namespace {

fs::path g_igea = fs::path(LIMN_SHARED_MODELS) / "tri" / "igea.obj";
fs::path g_terrain_obj, g_igea_ply;

void tinyobj_raw(benchmark::State& state, const fs::path& path) {
  for (auto _ : state) {
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    const bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err,
                                     path.string().c_str(), nullptr, false);
    if (!ok) state.SkipWithError(err.c_str());
    benchmark::DoNotOptimize(attrib.vertices.data());
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(fs::file_size(path)));
}

void limn_read(benchmark::State& state, const fs::path& path, bool adjacency) {
  for (auto _ : state) {
    const limn::Mesh m = limn::read_mesh(path);
    if (adjacency) {
      const limn::Topology t = limn::build_topology(m);
      benchmark::DoNotOptimize(t.corner_twin.data());
    }
    benchmark::DoNotOptimize(m.positions.data());
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(fs::file_size(path)));
}

// The same with TBB held to one thread: what validation costs when no second core is free.
void limn_read_serial(benchmark::State& state, const fs::path& path) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  limn_read(state, path, true);
}

void limn_topology(benchmark::State& state, const fs::path& path) {
  const limn::Mesh m = limn::read_mesh(path);
  for (auto _ : state) {
    const limn::Topology t = limn::build_topology(m);
    benchmark::DoNotOptimize(t.corner_twin.data());
  }
}

// Records each benchmark's mean real time so the ratios can be printed at the end.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs)
      if (r.run_type == Run::RT_Iteration || r.aggregate_name == "mean")
        ms[r.run_name.function_name] =
            r.GetAdjustedRealTime() * (r.time_unit == benchmark::kMillisecond ? 1.0 : 1e-6);
  }
  std::map<std::string, double> ms;
};

}  // namespace

int main(int argc, char** argv) {
  if (!fs::exists(g_igea)) {
    fmt::print(stderr, "missing {}\n", g_igea.string());
    return 2;
  }
  const fs::path tmp = fs::temp_directory_path() / fmt::format("limn-bench-{}", ::getpid());
  fs::create_directories(tmp);
  g_igea_ply = tmp / "igea.ply";
  g_terrain_obj = tmp / "terrain.obj";
  limn::write_mesh(limn::read_mesh(g_igea), g_igea_ply);
  limn::write_mesh(limn::make_shape("terrain"), g_terrain_obj);

  auto reg = [](const char* name, auto fn) {
    benchmark::RegisterBenchmark(name, fn)->Unit(benchmark::kMillisecond)->MinTime(1.0);
  };
  reg("igea_obj/tinyobjloader_raw", [](benchmark::State& s) { tinyobj_raw(s, g_igea); });
  reg("igea_obj/limn_read", [](benchmark::State& s) { limn_read(s, g_igea, false); });
  reg("igea_obj/limn_read+adjacency", [](benchmark::State& s) { limn_read(s, g_igea, true); });
  reg("igea_obj/limn_read+adjacency_1thread",
      [](benchmark::State& s) { limn_read_serial(s, g_igea); });
  reg("igea_obj/limn_adjacency_only", [](benchmark::State& s) { limn_topology(s, g_igea); });
  reg("igea_ply_binary/limn_read", [](benchmark::State& s) { limn_read(s, g_igea_ply, false); });
  reg("terrain800k_obj/tinyobjloader_raw",
      [](benchmark::State& s) { tinyobj_raw(s, g_terrain_obj); });
  reg("terrain800k_obj/limn_read+adjacency",
      [](benchmark::State& s) { limn_read(s, g_terrain_obj, true); });

  benchmark::Initialize(&argc, argv);
  RatioReporter rep;
  benchmark::RunSpecifiedBenchmarks(&rep);
  benchmark::Shutdown();

  auto ratio = [&](const char* a, const char* b) {
    if (!rep.ms.count(a) || !rep.ms.count(b)) return;
    fmt::print("{:<40} {:8.1f} ms  vs {:<34} {:8.1f} ms  ratio {:.2f}x\n", a, rep.ms[a], b,
               rep.ms[b], rep.ms[a] / rep.ms[b]);
  };
  fmt::print("\nRatios (goal: limn load incl. adjacency <= 1.5x tinyobjloader raw parse)\n");
  ratio("igea_obj/limn_read+adjacency", "igea_obj/tinyobjloader_raw");
  ratio("igea_obj/limn_read", "igea_obj/tinyobjloader_raw");
  ratio("igea_obj/limn_read+adjacency_1thread", "igea_obj/tinyobjloader_raw");
  ratio("terrain800k_obj/limn_read+adjacency", "terrain800k_obj/tinyobjloader_raw");
  if (rep.ms.count("igea_ply_binary/limn_read"))
    fmt::print(
        "binary PLY throughput: {:.0f} MB/s (goal >= 300 MB/s; file {:.1f} MB)\n",
        double(fs::file_size(g_igea_ply)) / 1e6 / (rep.ms["igea_ply_binary/limn_read"] / 1e3),
        double(fs::file_size(g_igea_ply)) / 1e6);
  fs::remove_all(tmp);
  return 0;
}
