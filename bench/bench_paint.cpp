// Octree texture benchmark: the paper's Table 1 on real models, and limn beside OpenVDB 10 in one
// run. Single thread throughout (lookups too).
//
// Table 1, per model and depth D (leaves at level D, 2^D over the mesh's bounding cube):
//  * dense: an RGBA8 volume, 4 * 8^D bytes; built (the surface voxelised into it) up to 1 GiB.
//  * regular: the full octree in GPU Gems 2's layout (every node a 2x2x2 grid of 4-byte cells,
//    children addressed by 8-bit RGB pool coordinates, so at most 2^24 nodes), every surface
//    cell refined to D: nodes, bytes, build time (voxelising the surface); "cannot be built"
//    past 2^24 nodes.
//  * adaptive: limn painting a fixed set of strokes (12 strokes of 6 dabs, radius 1/64 of the
//    cube) at depth D, from the coarse start tree: bytes, painted texels, time (paint + start).
//  * limn full: limn's octree with the whole surface refined to D and filled (limn's answer to
//    the regular octree), then compacted as limn paint saves it: bytes, bytes per painted texel,
//    time (refine + fill + compact).
//  * OpenVDB: an Int32Grid holding the same painted cells (limn full's leaves, RGBA8 as int32):
//    memUsage, bytes per texel, insert time (from the cell list: no surface work).
// Lookups at depth 10 on limn full (compacted, with a level-6 OctreeIndex, whose size is
// printed) and the VDB grid, the same points in the same order: 1M random points on the surface
// (area-weighted, with their face normal), in random order and in Morton order; nearest (limn
// OctreeSampler::nearest one point at a time, and nearest_batch; VDB ValueAccessor::probeValue)
// and trilinear (limn OctreeSampler::filtered / filtered_batch: 8 taps with side tags; VDB: 8
// probeValue taps blended with the same renormalised premultiplied weights, no sides). Medians
// of 3.
// Dab time at depth 10: strokes of dabs radius 4, 8, 16, 32 leaves at random surface points,
// first pass (refining from the start tree) and a second pass over the same dabs, each dab a
// stroke of its own (a click); then dabs in strokes of 12-13 dabs (a drag) at radius 16 and 32,
// with the stroke's reuse across dabs on and off (StrokePainter::set_reuse).
//   limn_bench_paint [--models DIR] [--depths 6,7,8,9,10,11] [--points N] [--quick] [--threads N]
//                    [--only table|lookups|dabs|strokes] [--dump FILE] [--cpu-clock] [--reps N]
// --only: one part (dabs: both dab tables; strokes: the second alone; lookups still build limn full
// and the VDB grid at depth 10, unprinted);
// --dump: writes a hash of every lookup result and of every dab configuration's painted samples
// (after each pass), to check that a change leaves results bit for bit as they were;
// --cpu-clock: lookup and dab times in thread CPU time instead of wall time (for a busy
// machine); --reps:
// lookup repetitions (3); --threads: TBB's threads for painting and refining (the dab tables,
// Table 1's adaptive strokes and limn full builds; 1; above 1, wall time even with --cpu-clock);
// the dense, regular and OpenVDB builds and the lookups stay on one thread.
#include <fmt/format.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wpedantic"
#include <openvdb/openvdb.h>
#pragma GCC diagnostic pop

#include "clock.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/texture.hpp"
#include "paint/geometry.hpp"
#include "paint_scene.hpp"

namespace fs = std::filesystem;
using namespace limn;

