// Classification of a level's faces: their corners' rings and spans, regular, single-crease and
// irregular vertices, and the faces each level refines (the builder's requests).
#include "patch_builder.hpp"

namespace limn::patch_detail {

// Whether an edge at v is non-manifold or joins two faces that disagree on its direction.
bool torn(const Topo& t, const uint32_t* fv, uint32_t v) {
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    const uint32_t c = t.vertex_corners[i];
    for (const uint32_t h : {c, t.corner_prev[c]}) {
      const uint32_t tw = t.corner_twin[h];
      if (tw == kNonManifold || (tw != kNone && fv[tw] == fv[h])) return true;
    }
  }
  return false;
}

RingView Builder::ring(Level& L, const RefinedLevel& R, uint32_t v) const {
  if (L.ring_slot.empty()) L.ring_slot.assign(R.vertex_count(), Level::RingSlot{});
  if (L.ring_slot[v].at == kNone) {
    const Topo& t = L.topo;
    const uint32_t* fv = R.face_vertices.data();
    const uint32_t s0 = t.vertex_offsets[v], n = t.vertex_offsets[v + 1] - s0;
    bool boundary = false, manifold = n > 0 && !torn(t, fv, v), quads = true;
    uint32_t start = n ? t.vertex_corners[s0] : kNone;
    for (uint32_t i = 0; i < n && !boundary; ++i) {
      const uint32_t c = t.vertex_corners[s0 + i];
      if (t.corner_twin[c] == kNone) start = c, boundary = true;
    }
    const uint32_t at = uint32_t(L.ring_face.size());
    uint32_t faces = 0;
    if (manifold) {
      uint32_t c = start;
      for (uint32_t i = 0; i < n; ++i) {
        const uint32_t f = t.corner_face[c];
        quads = quads && R.face_offsets[f + 1] - R.face_offsets[f] == 4;
        L.ring_edge.push_back(fv[t.corner_next[c]]);
        L.ring_diag.push_back(fv[t.corner_next[t.corner_next[c]]]);
        L.ring_face.push_back(f);
        ++faces;
        const uint32_t in = t.corner_prev[c];
        const uint32_t tw = t.corner_twin[in];
        if (tw == kNone) {
          L.ring_edge.push_back(fv[in]);
          break;
        }
        if (tw == start || tw >= kNonManifold) break;
        c = tw;
      }
      if (faces != n) manifold = false;  // faces in more than one fan
    }
    // Keep the three arrays in step (a boundary ring has one edge more than faces).
    while (L.ring_diag.size() < L.ring_edge.size()) L.ring_diag.push_back(kNone);
    while (L.ring_face.size() < L.ring_edge.size()) L.ring_face.push_back(kNone);
    Level::RingSlot& slot = L.ring_slot[v];
    slot.at = at;
    slot.faces = uint16_t(std::min<uint32_t>(faces, 0xFFFF));
    slot.flags =
        uint8_t((boundary ? 1 : 0) | (manifold && faces <= 0xFFFF ? 2 : 0) | (quads ? 4 : 0));
  }
  RingView g;
  const Level::RingSlot slot = L.ring_slot[v];
  g.edge_end = L.ring_edge.data() + slot.at;
  g.diagonal = L.ring_diag.data() + slot.at;
  g.face = L.ring_face.data() + slot.at;
  g.faces = slot.faces;
  g.boundary = slot.flags & 1;
  g.manifold = slot.flags & 2;
  g.all_quads = slot.flags & 4;
  return g;
}

Builder::SharpEdges Builder::sharp_edges(const Level& L, uint32_t v) const {
  const Topo& t = L.topo;
  SharpEdges e;
  e.faces = t.vertex_offsets[v + 1] - t.vertex_offsets[v];
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    const uint32_t c = t.vertex_corners[i];
    for (const uint32_t h : {c, t.corner_prev[c]}) {
      // Each interior edge is seen from both of its faces; count it once.
      const uint32_t tw = t.corner_twin[h];
      if (tw == kNone) e.boundary = true;
      if (!(tw >= kNonManifold || h == c)) continue;
      const float x = L.corner_sharpness[h];
      if (x >= kInf)
        ++e.inf;
      else if (x > 0.0f)
        ++e.semi;
    }
  }
  return e;
}

