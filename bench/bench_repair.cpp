// Repair benchmark: limn's repair_mesh beside CGAL 5.5's polygon-soup repair on the same soups,
// in one run. Soups are made from the shared `tri/` meshes three ways (tests/unit/soups.hpp, as
// the repair tests make them): shuffled (faces and vertices renumbered, faces rotated, 30%
// reversed), welded apart (every corner its own vertex, as STL stores a mesh, faces shuffled)
// and broken (a second copy touching the first at one vertex, 20 fins making non-manifold edges,
// 20 duplicate and 20 degenerate faces, then shuffled).
//   CGAL: repair_polygon_soup (merges equal points, drops invalid and duplicate polygons and
//         isolated points) then orient_polygon_soup (orients, duplicates points at non-manifold
//         edges and vertices): soup in, soup out.
//   limn: repair_mesh with weld tolerance 0 (equal positions only, as CGAL), and with the
//         default tolerance (1e-6 of the diagonal) for reference.
// Both start from indexed arrays in memory (the conversion to CGAL's vectors is not counted)
// and run on one thread. Medians of --repeat runs.
//   limn_bench_repair [--repeat N] [--models DIR] [--only NAME]
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <fmt/format.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "clock.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/repair.hpp"
#include "soups.hpp"

namespace fs = std::filesystem;

namespace {

using limn::Mesh;
using limn::bench::median;
using limn::bench::now_ms;
using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
using Polygons = std::vector<std::vector<std::size_t>>;

void to_soup(const Mesh& m, std::vector<Point>& points, Polygons& polygons) {
  points.clear();
  polygons.clear();
  for (size_t v = 0; v < m.vertex_count(); ++v)
    points.emplace_back(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    polygons.emplace_back(fv.begin(), fv.end());
  }
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 5;
  fs::path models = fs::path(LIMN_SHARED_MODELS) / "tri";
  std::string only;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--models") && i + 1 < argc)
      models = argv[++i];
    else if (!std::strcmp(argv[i], "--only") && i + 1 < argc)
      only = argv[++i];
    else {
      fmt::print(stderr, "usage: limn_bench_repair [--repeat N] [--models DIR] [--only NAME]\n");
      return 2;
    }
  }
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const char* names[] = {"spot.obj",           "fandisk.obj",        "rocker-arm.obj", "blade.off",
                         "stanford-bunny.obj", "armadillo-100k.obj", "ogre.obj",       "igea.obj"};
  fmt::print("{:<20} {:<9} {:>8} {:>10} {:>10} {:>10} {:>7} {:>8} {:>8}\n", "mesh", "soup", "faces",
             "limn ms", "limn tol", "CGAL ms", "ratio", "limn F", "CGAL F");
  std::mt19937 rng(1);
  for (const char* name : names) {
    if (!only.empty() && only != name) continue;
    limn::RepairOptions exact;
    exact.weld_tolerance = 0;
    const Mesh clean = limn::repair_mesh(limn::read_mesh(models / name), exact);
    std::vector<uint8_t> flipped;
    double duplicate_area = 0;
    const std::pair<const char*, Mesh> soups[] = {
        {"shuffled", limn::test::shuffled(clean, rng, flipped, 0.3)},
        {"apart", limn::test::welded_apart(clean, rng)},
        {"broken", limn::test::shuffled(limn::test::broken(clean, rng, 20, 20, 20, duplicate_area),
                                        rng, flipped, 0.3)}};
    for (const auto& [kind, soup] : soups) {
      std::vector<double> t_limn, t_tol, t_cgal;
      size_t limn_faces = 0, cgal_faces = 0;
      std::vector<Point> points;
      Polygons polygons;
      for (int r = 0; r < repeat; ++r) {
        double t0 = now_ms();
        limn_faces = limn::repair_mesh(soup, exact).face_count();
        t_limn.push_back(now_ms() - t0);
        t0 = now_ms();
        limn::repair_mesh(soup);
        t_tol.push_back(now_ms() - t0);
        to_soup(soup, points, polygons);
        t0 = now_ms();
        CGAL::Polygon_mesh_processing::repair_polygon_soup(points, polygons);
        CGAL::Polygon_mesh_processing::orient_polygon_soup(points, polygons);
        t_cgal.push_back(now_ms() - t0);
        cgal_faces = polygons.size();
      }
      const double l = median(t_limn), c = median(t_cgal);
      fmt::print("{:<20} {:<9} {:>8} {:>10.2f} {:>10.2f} {:>10.2f} {:>6.2f}x {:>8} {:>8}\n", name,
                 kind, soup.face_count(), l, median(t_tol), c, c / l, limn_faces, cgal_faces);
      std::fflush(stdout);
    }
  }
  return 0;
}
