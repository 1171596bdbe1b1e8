// Peak memory and wall time of uniform subdivision of the 800k-quad terrain, limn beside
// OpenSubdiv 3.5, each case in its own child process so its peak resident set is its own
// (wait4's ru_maxrss). The child's address space is capped (default 22 GiB, --cap-gb N) so a case
// that does not fit fails with bad_alloc instead of waking the kernel's OOM killer.
//   osd:       Far::TopologyRefinerFactory + RefineUniform + PrimvarRefiner::Interpolate level by
//              level (OpenSubdiv's leanest way to the points of one level), single-threaded;
//   limn full: refine_uniform (every level and its stencils kept) + positions;
//   limn lean: subdivide_uniform (only the last level kept; stencils streamed).
// Usage: limn_bench_subdiv_memory [--osd-max L] [--limn-max L] [--cap-gb N]
// (defaults: OpenSubdiv up to level 2, limn up to level 4; OpenSubdiv level 3 takes minutes).
#include <fmt/format.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include "isolated.hpp"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <new>
#include <string>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#pragma GCC diagnostic pop

#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/refine.hpp"

using namespace OpenSubdiv;

namespace {

struct Point {
  float x = 0, y = 0, z = 0;
  void Clear(void* = nullptr) { x = y = z = 0; }
  void AddWithWeight(const Point& p, float w) {
    x += w * p.x;
    y += w * p.y;
    z += w * p.z;
  }
};

// OpenSubdiv's points of level `level`, refining and interpolating level by level.
size_t osd_points(const limn::Mesh& m, int level) {
  std::vector<int> nvpf(m.face_count());
  for (size_t f = 0; f < m.face_count(); ++f) nvpf[f] = int(m.face_size(f));
  const std::vector<int> idx(m.face_vertices.begin(), m.face_vertices.end());
  Far::TopologyDescriptor d;
  d.numVertices = int(m.vertex_count());
  d.numFaces = int(m.face_count());
  d.numVertsPerFace = nvpf.data();
  d.vertIndicesPerFace = idx.data();
  Sdc::Options so;
  so.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> r(
      Factory::Create(d, Factory::Options(Sdc::SCHEME_CATMARK, so)));
  Far::TopologyRefiner::UniformOptions uo(level);
  uo.fullTopologyInLastLevel = false;
  r->RefineUniform(uo);
  std::vector<Point> cur(m.vertex_count()), next;
  for (size_t v = 0; v < m.vertex_count(); ++v)
    cur[v] = {m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]};
  const Far::PrimvarRefiner pr(*r);
  for (int k = 1; k <= level; ++k) {
    next.assign(size_t(r->GetLevel(k).GetNumVertices()), Point{});
    pr.Interpolate(k, cur, next);
    cur.swap(next);
  }
  return cur.size();
}

size_t limn_full(const limn::Mesh& m, int level) {
  const limn::UniformRefinement r = limn::refine_uniform(m, level, limn::subdiv_options(m));
  return r.positions(m, level).size() / 3;
}

size_t limn_lean(const limn::Mesh& m, int level) {
  return limn::subdivide_uniform(m, level, limn::subdiv_options(m)).vertex_count();
}

}  // namespace

using limn::bench::Outcome;
using limn::bench::run_isolated;

int main(int argc, char** argv) {
  int osd_max = 2, limn_max = 4;
  double cap_gb = 22;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--osd-max") osd_max = std::atoi(argv[i + 1]);
    if (a == "--limn-max") limn_max = std::atoi(argv[i + 1]);
    if (a == "--cap-gb") cap_gb = std::atof(argv[i + 1]);
  }
  const limn::Mesh terrain = limn::make_shape("terrain");
  fmt::print("terrain: {} vertices, {} quads; address-space cap {:.0f} GiB per case\n",
             terrain.vertex_count(), terrain.face_count(), cap_gb);
  fmt::print("{:<6} {:<10} {:>10} {:>11} {:>12}  {}\n", "level", "who", "points", "time ms",
             "peak MB", "note");
  for (int level = 1; level <= std::max(osd_max, limn_max); ++level) {
    Outcome osd;
    std::vector<std::pair<std::string, std::function<size_t()>>> cases;
    if (level <= osd_max) cases.emplace_back("osd", [&] { return osd_points(terrain, level); });
    if (level <= std::min(limn_max, 3))
      cases.emplace_back("limn full", [&] { return limn_full(terrain, level); });
    if (level <= limn_max)
      cases.emplace_back("limn lean", [&] { return limn_lean(terrain, level); });
    for (const auto& [who, fn] : cases) {
      const Outcome o = run_isolated(fn, cap_gb);
      if (who == "osd") osd = o;
      std::string note = o.why;
      if (o.ok && osd.ok && who != "osd")
        note = fmt::format("OpenSubdiv/limn: time {:.2f}x, memory {:.2f}x", osd.ms / o.ms,
                           osd.peak_mb / o.peak_mb);
      fmt::print("{:<6} {:<10} {:>10} {:>11.0f} {:>12.0f}  {}\n", level, who, o.points, o.ms,
                 o.peak_mb, note);
      std::fflush(stdout);
    }
  }
  return 0;
}
