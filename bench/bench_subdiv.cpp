// Uniform refinement benchmark: limn beside OpenSubdiv 3.5 in one run, on the FAS cages, the car
// and the 800k-quad terrain, levels 1-3.
//   (a) topology + refinement + stencil tables: limn refine_uniform vs Far TopologyRefinerFactory
//       + RefineUniform + StencilTableFactory (base-to-last-level stencils);
//   (b) applying stencils to positions: limn (per-level tables, 1 and 2 threads) vs Osd
//       CpuEvaluator::EvalStencils, beside a STREAM-style copy measuring memory bandwidth.
// Prints ratios after Google Benchmark's table.
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <cstring>
#include <filesystem>
#include <map>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/osd/bufferDescriptor.h>
#include <opensubdiv/osd/cpuEvaluator.h>
#pragma GCC diagnostic pop

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/refine.hpp"

namespace fs = std::filesystem;
using namespace OpenSubdiv;

namespace {

std::map<std::string, limn::Mesh> g_meshes;

struct OsdInput {
  std::vector<int> nvpf, idx, creases, corners, holes;
  Far::TopologyDescriptor desc;
};

OsdInput osd_input(const limn::Mesh& m) {
  OsdInput in;
  for (size_t f = 0; f < m.face_count(); ++f) in.nvpf.push_back(int(m.face_size(f)));
  in.idx.assign(m.face_vertices.begin(), m.face_vertices.end());
  in.creases.assign(m.crease_edges.begin(), m.crease_edges.end());
  in.corners.assign(m.corner_vertices.begin(), m.corner_vertices.end());
  in.holes.assign(m.hole_faces.begin(), m.hole_faces.end());
  Far::TopologyDescriptor& d = in.desc;
  d.numVertices = int(m.vertex_count());
  d.numFaces = int(m.face_count());
  d.numVertsPerFace = in.nvpf.data();
  d.vertIndicesPerFace = in.idx.data();
  d.numCreases = int(m.crease_sharpness.size());
  d.creaseVertexIndexPairs = in.creases.data();
  d.creaseWeights = m.crease_sharpness.data();
  d.numCorners = int(in.corners.size());
  d.cornerVertexIndices = in.corners.data();
  d.cornerWeights = m.corner_sharpness.data();
  d.numHoles = int(in.holes.size());
  d.holeIndices = in.holes.data();
  return in;
}

Sdc::Options osd_options(const limn::Mesh& m) {
  const limn::SubdivOptions o = limn::subdiv_options(m);
  Sdc::Options so;
  so.SetVtxBoundaryInterpolation(o.boundary == limn::BoundaryInterpolation::edge_only
                                     ? Sdc::Options::VTX_BOUNDARY_EDGE_ONLY
                                     : Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  so.SetCreasingMethod(o.crease_method == limn::CreaseMethod::chaikin
                           ? Sdc::Options::CREASE_CHAIKIN
                           : Sdc::Options::CREASE_UNIFORM);
  return so;
}

std::unique_ptr<Far::TopologyRefiner> osd_refine(const limn::Mesh& m, int level) {
  OsdInput in = osd_input(m);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> r(
      Factory::Create(in.desc, Factory::Options(Sdc::SCHEME_CATMARK, osd_options(m))));
  r->RefineUniform(Far::TopologyRefiner::UniformOptions(level));
  return r;
}

std::unique_ptr<const Far::StencilTable> osd_stencils(const Far::TopologyRefiner& r) {
  Far::StencilTableFactory::Options so;
  so.generateIntermediateLevels = false;
  so.generateOffsets = true;
  return std::unique_ptr<const Far::StencilTable>(Far::StencilTableFactory::Create(r, so));
}

void osd_build(benchmark::State& state, const std::string& name) {
  const limn::Mesh& m = g_meshes.at(name);
  const int level = int(state.range(0));
  for (auto _ : state) {
    auto r = osd_refine(m, level);
    auto st = osd_stencils(*r);
    benchmark::DoNotOptimize(st->GetWeights().data());
  }
}

void limn_build(benchmark::State& state, const std::string& name, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  const limn::Mesh& m = g_meshes.at(name);
  const int level = int(state.range(0));
  const limn::SubdivOptions o = limn::subdiv_options(m);
  for (auto _ : state) {
    const limn::UniformRefinement r = limn::refine_uniform(m, level, o);
    benchmark::DoNotOptimize(r.stencils.back().weights.data());
  }
}

// limn's build including the cage-flattened table, the like-for-like peer of OpenSubdiv's
// StencilTableFactory output.
void limn_build_flat(benchmark::State& state, const std::string& name) {
  const limn::Mesh& m = g_meshes.at(name);
  const int level = int(state.range(0));
  const limn::SubdivOptions o = limn::subdiv_options(m);
  for (auto _ : state) {
    const limn::UniformRefinement r = limn::refine_uniform(m, level, o);
    const limn::StencilTable flat = limn::cage_stencils(r, level);
    benchmark::DoNotOptimize(flat.weights.data());
  }
}

void limn_apply_flat(benchmark::State& state, const std::string& name, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  const limn::Mesh& m = g_meshes.at(name);
  const int level = int(state.range(0));
  const limn::UniformRefinement r = limn::refine_uniform(m, level, limn::subdiv_options(m));
  const limn::StencilTable flat = limn::cage_stencils(r, level);
  std::vector<float> dst(3 * flat.size());
  for (auto _ : state) {
    limn::apply_stencils(flat, m.positions.data(), dst.data(), 3);
    benchmark::DoNotOptimize(dst.data());
  }
  state.SetBytesProcessed(
      int64_t(state.iterations()) *
      int64_t(flat.indices.size() * 8 + flat.offsets.size() * 4 + dst.size() * 4));
}

void osd_apply(benchmark::State& state, const std::string& name) {
  const limn::Mesh& m = g_meshes.at(name);
  auto r = osd_refine(m, int(state.range(0)));
  auto st = osd_stencils(*r);
  const int n = st->GetNumStencils();
  std::vector<float> dst(3 * size_t(n));
  Osd::BufferDescriptor sd(0, 3, 3), dd(0, 3, 3);
  for (auto _ : state) {
    Osd::CpuEvaluator::EvalStencils(m.positions.data(), sd, dst.data(), dd, &st->GetSizes()[0],
                                    &st->GetOffsets()[0], &st->GetControlIndices()[0],
                                    &st->GetWeights()[0], 0, n);
    benchmark::DoNotOptimize(dst.data());
  }
  state.counters["points"] = n;
}

void limn_apply(benchmark::State& state, const std::string& name, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  const limn::Mesh& m = g_meshes.at(name);
  const int level = int(state.range(0));
  const limn::UniformRefinement r = limn::refine_uniform(m, level, limn::subdiv_options(m));
  size_t bytes = 0;
  for (const auto& s : r.stencils)
    bytes += s.indices.size() * 8 + s.offsets.size() * 4 + s.size() * 12;
  // Buffers are sized once, as for OpenSubdiv's evaluator below: the loop times the stencils.
  std::vector<std::vector<float>> buf(size_t(level) + 1);
  buf[0] = m.positions;
  for (int k = 1; k <= level; ++k) buf[size_t(k)].assign(3 * r.stencils[size_t(k) - 1].size(), 0);
  for (auto _ : state) {
    for (int k = 1; k <= level; ++k)
      limn::apply_stencils(r.stencils[size_t(k) - 1], buf[size_t(k) - 1].data(),
                           buf[size_t(k)].data(), 3);
    benchmark::DoNotOptimize(buf.back().data());
  }
  state.counters["points"] = double(r.levels.back().vertex_count());
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(bytes));
}

void stream_copy(benchmark::State& state) {
  const size_t n = size_t(64) << 20;  // 256 MB of floats each way: far beyond the caches
  std::vector<float> a(n, 1.0f), b(n);
  for (auto _ : state) {
    std::memcpy(b.data(), a.data(), n * sizeof(float));
    benchmark::DoNotOptimize(b.data());
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(2 * n * sizeof(float)));
}

// Sparse (feature-adaptive) refinement: OpenSubdiv's RefineAdaptive to an isolation level plus
// its stencil table for every refined vertex, beside limn's refine_sparse with the same depth on
// every extraordinary or tagged vertex (and one level on non-quads).
struct SparseRequest {
  std::vector<uint8_t> vertex, face;
};

SparseRequest sparse_request(const limn::Mesh& m, int depth) {
  SparseRequest q;
  q.vertex.assign(m.vertex_count(), 0);
  q.face.assign(m.face_count(), 0);
  std::vector<uint32_t> faces(m.vertex_count(), 0);
  for (uint32_t v : m.face_vertices) ++faces[v];
  std::vector<uint32_t> boundary(m.vertex_count(), 0);
  {
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (size_t f = 0; f < m.face_count(); ++f) {
      const auto fv = m.face(f);
      for (size_t i = 0; i < fv.size(); ++i) {
        const uint32_t a = fv[i], b = fv[(i + 1) % fv.size()];
        ++edges[{std::min(a, b), std::max(a, b)}];
      }
    }
    for (const auto& [e, n] : edges)
      if (n == 1) ++boundary[e.first], ++boundary[e.second];
  }
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    const bool on_boundary = boundary[v] > 0;
    if ((!on_boundary && faces[v] != 4) || (on_boundary && faces[v] != 2 && faces[v] != 1))
      q.vertex[v] = uint8_t(depth);
  }
  for (uint32_t v : m.crease_edges) q.vertex[v] = uint8_t(depth);
  for (uint32_t v : m.corner_vertices) q.vertex[v] = uint8_t(depth);
  for (size_t f = 0; f < m.face_count(); ++f)
    if (m.face_size(f) != 4) q.face[f] = 1;
  return q;
}

