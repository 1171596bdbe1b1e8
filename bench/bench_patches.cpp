// Feature-adaptive preprocessing benchmark: limn build_patches beside OpenSubdiv 3.5's Far
// adaptive path in one run (topology + RefineAdaptive + PatchTableFactory with Gregory-basis end
// caps + the refined-point stencils with the end-cap local points appended), at isolation depths
// 2, 3, 4, 6 on the FAS cages, the car and pole360. Single thread; medians of `--repeat` runs (one
// run where OpenSubdiv takes over 5 s). --special: both sides with single-crease and infinitely
// sharp patches (OpenSubdiv's useSingleCreasePatch / useInfSharpPatch; limn's defaults).
// --mesh PATH (repeatable) replaces the shared cages, e.g. `limn shape torus-dense` (the 800k-quad
// cage); --limn-only skips OpenSubdiv; --peak prints the peak resident memory after each side
// (one depth and --repeat 1 to read OpenSubdiv's). Runs alternate between the sides; --batched
// runs each side's repeats in a row (each then reuses the heap its own previous run left, as a
// long-running application would, instead of first-touching what the other side returned).
// --keep-heap: glibc keeps freed memory (no trimming, no mmap below 32 MB), so neither side pays
// the kernel for fresh pages after the first runs: what a long-running application with a
// caching allocator sees, and the compute-only comparison.
// --rss: every build runs in a child process of its own (forked after loading the cage), and the
// last two columns are each build's peak resident growth in MB (the kernel's peak RSS, reset at
// the start of the build, less the resident size then): the physical memory it took, as
// /usr/bin/time would count it, instead of page faults.
// --regions N: limn isolates regions of about N faces (PatchOptions::batch_faces) at any cage
// size, instead of only above 32,768 faces.
// limn_MB / osd_MB: the peak heap of one build (bytes held through operator new at once, the
// result included), counted by this program's own operator new.
// limn_pf / osd_pf: the median minor page faults of one build (fresh pages from the kernel; on
// this machine's virtualised kernel each costs ~10-20 us, so they can be most of the time).
//   limn_bench_patches [--repeat N] [--models DIR] [--depths 2,3,4,6] [--special] [--mesh PATH]
//                      [--limn-only] [--peak] [--batched] [--keep-heap] [--regions N] [--rss]
#include <fmt/format.h>
#include <tbb/global_control.h>

#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <new>
#include <string>
#include <vector>

#include "osd_bench.hpp"

#include "limn/io/mesh_io.hpp"
#include "limn/subdiv/patches.hpp"

using namespace OpenSubdiv;
using limn::bench::median;
using limn::bench::now_ms;
namespace fs = std::filesystem;

// Heap accounting: every allocation through operator new, so both libraries' peaks are counted
// the same way (sizes as malloc rounds them).
std::atomic<size_t> g_heap_now{0}, g_heap_peak{0};

void* counted_alloc(size_t n) {
  void* p = std::malloc(n ? n : 1);
  if (!p) throw std::bad_alloc();
  const size_t now = g_heap_now += malloc_usable_size(p);
  size_t peak = g_heap_peak.load();
  while (now > peak && !g_heap_peak.compare_exchange_weak(peak, now)) {
  }
  return p;
}

void counted_free(void* p) noexcept {
  if (!p) return;
  g_heap_now -= malloc_usable_size(p);
  std::free(p);
}

namespace {

// Peak heap of what `f` allocates beyond what is already held, in MB.
template <class F>
double heap_peak_mb(F&& f) {
  const size_t base = g_heap_now.load();
  g_heap_peak = base;
  f();
  return double(g_heap_peak.load() - base) / 1e6;
}

struct OsdResult {
  size_t patches = 0;
  double ms = 0;
};

OsdResult osd_build(const limn::Mesh& m, int depth, bool special) {
  const double t0 = now_ms();
  const limn::bench::OsdAdaptive a = limn::bench::osd_adaptive(m, depth, special, special);
  const Far::TopologyRefiner* r = a.refiner.get();
  const Far::PatchTable* pt = a.table.get();
  Far::StencilTableFactory::Options sto;
  sto.generateIntermediateLevels = true;
  sto.generateOffsets = true;
  std::unique_ptr<const Far::StencilTable> st(Far::StencilTableFactory::Create(*r, sto));
  std::unique_ptr<const Far::StencilTable> all(st.get());
  if (const Far::StencilTable* local = pt->GetLocalPointStencilTable()) {
    all.release();
    all.reset(Far::StencilTableFactory::AppendLocalPointStencilTable(*r, st.get(), local));
  } else {
    all.release();
  }
  OsdResult out;
  out.patches = size_t(pt->GetNumPatchesTotal());
  out.ms = now_ms() - t0;
  return out;
}

// Minor page faults of this process so far.
double minor_faults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_minflt);
}

