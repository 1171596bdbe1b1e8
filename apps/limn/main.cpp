// limn command-line tool: composes the library layers; no algorithm lives here.
#include <fmt/format.h>
#include <malloc.h>
#include <sys/mman.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "common.hpp"
#include "limn/version.hpp"

namespace {

// Asks for transparent huge pages over the heap above the next 2 MiB boundary (the heap's first
// sbrk is at least M_TOP_PAD, so that is most of it): on virtual machines a first touch of a 4 KiB
// page costs ~10-20 us, and a small job's heap faults (~400 of a 6k-face `limn simplify`'s 640)
// would cost more than its algorithm. The heap below the boundary is held by one block, so new
// allocations start above it. Nothing changes where huge pages are off.
void heap_in_huge_pages() {
#if !defined(__SANITIZE_ADDRESS__)  // sanitizers bring their own allocator
  const uintptr_t huge = uintptr_t(2) << 20;
  void* probe = std::malloc(64 << 10);  // too big for the bins: carved from the heap's top
  const uintptr_t at = reinterpret_cast<uintptr_t>(probe);
  std::free(probe);  // merged back into the top
  uintptr_t lo = (at + huge - 1) & ~(huge - 1);
  if (lo - at < 4096) lo += huge;  // room for the holding block
  static void* below = nullptr;    // held for the process's life; only its header is touched
  below = std::malloc(lo - at - 64);
  if (reinterpret_cast<uintptr_t>(below) != at) return;  // not from the top after all
  const uintptr_t hi = reinterpret_cast<uintptr_t>(sbrk(0)) & ~(huge - 1);
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  // One command runs, then the process ends: keep freed memory for reuse instead of handing it
  // back and faulting fresh pages in again (a vector that doubles would otherwise get a new
  // mapping each time). First touches of pages dominate small jobs on some virtual machines.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  mallopt(M_TOP_PAD, 64 << 20);
  heap_in_huge_pages();
  CLI::App app{"limn: adaptive subdivision, octree painting and shape approximation for surfaces",
               "limn"};
  app.set_version_flag("--version", std::string("limn ") + limn::version());
  app.require_subcommand(1);
  app.fallthrough(false);
  // Before the subcommand (whose work runs as it is parsed): results are the same on any number
  // of threads; this only caps how many work at once.
  std::unique_ptr<tbb::global_control> threads;
  app.add_option_function<int>(
         "--threads",
         [&](int n) {
           threads = std::make_unique<tbb::global_control>(
               tbb::global_control::max_allowed_parallelism, size_t(n));
         },
         "Threads at most (default: every core); results do not depend on it")
      ->check(CLI::Range(1, 1024))
      ->trigger_on_parse();
  limn::cli::add_info(app);
  limn::cli::add_convert(app);
  limn::cli::add_shape(app);
  limn::cli::add_subdivide(app);
  limn::cli::add_simplify(app);
  limn::cli::add_paint(app);
  limn::cli::add_bake(app);
  limn::cli::add_render(app);
  limn::cli::add_repair(app);
  limn::cli::add_unwrap(app);
  limn::cli::add_demo(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const limn::RepairableError& e) {
    // One line still: the problem, then what fixes it.
    bool has_flag = false;
    for (const CLI::App* sub : app.get_subcommands())
      has_flag |= sub->get_option_no_throw("--repair") != nullptr;
    std::fprintf(
        stderr, "limn: error: %s (%s)\n", e.what(),
        has_flag ? "rerun with --repair, or run limn repair on it" : "limn repair fixes this");
    return 2;
  } catch (const limn::InputError& e) {
    std::fprintf(stderr, "limn: error: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "limn: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "limn: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