// With infinitely sharp patches, whether the vertex's spans are cut at its infinitely sharp
// edges (OpenSubdiv: the vertex has such edges and is not a dart).
bool Builder::cuts_at_inf_sharp(const Level& L, const RefinedLevel& R, uint32_t v) const {
  if (!o_.inf_sharp_patches) return false;
  uint8_t& x = L.vinfo[v];
  if (!(x & Level::kCutsKnown)) {
    const SharpEdges e = sharp_edges(L, v);
    const bool dart = !e.boundary && e.inf + e.semi == 1 && R.vertex_sharpness[v] == 0.0f;
    x |= Level::kCutsKnown | (e.inf > 0 && !dart ? Level::kCuts : 0);
  }
  return x & Level::kCuts;
}

// The fan of faces around a patch corner that a patch sees (OpenSubdiv's corner spans): the
// whole ring, or, when non-manifold edges (or, with infinitely sharp patches, infinitely sharp
// edges) cut it, the faces between the cuts that hold the patch face, as a boundary. `corner` is
// the patch face's corner at the vertex. `sharp`: an end cap interpolates the vertex (with
// infinitely sharp features approximated as smooth: a one-face boundary vertex, OpenSubdiv's
// sharp and legacy corners; with infinitely sharp patches also corners of sharp edges and
// infinitely sharp vertices).
void Builder::span(const Level& L, const RefinedLevel& R, uint32_t corner, bool& sharp,
                   Ring& g) const {
  const Topo& t = L.topo;
  const uint32_t* fv = R.face_vertices.data();
  const uint32_t v = fv[corner];
  const uint32_t n = t.vertex_offsets[v + 1] - t.vertex_offsets[v];
  const bool cut_sharp = cuts_at_inf_sharp(L, R, v);
  auto cut = [&](uint32_t h) {
    const uint32_t tw = t.corner_twin[h];
    return tw >= kNonManifold || fv[tw] == fv[h] || (cut_sharp && L.corner_sharpness[h] >= kInf);
  };
  // Back up to the leading cut (or all the way round).
  uint32_t start = corner;
  for (uint32_t guard = 0; guard <= n; ++guard) {
    if (cut(start)) break;
    const uint32_t prev = t.corner_next[t.corner_twin[start]];
    if (prev == corner) break;
    start = prev;
  }
  g.edge_end.clear(), g.diagonal.clear(), g.face.clear();
  g.all_quads = true;
  g.boundary = cut(start);
  uint32_t c = start;
  for (uint32_t guard = 0; guard <= n; ++guard) {
    const uint32_t f = t.corner_face[c];
    g.all_quads = g.all_quads && R.face_offsets[f + 1] - R.face_offsets[f] == 4;
    g.edge_end.push_back(fv[t.corner_next[c]]);
    g.diagonal.push_back(fv[t.corner_next[t.corner_next[c]]]);
    g.face.push_back(f);
    const uint32_t in = t.corner_prev[c];
    if (cut(in)) {
      g.edge_end.push_back(fv[in]);
      break;
    }
    c = t.corner_twin[in];
    if (c == start) break;
  }
  g.manifold = g.face.size() == n || g.boundary;
  const bool fan = g.face.size() == n;  // the span is the vertex's only fan
  // One fan cut by boundaries or sharp edges, or several fans (non-manifold)?
  const bool manifold_vertex = fan || !torn(t, fv, v);
  if (!o_.inf_sharp_patches || !manifold_vertex) {
    sharp = g.boundary && g.face.size() == 1;
  } else {
    const SharpEdges e = sharp_edges(L, v);
    const float vs = R.vertex_sharpness[v];
    const bool corner_tag = n == 1 && vs >= kInf;
    const bool crease = e.inf == 2 && vs < kInf;
    sharp = corner_tag || (cut_sharp ? !crease : vs >= kInf);
    if (!sharp && e.boundary && n == 1) sharp = true;  // OpenSubdiv's legacy smooth corner
  }
  if (!L.sharp_corner.empty() && L.sharp_corner[v]) sharp = true;
}