// The process's peak resident memory so far (limn runs first: a later, larger peak is
// OpenSubdiv's).
double peak_gb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) * 1024.0 / 1e9;
}

// A field of /proc/self/status in MB ("VmRSS", "VmHWM": current and peak resident memory).
double status_mb(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const size_t n = std::strlen(field);
  while (std::getline(in, line))
    if (line.compare(0, n, field) == 0 && line.size() > n && line[n] == ':')
      return std::atof(line.c_str() + n + 1) * 1024.0 / 1e6;  // kB
  return 0;
}

// One build in a child process of its own (the heap as the parent left it, no pages either side
// returned): its time, patches and peak resident growth (the kernel's peak RSS, reset at the
// start, less the resident memory then), the physical memory the build took.
struct Forked {
  double ms = 0, rss_mb = 0, heap_mb = 0;
  size_t patches = 0;
  bool ok = false;
};
Forked run_forked(const std::function<void(Forked&)>& build) {
  int fd[2];
  if (pipe(fd) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    { std::ofstream("/proc/self/clear_refs") << "5"; }  // reset the peak to the current size
    const double before = status_mb("VmRSS");
    Forked r;
    build(r);
    r.rss_mb = status_mb("VmHWM") - before;
    r.ok = true;
    const ssize_t w = write(fd[1], &r, sizeof r);
    _exit(w == ssize_t(sizeof r) ? 0 : 1);
  }
  close(fd[1]);
  Forked r;
  if (pid < 0 || read(fd[0], &r, sizeof r) != ssize_t(sizeof r)) r = {};
  close(fd[0]);
  if (pid > 0) waitpid(pid, nullptr, 0);
  return r;
}

}  // namespace

void* operator new(size_t n) {
  return counted_alloc(n);
}
void* operator new[](size_t n) {
  return counted_alloc(n);
}
void operator delete(void* p) noexcept {
  counted_free(p);
}
void operator delete[](void* p) noexcept {
  counted_free(p);
}
void operator delete(void* p, size_t) noexcept {
  counted_free(p);
}
void operator delete[](void* p, size_t) noexcept {
  counted_free(p);
}

