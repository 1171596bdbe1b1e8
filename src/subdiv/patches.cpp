// Feature-adaptive patch tables: isolation by sparse refinement, classification per face, patch
// points, and Gregory end caps.
//
// The end-cap points follow OpenSubdiv 3.5's Far GREGORY_BASIS end caps (its GregoryConverter:
// limit position P, edge points Ep/Em from the limit tangent masks with its eigenvalue scaling,
// face points Fp/Fm from Loop et al. 2009's formula with its cosine terms), so that the test
// suite can hold limn to OpenSubdiv's adaptive surface at the same isolation level.
#include "limn/subdiv/patches.hpp"

#include "patch_builder.hpp"

namespace limn {

namespace patch_detail {

void Builder::build(PatchTable& out, SparseRefinement& r, PatchStats* stats) {
  const auto t0 = std::chrono::steady_clock::now();
  // The walking state goes first: the table is finished with only itself held.
  release(levels_);
  emit_pending_caps();
  release(shared_), release(shared_head_), cap_ = GregoryCap{};
  out = std::move(out_);
  out.options = o_.subdiv;
  out.level_offsets = std::move(level_offsets_);
  out.level_stencils = std::move(r.stencils);
  prune_points(out, level_points_);
  // The levels' regular patches joined, each level's arrays freed as they are copied.
  size_t n = 0;
  for (const std::vector<PatchParam>& p : level_params_) n += p.size();
  out.regular_points.reserve(16 * n), out.regular_params.reserve(n);
  for (size_t k = 0; k < level_params_.size(); ++k) {
    out.regular_points.insert(out.regular_points.end(), level_points_[k].begin(),
                              level_points_[k].end());
    out.regular_params.insert(out.regular_params.end(), level_params_[k].begin(),
                              level_params_[k].end());
    release(level_points_[k]), release(level_params_[k]);
  }
  out.ptex_count = ptex_first_.back();
  out.ptex_of_face = std::move(ptex_first_);
  resolve_cap_points(out);
  if (stats) {
    stats->regular_by_level.resize(out.level_offsets.size() - 1, 0);
    stats->gregory_by_level.resize(out.level_offsets.size() - 1, 0);
    stats->points = out.point_count();
    stats->patches_ms = emit_ms_ + ms_since(t0);
  }
}

}  // namespace patch_detail

using namespace patch_detail;

std::vector<float> PatchTable::points(std::span<const float> cage) const {
  std::vector<float> out(3 * point_count());
  points(cage, out);
  return out;
}

void PatchTable::points(std::span<const float> cage, std::span<float> out) const {
  if (selection)
    throw InputError("patches: a selection has no points of its own; use its hierarchy's");
  if (cage.size() != 3 * size_t(level_offsets.at(1)))
    throw InputError(fmt::format("patches: {} cage coordinates for {} points", cage.size(),
                                 3 * size_t(level_offsets.at(1))));
  if (out.size() != 3 * point_count())
    throw InputError(
        fmt::format("patches: room for {} coordinates, {} needed", out.size(), 3 * point_count()));
  std::copy(cage.begin(), cage.end(), out.begin());
  for (size_t k = 0; k < level_stencils.size(); ++k)
    apply_stencils(level_stencils[k], out.data() + 3 * size_t(level_offsets[k]),
                   out.data() + 3 * size_t(level_offsets[k + 1]), 3);
  const size_t corners = level_offsets.back(), faces = corners + gregory_stencils.size();
  if (gregory_stencils.size())
    apply_stencils(gregory_stencils, out.data(), out.data() + 3 * corners, 3);
  if (gregory_face_stencils.size())
    apply_stencils(gregory_face_stencils, out.data(), out.data() + 3 * faces, 3);
}

namespace patch_detail {

void check_depth(const PatchOptions& options) {
  if (options.depth < 0 || options.depth > 12)
    throw InputError(fmt::format("patches: depth {} out of range (0-12)", options.depth));
}

// Runs the isolation with `b` deciding each level (and emitting its patches); the levels are
// dropped as it goes, only the stencils come back.
SparseRefinement isolate(const Mesh& cage, const PatchOptions& options, Builder& b) {
  return refine_sparse(
      cage, options.subdiv,
      [&](size_t k, const SparseLevel& S, const LevelAdjacency& a, std::vector<uint8_t>& req) {
        b.request(k, S, a, req);
      },
      false,
      [&](size_t k, const SparseLevel& S, const LevelAdjacency& a) { b.level_done(k, S, a); });
}

}  // namespace patch_detail

PatchHierarchy build_patch_hierarchy(const Mesh& cage, const PatchOptions& options) {
  check_depth(options);
  PatchHierarchy h;
  Builder b(cage, options, {}, &h);
  SparseRefinement r = isolate(cage, options, b);
  b.build(h.table, r, nullptr);
  return h;
}

PatchTable select_patches(const PatchHierarchy& h, std::span<const uint8_t> vertex_depth) {
  const PatchTable& full = h.table;
  const size_t nv = full.level_offsets.size() > 1 ? full.level_offsets[1] : 0;
  if (vertex_depth.size() != nv)
    throw InputError(
        fmt::format("select patches: {} depths for {} cage vertices", vertex_depth.size(), nv));
  const size_t nn = h.node_count();
  // Pass 1: which nodes go deeper.
  std::vector<uint8_t> refined(nn, 0);
  std::vector<uint32_t> stack(h.roots.rbegin(), h.roots.rend()), leaves;
  while (!stack.empty()) {
    const uint32_t n = stack.back();
    stack.pop_back();
    bool deeper = h.node_force[n] != 0;
    for (uint32_t i = h.node_src_offsets[n]; i < h.node_src_offsets[n + 1] && !deeper; ++i)
      deeper = vertex_depth[h.node_src[i]] > h.node_level[n];
    if (deeper && h.node_first_child[n] != kNone) {
      refined[n] = 1;
      for (uint32_t c = h.node_children[n]; c-- > 0;) stack.push_back(h.node_first_child[n] + c);
    } else {
      if (h.node_patch[n] == kNone) throw std::logic_error("select patches: a node has no patch");
      leaves.push_back(n);
    }
  }
  // Pass 2: copy the leaves' patches, with their transition bits for this selection.
  PatchTable out;
  out.selection = true;
  out.options = full.options;
  out.level_offsets = full.level_offsets;
  out.ptex_count = full.ptex_count;
  out.ptex_of_face = full.ptex_of_face;
  for (const uint32_t n : leaves) {
    const uint32_t p = h.node_patch[n];
    const bool cap = p & kPatchGregory;
    const uint32_t i = p & ~kPatchGregory;
    PatchParam pp = cap ? full.gregory_params[i] : full.regular_params[i];
    pp.transition = 0;
    for (int e = 0; e < 4; ++e) {
      const uint32_t g = h.node_neighbours[4 * size_t(n) + size_t(e)];
      if (g != kNone && refined[g]) pp.transition |= uint8_t(1u << e);
    }
    if (cap) {
      out.gregory_params.push_back(pp);
      out.gregory_points.insert(out.gregory_points.end(),
                                full.gregory_points.begin() + 20 * long(i),
                                full.gregory_points.begin() + 20 * long(i) + 20);
    } else {
      out.regular_params.push_back(pp);
      out.regular_points.insert(out.regular_points.end(),
                                full.regular_points.begin() + 16 * long(i),
                                full.regular_points.begin() + 16 * long(i) + 16);
    }
  }
  return out;
}

}  // namespace limn