// Regular: the limit surface around the vertex is the B-spline of its ring (interior valence 4,
// regular boundary with two faces, corner with one face under the corner rule), with no sharp
// feature of its own.
bool Builder::regular_vertex(Level& L, const RefinedLevel& R, uint32_t v) const {
  const Topo& t = L.topo;
  if (plain_interior(L, R, v)) return true;
  const RingView g = ring(L, R, v);
  if (!g.manifold || !g.all_quads) return false;
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    const uint32_t c = t.vertex_corners[i];
    for (const uint32_t h : {c, t.corner_prev[c]})
      if (t.corner_twin[h] != kNone && L.corner_sharpness[h] > 0.0f) return false;
  }
  const float vs = R.vertex_sharpness[v];
  const size_t nf = g.faces;
  if (!g.boundary) return nf == 4 && vs == 0.0f;
  if (nf == 2) return vs == 0.0f;
  return nf == 1 && vs >= kInf;
}

// A single-crease face: a quad of interior valence-4 corners whose edge j runs along a semi-sharp
// crease that goes straight through both of its ends with one sharpness (the two crease edges at
// each end are opposite in its ring), the other two corners plain. Returns j, or -1.
int Builder::single_crease(Level& L, const RefinedLevel& R, uint32_t f, float& sharpness) const {
  const Topo& t = L.topo;
  const uint32_t b = R.face_offsets[f];
  if (R.face_offsets[f + 1] - b != 4) return -1;
  bool any = false;  // the crease runs along one of the face's own edges
  for (uint32_t i = 0; i < 4 && !any; ++i) any = L.corner_sharpness[b + i] > 0.0f;
  if (!any) return -1;
  int kind[4];  // 0 plain, 1 crease end, -1 neither
  float s_at[4] = {};
  for (uint32_t i = 0; i < 4; ++i) {
    const uint32_t v = R.face_vertices[b + i];
    const RingView g = ring(L, R, v);
    kind[i] = -1;
    if (!g.manifold || !g.all_quads || g.boundary || g.faces != 4 || R.vertex_sharpness[v] != 0)
      continue;
    // Sharp edges by their position in the ring (interior: one outgoing half-edge per edge).
    int count = 0, first = -1, second = -1;
    float s0 = 0, s1 = 0;
    for (uint32_t k = t.vertex_offsets[v]; k < t.vertex_offsets[v + 1]; ++k) {
      const uint32_t c = t.vertex_corners[k];
      const float x = L.corner_sharpness[c];
      if (x <= 0) continue;
      const uint32_t end = R.face_vertices[t.corner_next[c]];
      int m = -1;
      for (uint32_t q = 0; q < 4; ++q)
        if (g.edge_end[q] == end) m = int(q);
      (count == 0 ? first : second) = m;
      (count == 0 ? s0 : s1) = x;
      ++count;
    }
    if (count == 0) {
      kind[i] = 0;
    } else if (count == 2 && s0 == s1 && s0 < kInf && first >= 0 && second >= 0 &&
               (first - second + 4) % 4 == 2) {
      kind[i] = 1, s_at[i] = s0;
    }
  }
  for (int j = 0; j < 4; ++j) {
    const int n1 = (j + 1) % 4, n2 = (j + 2) % 4, n3 = (j + 3) % 4;
    if (kind[j] == 1 && kind[n1] == 1 && kind[n2] == 0 && kind[n3] == 0 && s_at[j] == s_at[n1] &&
        L.corner_sharpness[b + uint32_t(j)] == s_at[j]) {
      sharpness = s_at[j];
      return j;
    }
  }
  return -1;
}

