// The screen-space error of a patch table against a deep reference table of the same cage, for
// the equal-error benchmarks: 3 x 3 samples on every patch, evaluated on both, the largest
// distance in pixels at the reference point (samples outside the image skipped).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"

namespace limn::bench {

struct Reference {
  PatchTable table;
  std::vector<float> points;
};

inline double measured_error(const Mesh& cage, const PatchTable& t, const Reference& ref,
                             const Camera& cam) {
  const std::vector<float> pts = t.points(cage.positions);
  const PatchMap map(ref.table);
  std::vector<PatchCoord> a, b;
  const size_t nr = t.regular_params.size();
  for (uint32_t i = 0; i < t.patch_count(); ++i) {
    const PatchParam& p = i < nr ? t.regular_params[i] : t.gregory_params[i - nr];
    const double size = 1.0 / double(1u << p.depth);
    for (double s : {0.1, 0.5, 0.9})
      for (double u : {0.1, 0.5, 0.9}) {
        a.push_back({i, float(s), float(u)});
        b.push_back(map.find(p.ptex, (p.u + s) * size, (p.v + u) * size));
      }
  }
  std::vector<float> pa(3 * a.size()), pb(3 * b.size());
  evaluate_patches(t, pts, a, pa.data());
  evaluate_patches(ref.table, ref.points, b, pb.data());
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    double x, y;
    if (!cam.project(&pb[3 * i], x, y) || x < 0 || y < 0 || x > cam.width || y > cam.height)
      continue;
    const double d = std::hypot(pa[3 * i] - pb[3 * i], pa[3 * i + 1] - pb[3 * i + 1],
                                pa[3 * i + 2] - pb[3 * i + 2]);
    worst = std::max(worst, d * cam.scale_at(&pb[3 * i]));
  }
  return worst;
}

/// The equal-error benchmarks' camera path: the framing camera moved along its view axis to
/// `zoom` times its distance (near 0.35, mid 1, far 3).
struct PathStop {
  const char* label;
  float zoom;
};
inline constexpr PathStop kCameraPath[] = {{"near", 0.35f}, {"mid", 1.0f}, {"far", 3.0f}};

inline Camera path_camera(const Camera& framed, float zoom) {
  Camera cam = framed;
  for (int k = 0; k < 3; ++k)
    cam.eye[k] = cam.target[k] + zoom * (framed.eye[k] - framed.target[k]);
  return cam;
}

}  // namespace limn::bench