namespace {

using bench::median;
using bench::now_ms;
using bench::Sample;
using bench::surface_points;

// This thread's CPU time in ms: times with --cpu-clock (a busy machine's descheduling left
// out).
double cpu_ms() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

bool g_cpu_clock = false;
// The clock lookups and dabs are timed with.
double clock_ms() {
  return g_cpu_clock ? cpu_ms() : now_ms();
}

std::string mib(double bytes) {
  if (bytes >= 1024.0 * 1024 * 1024)
    return fmt::format("{:.2f} GiB", bytes / (1024.0 * 1024 * 1024));
  if (bytes >= 1024.0 * 1024) return fmt::format("{:.2f} MiB", bytes / (1024.0 * 1024));
  return fmt::format("{:.1f} KiB", bytes / 1024.0);
}

// The regular octree of GPU Gems 2 (ch. 37): a pool of 2x2x2 grids of RGBA8 cells; a cell is
// empty, a colour, or a child grid's pool coordinates in RGB (so at most 256^3 grids).
struct GemsOctree {
  std::vector<uint32_t> cells;  // 8 per node
  size_t nodes = 0;
  bool overflow = false;
};

struct Voxeliser {
  const PaintSurface& s;
  float origin[3];
  float size;
  int depth;
  float slack;
  GemsOctree* gems = nullptr;
  uint32_t* dense = nullptr;
  size_t leaves = 0;

