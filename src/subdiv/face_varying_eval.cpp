// Face-varying values on the limit surface where the channel is linear (FVarInterpolation::all):
// refining bilinearly converges to the bilinear map over each ptex face's quad, so no patches.
#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "face_varying.hpp"
#include "limn/subdiv/patches.hpp"

namespace limn {

PtexCoord ptex_coord(const PatchTable& table, const PatchCoord& c) {
  const size_t nr = table.regular_params.size();
  const PatchParam& p =
      c.patch < nr ? table.regular_params[c.patch] : table.gregory_params[c.patch - nr];
  const float scale = 1.0f / float(1u << p.depth);
  return {p.ptex, (float(p.u) + c.s) * scale, (float(p.v) + c.t) * scale};
}

namespace {

void check_channel(const Mesh& cage, const FaceVaryingInput& ch, int width) {
  refine_detail::check_face_varying(ch, cage.corner_count());
  if (width < 1 || width > 4) throw InputError("face-varying evaluation: width must be 1-4");
}

// Channel k of the corners of ptex face `corner` of cage face f (its only one for a quad).
void ptex_quad(const Mesh& cage, const FaceVaryingInput& ch, const float* values, size_t w,
               size_t f, uint32_t corner, size_t k, double q[4]) {
  const uint32_t b = cage.face_offsets[f], n = cage.face_size(f);
  auto value = [&](uint32_t c) { return double(values[size_t(ch.corner_values[c]) * w + k]); };
  if (n == 4) {
    for (uint32_t j = 0; j < 4; ++j) q[j] = value(b + j);
    return;
  }
  double mean = 0;
  for (uint32_t j = 0; j < n; ++j) mean += value(b + j);
  const double here = value(b + corner);
  q[0] = here;
  q[1] = 0.5 * (here + value(b + (corner + 1) % n));
  q[2] = mean / double(n);
  q[3] = 0.5 * (here + value(b + (corner + n - 1) % n));
}

}  // namespace

std::vector<float> ptex_corner_values(const Mesh& cage, const FaceVaryingInput& ch,
                                      const float* values, int width) {
  check_channel(cage, ch, width);
  const size_t w = size_t(width);
  std::vector<float> out;
  for (size_t f = 0; f < cage.face_count(); ++f) {
    const uint32_t n = cage.face_size(f), faces = n == 4 ? 1 : n;
    for (uint32_t c = 0; c < faces; ++c) {
      const size_t base = out.size();
      out.resize(base + 4 * w);
      for (size_t k = 0; k < w; ++k) {
        double q[4];
        ptex_quad(cage, ch, values, w, f, c, k, q);
        for (size_t j = 0; j < 4; ++j) out[base + j * w + k] = float(q[j]);
      }
    }
  }
  return out;
}

void evaluate_linear_face_varying(const Mesh& cage, const FaceVaryingInput& ch, const float* values,
                                  int width, std::span<const PtexCoord> coords, float* out,
                                  float* du, float* dv) {
  check_channel(cage, ch, width);
  // First ptex face of each cage face (a quad is one, another face one per corner).
  std::vector<uint32_t> first(cage.face_count() + 1, 0);
  for (size_t f = 0; f < cage.face_count(); ++f) {
    const uint32_t n = cage.face_size(f);
    first[f + 1] = first[f] + (n == 4 ? 1 : n);
  }
  const size_t w = size_t(width);
  for (size_t i = 0; i < coords.size(); ++i) {
    const PtexCoord& pc = coords[i];
    if (pc.ptex >= first.back())
      throw InputError(fmt::format("face-varying evaluation: ptex face {} out of range", pc.ptex));
    const size_t f =
        size_t(std::upper_bound(first.begin(), first.end(), pc.ptex) - first.begin()) - 1;
    const double u = pc.u, v = pc.v;
    for (size_t k = 0; k < w; ++k) {
      double q[4];  // the ptex face's quad: corners at (0,0), (1,0), (1,1), (0,1)
      ptex_quad(cage, ch, values, w, f, pc.ptex - first[f], k, q);
      out[i * w + k] =
          float((1 - u) * (1 - v) * q[0] + u * (1 - v) * q[1] + u * v * q[2] + (1 - u) * v * q[3]);
      if (du) du[i * w + k] = float((1 - v) * (q[1] - q[0]) + v * (q[2] - q[3]));
      if (dv) dv[i * w + k] = float((1 - u) * (q[3] - q[0]) + u * (q[2] - q[1]));
    }
  }
}

}  // namespace limn
