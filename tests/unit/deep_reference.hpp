// A deep reference for adaptive surfaces: limit points at the corners of every face of a uniform
// refinement (limn's, verified against OpenSubdiv), with each corner's ptex coordinates, so a
// patch table can be evaluated at exactly the same surface points. Shares no code with patches.
#pragma once

#include <vector>

#include "limn/mesh/mesh.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn::test {

// Ptex coordinates of the corners of every face of a uniform level, by following child faces
// (child face c of a level is the parent's corner c, its corner 0 the parent's corner).
struct FaceParam {
  uint32_t ptex;
  double u, v, size;
  int rot;
};

inline std::vector<FaceParam> uniform_params(const UniformRefinement& r, const Mesh& cage) {
  std::vector<FaceParam> cur;
  uint32_t ptex = 0;
  std::vector<uint32_t> first(cage.face_count());
  for (size_t f = 0; f < cage.face_count(); ++f) {
    first[f] = ptex;
    cur.push_back({ptex, 0, 0, 1, 0});
    ptex += cage.face_size(f) == 4 ? 1 : cage.face_size(f);
  }
  for (size_t k = 1; k < r.levels.size(); ++k) {
    const RefinedLevel& P = r.levels[k - 1];
    std::vector<FaceParam> next(r.levels[k].face_count());
    for (uint32_t f = 0; f < P.face_count(); ++f)
      for (uint32_t c = P.face_offsets[f]; c < P.face_offsets[f + 1]; ++c) {
        const uint32_t child = c - P.face_offsets[f];
        FaceParam p = cur[f];
        if (k == 1 && P.face_offsets[f + 1] - P.face_offsets[f] != 4) {
          p = {first[f] + child, 0, 0, 1, 0};
        } else {
          const int q = int(child + uint32_t(p.rot)) % 4;
          p.size *= 0.5;
          p.u += (q == 1 || q == 2) ? p.size : 0.0;
          p.v += q >= 2 ? p.size : 0.0;
          p.rot = q;
        }
        next[c] = p;
      }
    cur = std::move(next);
  }
  return cur;
}

// The deep reference: limit points at the corners of every face of a uniform level, with their
// ptex coordinates.
struct Reference {
  std::vector<float> limit;
  std::vector<FaceParam> faces;
  RefinedLevel level;
};

inline Reference reference(const Mesh& cage, int ref_level) {
  const UniformRefinement r = refine_uniform(cage, ref_level, subdiv_options(cage));
  const std::vector<float> pos = r.positions(cage, ref_level);
  const LimitStencils ls = limit_stencils(r, ref_level);
  Reference out;
  out.limit.resize(pos.size());
  apply_stencils(ls.position, pos.data(), out.limit.data(), 3);
  out.faces = uniform_params(r, cage);
  out.level = r.levels.back();
  return out;
}

// Where a patch table puts each reference corner (hole faces skipped): coords[i] is the patch
// coordinate of reference point at[i].
inline void reference_samples(const Reference& ref, const PatchMap& map,
                              std::vector<PatchCoord>& coords, std::vector<uint32_t>& at) {
  static constexpr double kCu[4] = {0, 1, 1, 0}, kCv[4] = {0, 0, 1, 1};
  const RefinedLevel& L = ref.level;
  coords.clear(), at.clear();
  for (uint32_t f = 0; f < L.face_count(); ++f) {
    if (L.face_hole[f]) continue;
    for (int j = 0; j < 4; ++j) {
      const FaceParam& p = ref.faces[f];
      const int s = (j + p.rot) % 4;
      coords.push_back(map.find(p.ptex, p.u + kCu[s] * p.size, p.v + kCv[s] * p.size));
      at.push_back(L.face_vertices[L.face_offsets[f] + uint32_t(j)]);
    }
  }
}

}  // namespace limn::test