  void box(int level, uint32_t x, uint32_t y, uint32_t z, paint_detail::V3& c, float& h) const {
    const double cell = double(size) / double(1u << level);
    c = {float(origin[0] + (x + 0.5) * cell), float(origin[1] + (y + 0.5) * cell),
         float(origin[2] + (z + 0.5) * cell)};
    h = float(cell / 2);
  }
  // Node covering cell (level, x, y, z), with the triangles meeting it.
  void node(int level, uint32_t x, uint32_t y, uint32_t z, const std::vector<uint32_t>& tris,
            size_t index) {
    std::vector<uint32_t> sub;
    for (int c = 0; c < 8; ++c) {
      const uint32_t cx = 2 * x + uint32_t(c & 1), cy = 2 * y + uint32_t(c >> 1 & 1),
                     cz = 2 * z + uint32_t(c >> 2 & 1);
      paint_detail::V3 bc;
      float h;
      box(level + 1, cx, cy, cz, bc, h);
      sub.clear();
      for (uint32_t t : tris)
        if (paint_detail::tri_box_overlap(bc, h, paint_detail::v3(s.corner(t, 0)),
                                          paint_detail::v3(s.corner(t, 1)),
                                          paint_detail::v3(s.corner(t, 2)), slack))
          sub.push_back(t);
      if (sub.empty()) continue;
      if (level + 1 == depth) {
        ++leaves;
        const uint32_t colour = 0xff000000u | (cx * 2654435761u ^ cy * 40503u ^ cz) & 0xffffffu;
        if (gems) gems->cells[8 * index + size_t(c)] = colour;
        if (dense) {
          const size_t n = size_t(1) << depth;
          dense[(size_t(cz) * n + cy) * n + cx] = colour;
        }
        continue;
      }
      size_t child = 0;
      if (gems) {
        if (gems->nodes >= (size_t(1) << 24)) {
          gems->overflow = true;
          return;
        }
        child = gems->nodes++;
        gems->cells.resize(8 * gems->nodes, 0);
        // RGB = the child grid's pool coordinates, alpha 128 marks a pointer.
        gems->cells[8 * index + size_t(c)] = 0x80000000u | uint32_t(child & 0xffffffu);
      }
      node(level + 1, cx, cy, cz, sub, child);
      if (gems && gems->overflow) return;
    }
  }
};

std::vector<uint32_t> all_triangles(const PaintSurface& s) {
  std::vector<uint32_t> v;
  for (uint32_t t = 0; t < s.triangle_count(); ++t) {
    const float* n = s.normal(t);
    if (n[0] != 0 || n[1] != 0 || n[2] != 0) v.push_back(t);
  }
  return v;
}

uint64_t morton_key(const OctreeTexture& t, const float p[3]) {
  uint32_t c[3];
  for (int k = 0; k < 3; ++k) {
    const double u = std::clamp((double(p[k]) - t.origin()[k]) / t.size(), 0.0, 0.9999999);
    c[k] = uint32_t(u * 65536.0);
  }
  return paint_detail::morton3(c[0], c[1], c[2]);
}

// Painted strokes for the adaptive column (paint_scene.hpp), timed.
double timed_strokes(OctreeTexture& t, const PaintSurface& s, int depth,
                     const std::vector<Sample>& starts) {
  const double t0 = now_ms();
  bench::paint_strokes(t, s, depth, starts);
  return now_ms() - t0;
}

openvdb::Int32Grid::Ptr vdb_from(const OctreeTexture& t, int depth, double& ms) {
  std::vector<std::pair<openvdb::Coord, int32_t>> cells;
  t.for_each_sample([&](const OctreeSample& x) {
    if (x.side == 0 && x.level == depth)
      cells.push_back({openvdb::Coord(int(x.x), int(x.y), int(x.z)), int32_t(x.color)});
  });
  const double t0 = now_ms();
  openvdb::Int32Grid::Ptr g = openvdb::Int32Grid::create(0);
  openvdb::Int32Grid::Accessor acc = g->getAccessor();
  for (const auto& [c, v] : cells) acc.setValue(c, v);
  ms = now_ms() - t0;
  return g;
}

// Trilinear over the VDB grid with the same weights, renormalised over active taps.
template <class Acc>
bool vdb_trilinear(Acc& acc, const double u[3], int depth, float out[4]) {
  const double cells = double(1u << depth);
  int i0[3];
  double t[3];
  for (int k = 0; k < 3; ++k) {
    const double g = u[k] * cells - 0.5, f = std::floor(g);
    i0[k] = int(f), t[k] = g - f;
  }
  float acc4[5] = {0, 0, 0, 0, 0};
  for (int corner = 0; corner < 8; ++corner) {
    double w = 1;
    for (int k = 0; k < 3; ++k) w *= (corner >> k & 1) ? t[k] : 1 - t[k];
    int32_t v;
    if (!acc.probeValue(openvdb::Coord(i0[0] + (corner & 1), i0[1] + (corner >> 1 & 1),
                                       i0[2] + (corner >> 2 & 1)),
                        v))
      continue;
    const uint32_t c = uint32_t(v);
    const float a = float(channel(c, 3)) / 255.0f, fw = float(w);
    for (int k = 0; k < 3; ++k) acc4[k] += fw * a * float(channel(c, k)) / 255.0f;
    acc4[3] += fw * a, acc4[4] += fw;
  }
  if (!(acc4[4] > 0)) return false;
  for (int k = 0; k < 3; ++k) out[k] = acc4[3] > 0 ? acc4[k] / acc4[3] : 0;
  out[3] = acc4[3] / acc4[4];
  return true;
}

struct Args {
  fs::path models = LIMN_SHARED_MODELS;
  std::vector<int> depths = {6, 7, 8, 9, 10, 11};
  size_t points = 1000000;
  bool quick = false;
  std::string only;  // "", "table", "lookups" or "dabs"
  bool cpu_clock = false;
  int threads = 1;
  int reps = 3;  // lookup repetitions (medians)
  fs::path dump;
};

// FNV-1a over 32-bit words.
struct Hash {
  uint64_t h = 1469598103934665603ull;
  void add(uint32_t v) {
    for (int k = 0; k < 4; ++k) h = (h ^ (v >> (8 * k) & 255u)) * 1099511628211ull;
  }
  void add(float f) {
    uint32_t v;
    std::memcpy(&v, &f, 4);
    add(v);
  }
};

// A hash of every sample of a texture (cell, side, tag, colour), independent of the pool layout.
uint64_t sample_hash(const OctreeTexture& t) {
  std::vector<std::array<uint32_t, 7>> v;
  t.for_each_sample([&](const OctreeSample& x) {
    v.push_back({uint32_t(x.level), x.x, x.y, x.z, uint32_t(x.side), uint32_t(x.tag), x.color});
  });
  std::sort(v.begin(), v.end());
  Hash h;
  for (const auto& e : v)
    for (uint32_t w : e) h.add(w);
  return h.h;
}

}  // namespace