// With infinitely sharp patches: regular when every span between infinitely sharp (or boundary)
// edges is a regular boundary (two faces, crease rule) or a regular corner (one face, corner
// rule), with nothing semi-sharp.
bool Builder::regular_vertex_inf(Level& L, const RefinedLevel& R, uint32_t v) const {
  const Topo& t = L.topo;
  if (plain_interior(L, R, v)) return true;
  const RingView g = ring(L, R, v);
  if (!g.manifold || !g.all_quads) return false;
  const SharpEdges e = sharp_edges(L, v);
  const float vs = R.vertex_sharpness[v];
  if (e.semi > 0 || (vs > 0.0f && vs < kInf)) return false;
  if (e.inf == 0) return g.faces == 4 && vs == 0.0f;
  if (!cuts_at_inf_sharp(L, R, v)) return false;  // a dart
  const size_t want = vs >= kInf || e.inf >= 3 ? 1 : 2;
  for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1]; ++i) {
    bool sharp = false;
    span(L, R, t.vertex_corners[i], sharp, span_scratch_);
    if (span_scratch_.face.size() != want) return false;
  }
  return true;
}

// The four corners of quad f in ptex order (corner s at ptex square corner s).
void Builder::aligned_corners(const Level& L, const RefinedLevel& R, uint32_t f,
                              uint32_t c[4]) const {
  const uint32_t b = R.face_offsets[f];
  const uint32_t rot = L.param[f].rot;
  for (uint32_t s = 0; s < 4; ++s) c[s] = b + (s + 4 - rot) % 4;  // corner ids
}

bool Builder::replayed(size_t k, const Level::Face& f) const {
  uint32_t ptex = f.ptex;
  if (!replay_ptex_.empty()) {
    const uint32_t face = base_face(ptex);
    ptex = replay_ptex_[face] + (ptex - ptex_first_[face]);
  }
  if (k == 0) return ptex < replay_->cage.size() && replay_->cage[ptex];
  if (k >= replay_->keys.size()) return false;
  const std::vector<uint64_t>& keys = replay_->keys[k];
  return std::binary_search(keys.begin(), keys.end(), face_key(ptex, f.u, f.v));
}

