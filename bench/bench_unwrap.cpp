// limn unwrap beside xatlas on the shared tri/ meshes: charts, utilisation at a 1024 x 1024 atlas
// with 2 texels of padding, Sander's L2 / Linf stretch, and time; then the time to bake a painted
// octree texture into that atlas (1024^2, gutter 8), which xatlas does not do: its base colour
// alone ("bake s"), and every material channel with a normal map of the height ("mat s").
// Utilisation is xatlas's measure (texels of the padded charts over the atlas); cover is the texels
// the triangles touch alone.
//
// xatlas is not packaged for Debian, so its columns are the figures measured on this machine
// model for ../shared/design/pipeline.md ("Numbers to beat": xatlas defaults, padding 2,
// resolution 1024; utilisation with its random and brute-force packers; stretch computed on
// xatlas' output), not a run here. limn is timed here, best of --repeat runs.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "limn/atlas/unwrap.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/paint/bake.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/surface.hpp"

namespace {

struct Xatlas {
  const char* mesh;
  int charts;
  double random_pct, brute_pct, l2, linf;
  const char* seconds;  ///< charts + pack (random), as recorded
};

// ../shared/design/pipeline.md, "Numbers to beat".
constexpr Xatlas kXatlas[] = {
    {"spot", 39, 69.9, 70.0, 1.003, 1.22, "0.36 + 0.08"},
    {"fandisk", 15, 67.0, 71.1, 1.001, 1.18, "0.18 + 0.08"},
    {"homer", 124, 66.9, 74.3, 1.023, 20.9, "0.9 + 0.09"},
    {"rocker-arm", 43, 65.7, 70.3, 1.003, 2.54, "5-10 + 0.10"},
    {"stanford-bunny", 1053, 79.9, 84.4, 1.023, 18.8, "~30 + 0.16"},
    {"armadillo-100k", 322, 69.1, 75.5, 1.021, 9.71, "24-40 + 0.21"},
};

}  // namespace

int main(int argc, char** argv) {
  int repeat = 1;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
  const std::string dir = std::string(LIMN_SHARED_MODELS) + "/tri/";
  fmt::print(
      "{:<15} {:>6} {:>7} {:>7} {:>8} {:>8} {:>8} {:>7} {:>6} | {:>6} {:>13} {:>7} {:>6} {:>14}\n",
      "mesh", "charts", "util %", "cover %", "L2", "Linf", "s", "bake s", "mat s", "xatlas",
      "util % (r/b)", "L2", "Linf", "s");
  for (const Xatlas& x : kXatlas) {
    const std::string path = dir + x.mesh + ".obj";
    if (!std::filesystem::exists(path)) {
      fmt::print("{:<15} missing: {}\n", x.mesh, path);
      continue;
    }
    const limn::Mesh mesh = limn::read_mesh(path);
    limn::UnwrapOptions o;
    o.size = 1024;
    o.padding = 2;
    double best = 1e30;
    limn::UnwrapStats st;
    limn::UnwrapResult atlas;
    for (int r = 0; r < repeat; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      atlas = limn::unwrap_mesh(mesh, o, path);
      best = std::min(best,
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    st = atlas.stats;
    // The bake that follows: a material with a few dabs, baked into the 1024^2 atlas.
    const limn::PaintSurface surface(mesh);
    limn::MaterialTexture texture = limn::MaterialTexture::from_color(
        limn::OctreeTexture::create(surface, limn::pack_rgba8(200, 200, 190, 255)));
    for (size_t v = 0; v < mesh.vertex_count(); v += mesh.vertex_count() / 16 + 1) {
      limn::Brush b;
      b.depth = 9, b.radius = texture.color.size() * 0.05f;
      for (limn::ChannelPaint& c : b.material) c = {true, 0.8f, limn::BlendMode::mix, 1.0f};
      limn::MaterialPainter p(texture, surface);
      p.begin(b);
      p.dab_world(&mesh.positions[3 * v]);
      p.end();
    }
    auto best_of = [&](auto&& f) {
      double t = 1e30;
      for (int r = 0; r < repeat; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        t = std::min(t,
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
      return t;
    };
    const double bake =
        best_of([&] { limn::bake_uv_texture(texture.color, atlas.mesh, o.size, o.size, 8); });
    const double bake_material =
        best_of([&] { limn::bake_material(texture, atlas.mesh, o.size, o.size, 8, {}, true); });
    fmt::print(
        "{:<15} {:>6} {:>7.1f} {:>7.1f} {:>8.4f} {:>8.3f} {:>8.2f} {:>7.2f} {:>6.2f} | {:>6} "
        "{:>6.1f}/{:<6.1f} "
        "{:>7.3f} "
        "{:>6.2f} {:>14}\n",
        x.mesh, st.charts, 100 * st.utilization, 100 * st.coverage, st.stretch_l2, st.stretch_linf,
        best, bake, bake_material, x.charts, x.random_pct, x.brute_pct, x.l2, x.linf, x.seconds);
  }
  return 0;
}
