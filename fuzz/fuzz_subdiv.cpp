// libFuzzer target for subdividing hostile cages: any OBJ (with OpenSubdiv tags) that parses must
// refine uniformly, sparsely and leanly, give limit stencils and an adaptive patch table (fixed
// and per-vertex depth, whole or region by region) that tiles every ptex face, or throw
// InputError; never crash, never break an internal invariant (std::logic_error escapes and is a
// finding). The lean path must also reproduce the full refinement's points exactly.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "limn/io/mesh_io.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/refine.hpp"
#include "limn/subdiv/tessellate.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  limn::Mesh m;
  try {
    m = limn::read_obj(in, "fuzz.obj");
  } catch (const limn::InputError&) {
    return 0;
  }
  if (m.corner_count() > 4000 || m.vertex_count() == 0) return 0;  // keep each run fast
  const limn::SubdivOptions o = limn::subdiv_options(m);
  try {
    const limn::UniformRefinement r = limn::refine_uniform(m, 2, o);
    const std::vector<float> points = r.positions(m, 2);
    if (limn::subdivide_uniform(m, 2, o).positions != points) __builtin_trap();
    try {
      const limn::LimitStencils ls = limn::limit_stencils(r, 2);
      if (ls.position.size() != points.size() / 3) __builtin_trap();
    } catch (const limn::InputError&) {
    }
    // Depth requests taken from the input bytes: 0-3 per vertex, 0-2 per face.
    std::vector<uint8_t> vd(m.vertex_count()), fd(m.face_count());
    for (size_t v = 0; v < vd.size(); ++v) vd[v] = uint8_t(data[(7 * v) % size] % 4);
    for (size_t f = 0; f < fd.size(); ++f) fd[f] = uint8_t(data[(13 * f + 1) % size] % 3);
    const limn::SparseRefinement s = limn::refine_sparse(m, vd, fd, o);
    for (size_t k = 0; k < s.levels.size(); ++k)
      if (s.positions(m, int(k)).size() != 3 * s.levels[k].level.vertex_count()) __builtin_trap();
    limn::PatchOptions po;
    po.subdiv = o;
    po.depth = 2;
    for (const bool per_vertex : {false, true}) {
      const limn::PatchTable t =
          limn::build_patches(m, po, per_vertex ? vd : std::vector<uint8_t>{});
      const std::vector<float> pts = t.points(m.positions);
      const limn::PatchMap map(t);
      std::vector<limn::PatchCoord> coords;
      for (uint32_t p = 0; p < t.ptex_count; ++p) {
        try {
          coords.push_back(map.find(p, 0.3, 0.6));
        } catch (const limn::InputError&) {  // a hole
        }
      }
      std::vector<float> pos(3 * coords.size()), du(pos.size()), dv(pos.size());
      limn::evaluate_patches(t, pts, coords, pos.data(), du.data(), dv.data());
      // Grids: every covered ptex face's points written, and finite.
      std::vector<float> grid(3 * size_t(t.ptex_count) * 9, 0.0f);
      limn::evaluate_grids(t, pts, 3, grid.data());
      for (float x : grid)
        if (!std::isfinite(x)) __builtin_trap();
      limn::TessellateOptions to;
      to.factor = 2;
      const limn::Mesh tess = limn::tessellate_patches(m, t, pts, to);
      for (float x : tess.positions)
        if (!std::isfinite(x)) __builtin_trap();
    }
    // A view change from the hierarchy gives what a direct build gives.
    const limn::PatchHierarchy h = limn::build_patch_hierarchy(m, po);
    const limn::PatchTable sel = limn::select_patches(h, vd);
    const limn::PatchTable direct = limn::build_patches(m, po, vd);
    if (sel.patch_count() != direct.patch_count()) __builtin_trap();
    // Region by region (regions of a few faces): the same patches.
    limn::PatchOptions regions = po;
    regions.batch_faces = 1 + data[0] % 5;
    const limn::PatchTable split = limn::build_patches(m, regions, vd);
    if (split.regular_params.size() != direct.regular_params.size() ||
        split.gregory_params.size() != direct.gregory_params.size())
      __builtin_trap();
  } catch (const limn::InputError&) {
  }
  return 0;
}
