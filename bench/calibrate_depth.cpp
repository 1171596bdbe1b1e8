// Calibrates the depth-selection error model (src/subdiv/depth.cpp): for random tori with
// extraordinary vertices of each valence (and the crease cage for other features), builds patch
// tables at depths 1-4 and a reference six levels deeper, and reports the largest ratio of the
// end-cap error (samples on every end cap, compared at the same ptex coordinates) to
// D_v * mu^d, attributed to the irregular cage vertices of each end cap's base face. Prints
// c per valence and for other features; depth.cpp's constants are these times a margin.
//   limn_calibrate_depth [--seeds N]
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"

using namespace limn;

namespace {

uint64_t g_state = 1;
double uniform() {
  g_state = g_state * 6364136223846793005ull + 1442695040888963407ull;
  return double(g_state >> 11) * 0x1.0p-53;
}

// Largest error / (D mu^d) per "class" (valence for smooth vertices, 0 for other features).
void measure(const Mesh& cage, std::map<int, double>& worst) {
  const SubdivOptions so = subdiv_options(cage);
  // The model with unit constants: K_v / c = D_v.
  VertexErrorModel m = vertex_error_model(cage, so);
  const std::vector<uint32_t>& fo = cage.face_offsets;
  PatchOptions ref_o;
  ref_o.subdiv = so;
  ref_o.depth = 12;
  const PatchTable ref = build_patches(cage, ref_o);
  const PatchMap ref_map(ref);
  const std::vector<float> ref_pts = ref.points(cage.positions);
  for (int d = 1; d <= 6; ++d) {
    PatchOptions o = ref_o;
    o.depth = d;
    const PatchTable t = build_patches(cage, o);
    const PatchMap map(t);
    const std::vector<float> pts = t.points(cage.positions);
    const size_t nr = t.regular_params.size();
    for (size_t g = 0; g < t.gregory_params.size(); ++g) {
      const PatchParam& pp = t.gregory_params[g];
      double bound = 0;
      int cls = -1;
      for (uint32_t c = fo[pp.base_face]; c < fo[pp.base_face + 1]; ++c) {
        const uint32_t v = cage.face_vertices[c];
        if (m.k[v] <= 0) continue;
        const double b = m.d[v] * std::pow(double(m.mu[v]), d);
        if (b > bound) bound = b, cls = m.smooth[v];
      }
      if (bound <= 0) continue;
      double err = 0;
      const double size = 1.0 / double(1u << pp.depth);
      for (double s : {0.0, 0.25, 0.5, 0.75, 1.0})
        for (double tt : {0.0, 0.25, 0.5, 0.75, 1.0}) {
          PatchCoord a{uint32_t(nr + g), float(s), float(tt)};
          const PatchCoord b = ref_map.find(pp.ptex, (pp.u + s) * size, (pp.v + tt) * size);
          float pa[3], pb[3];
          evaluate_patches(t, pts, std::span(&a, 1), pa);
          evaluate_patches(ref, ref_pts, std::span(&b, 1), pb);
          err = std::max(err, double(std::hypot(pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2])));
        }
      worst[cls] = std::max(worst[cls], err / bound);
      worst[100 + 10 * cls + d] = std::max(worst[100 + 10 * cls + d], err / bound);
      worst[200 + d] = std::max(worst[200 + d], err);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 4;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--seeds") && i + 1 < argc) seeds = std::atoi(argv[++i]);
  std::map<int, double> worst;  // 1 = smooth extraordinary, 0 = other features
  for (int n : {3, 5, 6, 7, 8, 9, 10, 11, 12}) {
    std::map<int, double> w;
    for (int s = 0; s < seeds; ++s) {
      g_state = uint64_t(n * 1000 + s);
      const int vals[] = {n, n};
      Mesh cage = make_torus(24, 12, vals);
      for (float& x : cage.positions) x += float((uniform() - 0.5) * 0.08);
      measure(cage, w);
    }
    fmt::print("valence {:>2}: c = {:.3f} (smooth), {:.3f} (others seen); by depth:", n, w[1],
               w[0]);
    for (int d = 1; d <= 6; ++d) fmt::print(" {:.3f}", w[110 + d]);
    fmt::print(" abs:");
    for (int d = 1; d <= 6; ++d) fmt::print(" {:.2e}", w[200 + d]);
    fmt::print("\n");
    for (const auto& [k, v] : w) worst[k] = std::max(worst[k], v);
  }
  {
    std::map<int, double> w;
    measure(make_crease_cage(), w);
    fmt::print("crease cage: c = {:.3f} (smooth), {:.3f} (other features)\n", w[1], w[0]);
    for (const auto& [k, v] : w) worst[k] = std::max(worst[k], v);
  }
  fmt::print("overall: smooth {:.3f}, other features {:.3f}\n", worst[1], worst[0]);
}