int main(int argc, char** argv) {
  int repeat = 3;
  bool special = false;
  fs::path models = LIMN_SHARED_MODELS;
  std::vector<int> depths = {2, 3, 4, 6};
  std::vector<fs::path> paths;
  bool limn_only = false, peak = false, batched = false, rss = false;
  uint32_t batch_faces = 0;  // limn's region size (0: its default)
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--models") && i + 1 < argc)
      models = argv[++i];
    else if (!std::strcmp(argv[i], "--mesh") && i + 1 < argc)
      paths.emplace_back(argv[++i]);
    else if (!std::strcmp(argv[i], "--limn-only"))
      limn_only = true;
    else if (!std::strcmp(argv[i], "--regions") && i + 1 < argc)
      batch_faces = uint32_t(std::max(0, std::atoi(argv[++i])));
    else if (!std::strcmp(argv[i], "--batched"))
      batched = true;
    else if (!std::strcmp(argv[i], "--rss"))
      rss = true;
    else if (!std::strcmp(argv[i], "--peak"))
      peak = true;
    else if (!std::strcmp(argv[i], "--keep-heap"))
      mallopt(M_TRIM_THRESHOLD, INT_MAX), mallopt(M_MMAP_THRESHOLD, 32 << 20);
    else if (!std::strcmp(argv[i], "--special"))
      special = true;
    else if (!std::strcmp(argv[i], "--depths") && i + 1 < argc) {
      depths.clear();
      for (const char* p = argv[++i]; *p;) {
        depths.push_back(std::atoi(p));
        while (*p && *p != ',') ++p;
        if (*p) ++p;
      }
    }
  }
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const char* names[] = {"quads/bigguy.obj", "quads/monsterfrog.obj", "osd/catmark_car.obj",
                         "osd/catmark_pole360.obj"};
  fmt::print("{:<22} {:>5} {:>10} {:>10} {:>10} {:>10} {:>8} {:>8} {:>8} {:>8} {:>8}\n", "model",
             "depth", "limn_patch", "osd_patch", "limn_ms", "osd_ms", "osd/limn", "limn_MB",
             "osd_MB", rss ? "limn_RSS" : "limn_pf", rss ? "osd_RSS" : "osd_pf");
  if (paths.empty())
    for (const char* name : names) paths.push_back(models / name);
  for (const fs::path& path : paths) {
    if (!fs::exists(path)) {
      fmt::print("{:<22} missing\n", path.string());
      continue;
    }
    const limn::Mesh m = limn::read_mesh(path);
    for (int depth : depths) {
      // One side's runs: times, page faults or (--rss) resident growth, patches, peak heap MB
      // (the same every run).
      struct Side {
        std::vector<double> ms, faults, rss;
        size_t patches = 0;
        double heap = 0;
      } L, O;
      auto limn_once = [&](Forked& r) {
        limn::PatchOptions opt;
        opt.subdiv = limn::subdiv_options(m);
        opt.depth = depth;
        opt.batch_faces = batch_faces;
        opt.inf_sharp_patches = opt.single_crease_patches = special;  // as the OpenSubdiv side
        const double t0 = now_ms();
        r.heap_mb = heap_peak_mb([&] {
          const limn::PatchTable t = limn::build_patches(m, opt);
          r.ms = now_ms() - t0;
          r.patches = t.patch_count();
        });
      };
      auto osd_once = [&](Forked& r) {
        OsdResult o;
        r.heap_mb = heap_peak_mb([&] { o = osd_build(m, depth, special); });
        r.ms = o.ms, r.patches = o.patches;
      };
      // One build of a side, here or (--rss) in a child process.
      auto once = [&](const std::function<void(Forked&)>& build, Side& side) {
        const double f0 = minor_faults();
        Forked r;
        if (rss) {
          r = run_forked(build);
          if (!r.ok) throw std::runtime_error("a forked build failed");
          side.rss.push_back(r.rss_mb);
        } else {
          build(r);
          side.faults.push_back(minor_faults() - f0);
        }
        side.ms.push_back(r.ms), side.patches = r.patches, side.heap = r.heap_mb;
        return r.ms;
      };
      auto run_limn = [&] {
        once(limn_once, L);
        if (peak) fmt::print("  peak RSS after limn: {:.2f} GB\n", peak_gb());
      };
      auto run_osd = [&] {
        const double ms = once(osd_once, O);
        if (peak) fmt::print("  peak RSS after OpenSubdiv: {:.2f} GB\n", peak_gb());
        return ms <= 5000;  // OpenSubdiv's high-valence pathology: one run says enough
      };
      if (batched) {  // each side's runs in a row: each finds the heap its own last run left
        for (int k = 0; k < repeat; ++k) run_limn();
        for (int k = 0; k < repeat && !limn_only; ++k)
          if (!run_osd()) break;
      } else {  // interleaved: each run finds the heap the other side left
        for (int k = 0; k < repeat; ++k) {
          run_limn();
          if (!limn_only && !run_osd()) break;
        }
      }
      auto med = [](const std::vector<double>& v) { return v.empty() ? 0.0 : median(v); };
      const double ml = med(L.ms), mo = med(O.ms);
      // --rss: the last two columns are each side's peak resident growth (MB), not faults.
      fmt::print(
          "{:<22} {:>5} {:>10} {:>10} {:>10.2f} {:>10.2f} {:>7.2f}x {:>8.2f} {:>8.2f} {:>8.{}f} "
          "{:>8.{}f}\n",
          path.filename().string(), depth, L.patches, O.patches, ml, mo, mo / ml, L.heap, O.heap,
          med(rss ? L.rss : L.faults), rss ? 2 : 0, med(rss ? O.rss : O.faults), rss ? 2 : 0);
      std::fflush(stdout);
    }
  }
}