void Builder::request(size_t k, const SparseLevel& S, const LevelAdjacency& adj,
                      std::vector<uint8_t>& requested) {
  const RefinedLevel& R = S.level;
  const size_t nv = R.vertex_count(), nf = R.face_count();
  Level& L = levels_.emplace_back();

  // Depth wanted around each vertex.
  L.rem.assign(nv, 0);
  if (k == 0) {
    for (size_t v = 0; v < nv; ++v)
      L.rem[v] = uint8_t(depth_.empty() ? o_.depth : std::min<int>(depth_[v], o_.depth));
  } else {
    const Level& P = levels_[k - 1];
    auto dec = [](int d) { return uint8_t(d > 0 ? d - 1 : 0); };
    size_t i = 0;
    for (uint32_t f : S.parent_faces) {
      int d = 0;
      for (uint32_t c = P.level->face_offsets[f]; c < P.level->face_offsets[f + 1]; ++c)
        d = std::max<int>(d, P.rem[P.level->face_vertices[c]]);
      L.rem[i++] = dec(d);
    }
    for (uint32_t e : S.parent_edges)
      L.rem[i++] = dec(std::max(P.rem[P.level->edge_vertices[2 * size_t(e)]],
                                P.rem[P.level->edge_vertices[2 * size_t(e) + 1]]));
    for (uint32_t v : S.parent_vertices) L.rem[i++] = dec(P.rem[v]);
  }

  if (!sharp_corners_.empty()) {
    if (k == 0) {
      L.sharp_corner.assign(sharp_corners_.begin(), sharp_corners_.end());
    } else {
      L.sharp_corner.assign(nv, 0);
      const size_t first = S.parent_faces.size() + S.parent_edges.size();
      for (size_t i = 0; i < S.parent_vertices.size(); ++i)
        L.sharp_corner[first + i] = levels_[k - 1].sharp_corner[S.parent_vertices[i]];
    }
  }

  // Which faces this level covers, and their ptex placement.
  L.owned.assign(nf, 0);
  L.param.resize(nf);
  if (k == 0) {
    ptex_first_ = ptex_offsets(cage_);  // level 0 is the cage
    for (uint32_t f = 0; f < nf; ++f) {
      L.owned[f] = !R.face_hole[f];
      L.param[f].ptex = ptex_first_[f];
    }
  } else {
    const Level& P = levels_[k - 1];
    uint32_t child = 0;
    for (uint32_t f = 0; f < nf; ++f) {
      const uint32_t pf = S.face_parent[f];
      child = f > 0 && S.face_parent[f - 1] == pf ? child + 1 : 0;
      L.owned[f] = P.requested[pf] && !R.face_hole[f];
      const Level::Face& pp = P.param[pf];
      Level::Face& cp = L.param[f];
      if (k == 1 && P.level->face_offsets[pf + 1] - P.level->face_offsets[pf] != 4) {
        cp.ptex = pp.ptex + child;  // a non-quad's corner quad is a ptex face of its own
        cp.corner = uint8_t(child);
        cp.rot = 0;
      } else {
        const uint32_t q = (child + pp.rot) % 4;
        cp.ptex = pp.ptex;
        cp.corner = pp.corner;
        cp.rot = uint8_t(q);
        cp.depth = uint8_t(pp.depth + 1);
        cp.u = uint16_t(2 * pp.u + (q == 1 || q == 2));
        cp.v = uint16_t(2 * pp.v + (q >= 2));
      }
    }
  }

  if (!roles_.empty()) {
    if (k == 0) {
      L.role.assign(roles_.begin(), roles_.end());
    } else {
      L.role.resize(nf);
      for (uint32_t f = 0; f < nf; ++f) L.role[f] = levels_[k - 1].role[S.face_parent[f]];
    }
  }
  L.level = &R;
  if (h_) {  // where each vertex's depth comes from: itself, or what it was made from
    L.src_offsets.assign(1, 0);
    if (k == 0) {
      for (uint32_t v = 0; v < nv; ++v) L.src.push_back(v), L.src_offsets.push_back(v + 1);
    } else {
      const Level& P = levels_[k - 1];
      const RefinedLevel& PR = *P.level;
      for (uint32_t f : S.parent_faces)
        append_union(L.src, L.src_offsets, P,
                     std::span(PR.face_vertices.data() + PR.face_offsets[f],
                               PR.face_offsets[f + 1] - PR.face_offsets[f]));
      for (uint32_t e : S.parent_edges)
        append_union(L.src, L.src_offsets, P,
                     std::span(PR.edge_vertices.data() + 2 * size_t(e), 2));
      for (uint32_t v : S.parent_vertices) append_union(L.src, L.src_offsets, P, std::span(&v, 1));
    }
  }
  // A level where no vertex wants more depth refines nothing (faces are forced only at the
  // cage): its corner table, rings and tags wait for level_done, when level k - 1 is gone.
  L.deferred = k > 0 && !replay_ &&
               std::all_of(L.rem.begin(), L.rem.end(), [](uint8_t d) { return d == 0; });
  if (!L.deferred) classify(k, S, adj, &requested);
  // Level k - 1 has given level k what it needs (depths, placement, sources).
  if (k > 0) {
    Level& P = levels_[k - 1];
    release(P.rem), release(P.requested), release(P.param), release(P.src), release(P.src_offsets);
    release(P.sharp_corner);
    release(P.role);
  }
}