void osd_sparse(benchmark::State& state, const std::string& name) {
  const limn::Mesh& m = g_meshes.at(name);
  const int depth = int(state.range(0));
  size_t points = 0;
  for (auto _ : state) {
    OsdInput in = osd_input(m);
    using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
    std::unique_ptr<Far::TopologyRefiner> r(
        Factory::Create(in.desc, Factory::Options(Sdc::SCHEME_CATMARK, osd_options(m))));
    r->RefineAdaptive(Far::TopologyRefiner::AdaptiveOptions(depth));
    Far::StencilTableFactory::Options so;
    so.generateIntermediateLevels = true;
    so.generateOffsets = true;
    std::unique_ptr<const Far::StencilTable> st(Far::StencilTableFactory::Create(*r, so));
    points = size_t(st->GetNumStencils());
    benchmark::DoNotOptimize(st->GetWeights().data());
  }
  state.counters["points"] = double(points);
}

void limn_sparse(benchmark::State& state, const std::string& name) {
  const limn::Mesh& m = g_meshes.at(name);
  const int depth = int(state.range(0));
  const SparseRequest q = sparse_request(m, depth);
  const limn::SubdivOptions o = limn::subdiv_options(m);
  size_t points = 0;
  for (auto _ : state) {
    const limn::SparseRefinement r = limn::refine_sparse(m, q.vertex, q.face, o);
    points = 0;
    for (size_t k = 1; k < r.levels.size(); ++k) points += r.levels[k].level.vertex_count();
    benchmark::DoNotOptimize(r.stencils.back().weights.data());
  }
  state.counters["points"] = double(points);
}

