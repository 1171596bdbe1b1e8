// VSA benchmark: limn's greedy optimiser beside limn's Lloyd baseline and CGAL 5.5's
// Variational_shape_approximation (L21, hierarchical seeding, 30 iterations, meshing) in one
// run, on the seed paper's cases (fandisk K=30, bunny K=100, feline K=200, armadillo-100k K=200,
// igea K=300) and igea refined twice by 1-to-4 midpoint splits (~4.3M faces, K=300). Meshes are
// scaled to a unit bounding-box diagonal, so E = sum 2(S - |N|) compares with
// ../shared/design/vsa.md. E of every side is computed from its face labels the same way. Each
// side's total runs from an indexed mesh in memory to output triangles (limn: corner table,
// seeding, optimisation, meshing; CGAL: seeding, iterations, extract_mesh; its Surface_mesh
// construction is not counted). One thread (CGAL is serial) unless --threads N. Medians of
// --repeat runs (one run on the refined mesh).
//   limn_bench_simplify [--repeat N] [--models DIR] [--threads N] [--no-cgal] [--no-lloyd]
//                       [--no-big] [--only NAME]
#include <fmt/format.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "cgal_vsa.hpp"
#include "clock.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/simplify/vsa.hpp"

namespace fs = std::filesystem;

namespace {

using limn::bench::median;
using limn::bench::now_ms;

// One 1-to-4 split of every triangle (edge midpoints shared between neighbours).
limn::Mesh midpoint_split(const limn::Mesh& m) {
  limn::Mesh out;
  out.positions = m.positions;
  std::unordered_map<uint64_t, uint32_t> mid;
  mid.reserve(m.face_count() * 2);
  auto midpoint = [&](uint32_t a, uint32_t b) {
    const uint64_t key = a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a);
    auto [it, fresh] = mid.try_emplace(key, 0u);
    if (fresh) {
      const float* p = &m.positions[3 * size_t(a)];
      const float* q = &m.positions[3 * size_t(b)];
      it->second = out.add_vertex(0.5f * (p[0] + q[0]), 0.5f * (p[1] + q[1]), 0.5f * (p[2] + q[2]));
    }
    return it->second;
  };
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto v = m.face(f);
    const uint32_t ab = midpoint(v[0], v[1]), bc = midpoint(v[1], v[2]), ca = midpoint(v[2], v[0]);
    out.add_face({v[0], ab, ca});
    out.add_face({v[1], bc, ab});
    out.add_face({v[2], ca, bc});
    out.add_face({ab, bc, ca});
  }
  return out;
}

double energy_of(const limn::VsaSurface& s, const std::vector<uint32_t>& labels) {
  size_t k = 0;
  for (uint32_t l : labels) k = std::max<size_t>(k, l + 1);
  return limn::partition_from_labels(s, labels, k).energy();
}

struct Side {
  std::vector<double> total, prep, seed, opt, mesh;
  double energy = 0;
  size_t clusters = 0, triangles = 0, iterations = 0;
};

}  // namespace

