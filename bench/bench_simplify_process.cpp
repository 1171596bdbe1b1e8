// `limn simplify` as a user runs it, a whole process from file to file, beside a CGAL 5.5 program
// doing the same job: read the mesh, variational shape approximation with K proxies (CGAL:
// approximate_triangle_mesh with hierarchical seeding and 30 iterations, its documented way;
// limn: its default greedy optimiser), mesh the result, write an OBJ. Wall time of each process,
// the best of --repeat runs, on the shared tri/ meshes of 5k-125k faces.
//   limn_bench_simplify_process [--repeat N] [--proxies K] [--models DIR]
//   limn_bench_simplify_process --cgal IN OUT K      (the CGAL program itself)
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_approximation/approximate_triangle_mesh.h>
#include <CGAL/boost/graph/IO/polygon_mesh_io.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "clock.hpp"

extern char** environ;

namespace fs = std::filesystem;

namespace {

int cgal_program(const char* in, const char* out, size_t proxies) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using SM = CGAL::Surface_mesh<Kernel::Point_3>;
  namespace VSA = CGAL::Surface_mesh_approximation;
  SM mesh;
  if (!CGAL::IO::read_polygon_mesh(in, mesh) || !CGAL::is_triangle_mesh(mesh)) {
    fmt::print(stderr, "{}: not a triangle mesh CGAL can read\n", in);
    return 2;
  }
  std::vector<Kernel::Point_3> anchors;
  std::vector<std::array<std::size_t, 3>> triangles;
  VSA::approximate_triangle_mesh(mesh, CGAL::parameters::seeding_method(VSA::HIERARCHICAL)
                                           .max_number_of_proxies(proxies)
                                           .number_of_iterations(30)
                                           .anchors(std::back_inserter(anchors))
                                           .triangles(std::back_inserter(triangles)));
  return CGAL::IO::write_polygon_soup(out, anchors, triangles) ? 0 : 1;
}

// Runs argv as a process; its wall time in ms, or a negative number when it fails.
double run(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const double t0 = limn::bench::now_ms();
  pid_t pid = 0;
  posix_spawn_file_actions_t quiet;  // the report lines would bury the table
  posix_spawn_file_actions_init(&quiet);
  posix_spawn_file_actions_addopen(&quiet, 1, "/dev/null", O_WRONLY, 0);
  const int spawned = posix_spawn(&pid, argv[0], &quiet, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&quiet);
  if (spawned != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return -1;
  const double ms = limn::bench::now_ms() - t0;
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? ms : -1;
}

double best_of(int repeat, const std::vector<std::string>& args) {
  double best = -1;
  for (int i = 0; i < repeat; ++i) {
    const double ms = run(args);
    if (ms < 0) return -1;
    if (best < 0 || ms < best) best = ms;
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 5 && std::strcmp(argv[1], "--cgal") == 0)
    return cgal_program(argv[2], argv[3], std::strtoul(argv[4], nullptr, 10));
  int repeat = 3;
  size_t proxies = 100;
  fs::path models = fs::path(LIMN_SHARED_MODELS) / "tri";
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--repeat") == 0)
      repeat = std::atoi(argv[++i]);
    else if (std::strcmp(argv[i], "--proxies") == 0)
      proxies = std::strtoul(argv[++i], nullptr, 10);
    else if (std::strcmp(argv[i], "--models") == 0)
      models = argv[++i];
  }
  const std::string self = fs::canonical("/proc/self/exe").string(), limn = LIMN_CLI;
  const fs::path out_dir = fs::temp_directory_path() / fmt::format("limn-simplify-{}", getpid());
  fs::create_directories(out_dir);
  fmt::print("whole processes, file to file, K = {}, best of {}\n", proxies, repeat);
  fmt::print("{:<22} {:>8} {:>11} {:>11}  {}\n", "mesh", "faces", "CGAL ms", "limn ms",
             "CGAL/limn");
  for (const char* name :
       {"spot.obj", "homer.obj", "fandisk.obj", "rocker-arm.obj", "stanford-bunny.obj",
        "armadillo-100k.obj", "feline.obj", "nefertiti.obj", "ogre.obj"}) {
    const fs::path in = models / name;
    if (!fs::exists(in)) continue;
    size_t faces = 0;
    {
      std::FILE* f = std::fopen(in.c_str(), "r");
      char line[512];
      while (f && std::fgets(line, sizeof line, f)) faces += line[0] == 'f' && line[1] == ' ';
      if (f) std::fclose(f);
    }
    const std::string k = std::to_string(proxies);
    const double cgal = best_of(repeat, {self, "--cgal", in, out_dir / "cgal.obj", k});
    const double ours =
        best_of(repeat, {limn, "simplify", in, "-o", out_dir / "limn.obj", "--proxies", k});
    const std::string ratio =
        cgal > 0 && ours > 0 ? fmt::format("{:.2f}x", cgal / ours) : "(a side failed)";
    fmt::print("{:<22} {:>8} {:>11.1f} {:>11.1f}  {}\n", name, faces, cgal, ours, ratio);
    std::fflush(stdout);
  }
  fs::remove_all(out_dir);
  return 0;
}
