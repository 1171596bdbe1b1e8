// Emission of a level's patches: the hierarchy's nodes, regular and single-crease patches' 16
// points, end caps' corner fans (patch_caps.cpp makes their rows), the table's final points.
#include "patch_builder.hpp"

namespace limn::patch_detail {

// Room in the table's arrays for this level's patches, so they grow once a level instead of
// doubling (each doubling a copy into fresh pages, beside the old array).

void Builder::reserve_output(const Level& L, const RefinedLevel& R) {
  size_t regular = 0, caps = 0;
  for (uint32_t f = 0; f < R.face_count(); ++f) {
    if (!L.owned[f] || (L.requested[f] && !h_) || (!L.role.empty() && L.role[f] < 2)) continue;
    const uint32_t b = R.face_offsets[f];
    if (R.face_offsets[f + 1] - b != 4 || L.force[f]) continue;
    bool reg = L.crease_edge[f] >= 0;
    if (!reg) {
      reg = true;
      for (uint32_t c = b; c < b + 4; ++c) reg = reg && !L.irregular[R.face_vertices[c]];
    }
    ++(reg ? regular : caps);
  }
  // The counts are exact for this level (regular and caps are the patches emit makes). A
  // level's regular patches go to arrays of their own, sized exactly and joined in build(),
  // when the levels' topology is gone: no room is held ahead of the levels to come, and no
  // array is copied while two levels are held (room guessed a few patches short copied car L6's
  // 1.4 MB of points at its last level, its peak).
  level_points_.emplace_back().reserve(16 * regular);
  level_params_.emplace_back().reserve(regular);
  reserve_more(out_.gregory_params, caps);
}

// A regular patch's 4x4 points: corner i's point at kPos[i], its neighbours along kD1[i]
// (towards corner i + 1) and kD2[i] (towards corner i - 1).
constexpr int kPos[4][2] = {{1, 1}, {2, 1}, {2, 2}, {1, 2}};
constexpr int kD1[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
constexpr int kD2[4][2] = {{0, 1}, {-1, 0}, {0, -1}, {1, 0}};

// The hierarchy's nodes of level k: every face this level covers, a child of the node of the face
// it came from; node_of gets each face's node (kNone: not covered).
void Builder::add_nodes(size_t k, const SparseLevel& S, std::vector<uint32_t>& node_of) {
  const Level& L = levels_[k];
  const RefinedLevel& R = S.level;
  // Nodes: every face this level covers; a child of the node of the face it came from.
  node_of.assign(R.face_count(), kNone);
  for (uint32_t f = 0; f < R.face_count(); ++f) {
    if (!L.owned[f]) continue;
    const uint32_t n = uint32_t(h_->node_level.size());
    node_of[f] = n;
    h_->node_level.push_back(uint8_t(k));
    h_->node_force.push_back(L.force[f]);
    h_->node_patch.push_back(kNone);
    h_->node_first_child.push_back(kNone);
    h_->node_children.push_back(0);
    h_->node_neighbours.insert(h_->node_neighbours.end(), {kNone, kNone, kNone, kNone});
    // Depth sources of the irregular corners (none for a single-crease face).
    std::vector<uint32_t> irregular;
    for (uint32_t c = R.face_offsets[f]; c < R.face_offsets[f + 1]; ++c)
      if (L.irregular[R.face_vertices[c]] && L.crease_edge[f] < 0)
        irregular.push_back(R.face_vertices[c]);
    append_union(h_->node_src, h_->node_src_offsets, L, irregular);
    if (k == 0) {
      h_->roots.push_back(n);
    } else {
      const uint32_t parent = node_of_level_[k - 1][S.face_parent[f]];
      if (h_->node_first_child[parent] == kNone) h_->node_first_child[parent] = n;
      ++h_->node_children[parent];
    }
  }
}

// A regular or single-crease patch of face f (corners `corner`, points a, level k's points from
// `off`): its 16 points from its corners' rings (spans where cut at infinitely sharp edges),
// phantom points on boundaries.
void Builder::emit_regular(size_t k, Level& L, const RefinedLevel& R, uint32_t f,
                           const uint32_t corner[4], const uint32_t a[4], uint32_t off,
                           PatchParam& pp) {
  const Topo& t = L.topo;
  const bool crease = L.crease_edge[f] >= 0;
  PatchStats* stats = stats_;
  RingView rings[4];
  Ring* spans = spans_;
  int in_ring[4];
  bool cut[4], plain[4];
  uint32_t near_edge[4][4], near_diag[4][4];  // plain corners' rings, from the patch face
  // Rings are cached in growing arrays: make all four before holding views into them.
  // Plain interior corners (valence 4, no sharpness, quads) need no cached ring: their
  // faces are reached through the twins, starting at the patch face.
  for (int i = 0; i < 4; ++i) {
    plain[i] = plain_interior(L, R, a[i]);
    cut[i] = !plain[i] && cuts_at_inf_sharp(L, R, a[i]);
    if (!cut[i] && !plain[i]) ring(L, R, a[i]);
  }
  const uint32_t* fv = R.face_vertices.data();
  for (int i = 0; i < 4; ++i) {
    if (plain[i]) {
      uint32_t c = corner[i];
      for (int m = 0; m < 4; ++m) {
        const uint32_t n = t.corner_next[c];
        near_edge[i][m] = fv[n], near_diag[i][m] = fv[t.corner_next[n]];
        c = t.corner_twin[t.corner_prev[c]];
      }
      RingView& g = rings[i];
      g.edge_end = near_edge[i], g.diagonal = near_diag[i], g.face = nullptr;
      g.faces = 4, g.boundary = false, g.manifold = g.all_quads = true;
      in_ring[i] = 0;
      continue;
    }
    if (cut[i]) {
      // Cut at infinitely sharp edges: the patch sees its span, as a boundary.
      bool sharp = false;
      span(L, R, corner[i], sharp, spans[i]);
      RingView& g = rings[i];
      g.edge_end = spans[i].edge_end.data();
      g.diagonal = spans[i].diagonal.data();
      g.face = spans[i].face.data();
      g.faces = uint32_t(spans[i].face.size());
      g.boundary = spans[i].boundary;
      g.manifold = g.all_quads = true;
    } else {
      rings[i] = ring(L, R, a[i]);
    }
    in_ring[i] = rings[i].index_of(f);
    if (in_ring[i] < 0) throw std::logic_error("patches: face missing in ring");
  }
  pp.type = crease ? PatchType::single_crease : PatchType::regular;
  if (crease) {
    pp.crease_edge = uint8_t((L.crease_edge[f] + L.param[f].rot) % 4);
    pp.sharpness = L.crease_sharpness[f];
  }
  uint32_t grid[16];
  bool have[16] = {};
  auto put = [&](int x, int y, uint32_t p) {
    grid[4 * y + x] = off + p;
    have[4 * y + x] = true;
  };
  for (int i = 0; i < 4; ++i) {
    const RingView& g = rings[i];
    const size_t j = size_t(in_ring[i]);
    const int x = kPos[i][0], y = kPos[i][1];
    const int* d1 = kD1[i];
    const int* d2 = kD2[i];
    auto edge = [&](size_t m, int px, int py) {
      const size_t id = (j + m) % 4;
      if (id < g.edges()) put(px, py, g.edge_end[id]);
    };
    auto diag = [&](size_t m, int px, int py) {
      const size_t id = (j + m) % 4;
      if (id < g.faces) put(px, py, g.diagonal[id]);
    };
    put(x, y, a[i]);
    edge(2, x - d1[0], y - d1[1]);
    edge(3, x - d2[0], y - d2[1]);
    diag(2, x - d1[0] - d2[0], y - d1[1] - d2[1]);
    diag(1, x + d2[0] - d1[0], y + d2[1] - d1[1]);
    diag(3, x + d1[0] - d2[0], y + d1[1] - d2[1]);
  }
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      if (have[4 * y + x]) continue;
      const bool phantom = (y == 0 && (pp.boundary & 1)) || (x == 3 && (pp.boundary & 2)) ||
                           (y == 3 && (pp.boundary & 4)) || (x == 0 && (pp.boundary & 8));
      if (!phantom) throw std::logic_error("patches: a regular patch misses a point");
      grid[4 * y + x] = off + a[0];
    }
  level_points_.back().insert(level_points_.back().end(), grid, grid + 16);
  level_params_.back().push_back(pp);
  if (stats) ++stats->regular_by_level[k];
}

// An end cap of face f: its corners' fans kept for emit_pending_caps (a long fan's ring once).
void Builder::emit_gregory(size_t k, Level& L, const RefinedLevel& R, uint32_t f,
                           const uint32_t corner[4], const uint32_t a[4], uint32_t off,
                           PatchParam& pp) {
  PatchStats* stats = stats_;
  pp.type = PatchType::gregory;
  // Its corners' fans, for emit_pending_caps.
  for (int i = 0; i < 4; ++i) {
    PendingCorner cc;
    const Ring& g = spans_[i];
    bool sharp = false;
    span(L, R, corner[i], sharp, spans_[i]);
    if (!g.all_quads) throw std::logic_error("patches: an end cap next to a non-quad");
    const uint32_t nf = uint32_t(g.face.size());
    cc.a = a[i];
    const auto least = std::min_element(g.face.begin(), g.face.end());
    cc.fan = *least, cc.fan_at = uint32_t(least - g.face.begin());
    cc.faces = nf & 0x3fffffffu;  // a level's faces are fewer than 2^30 (corners are 32-bit)
    cc.boundary = g.boundary, cc.sharp = sharp;
    cc.face_in_ring = uint32_t(std::find(g.face.begin(), g.face.end(), f) - g.face.begin());
    // The same fan met again: its ring is the kept one turned to start where this one
    // does (a boundary fan's always starts at its boundary).
    const uint64_t key = uint64_t(off + a[i]) << 32 | cc.fan;
    const auto it = nf >= kLongFan ? long_fans_.find(key) : long_fans_.end();
    if (it != long_fans_.end() && (!g.boundary || it->second.second == cc.fan_at)) {
      cc.ring_at = it->second.first;
      cc.ring_rot = (it->second.second + nf - cc.fan_at) % nf;
    } else {
      if (pending_rings_.size() > UINT32_MAX - 2 * size_t(nf) - 1)
        throw InputError("patches: end-cap rings of more than 2^32 points");
      cc.ring_at = uint32_t(pending_rings_.size());
      if (nf >= kLongFan) long_fans_[key] = {cc.ring_at, cc.fan_at};
      for (size_t m = 0; m < nf; ++m) {
        pending_rings_.push_back(off + g.edge_end[m]);
        pending_rings_.push_back(off + g.diagonal[m]);
      }
      if (g.boundary) pending_rings_.push_back(off + g.edge_end.back());
    }
    pending_corners_.push_back(cc);
  }
  out_.gregory_params.push_back(pp);
  if (stats) ++stats->gregory_by_level[k];
}

void Builder::emit(size_t k, const SparseLevel& S) {
  const auto t0 = std::chrono::steady_clock::now();
  PatchTable& out = out_;
  PatchStats* stats = stats_;
  if (stats && stats->regular_by_level.size() <= k) {
    stats->regular_by_level.resize(k + 1, 0);
    stats->gregory_by_level.resize(k + 1, 0);
  }
  std::vector<std::vector<uint32_t>>& node_of_level = node_of_level_;
  {
    Level& L = levels_[k];
    const RefinedLevel& R = S.level;
    const Topo& t = L.topo;
    const uint32_t off = level_offsets_.back();
    std::vector<uint32_t>& node_of = node_of_level.emplace_back();
    if (h_) add_nodes(k, S, node_of);
    reserve_output(L, R);
    size_t regular_before = 0;  // the hierarchy's regular index of this level's first patch
    for (size_t i = 0; i + 1 < level_params_.size(); ++i) regular_before += level_params_[i].size();
    for (uint32_t f = 0; f < R.face_count(); ++f) {
      if (!L.owned[f] || (L.requested[f] && !h_) || (!L.role.empty() && L.role[f] < 2)) continue;
      if (R.face_offsets[f + 1] - R.face_offsets[f] != 4 || L.force[f]) {
        if (h_) continue;  // a node without a patch of its own: always refined
        throw std::logic_error("patches: a non-quad face was left unrefined");
      }
      uint32_t corner[4], a[4];
      aligned_corners(L, R, f, corner);
      const bool crease = L.crease_edge[f] >= 0;
      bool regular = true;
      for (int i = 0; i < 4; ++i) {
        a[i] = R.face_vertices[corner[i]];
        regular = regular && (crease || !L.irregular[a[i]]);
      }
      PatchParam pp;
      const Level::Face& fp = L.param[f];
      pp.ptex = fp.ptex, pp.u = fp.u, pp.v = fp.v, pp.depth = fp.depth;
      pp.level = uint8_t(k), pp.base_face = base_face(fp.ptex), pp.corner = fp.corner;
      for (int e = 0; e < 4; ++e) {
        const uint32_t tw = t.corner_twin[corner[e]];
        const bool sharp_cut = o_.inf_sharp_patches && L.corner_sharpness[corner[e]] >= kInf &&
                               regular && cuts_at_inf_sharp(L, R, a[e]);
        if (tw == kNone || sharp_cut) pp.boundary |= uint8_t(1u << e);
        if (tw < kNonManifold) {
          const uint32_t g = t.corner_face[tw];
          if (L.owned[g] && L.requested[g]) pp.transition |= uint8_t(1u << e);
          if (h_ && L.owned[g])
            h_->node_neighbours[4 * size_t(node_of[f]) + size_t(e)] = node_of[g];
        }
      }
      if (h_)
        h_->node_patch[node_of[f]] = regular
                                         ? uint32_t(regular_before + level_params_.back().size())
                                         : kPatchGregory | uint32_t(out.gregory_params.size());
      bool plain4 = regular && !crease;
      for (int i = 0; i < 4 && plain4; ++i) plain4 = plain_interior(L, R, a[i]);
      if (plain4) {
        // The common case: four plain interior corners, so no boundary, no phantom point, and
        // each corner's three other faces are reached through the twins from the patch face.
        // Points are put as the general case below puts them (same values, same order).
        const uint32_t* fv = R.face_vertices.data();
        uint32_t grid[16];
        for (int i = 0; i < 4; ++i) {
          const uint32_t c1 = t.corner_twin[t.corner_prev[corner[i]]];
          const uint32_t c2 = t.corner_twin[t.corner_prev[c1]];
          const uint32_t c3 = t.corner_twin[t.corner_prev[c2]];
          const int x = kPos[i][0], y = kPos[i][1];
          const int* d1 = kD1[i];
          const int* d2 = kD2[i];
          auto put = [&](int px, int py, uint32_t p) { grid[4 * py + px] = off + p; };
          put(x, y, a[i]);
          put(x - d1[0], y - d1[1], fv[t.corner_next[c2]]);
          put(x - d2[0], y - d2[1], fv[t.corner_next[c3]]);
          put(x - d1[0] - d2[0], y - d1[1] - d2[1], fv[t.corner_next[t.corner_next[c2]]]);
          put(x + d2[0] - d1[0], y + d2[1] - d1[1], fv[t.corner_next[t.corner_next[c1]]]);
          put(x + d1[0] - d2[0], y + d1[1] - d2[1], fv[t.corner_next[t.corner_next[c3]]]);
        }
        pp.type = PatchType::regular;
        level_points_.back().insert(level_points_.back().end(), grid, grid + 16);
        level_params_.back().push_back(pp);
        if (stats) ++stats->regular_by_level[k];
      } else if (regular) {
        emit_regular(k, L, R, f, corner, a, off, pp);
      } else {
        emit_gregory(k, L, R, f, corner, a, off, pp);
      }
    }
  }
  if (pending_corners_.size() / 4 > (pending_levels_.empty() ? 0 : pending_levels_.back().caps_end))
    pending_levels_.push_back({uint32_t(k), level_offsets_.back(), uint32_t(S.level.vertex_count()),
                               pending_corners_.size() / 4});
  level_offsets_.push_back(level_offsets_.back() + uint32_t(S.level.vertex_count()));
  emit_ms_ += ms_since(t0);
}

// prune_points gives a level's spare room back only past this many bytes.
constexpr size_t kShrinkBytes = size_t(4) << 20;

// Drops the refined points no patch uses, directly or through a later level's stencils (the
// sparse refinement makes whole rings around what it refines; its lean runs already leave out
// the rows nothing can read, so every shared cage's whole-cage build needs all that is left, and
// then nothing is renumbered). Cage points stay: they are the input. Renumbers in place, keeping
// each level's order (the regular patches' points are each level's array, not yet joined).
// O(stencil entries).
void prune_points(PatchTable& t, std::span<std::vector<uint32_t>> regular_points) {
  const size_t nl = t.level_offsets.size() - 1;  // levels, the cage included
  std::vector<uint8_t> need(t.level_offsets.back(), 0);
  for (const std::vector<uint32_t>& level : regular_points)
    for (const uint32_t p : level) need[p] = 1;
  for (const uint32_t p : t.gregory_stencils.indices) need[p] = 1;
  for (const uint32_t p : t.gregory_face_stencils.indices)
    if (!(p & kCapRef)) need[p] = 1;
  for (size_t k = nl - 1; k >= 1; --k) {
    const StencilTable& s = t.level_stencils[k - 1];
    const uint32_t base = t.level_offsets[k], prev = t.level_offsets[k - 1];
    for (size_t i = 0; i < s.size(); ++i)
      if (need[base + i])
        for (uint32_t j = s.offsets[i]; j < s.offsets[i + 1]; ++j) need[prev + s.indices[j]] = 1;
  }
  // Every point needed: the ids stay as they are.
  if (std::all_of(need.begin() + t.level_offsets[1], need.end(), [](uint8_t x) { return x != 0; }))
    return;
  // New global ids; the cage keeps its own.
  std::vector<uint32_t> id(t.level_offsets.back(), kNone);
  std::vector<uint32_t> offsets(nl + 1, 0);
  for (uint32_t p = 0; p < t.level_offsets[1]; ++p) id[p] = p;
  offsets[1] = t.level_offsets[1];
  for (size_t k = 1; k < nl; ++k) {
    StencilTable& s = t.level_stencils[k - 1];
    const uint32_t base = t.level_offsets[k], prev = t.level_offsets[k - 1];
    const size_t n = s.size();
    const bool shared = s.shared();
    uint32_t kept = 0, at = 0, begin = 0;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t end = s.offsets[i + 1];  // read before the compaction writes over it
      if (!need[base + i]) {
        begin = end;
        continue;
      }
      id[base + i] = offsets[k] + kept;
      for (uint32_t j = begin; j < end; ++j, ++at) {
        s.indices[at] = id[prev + s.indices[j]] - offsets[k - 1];
        if (!shared) s.weights[at] = s.weights[j];
      }
      if (shared) s.weight_offsets[kept] = s.weight_offsets[i];
      s.offsets[++kept] = at;
      begin = end;
    }
    s.offsets.resize(kept + 1), s.indices.resize(at);
    if (shared)
      s.weight_offsets.resize(kept);
    else
      s.weights.resize(at);
    // Giving the room back means a copy into fresh pages (the kernel's page faults cost more
    // than the copy): only when it frees enough to matter. Region tables are copied into the
    // merged table anyway.
    if ((s.indices.capacity() - at) * sizeof(uint32_t) > kShrinkBytes) {
      s.offsets.shrink_to_fit(), s.indices.shrink_to_fit(), s.weights.shrink_to_fit();
      s.weight_offsets.shrink_to_fit();
    }
    offsets[k + 1] = offsets[k] + kept;
  }
  for (std::vector<uint32_t>& level : regular_points)
    for (uint32_t& p : level) p = id[p];
  for (uint32_t& p : t.gregory_stencils.indices) p = id[p];
  for (uint32_t& p : t.gregory_face_stencils.indices)
    if (!(p & kCapRef)) p = id[p];
  t.level_offsets = std::move(offsets);
}

}  // namespace limn::patch_detail
