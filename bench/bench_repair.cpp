// Repair benchmark: limn's repair_mesh beside CGAL 5.5's polygon-soup repair on the same soups,
// in one run. Soups are made from the shared `tri/` meshes three ways: shuffled (faces and
// vertices renumbered, 30% of faces reversed), welded apart (every corner its own vertex, as STL
// stores a mesh) and broken (a second copy touching the first at one vertex, 20 fins making
// non-manifold edges, duplicate and degenerate faces, then shuffled).
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
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "clock.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/repair.hpp"

namespace fs = std::filesystem;

namespace {

using limn::Mesh;
using limn::bench::median;
using limn::bench::now_ms;
using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
using Polygons = std::vector<std::vector<std::size_t>>;

Mesh shuffled(const Mesh& m, std::mt19937& rng) {
  std::vector<uint32_t> vperm(m.vertex_count()), forder(m.face_count());
  std::iota(vperm.begin(), vperm.end(), 0u);
  std::iota(forder.begin(), forder.end(), 0u);
  std::shuffle(vperm.begin(), vperm.end(), rng);
  std::shuffle(forder.begin(), forder.end(), rng);
  Mesh out;
  out.positions.resize(m.positions.size());
  for (size_t v = 0; v < m.vertex_count(); ++v)
    std::memcpy(&out.positions[3 * size_t(vperm[v])], &m.positions[3 * v], 3 * sizeof(float));
  std::bernoulli_distribution flip(0.3);
  std::vector<uint32_t> face;
  for (const uint32_t f : forder) {
    face.clear();
    for (const uint32_t v : m.face(f)) face.push_back(vperm[v]);
    if (flip(rng)) std::reverse(face.begin(), face.end());
    out.add_face(face);
  }
  return out;
}

Mesh welded_apart(const Mesh& m) {
  Mesh out;
  std::vector<uint32_t> face;
  for (size_t f = 0; f < m.face_count(); ++f) {
    face.clear();
    for (const uint32_t v : m.face(f)) {
      const float* p = &m.positions[3 * size_t(v)];
      face.push_back(out.add_vertex(p[0], p[1], p[2]));
    }
    out.add_face(face);
  }
  return out;
}

Mesh broken(const Mesh& clean, std::mt19937& rng) {
  Mesh m = clean;
  const uint32_t nv = static_cast<uint32_t>(clean.vertex_count());
  const size_t nf = clean.face_count();
  uint32_t lo = 0, hi = 0;
  for (uint32_t v = 0; v < nv; ++v) {
    if (clean.positions[3 * v] < clean.positions[3 * lo]) lo = v;
    if (clean.positions[3 * v] > clean.positions[3 * hi]) hi = v;
  }
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t s = v == hi ? lo : v;
    float p[3];
    for (int k = 0; k < 3; ++k)
      p[k] = clean.positions[3 * size_t(s) + k] +
             (v == hi ? 0.0f : clean.positions[3 * lo + k] - clean.positions[3 * hi + k]);
    m.add_vertex(p[0], p[1], p[2]);
  }
  std::vector<uint32_t> face;
  for (size_t f = 0; f < nf; ++f) {
    face.clear();
    for (const uint32_t v : clean.face(f)) face.push_back(v + nv);
    m.add_face(face);
  }
  std::uniform_int_distribution<size_t> pick(0, nf - 1);
  for (int i = 0; i < 20; ++i) {  // fins
    const auto fv = clean.face(pick(rng));
    const float* a = &clean.positions[3 * size_t(fv[0])];
    const float* b = &clean.positions[3 * size_t(fv[1])];
    m.add_face(
        {fv[0], fv[1],
         m.add_vertex(0.5f * (a[0] + b[0]), 0.5f * (a[1] + b[1]) + 0.1f, 0.5f * (a[2] + b[2]))});
  }
  for (int i = 0; i < 20; ++i) m.add_face(clean.face(pick(rng)));  // duplicates
  for (int i = 0; i < 20; ++i) {  // degenerate: a corner's exact copy
    const auto fv = clean.face(pick(rng));
    const float* a = &clean.positions[3 * size_t(fv[0])];
    m.add_face({fv[0], fv[1], m.add_vertex(a[0], a[1], a[2])});
  }
  return shuffled(m, rng);
}

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
    const std::pair<const char*, Mesh> soups[] = {{"shuffled", shuffled(clean, rng)},
                                                  {"apart", welded_apart(clean)},
                                                  {"broken", broken(clean, rng)}};
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
