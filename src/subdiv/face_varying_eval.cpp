// Face-varying values on the limit surface where the channel is linear (FVarInterpolation::all):
// refining bilinearly converges to the bilinear map over each ptex face's quad, so no patches.
#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "limn/subdiv/patches.hpp"

namespace limn {

PtexCoord ptex_coord(const PatchTable& table, const PatchCoord& c) {
  const size_t nr = table.regular_params.size();
  const PatchParam& p =
      c.patch < nr ? table.regular_params[c.patch] : table.gregory_params[c.patch - nr];
  const float scale = 1.0f / float(1u << p.depth);
  return {p.ptex, (float(p.u) + c.s) * scale, (float(p.v) + c.t) * scale};
}

void evaluate_linear_face_varying(const Mesh& cage, const FaceVaryingInput& ch, const float* values,
                                  int width, std::span<const PtexCoord> coords, float* out,
                                  float* du, float* dv) {
  if (ch.corner_values.size() != cage.corner_count())
    throw InputError(fmt::format("face-varying channel has {} corner indices for {} corners",
                                 ch.corner_values.size(), cage.corner_count()));
  if (width < 1 || width > 4) throw InputError("face-varying evaluation: width must be 1-4");
  // First ptex face of each cage face (a quad is one, another face one per corner).
  std::vector<uint32_t> first(cage.face_count() + 1, 0);
  for (size_t f = 0; f < cage.face_count(); ++f) {
    const uint32_t n = cage.face_size(f);
    first[f + 1] = first[f] + (n == 4 ? 1 : n);
  }
  const size_t w = size_t(width);
  auto value = [&](uint32_t corner, size_t k) {
    const uint32_t x = ch.corner_values[corner];
    if (x >= ch.value_count)
      throw InputError(fmt::format("face-varying index {} at corner {} is past the {} values", x,
                                   corner, ch.value_count));
    return double(values[size_t(x) * w + k]);
  };
  for (size_t i = 0; i < coords.size(); ++i) {
    const PtexCoord& pc = coords[i];
    if (pc.ptex >= first.back())
      throw InputError(fmt::format("face-varying evaluation: ptex face {} out of range", pc.ptex));
    const size_t f =
        size_t(std::upper_bound(first.begin(), first.end(), pc.ptex) - first.begin()) - 1;
    const uint32_t b = cage.face_offsets[f], n = cage.face_size(f), c = pc.ptex - first[f];
    const double u = pc.u, v = pc.v;
    for (size_t k = 0; k < w; ++k) {
      double q[4];  // the ptex face's quad: corners at (0,0), (1,0), (1,1), (0,1)
      if (n == 4) {
        for (uint32_t j = 0; j < 4; ++j) q[j] = value(b + j, k);
      } else {
        double mean = 0;
        for (uint32_t j = 0; j < n; ++j) mean += value(b + j, k);
        const double here = value(b + c, k);
        q[0] = here;
        q[1] = 0.5 * (here + value(b + (c + 1) % n, k));
        q[2] = mean / double(n);
        q[3] = 0.5 * (here + value(b + (c + n - 1) % n, k));
      }
      out[i * w + k] =
          float((1 - u) * (1 - v) * q[0] + u * (1 - v) * q[1] + u * v * q[2] + (1 - u) * v * q[3]);
      if (du) du[i * w + k] = float((1 - v) * (q[1] - q[0]) + v * (q[2] - q[3]));
      if (dv) dv[i * w + k] = float((1 - u) * (q[3] - q[0]) + u * (q[2] - q[1]));
    }
  }
}

}  // namespace limn
