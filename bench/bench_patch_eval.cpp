// Limit-surface evaluation throughput: points per second on an N x N grid (9 by default) of every
// ptex face (a quad, or one of the n quad sub-faces of an n-gon), limn (evaluate_grids on its
// patch table, 1 and 2 threads; and the lookup path, PatchMap + evaluate_patches, 1 thread)
// beside OpenSubdiv 3.5's two CPU paths in one run, each on 1 and 2 threads: Far (adaptive
// PatchTable with Gregory-basis end caps: PatchMap + EvaluateBasis + the weighted sums, ptex
// faces split between threads) and Bfr (RefinerSurfaceFactory: one Surface per face,
// PreparePatchPoints, Evaluate; faces split between threads, a thread-safe cache on 2 threads).
// Positions and first derivatives; each side's point preparation (refined and end-cap points) is
// timed with it (serial on Far's side, as PrimvarRefiner and ComputeLocalPointValues are), into
// buffers sized outside the timing on both sides (as a frame loop keeps them); pts1t is limn's
// PatchTable::points alone, one thread.
//
// The same points in the same order on every side: ptex face by ptex face, row by row. An n-gon's
// sub-face c is limn's and Far's ptex face ptex_of_face[f] + c; Bfr parameterises the n-gon with
// quad sub-faces (Parameterization::QUAD_SUBFACES) and its normalised sub-face coordinates are
// the ptex coordinates, so its grid points are converted once, outside the timing. Holes: no
// side evaluates them. Isolation depth 3 for limn and Far, both with infinitely sharp patches
// (useInfSharpPatch, limn's default) and without single-crease patches: Far's EvaluateBasis
// evaluates a single-crease patch as a plain B-spline patch, ignoring its sharpness (the car and
// other semi-sharp cages then disagree by up to 1e-2 of the diagonal), so both sides isolate
// semi-sharp creases instead. Bfr at its defaults. Medians of 3 (9 under 100 ms) after a warm-up
// run, ms. The dev_* columns are each side's largest distance to limn's grid positions over the
// cage's bounding-box diagonal (Far should agree to float rounding; Bfr evaluates the exact limit
// where Far and limn use depth-3 end caps).
//
// Models: bigguy, monsterfrog (shared quads/), car, pole360 (shared osd/), terrain and
// torus-dense (limn's procedural ~800k-quad cages, make_shape), or paths to meshes.
//   limn_bench_patch_eval [--grid N] [--models a,b,...] [--skip-far-over SECONDS]
// --skip-far-over S: Far's evaluation is not timed on a cage whose Far table took over S seconds
// to build, and a Far run over S seconds is not repeated (no cap by default: the adaptive table
// alone builds in under a second on pole360, whose tens of seconds in limn_bench_patches are
// Far's stencil tables, and in ~35 s on the 800k torus; both are printed when over a second).
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <vector>

#include "osd_bench.hpp"

#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/patches.hpp"