void stream_copy_2t(benchmark::State& state) {
  const size_t n = size_t(64) << 20;
  std::vector<float> a(n, 1.0f), b(n);
  for (auto _ : state) {
    tbb::parallel_for(size_t(0), size_t(2), [&](size_t h) {
      std::memcpy(b.data() + h * n / 2, a.data() + h * n / 2, n / 2 * sizeof(float));
    });
    benchmark::DoNotOptimize(b.data());
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(2 * n * sizeof(float)));
}

class Recorder : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      // With --benchmark_repetitions the ratios use the medians.
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name != "median") continue;
      const std::string name = r.run_name.str();
      ms[name] = r.GetAdjustedRealTime();
      if (r.counters.count("bytes_per_second")) bps[name] = r.counters.at("bytes_per_second");
    }
  }
  std::map<std::string, double> ms, bps;
};

}  // namespace

int main(int argc, char** argv) {
  const fs::path models = LIMN_SHARED_MODELS;
  for (const char* f : {"quads/bigguy.obj", "quads/monsterfrog.obj", "osd/catmark_car.obj"})
    g_meshes[fs::path(f).stem().string()] = limn::read_mesh(models / f);
  g_meshes["terrain800k"] = limn::make_shape("terrain");

  std::vector<std::string> names = {"bigguy", "monsterfrog", "catmark_car", "terrain800k"};
  for (const std::string& n : names) {
    const int max_level = n == "terrain800k" ? 2 : 3;  // terrain L3 needs ~13 GB in OpenSubdiv
    auto reg = [&](const std::string& what, auto fn) {
      benchmark::RegisterBenchmark((n + "/" + what).c_str(), fn)
          ->DenseRange(1, max_level)
          ->Unit(benchmark::kMillisecond);
    };
    reg("build/osd", [n](benchmark::State& s) { osd_build(s, n); });
    reg("build/limn", [n](benchmark::State& s) { limn_build(s, n, 2); });
    reg("build/limn_1t", [n](benchmark::State& s) { limn_build(s, n, 1); });
    reg("build/limn_flat", [n](benchmark::State& s) { limn_build_flat(s, n); });
    reg("apply/limn_flat_1t", [n](benchmark::State& s) { limn_apply_flat(s, n, 1); });
    reg("apply/limn_flat_2t", [n](benchmark::State& s) { limn_apply_flat(s, n, 2); });
    reg("apply/osd_1t", [n](benchmark::State& s) { osd_apply(s, n); });
    reg("apply/limn_1t", [n](benchmark::State& s) { limn_apply(s, n, 1); });
    reg("apply/limn_2t", [n](benchmark::State& s) { limn_apply(s, n, 2); });
  }
  for (const std::string& n : names) {
    const int max_depth = n == "terrain800k" ? 3 : 6;
    for (const char* who : {"osd", "limn"}) {
      auto fn = [n, who](benchmark::State& s) {
        std::string(who) == "osd" ? osd_sparse(s, n) : limn_sparse(s, n);
      };
      benchmark::RegisterBenchmark((n + "/sparse/" + who).c_str(), fn)
          ->DenseRange(2, max_depth, 2)
          ->Unit(benchmark::kMillisecond);
    }
  }
  benchmark::RegisterBenchmark("stream_copy", stream_copy)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("stream_copy_2t", stream_copy_2t)->Unit(benchmark::kMillisecond);

  benchmark::Initialize(&argc, argv);
  Recorder rec;
  benchmark::RunSpecifiedBenchmarks(&rec);
  benchmark::Shutdown();

  const double bw1 = rec.bps.count("stream_copy") ? rec.bps["stream_copy"] : 0.0;
  const double bw2 = rec.bps.count("stream_copy_2t") ? rec.bps["stream_copy_2t"] : 0.0;
  fmt::print("\nRatios (OpenSubdiv time / limn time; > 1 means limn is faster)\n");
  for (const std::string& n : names)
    for (int l = 1; l <= 3; ++l) {
      const std::string sfx = "/" + std::to_string(l);
      auto get = [&](const std::string& k) {
        auto it = rec.ms.find(n + "/" + k + sfx);
        return it == rec.ms.end() ? -1.0 : it->second;
      };
      auto bw = [&](const std::string& k) {
        auto it = rec.bps.find(n + "/" + k + sfx);
        return it == rec.bps.end() ? 0.0 : it->second;
      };
      const double ob = get("build/osd"), lb = get("build/limn"), lb1 = get("build/limn_1t"),
                   oa = get("apply/osd_1t"), l1 = get("apply/limn_1t"), l2 = get("apply/limn_2t"),
                   lbf = get("build/limn_flat"), f1 = get("apply/limn_flat_1t"),
                   f2 = get("apply/limn_flat_2t");
      if (ob < 0 || lb < 0) continue;
      fmt::print(
          "{:<12} L{}  build {:8.2f} / {:7.2f} ms = {:5.2f}x (1 thread {:5.2f}x)   apply 1t "
          "{:6.2f} / {:6.2f} ms = {:5.2f}x   2t {:5.2f}x   bandwidth 1t {:3.0f}% 2t {:3.0f}%\n",
          n, l, ob, lb, ob / lb, ob / lb1, oa, l1, oa / l1, oa / l2,
          bw1 > 0 ? 100 * bw("apply/limn_1t") / bw1 : 0.0,
          bw2 > 0 ? 100 * bw("apply/limn_2t") / bw2 : 0.0);
      fmt::print(
          "{:<12} L{}  flat: build {:7.2f} ms = {:5.2f}x   apply 1t {:6.2f} ms = {:5.2f}x   "
          "2t {:5.2f}x\n",
          n, l, lbf, ob / lbf, f1, oa / f1, oa / f2);
    }
  for (const std::string& n : names)
    for (int d = 2; d <= 6; d += 2) {
      const std::string o = n + "/sparse/osd/" + std::to_string(d),
                        l = n + "/sparse/limn/" + std::to_string(d);
      if (!rec.ms.count(o) || !rec.ms.count(l)) continue;
      fmt::print(
          "{:<12} sparse depth {}  OpenSubdiv RefineAdaptive+stencils {:8.2f} ms, limn "
          "refine_sparse {:7.2f} ms = {:5.2f}x\n",
          n, d, rec.ms[o], rec.ms[l], rec.ms[o] / rec.ms[l]);
    }
  fmt::print("memory bandwidth (STREAM-style copy): {:.1f} GB/s one thread, {:.1f} GB/s two\n",
             bw1 / 1e9, bw2 / 1e9);
  return 0;
}