void Builder::classify(size_t k, const SparseLevel& S, const LevelAdjacency& adj,
                       std::vector<uint8_t>* requested) {
  const RefinedLevel& R = S.level;
  const size_t nv = R.vertex_count(), nf = R.face_count();
  Level& L = levels_[k];
  L.topo = make_topo(R, adj);
  const Topo& t = L.topo;
  L.corner_sharpness = {adj.corner_edge, R.edge_sharpness.data()};
  L.vinfo.assign(nv, 0);
  // Irregular corners of covered faces; a face is refined while one of them wants depth.
  L.irregular.assign(nv, 0);
  std::vector<uint8_t> seen(nv, 0);
  L.requested.assign(nf, 0);
  L.force.assign(nf, 0);
  L.crease_edge.assign(nf, -1);
  L.crease_sharpness.assign(nf, 0.0f);
  auto tag = [&](uint32_t v) {
    if (!seen[v])
      seen[v] = 1, L.irregular[v] = o_.inf_sharp_patches ? !regular_vertex_inf(L, R, v)
                                                         : !regular_vertex(L, R, v);
  };
  for (uint32_t f = 0; f < nf; ++f) {
    if (!L.owned[f]) continue;
    const uint32_t b = R.face_offsets[f], e = R.face_offsets[f + 1];
    if (replay_) {
      for (uint32_t c = b; c < e; ++c) tag(R.face_vertices[c]);
      L.requested[f] = replayed(k, L.param[f]) && (L.role.empty() || L.role[f]);
      if (requested) (*requested)[f] = L.requested[f];
      float sharp = 0;
      const int j =
          L.requested[f] || !o_.single_crease_patches ? -1 : single_crease(L, R, f, sharp);
      if (j >= 0) L.crease_edge[f] = int8_t(j), L.crease_sharpness[f] = sharp;
      continue;
    }
    if (o_.single_crease_patches) {
      float sharp = 0;
      const int j = single_crease(L, R, f, sharp);
      if (j >= 0) {
        L.crease_edge[f] = int8_t(j), L.crease_sharpness[f] = sharp;
        for (uint32_t c = b; c < e; ++c) tag(R.face_vertices[c]);  // for their other faces
        continue;  // an exact patch as it is: never refined for its own sake
      }
    }
    // Non-quads go down once, and so do the faces next to them: patches need quads all round
    // their corners.
    bool force = e - b != 4 && k == 0, want = false;
    for (uint32_t c = b; c < e; ++c) {
      const uint32_t v = R.face_vertices[c];
      tag(v);
      want = want || (L.irregular[v] && L.rem[v] > 0);
      if (k == 0 && !force)
        for (uint32_t i = t.vertex_offsets[v]; i < t.vertex_offsets[v + 1] && !force; ++i) {
          const uint32_t g = t.corner_face[t.vertex_corners[i]];
          force = R.face_offsets[g + 1] - R.face_offsets[g] != 4;
        }
    }
    L.force[f] = force;
    L.requested[f] = (want || force) && k < size_t(kMaxDepth) && (L.role.empty() || L.role[f]);
    if (requested) (*requested)[f] = L.requested[f];
  }
}

void Builder::level_done(size_t k, const SparseLevel& S, const LevelAdjacency& adj) {
  // Level k - 1 is gone (refine_sparse drops it before this call): its end caps can be made.
  emit_pending_caps();
  if (levels_[k].deferred) classify(k, S, adj, nullptr);
  emit(k, S);
  // What the next level needs stays (depths, requests, placement, sources); the rest goes.
  Level& L = levels_[k];
  L.topo = {};
  release(L.ring_slot), release(L.ring_edge), release(L.ring_diag), release(L.ring_face);
  release(L.vinfo), release(L.irregular), release(L.owned), release(L.crease_edge);
  release(L.crease_sharpness), release(L.force);
  L.corner_sharpness = {};
}

}  // namespace limn::patch_detail