int main(int argc, char** argv) {
  int repeat = 3, threads = 1;
  bool cgal = true, big = true, lloyd = true;
  std::string only;
  fs::path models = LIMN_SHARED_MODELS;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--models") && i + 1 < argc)
      models = argv[++i];
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc)
      threads = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--no-cgal"))
      cgal = false;
    else if (!std::strcmp(argv[i], "--no-lloyd"))
      lloyd = false;
    else if (!std::strcmp(argv[i], "--no-big"))
      big = false;
    else if (!std::strcmp(argv[i], "--only") && i + 1 < argc)
      only = argv[++i];
  }
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
  struct Case {
    std::string name, file;
    size_t K;
    int refine;
  };
  std::vector<Case> cases = {{"fandisk", "tri/fandisk.obj", 30, 0},
                             {"bunny", "tri/stanford-bunny.obj", 100, 0},
                             {"feline", "tri/feline.obj", 200, 0},
                             {"armadillo-100k", "tri/armadillo-100k.obj", 200, 0},
                             {"igea", "tri/igea.obj", 300, 0}};
  if (big) cases.push_back({"igea x16", "tri/igea.obj", 300, 2});

  // Sides: limn greedy with its defaults (16 teleports), the seed's method as published (no
  // teleports), limn Lloyd (30 iterations at most, stops when stable), CGAL.
  const char* side_names[4] = {"limn greedy", "limn greedy, no teleports", "limn Lloyd", "CGAL"};
  fmt::print(
      "| model | faces | K | side | total ms | prepare | seeding | optimisation | meshing | E | "
      "output faces |\n|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|\n");
  std::string summary =
      "\n| model | faces | CGAL / greedy | Lloyd / greedy | greedy / no teleports | E greedy / "
      "CGAL | E no teleports / CGAL | E Lloyd / CGAL | greedy us/face |\n"
      "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Case& c : cases) {
    if (!only.empty() && c.name != only) continue;
    limn::Mesh m = limn::test::unit_diagonal(limn::read_mesh(models / c.file));
    for (int r = 0; r < c.refine; ++r) m = midpoint_split(m);
    const int reps = c.refine ? 1 : repeat;
    const limn::VsaSurface surface = limn::prepare_surface(m, c.name);
    Side sides[4];
    bool ran[4] = {true, true, lloyd, cgal};
    for (int rep = 0; rep < reps; ++rep) {
      for (int side = 0; side < 3; ++side) {
        if (!ran[side]) continue;
        limn::VsaOptions o;
        o.proxies = c.K;
        if (side == 1) o.teleports = 0;
        if (side == 2) o.method = limn::VsaMethod::lloyd;
        const double t0 = now_ms();
        const limn::VsaResult res = limn::simplify_vsa(m, o, c.name);
        const double t = now_ms() - t0;
        Side& s = sides[side];
        s.total.push_back(t);
        s.prep.push_back(res.stats.prepare_ms);
        s.seed.push_back(res.stats.seeding_ms);
        s.opt.push_back(res.stats.optimise_ms);
        s.mesh.push_back(res.stats.meshing_ms);
        s.energy = energy_of(surface, res.labels);
        s.clusters = res.stats.clusters;
        s.triangles = res.output.mesh.face_count();
        s.iterations = res.stats.lloyd.iterations;
      }
      if (cgal) {
        const limn::test::CgalVsaResult cr = limn::test::run_cgal_vsa(m, c.K, 30);
        Side& s = sides[3];
        s.total.push_back(cr.seeding_ms + cr.iterations_ms + cr.meshing_ms);
        s.prep.push_back(0);
        s.seed.push_back(cr.seeding_ms);
        s.opt.push_back(cr.iterations_ms);
        s.mesh.push_back(cr.meshing_ms);
        s.energy = energy_of(surface, cr.labels);
        s.clusters = cr.proxies;
        s.triangles = cr.triangles.size();
      }
    }
    for (int side = 0; side < 4; ++side) {
      if (!ran[side]) continue;
      const Side& s = sides[side];
      fmt::print(
          "| {} | {} | {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.4f} | {} |\n",
          c.name, m.face_count(), s.clusters, side_names[side], median(s.total), median(s.prep),
          median(s.seed), median(s.opt), median(s.mesh), s.energy, s.triangles);
    }
    const Side &g = sides[0], &pp = sides[1], &l = sides[2], &cg = sides[3];
    auto ratio = [](bool ok, double a, double b, int digits = 2) {
      return ok && b > 0 ? fmt::format("{:.{}f}", a / b, digits) : std::string("-");
    };
    summary += fmt::format(
        "| {} | {} | {}x | {}x | {}x | {} | {} | {} | {:.2f} |\n", c.name, m.face_count(),
        ratio(cgal, median(cg.total), median(g.total)),
        ratio(lloyd, median(l.total), median(g.total)),
        ratio(true, median(g.total), median(pp.total)), ratio(cgal, g.energy, cg.energy, 3),
        ratio(cgal, pp.energy, cg.energy, 3), ratio(cgal && lloyd, l.energy, cg.energy, 3),
        1000.0 * median(g.total) / double(m.face_count()));
    std::fflush(stdout);
  }
  fmt::print("{}", summary);
  return 0;
}