using namespace OpenSubdiv;
using limn::bench::now_ms;
namespace fs = std::filesystem;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Medians of 3 runs (9 when they take under 100 ms) after an untimed one (first touches of each
// side's fresh memory: limn's first two PatchTable::points on the car took 7.5 ms, later ones 1.1);
// `cap_ms` > 0: no warm-up run, and no more runs after one over it (the median of those done).
template <class F>
double median_ms(F&& f, double cap_ms = 0) {
  if (cap_ms <= 0) f();
  std::vector<double> t;
  for (int i = 0; i < 9; ++i) {
    const double t0 = now_ms();
    f();
    t.push_back(now_ms() - t0);
    if (cap_ms > 0 && t.back() > cap_ms) break;
    // Runs of a few ms are at the mercy of one scheduler hiccup: 9 of them, 3 of longer ones.
    if (i == 2 && *std::max_element(t.begin(), t.end()) > 100) break;
  }
  return limn::bench::median(t);
}

struct P3 {
  float x = 0, y = 0, z = 0;
  void Clear(void* = nullptr) { x = y = z = 0; }
  void AddWithWeight(const P3& p, float w) { x += w * p.x, y += w * p.y, z += w * p.z; }
};

using ThreadedCache =
    Bfr::SurfaceFactoryCacheThreaded<std::shared_mutex, std::shared_lock<std::shared_mutex>,
                                     std::unique_lock<std::shared_mutex>>;

struct Model {
  std::string label;
  limn::Mesh cage;
};

// A name of the list, a make_shape name, or a path.
Model load_model(const std::string& spec, const fs::path& shared) {
  static const std::pair<const char*, const char*> known[] = {
      {"bigguy", "quads/bigguy.obj"},         {"monsterfrog", "quads/monsterfrog.obj"},
      {"car", "osd/catmark_car.obj"},         {"catmark_car", "osd/catmark_car.obj"},
      {"pole360", "osd/catmark_pole360.obj"}, {"catmark_pole360", "osd/catmark_pole360.obj"}};
  for (const auto& [name, rel] : known)
    if (spec == name) return {fs::path(rel).filename().string(), limn::read_mesh(shared / rel)};
  for (const std::string& s : limn::shape_names())
    if (spec == s) return {s, limn::make_shape(s)};
  return {fs::path(spec).filename().string(), limn::read_mesh(spec)};
}

std::vector<std::string> split(const char* s) {
  std::vector<std::string> out(1);
  for (; *s; ++s)
    if (*s == ',')
      out.emplace_back();
    else
      out.back() += *s;
  return out;
}

// How one side's positions compare with limn's grid: the largest distance over live points,
// live points it left unwritten (NaN), and dead points (holes) it wrote.
struct Agreement {
  double max_dist = 0;
  size_t missing = 0, extra = 0;
  void add(const Agreement& o) {
    max_dist = std::max(max_dist, o.max_dist), missing += o.missing, extra += o.extra;
  }
};

// `at(k)`: the side's position of live point k (ptex-ordered index `ptex * per + i`), or NaN.
Agreement compare(const std::vector<float>& ref, const std::vector<uint8_t>& live, size_t per,
                  const float* got, bool compact) {
  Agreement a;
  size_t c = 0;
  for (size_t g = 0; g < live.size(); ++g)
    for (size_t i = 0; i < per; ++i) {
      const size_t o = 3 * (g * per + i);
      if (!live[g]) {
        if (!compact && !std::isnan(got[o])) ++a.extra;
        continue;
      }
      const float* p = got + (compact ? 3 * c++ : o);
      if (std::isnan(p[0])) {
        ++a.missing;
        continue;
      }
      a.max_dist = std::max<double>(
          a.max_dist, std::hypot(p[0] - ref[o], p[1] - ref[o + 1], p[2] - ref[o + 2]));
    }
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  int grid = 9;
  double skip_far_s = 0;
  std::vector<std::string> specs = {"bigguy",  "monsterfrog", "car",
                                    "pole360", "terrain",     "torus-dense"};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--grid") && i + 1 < argc)
      grid = std::max(2, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--models") && i + 1 < argc)
      specs = split(argv[++i]);
    else if (!std::strcmp(argv[i], "--skip-far-over") && i + 1 < argc)
      skip_far_s = std::max(0.0, std::atof(argv[++i]));
    else {
      fmt::print(stderr,
                 "usage: limn_bench_patch_eval [--grid N] [--models a,b,...] "
                 "[--skip-far-over SECONDS]\n");
      return 2;
    }
  }
  const int depth = 3;
  const fs::path shared = LIMN_SHARED_MODELS;
  fmt::print(
      "{:<20} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>7} {:>7} {:>7} {:>7} "
      "{:>7} {:>8} {:>8} {:>8}\n",
      "model", "points", "pts1t", "limn1t", "limn2t", "look1t", "far1t", "far2t", "bfr1t", "bfr2t",
      "far/l1", "far/l2", "bfr/l1", "bfr/l2", "far/lk", "dev_far", "dev_bfr", "dev_look");
  for (const std::string& spec : specs) {
    const Model model = load_model(spec, shared);
    const limn::Mesh& cage = model.cage;
    const float diag = limn::bounding_box(cage).diagonal();
    std::vector<float> uv;
    for (int j = 0; j < grid; ++j)
      for (int i = 0; i < grid; ++i)
        uv.push_back(float(i) / float(grid - 1)), uv.push_back(float(j) / float(grid - 1));
    const size_t nf = cage.face_count(), per = uv.size() / 2;

    // limn: the table is built once (preprocessing is benchmarked elsewhere).
    limn::PatchOptions po;
    po.subdiv = limn::subdiv_options(cage);
    po.depth = depth;
    po.single_crease_patches = false;  // Far's EvaluateBasis ignores crease sharpness
    auto table = std::make_unique<limn::PatchTable>(limn::build_patches(cage, po));
    const std::vector<uint32_t> ptex_of_face = table->ptex_of_face;
    const size_t nptex = table->ptex_count, slots = nptex * per;
    // Live ptex faces: those limn's patches cover (not holes).
    std::vector<uint8_t> live(nptex, 0);
    for (const auto* params : {&table->regular_params, &table->gregory_params})
      for (const limn::PatchParam& p : *params) live[p.ptex] = 1;
    std::vector<uint32_t> live_ptex;
    for (uint32_t g = 0; g < nptex; ++g)
      if (live[g]) live_ptex.push_back(g);
    const size_t total = live_ptex.size() * per;

    std::vector<float> out(3 * slots, kNaN), du(3 * slots), dv(3 * slots);
    double limn1, limn2, lookup1, points1;
    Agreement dev_look;
    std::vector<float> ref;
    {
      const limn::PatchMap map(*table);
      std::vector<limn::PatchCoord> coords(total);
      // The same points, in the same order (ptex face by ptex face, row by row), no lookups.
      // The points go into a buffer sized (and touched) outside the timing, as Far's do: a
      // fresh vector per run would time the kernel's page faults (on the dense torus's 15M
      // points, 0.5 s of this machine's 0.6 s for PatchTable::points).
      std::vector<float> pts = table->points(cage.positions);
      auto limn_grid = [&] {
        table->points(cage.positions, pts);
        limn::evaluate_grids(*table, pts, grid, out.data(), du.data(), dv.data());
      };
      // The lookup path: the live points, compact.
      auto limn_lookup = [&] {
        table->points(cage.positions, pts);
        size_t c = 0;
        for (const uint32_t g : live_ptex)
          for (size_t k = 0; k < per; ++k) coords[c++] = map.find(g, uv[2 * k], uv[2 * k + 1]);
        limn::evaluate_patches(*table, pts, coords, out.data(), du.data(), dv.data());
      };
      {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        limn1 = median_ms(limn_grid);
        points1 = median_ms([&] { table->points(cage.positions, pts); });
        ref = out;  // limn's grid: every other side is compared with it
        std::fill(out.begin(), out.end(), kNaN);
        lookup1 = median_ms(limn_lookup);
        dev_look = compare(ref, live, per, out.data(), true);
      }
      {
        tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
        std::fill(out.begin(), out.end(), kNaN);
        limn2 = median_ms(limn_grid);
        dev_look.add(compare(ref, live, per, out.data(), false));  // 2t grid == 1t grid
      }
      table.reset();
    }

    // Far: ptex face by ptex face; a thread takes a range of ptex faces.
    double far1 = kNaN, far2 = kNaN, far_build_s = 0;
    Agreement dev_far;
    dev_far.max_dist = kNaN;  // until Far is timed
    {
      const double t0 = now_ms();
      const limn::bench::OsdAdaptive far = limn::bench::osd_adaptive(cage, depth, false, true);
      far_build_s = (now_ms() - t0) / 1000;
      if (skip_far_s <= 0 || far_build_s <= skip_far_s) {
        const Far::PatchTable* pt = far.table.get();
        const Far::PatchMap far_map(*pt);
        std::vector<P3> verts;
        limn::bench::osd_points(far, cage, verts);  // sized (and touched) outside the timing
        auto eval_range = [&](size_t g0, size_t g1) {
          float wp[20], wu[20], wv[20];
          for (size_t g = g0; g < g1; ++g)
            for (size_t k = 0; k < per; ++k) {
              const auto* h = far_map.FindPatch(int(g), uv[2 * k], uv[2 * k + 1]);
              if (!h) continue;  // a hole
              pt->EvaluateBasis(*h, uv[2 * k], uv[2 * k + 1], wp, wu, wv);
              const auto cvs = pt->GetPatchVertices(*h);
              P3 p, a, b;
              for (int i = 0; i < cvs.size(); ++i) {
                const P3& c = verts[size_t(cvs[i])];
                p.AddWithWeight(c, wp[i]), a.AddWithWeight(c, wu[i]), b.AddWithWeight(c, wv[i]);
              }
              const size_t o = 3 * (g * per + k);
              out[o] = p.x, out[o + 1] = p.y, out[o + 2] = p.z;
              du[o] = a.x, du[o + 1] = a.y, du[o + 2] = a.z;
              dv[o] = b.x, dv[o + 1] = b.y, dv[o + 2] = b.z;
            }
        };
        auto far_run = [&] {
          limn::bench::osd_points(far, cage, verts);
          tbb::parallel_for(tbb::blocked_range<size_t>(0, nptex, 64),
                            [&](const auto& r) { eval_range(r.begin(), r.end()); });
        };
        const double cap_ms = skip_far_s * 1000;
        {
          tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
          std::fill(out.begin(), out.end(), kNaN);
          far1 = median_ms(far_run, cap_ms);
          dev_far = compare(ref, live, per, out.data(), false);
        }
        {
          tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
          std::fill(out.begin(), out.end(), kNaN);
          far2 = median_ms(far_run, cap_ms);
          dev_far.add(compare(ref, live, per, out.data(), false));
        }
      }
    }

    // Bfr: face by face; an n-gon's sub-faces in order, at their ptex points converted to the
    // face's parameterisation (once per face size, outside the timing).
    double bfr1, bfr2;
    Agreement dev_bfr;
    {
      std::vector<std::vector<float>> face_uv;  // by face size: sub-face by sub-face
      for (size_t f = 0; f < nf; ++f) {
        const size_t n = cage.face_size(f);
        if (n == 4 || (n < face_uv.size() && !face_uv[n].empty())) continue;
        if (face_uv.size() <= n) face_uv.resize(n + 1);
        const Bfr::Parameterization param(Sdc::SCHEME_CATMARK, int(n));
        for (int c = 0; c < int(n); ++c)
          for (size_t k = 0; k < per; ++k) {
            float w[2];
            param.ConvertNormalizedSubFaceToCoord(c, &uv[2 * k], w);
            face_uv[n].push_back(w[0]), face_uv[n].push_back(w[1]);
          }
      }
      auto bfr_refiner = limn::bench::osd_refiner(cage);
      auto eval_faces = [&](const Bfr::SurfaceFactory& factory, size_t f0, size_t f1) {
        Bfr::Surface<float> surface;
        std::vector<float> patch_points;
        const Bfr::Surface<float>::PointDescriptor desc(3);
        for (size_t f = f0; f < f1; ++f) {
          if (!factory.InitVertexSurface(int(f), &surface)) continue;
          patch_points.resize(3 * size_t(surface.GetNumPatchPoints()));
          surface.PreparePatchPoints(cage.positions.data(), desc, patch_points.data(), desc);
          const size_t n = cage.face_size(f);
          const float* fuv = n == 4 ? uv.data() : face_uv[n].data();
          const size_t first = 3 * ptex_of_face[f] * per, count = (n == 4 ? 1 : n) * per;
          for (size_t k = 0; k < count; ++k) {
            const size_t o = first + 3 * k;
            surface.Evaluate(&fuv[2 * k], patch_points.data(), desc, &out[o], &du[o], &dv[o]);
          }
        }
      };
      {
        const Bfr::RefinerSurfaceFactory<> factory(*bfr_refiner);
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        std::fill(out.begin(), out.end(), kNaN);
        bfr1 = median_ms([&] { eval_faces(factory, 0, nf); });
        dev_bfr = compare(ref, live, per, out.data(), false);
      }
      {
        const Bfr::RefinerSurfaceFactory<ThreadedCache> factory(*bfr_refiner);
        tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
        std::fill(out.begin(), out.end(), kNaN);
        bfr2 = median_ms([&] {
          tbb::parallel_for(tbb::blocked_range<size_t>(0, nf, 16),
                            [&](const auto& r) { eval_faces(factory, r.begin(), r.end()); });
        });
        dev_bfr.add(compare(ref, live, per, out.data(), false));
      }
    }

    fmt::print(
        "{:<20} {:>9} {:>8.2f} {:>8.2f} {:>8.2f} {:>8.2f} {:>8.2f} {:>8.2f} {:>8.2f} {:>8.2f} "
        "{:>6.2f}x "
        "{:>6.2f}x {:>6.2f}x {:>6.2f}x {:>6.2f}x {:>8.1e} {:>8.1e} {:>8.1e}\n",
        model.label, total, points1, limn1, limn2, lookup1, far1, far2, bfr1, bfr2, far1 / limn1,
        far2 / limn2, bfr1 / limn1, bfr2 / limn2, far1 / lookup1, dev_far.max_dist / diag,
        dev_bfr.max_dist / diag, dev_look.max_dist / diag);
    if (far_build_s > 1 || std::isnan(far1))
      fmt::print("  {}: Far's table took {:.1f} s to build{}\n", model.label, far_build_s,
                 std::isnan(far1) ? " (over --skip-far-over: its evaluation not timed)" : "");
    for (const auto& [side, a] :
         {std::pair{"Far", dev_far}, std::pair{"Bfr", dev_bfr}, std::pair{"limn lookup", dev_look}})
      if (a.missing || a.extra)
        fmt::print("  {}: {} left {} live points unevaluated and wrote {} in holes\n", model.label,
                   side, a.missing, a.extra);
    std::fflush(stdout);
  }
}