std::string threads_label(const Args& a) {
  return a.threads == 1 ? std::string("single thread")
                        : fmt::format("{} threads, wall time", a.threads);
}

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--models") && i + 1 < argc) a.models = argv[++i];
    if (!std::strcmp(argv[i], "--points") && i + 1 < argc) a.points = size_t(std::atoll(argv[++i]));
    if (!std::strcmp(argv[i], "--quick")) a.quick = true, a.depths = {6, 8, 10}, a.points = 200000;
    if (!std::strcmp(argv[i], "--only") && i + 1 < argc) a.only = argv[++i];
    if (!std::strcmp(argv[i], "--dump") && i + 1 < argc) a.dump = argv[++i];
    if (!std::strcmp(argv[i], "--cpu-clock")) a.cpu_clock = true;
    if (!std::strcmp(argv[i], "--threads") && i + 1 < argc)
      a.threads = std::max(1, std::atoi(argv[++i]));
    if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) a.reps = std::max(1, std::atoi(argv[++i]));
    if (!std::strcmp(argv[i], "--depths") && i + 1 < argc) {
      a.depths.clear();
      for (char* tok = std::strtok(argv[++i], ","); tok; tok = std::strtok(nullptr, ","))
        a.depths.push_back(std::atoi(tok));
    }
  }
  // A thread's CPU time says nothing of a parallel dab's wait: wall time with threads.
  g_cpu_clock = a.cpu_clock && a.threads == 1;
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, size_t(a.threads));
  openvdb::initialize();
  const std::vector<std::string> names = {"tri/stanford-bunny.obj", "tri/spot.obj",
                                          "tri/armadillo-100k.obj"};
  const bool do_table = a.only.empty() || a.only == "table",
             do_lookups = a.only.empty() || a.only == "lookups",
             do_dabs = a.only.empty() || a.only == "dabs",
             do_strokes = do_dabs || a.only == "strokes";
  FILE* dump = a.dump.empty() ? nullptr : std::fopen(a.dump.c_str(), "w");

  if (do_table) fmt::print("## Table 1: memory and build time by depth (single thread)\n\n");
  if (do_table)
    fmt::print(
        "| model | D | dense | regular (GPU Gems) nodes | regular bytes | regular ms | adaptive "
        "bytes | adaptive texels | adaptive ms | limn full bytes | limn full texels | B/texel | "
        "limn full ms | OpenVDB bytes | B/texel | VDB insert ms | VDB/limn bytes |\n");
  if (do_table)
    fmt::print(
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  struct LookupCase {
    std::string model;
    OctreeTexture tex;
    openvdb::Int32Grid::Ptr grid;
  };
  std::vector<LookupCase> at10;
  for (const std::string& name : do_table || do_lookups ? names : std::vector<std::string>{}) {
    const Mesh mesh = read_mesh(a.models / name);
    const PaintSurface surf(mesh);
    const std::vector<uint32_t> tris = all_triangles(surf);
    const OctreeTexture start = OctreeTexture::create(surf);
    const std::vector<Sample> starts = surface_points(surf, 12, 99);
    const std::string model = fs::path(name).stem().string();
    for (int depth : a.depths) {
      if (!do_table && depth != 10) continue;
      Voxeliser vox{surf,
                    {start.origin()[0], start.origin()[1], start.origin()[2]},
                    start.size(),
                    depth,
                    start.size() * float(1.0 / double(1u << 22))};
      // Dense.
      const double dense_bytes = 4.0 * std::pow(8.0, depth);
      std::string dense = mib(dense_bytes);
      if (do_table && dense_bytes <= 1024.0 * 1024 * 1024) {
        const double t0 = now_ms();
        std::vector<uint32_t> vol(size_t(dense_bytes / 4), 0);
        vox.dense = vol.data();
        vox.node(0, 0, 0, 0, tris, 0);
        vox.dense = nullptr;
        dense += fmt::format(" ({:.0f} ms)", now_ms() - t0);
      } else {
        dense += " (not built)";
      }
      // Regular octree, GPU Gems layout.
      GemsOctree gems;
      gems.cells.assign(8, 0);
      gems.nodes = 1;
      vox.gems = &gems;
      vox.leaves = 0;
      double t0 = now_ms();
      if (do_table) vox.node(0, 0, 0, 0, tris, 0);
      const double gems_ms = now_ms() - t0;
      vox.gems = nullptr;
      std::string gems_nodes, gems_bytes, gems_time;
      if (gems.overflow) {
        gems_nodes = "> 2^24: cannot be built", gems_bytes = "-", gems_time = "-";
      } else {
        gems_nodes = fmt::format("{}", gems.nodes), gems_bytes = mib(32.0 * double(gems.nodes));
        gems_time = fmt::format("{:.0f}", gems_ms);
      }
      gems = {};
      // Adaptive: strokes from the start tree.
      OctreeTexture ad = start;
      const double ad_ms = do_table ? timed_strokes(ad, surf, depth, starts) : 0.0;
      const OctreeTextureStats ads = ad.stats();
      // limn full.
      OctreeTexture full = start;
      t0 = now_ms();
      const float colour[4] = {0.8f, 0.5f, 0.2f, 1.0f};
      fill(full, surf, colour, BlendMode::mix, 1.0f, depth);
      full.compact();  // as limn paint saves it
      const double full_ms = now_ms() - t0;
      const OctreeTextureStats fs_ = full.stats();
      // OpenVDB with the same cells.
      double vdb_ms = 0;
      openvdb::Int32Grid::Ptr grid = vdb_from(full, depth, vdb_ms);
      const double vdb_bytes = double(grid->memUsage());
      const double vdb_texels = double(grid->activeVoxelCount());
      if (do_table)
        fmt::print(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.0f} | {} | {} | {:.2f} | {:.0f} | {} | "
            "{:.1f} | {:.0f} | {:.1f}x |\n",
            model, depth, dense, gems_nodes, gems_bytes, gems_time, mib(double(ads.bytes)),
            ads.painted_samples, ad_ms, mib(double(fs_.bytes)), fs_.painted_samples,
            fs_.bytes_per_painted_texel, full_ms, mib(vdb_bytes), vdb_bytes / vdb_texels, vdb_ms,
            vdb_bytes / double(fs_.bytes));
      std::fflush(stdout);
      if (depth == 10) at10.push_back({model, std::move(full), grid});
    }
  }

  if (do_lookups)
    fmt::print("\n## Lookups at depth 10 (single thread, {} surface points, M lookups/s)\n\n",
               a.points);
  if (do_lookups)
    fmt::print(
        "| model | order | limn nearest | limn batched | VDB nearest | limn/VDB | batched/VDB | "
        "limn "
        "trilinear | limn batched | VDB trilinear | limn/VDB | batched/VDB | nearest agree | index "
        "|\n");
  if (do_lookups)
    fmt::print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (LookupCase& c : at10) {
    if (!do_lookups) break;
    const Mesh mesh = read_mesh(a.models / (c.model == "stanford-bunny" ? "tri/stanford-bunny.obj"
                                            : c.model == "spot"         ? "tri/spot.obj"
                                                                : "tri/armadillo-100k.obj"));
    const PaintSurface surf(mesh);
    std::vector<Sample> pts = surface_points(surf, a.points, 7);
    const OctreeIndex index(c.tex, 6);
    for (const char* order : {"random", "Morton"}) {
      if (!std::strcmp(order, "Morton"))
        std::sort(pts.begin(), pts.end(), [&](const Sample& x, const Sample& y) {
          return morton_key(c.tex, x.p) < morton_key(c.tex, y.p);
        });
      std::vector<float> xyz, nrm;
      for (const Sample& x : pts)
        xyz.insert(xyz.end(), x.p, x.p + 3), nrm.insert(nrm.end(), x.n, x.n + 3);
      std::vector<Rgba8> outb(pts.size());
      std::vector<float> outf(4 * pts.size());
      std::vector<double> ln, lb, vn, lt, ltb, vt;
      size_t agree = 0, found = 0;
      for (int rep = 0; rep < a.reps; ++rep) {
        // limn nearest, one point at a time, then in batches.
        OctreeSampler smp(c.tex, &index);
        uint64_t sum = 0;
        double t0 = clock_ms();
        for (const Sample& x : pts) {
          Rgba8 col;
          smp.nearest(x.p, x.n, col);
          sum += col;
        }
        ln.push_back(clock_ms() - t0);
        OctreeSampler sb(c.tex, &index);
        t0 = clock_ms();
        sb.nearest_batch(xyz.data(), nrm.data(), pts.size(), outb.data());
        lb.push_back(clock_ms() - t0);
        // VDB nearest (the same world-to-index conversion).
        openvdb::Int32Grid::ConstAccessor acc = c.grid->getConstAccessor();
        uint64_t vsum = 0;
        t0 = clock_ms();
        const double scale = double(1u << 10) / c.tex.size();
        for (const Sample& x : pts) {
          const openvdb::Coord ijk(int(std::floor((x.p[0] - c.tex.origin()[0]) * scale)),
                                   int(std::floor((x.p[1] - c.tex.origin()[1]) * scale)),
                                   int(std::floor((x.p[2] - c.tex.origin()[2]) * scale)));
          int32_t v = 0;
          acc.probeValue(ijk, v);
          vsum += uint32_t(v);
        }
        vn.push_back(clock_ms() - t0);
        if (rep == 0) {
          // Agreement on the same points (cells with two sides differ only on the back).
          OctreeSampler s2(c.tex, &index);
          openvdb::Int32Grid::ConstAccessor a2 = c.grid->getConstAccessor();
          for (const Sample& x : pts) {
            Rgba8 col;
            const bool f = s2.nearest(x.p, x.n, col);
            const openvdb::Coord ijk(int(std::floor((x.p[0] - c.tex.origin()[0]) * scale)),
                                     int(std::floor((x.p[1] - c.tex.origin()[1]) * scale)),
                                     int(std::floor((x.p[2] - c.tex.origin()[2]) * scale)));
            int32_t v = 0;
            const bool g = a2.probeValue(ijk, v);
            found += f;
            agree += f == g && (!f || col == uint32_t(v));
          }
        }
        // Trilinear.
        float acc4[4], total = 0;
        t0 = clock_ms();
        for (const Sample& x : pts) {
          smp.filtered(x.p, x.n, 0.0f, acc4);
          total += acc4[0];
        }
        lt.push_back(clock_ms() - t0);
        OctreeSampler sfb(c.tex, &index);
        t0 = clock_ms();
        sfb.filtered_batch(xyz.data(), nrm.data(), pts.size(), 0.0f, outf.data());
        ltb.push_back(clock_ms() - t0);
        openvdb::Int32Grid::ConstAccessor acc2 = c.grid->getConstAccessor();
        float vtotal = 0;
        t0 = clock_ms();
        for (const Sample& x : pts) {
          double u[3];
          c.tex.to_unit(x.p, u);
          vdb_trilinear(acc2, u, 10, acc4);
          vtotal += acc4[0];
        }
        vt.push_back(clock_ms() - t0);
        if (rep == 0 && dump) {
          // Every result of this repetition, and filtered one at a time from a fresh sampler.
          Hash hn, hb, hf, hfb;
          for (Rgba8 v : outb) hb.add(v);
          for (float v : outf) hfb.add(v);
          OctreeSampler s3(c.tex, &index);
          for (const Sample& x : pts) {
            Rgba8 col;
            hn.add(uint32_t(s3.nearest(x.p, x.n, col))), hn.add(col);
          }
          OctreeSampler s4(c.tex, &index);
          for (const Sample& x : pts) {
            float r4[4];
            hf.add(uint32_t(s4.filtered(x.p, x.n, 0.0f, r4)));
            for (float v : r4) hf.add(v);
          }
          fmt::print(dump,
                     "lookups {} {} nearest {:016x} nearest_batch {:016x} filtered {:016x} "
                     "filtered_batch {:016x}\n",
                     c.model, order, hn.h, hb.h, hf.h, hfb.h);
        }
        if (sum == 1 || vsum == 1 || total < 0 || vtotal < 0) fmt::print("(impossible)\n");
      }
      const double n = double(pts.size()) / 1000.0;  // per ms -> M/s
      const double lnr = n / median(ln), lbr = n / median(lb), vnr = n / median(vn),
                   ltr = n / median(lt), ltbr = n / median(ltb), vtr = n / median(vt);
      fmt::print(
          "| {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.2f}x | {:.2f}x | {:.2f} | {:.2f} | {:.2f} | "
          "{:.2f}x | {:.2f}x | {:.2f}% | {} |\n",
          c.model, order, lnr, lbr, vnr, lnr / vnr, lbr / vnr, ltr, ltbr, vtr, ltr / vtr,
          ltbr / vtr, 100.0 * double(agree) / double(pts.size()), mib(double(index.bytes())));
      std::fflush(stdout);
    }
  }

  if (do_dabs)
    fmt::print("\n## Dab time at depth 10 ({}; radius in depth-10 leaves)\n\n", threads_label(a));
  if (do_dabs)
    fmt::print(
        "| model | radius | dabs | first pass ms/dab (median) | mean | second pass ms/dab (median) "
        "| texels per dab | rays per dab |\n");
  if (do_dabs) fmt::print("|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& name : do_dabs ? names : std::vector<std::string>{}) {
    const Mesh mesh = read_mesh(a.models / name);
    const PaintSurface surf(mesh);
    const std::vector<Sample> at = surface_points(surf, a.quick ? 40 : 100, 5);
    for (int leaves : {4, 8, 16, 32}) {
      OctreeTexture t = OctreeTexture::create(surf);
      Brush b;
      b.depth = 10, b.radius = t.size() * float(leaves) / 1024.0f, b.hardness = 0.5f;
      std::vector<double> first, second;
      size_t changed = 0, rays = 0, all_changed = 0, all_created = 0;
      for (int pass = 0; pass < 2; ++pass) {
        b.color[0] = pass ? 0.2f : 0.9f;
        for (const Sample& x : at) {
          StrokePainter p(t, surf);
          p.begin(b);
          const double t0 = clock_ms();
          p.dab_world(x.p);
          const double ms = clock_ms() - t0;
          const StrokeStats st = p.end();
          (pass ? second : first).push_back(ms);
          if (pass) changed += st.samples_changed, rays += st.rays;
          all_changed += st.samples_changed, all_created += st.leaves_created + st.nodes_created;
        }
        if (dump) {
          Hash words;
          for (uint32_t w : t.words()) words.add(w);
          fmt::print(dump,
                     "dabs {} {} pass {} samples {:016x} pool {:016x} changed {} created {}\n",
                     fs::path(name).stem().string(), leaves, pass, sample_hash(t), words.h,
                     all_changed, all_created);
        }
      }
      double mean = 0;
      for (double v : first) mean += v;
      mean /= double(first.size());
      fmt::print("| {} | {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.0f} | {:.0f} |\n",
                 fs::path(name).stem().string(), leaves, at.size(), median(first), mean,
                 median(second), double(changed) / double(at.size()),
                 double(rays) / double(at.size()));
      std::fflush(stdout);
    }
  }
  // Dabs in strokes: radius 16 and 32 leaves, dabs at the brush's default spacing along paths on
  // the surface (a surface point, then steps along the surface in a tangent direction), each path
  // one stroke, painted with reuse across dabs on and off (the same texture, bit for bit).
  if (do_strokes)
    fmt::print(
        "\n## Dabs in strokes at depth 10 ({}; spacing 0.25 radius; ms per dab)\n\n"
        "| model | radius | strokes | dabs | first pass, reuse | repaint, reuse | first pass, no "
        "reuse | repaint, no reuse |\n|---|---:|---:|---:|---:|---:|---:|---:|\n",
        threads_label(a));
  for (const std::string& name : do_strokes ? names : std::vector<std::string>{}) {
    const Mesh mesh = read_mesh(a.models / name);
    const PaintSurface surf(mesh);
    const std::vector<Sample> at = surface_points(surf, a.quick ? 8 : 20, 7);
    for (int leaves : {16, 32}) {
      double ms[2][2] = {};  // [reuse off, on][pass]
      size_t dabs = 0;
      for (int reuse = 1; reuse >= 0; --reuse) {
        OctreeTexture t = OctreeTexture::create(surf);
        Brush b;
        b.depth = 10, b.radius = t.size() * float(leaves) / 1024.0f, b.hardness = 0.5f;
        // Paths 3 radii long in steps of an eighth of the spacing.
        std::vector<std::vector<float>> paths;
        for (const Sample& x : at) {
          paint_detail::V3 p = paint_detail::v3(x.p), n = paint_detail::v3(x.n);
          paint_detail::V3 d = cross(
              n, std::fabs(n.x) < 0.9f ? paint_detail::V3{1, 0, 0} : paint_detail::V3{0, 1, 0});
          d = (1 / length(d)) * d;
          std::vector<float> xyz = {p.x, p.y, p.z};
          const float step = b.spacing * b.radius / 8;
          for (int i = 0; i < 96; ++i) {
            const paint_detail::V3 g = p + step * d;
            const float gq[3] = {g.x, g.y, g.z};
            SurfaceHit hit;
            if (!surf.closest_point(gq, b.radius, hit)) break;
            const paint_detail::V3 np = paint_detail::v3(hit.p);
            n = paint_detail::v3(hit.n);
            d = np - p;
            d = d - dot(d, n) * n;
            const float l = length(d);
            if (!(l > 0)) break;
            d = (1 / l) * d, p = np;
            xyz.insert(xyz.end(), {p.x, p.y, p.z});
          }
          paths.push_back(std::move(xyz));
        }
        size_t changed = 0;
        for (int pass = 0; pass < 2; ++pass) {
          b.color[0] = pass ? 0.2f : 0.9f;
          double total = 0;
          dabs = 0;
          for (const std::vector<float>& xyz : paths) {
            StrokePainter p(t, surf);
            p.set_reuse(reuse != 0);
            p.begin(b);
            const double t0 = clock_ms();
            p.stroke_world(xyz);
            total += clock_ms() - t0;
            const StrokeStats st = p.end();
            dabs += st.dabs, changed += st.samples_changed;
          }
          ms[reuse][pass] = total / double(std::max<size_t>(dabs, 1));
          if (dump) {
            Hash words;
            for (uint32_t w : t.words()) words.add(w);
            fmt::print(dump,
                       "strokes {} {} reuse {} pass {} samples {:016x} pool {:016x} changed {}\n",
                       fs::path(name).stem().string(), leaves, reuse, pass, sample_hash(t), words.h,
                       changed);
          }
        }
      }
      fmt::print("| {} | {} | {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.3f} |\n",
                 fs::path(name).stem().string(), leaves, at.size(), dabs, ms[1][0], ms[1][1],
                 ms[0][0], ms[0][1]);
      std::fflush(stdout);
    }
  }
  if (dump && do_dabs) {
    // Screen dabs through cameras (rays toward the eye, not along the normal): strokes across
    // each model from three sides, hashed as above.
    for (const std::string& name : names) {
      const Mesh mesh = read_mesh(a.models / name);
      const PaintSurface surf(mesh);
      OctreeTexture t = OctreeTexture::create(surf);
      Brush b;
      b.depth = 10, b.radius = 12, b.hardness = 0.3f, b.spacing = 0.5f;
      size_t changed = 0, rays = 0;
      for (int view = 0; view < 3; ++view) {
        PaintCamera cam;
        cam.width = 640, cam.height = 480, cam.fovy_deg = 40;
        for (int k = 0; k < 3; ++k)
          cam.target[k] = t.origin()[k] + 0.5f * t.size(), cam.eye[k] = cam.target[k];
        cam.eye[view == 0 ? 2 : view == 1 ? 0 : 1] += (view == 1 ? -1.6f : 1.6f) * t.size();
        if (view == 2) cam.up[0] = 0, cam.up[1] = 0, cam.up[2] = 1;
        b.color[0] = 0.3f * float(view), b.color[1] = 0.8f;
        StrokePainter p(t, surf);
        p.begin(b, &cam);
        std::vector<double> xy;
        for (int i = 0; i <= 40; ++i)
          xy.push_back(120.0 + 10.0 * i), xy.push_back(240.0 + 60.0 * std::sin(0.2 * i));
        p.stroke_screen(xy);
        const StrokeStats st = p.end();
        changed += st.samples_changed, rays += st.rays;
      }
      Hash words;
      for (uint32_t w : t.words()) words.add(w);
      fmt::print(dump, "screen {} samples {:016x} pool {:016x} changed {}\n",
                 fs::path(name).stem().string(), sample_hash(t), words.h, changed);
    }
  }
  if (dump) std::fclose(dump);
  return 0;
}
