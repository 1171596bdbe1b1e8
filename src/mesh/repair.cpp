// Repair of polygon soups, in steps over a working face list that remembers the input corner of
// each of its corners:
//  1. weld (weld_map_within), each vertex onto its group's first vertex;
//  2. faces cleaned of repeated neighbours and split where they pass a vertex twice;
//  3. zero-area and duplicate faces dropped;
//  4. orientation spread across the edges of exactly two faces; an edge whose faces cannot agree
//     is cut;
//  5. faces glued across those edges share their corners' vertices, and each fan of faces around
//     a vertex gets its own copy: edges of three or more faces and pinched vertices come apart.
// A second pass of 4-5 runs only when the first cut something; it finds work only where a fan's
// two ends met on one edge.
#include "limn/mesh/repair.hpp"

#include <fmt/format.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "core/vec3.hpp"
#include "limn/mesh/weld.hpp"
#include "union_find.hpp"

namespace limn {

namespace {

constexpr uint32_t kNo = 0xFFFFFFFFu;

struct Faces {
  std::vector<uint32_t> offsets{0};
  std::vector<uint32_t> verts;       // vertex per corner
  std::vector<uint32_t> src_corner;  // input corner per corner
  std::vector<uint32_t> src_face;    // input face per face
  size_t count() const { return offsets.size() - 1; }
};

struct Corner {
  uint32_t v, c;
};

void add_face(Faces& F, uint32_t face, const Corner* loop, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    F.verts.push_back(loop[i].v);
    F.src_corner.push_back(loop[i].c);
  }
  F.offsets.push_back(static_cast<uint32_t>(F.verts.size()));
  F.src_face.push_back(face);
}

// Twice the area of a polygon.
double area2(const float* P, const uint32_t* v, size_t n) {
  double s[3];
  newell_double(P, v, n, s);
  return std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
}

// Step 2 for one face: `loop` holds its welded corners without repeated neighbours; emits the
// simple loops it is made of (pieces of fewer than 3 corners are spikes and vanish). Returns the
// number of loops emitted.
size_t split_pinched(Faces& F, uint32_t face, const std::vector<Corner>& loop,
                     std::vector<Corner>& stack, std::unordered_map<uint32_t, size_t>& at) {
  stack.clear();
  at.clear();
  size_t emitted = 0;
  const bool big = loop.size() > 16;
  for (const Corner& e : loop) {
    size_t p = kNo;
    if (big) {
      if (const auto it = at.find(e.v); it != at.end()) p = it->second;
    } else {
      for (size_t i = 0; i < stack.size() && p == kNo; ++i)
        if (stack[i].v == e.v) p = i;
    }
    if (p == kNo) {
      if (big) at[e.v] = stack.size();
      stack.push_back(e);
      continue;
    }
    // stack[p..] closes a loop at e.v: e's corner has the loop's incoming edge.
    if (stack.size() - p >= 3) {
      const uint32_t kept = stack[p].c;
      stack[p].c = e.c;
      add_face(F, face, &stack[p], stack.size() - p);
      stack[p].c = kept;
      ++emitted;
    }
    for (size_t i = p + 1; i < stack.size(); ++i) at.erase(stack[i].v);
    stack.resize(p + 1);
  }
  if (stack.size() >= 3) {
    add_face(F, face, stack.data(), stack.size());
    ++emitted;
  }
  return emitted;
}

// Steps 4-5 over F; vertices are numbered in `source` (the input vertex of each, copies
// appended). Returns whether any edge was cut or any vertex split.
bool orient_and_split(Faces& F, std::vector<uint32_t>& source, const float* P,
                      const double center[3], RepairReport& r) {
  const size_t nf = F.count(), nc = F.verts.size();
  std::vector<uint32_t> corner_face(nc), next(nc);
  for (size_t f = 0; f < nf; ++f)
    for (uint32_t c = F.offsets[f]; c < F.offsets[f + 1]; ++c) {
      corner_face[c] = static_cast<uint32_t>(f);
      next[c] = c + 1 < F.offsets[f + 1] ? c + 1 : F.offsets[f];
    }

  // Undirected edges by sorting corners on (smaller vertex, larger vertex).
  struct Key {
    uint64_t edge;
    uint32_t c;
    bool operator<(const Key& o) const { return edge != o.edge ? edge < o.edge : c < o.c; }
  };
  std::vector<Key> keys(nc);
  for (uint32_t c = 0; c < nc; ++c) {
    const uint64_t a = F.verts[c], b = F.verts[next[c]];
    keys[c] = {std::min(a, b) << 32 | std::max(a, b), c};
  }
  // Small meshes sort on this thread: TBB's pool costs milliseconds to start in a fresh process.
  if (nc < (size_t(1) << 17))
    std::sort(keys.begin(), keys.end());
  else
    tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<uint32_t> twin(nc, kNo);
  size_t cut = 0;
  for (size_t i = 0; i < nc;) {
    size_t j = i + 1;
    while (j < nc && keys[j].edge == keys[i].edge) ++j;
    if (j - i == 2) twin[keys[i].c] = keys[i + 1].c, twin[keys[i + 1].c] = keys[i].c;
    if (j - i > 2) ++r.non_manifold_edges, ++cut;
    i = j;
  }

  // Orientation: breadth-first over twins; a face's flip makes it agree with the one it was
  // reached from, and an edge whose two faces were already set and disagree is cut.
  std::vector<uint8_t> flip(nf, 0);
  std::vector<uint32_t> comp(nf, kNo), queue;
  uint32_t comps = 0;
  for (uint32_t seed = 0; seed < nf; ++seed) {
    if (comp[seed] != kNo) continue;
    comp[seed] = comps;
    queue.assign(1, seed);
    for (size_t q = 0; q < queue.size(); ++q) {
      const uint32_t f = queue[q];
      for (uint32_t c = F.offsets[f]; c < F.offsets[f + 1]; ++c) {
        const uint32_t t = twin[c];
        if (t == kNo) continue;
        const uint32_t g = corner_face[t];
        const uint8_t want = flip[f] ^ uint8_t(F.verts[c] == F.verts[t]);
        if (comp[g] == kNo) {
          comp[g] = comps, flip[g] = want;
          queue.push_back(g);
        } else if (flip[g] != want) {
          twin[c] = twin[t] = kNo;
          ++r.unorientable_edges, ++cut;
        }
      }
    }
    ++comps;
  }

  // Per piece: closed pieces face outward (positive signed volume), open ones keep the
  // orientation most of their faces had.
  std::vector<size_t> faces(comps, 0), flipped(comps, 0);
  std::vector<uint8_t> open(comps, 0);
  std::vector<double> volume(comps, 0.0);
  for (uint32_t f = 0; f < nf; ++f) {
    const uint32_t k = comp[f], o = F.offsets[f], n = F.offsets[f + 1] - o;
    ++faces[k];
    flipped[k] += flip[f];
    double v = 0;
    const float* a = P + 3 * size_t(source[F.verts[o]]);
    for (uint32_t i = 0; i < n; ++i) open[k] |= twin[o + i] == kNo;
    for (uint32_t i = 1; i + 1 < n; ++i) {
      const float* b = P + 3 * size_t(source[F.verts[o + i]]);
      const float* c = P + 3 * size_t(source[F.verts[o + i + 1]]);
      double x[3], y[3], z[3];
      for (int d = 0; d < 3; ++d)
        x[d] = a[d] - center[d], y[d] = b[d] - center[d], z[d] = c[d] - center[d];
      v += x[0] * (y[1] * z[2] - y[2] * z[1]) - x[1] * (y[0] * z[2] - y[2] * z[0]) +
           x[2] * (y[0] * z[1] - y[1] * z[0]);
    }
    volume[k] += flip[f] ? -v : v;
  }
  std::vector<uint8_t> invert(comps);
  r.components = comps, r.closed_components = 0;
  for (uint32_t k = 0; k < comps; ++k) {
    invert[k] = open[k] ? 2 * flipped[k] > faces[k] : volume[k] < 0;
    r.closed_components += !open[k];
    r.flipped_faces += invert[k] ? faces[k] - flipped[k] : flipped[k];
  }

  // Fans: corners at one vertex of two faces glued across an edge share a vertex.
  detail::UnionFind fans(nc);
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t t = twin[c];
    if (t == kNo || t < c) continue;
    if (F.verts[c] == F.verts[t]) {
      fans.unite(c, t), fans.unite(next[c], next[t]);
    } else {
      fans.unite(c, next[t]), fans.unite(next[c], t);
    }
  }
  std::vector<uint32_t> fan_vertex(nc, kNo);
  std::vector<uint8_t> used(source.size(), 0);
  size_t splits = 0;
  for (uint32_t c = 0; c < nc; ++c) {
    const uint32_t root = fans.find(c);
    if (fan_vertex[root] == kNo) {
      const uint32_t v = F.verts[c];
      if (!used[v]) {
        used[v] = 1, fan_vertex[root] = v;
      } else {
        fan_vertex[root] = static_cast<uint32_t>(source.size());
        source.push_back(source[v]);
        ++splits;
      }
    }
    F.verts[c] = fan_vertex[root];
  }
  r.split_vertices += splits;

  // Flipping keeps a face's first corner: v0 v1 ... vn-1 becomes v0 vn-1 ... v1.
  for (uint32_t f = 0; f < nf; ++f)
    if (flip[f] ^ invert[comp[f]]) {
      std::reverse(F.verts.begin() + F.offsets[f] + 1, F.verts.begin() + F.offsets[f + 1]);
      std::reverse(F.src_corner.begin() + F.offsets[f] + 1,
                   F.src_corner.begin() + F.offsets[f + 1]);
    }
  return cut + splits > 0;
}

}  // namespace

Mesh repair_mesh(const Mesh& in, const RepairOptions& options, RepairReport* report) {
  validate_soup(in, "mesh");
  if (!(options.weld_tolerance >= 0 && options.weld_tolerance <= 0.1))
    throw InputError(
        fmt::format("repair: weld tolerance {} is outside [0, 0.1]", options.weld_tolerance));
  RepairReport r;
  const size_t nv = in.vertex_count(), nf = in.face_count();
  const float* P = in.positions.data();

  Box box;
  for (const uint32_t v : in.face_vertices)
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min(box.min[k], P[3 * size_t(v) + k]);
      box.max[k] = std::max(box.max[k], P[3 * size_t(v) + k]);
    }
  const double diag = box.diagonal();
  double center[3] = {0, 0, 0};
  if (!box.empty())
    for (int k = 0; k < 3; ++k) center[k] = 0.5 * (double(box.min[k]) + box.max[k]);

  // 1. Weld: each vertex onto the first vertex of its group.
  uint32_t groups = 0;
  const std::vector<uint32_t> group =
      weld_map_within(in.positions, options.weld_tolerance * diag, &groups);
  std::vector<uint32_t> first(groups, kNo), vmap(nv);
  for (uint32_t v = 0; v < nv; ++v) {
    if (first[group[v]] == kNo) first[group[v]] = v;
    vmap[v] = first[group[v]];
    r.welded_vertices += vmap[v] != v;
  }

  // 2-3. Faces: welded, cleaned, split at pinches, then zero-area and duplicate ones dropped.
  Faces F;
  F.verts.reserve(in.corner_count());
  F.src_corner.reserve(in.corner_count());
  const double min_area2 = 2e-12 * diag * diag;
  std::vector<Corner> loop, stack;
  std::vector<uint32_t> scratch, sorted;
  std::unordered_map<uint32_t, size_t> at;
  std::vector<uint32_t> table(16, kNo);  // open addressing: face of F by sorted vertex set
  size_t stored = 0;
  const auto hash_of = [](const uint32_t* s, size_t n) {
    uint64_t h = n * 0x9E3779B97F4A7C15ull;
    for (size_t i = 0; i < n; ++i) h = (h ^ s[i]) * 0xBF58476D1CE4E5B9ull, h ^= h >> 29;
    return h;
  };
  std::vector<uint32_t> sorted_verts;  // sorted vertex set of every kept face, like F.verts
  const auto grow = [&] {
    std::vector<uint32_t> bigger(2 * table.size(), kNo);
    for (const uint32_t g : table) {
      if (g == kNo) continue;
      const uint32_t o = F.offsets[g], n = F.offsets[g + 1] - o;
      for (size_t s = hash_of(&sorted_verts[o], n) & (bigger.size() - 1);;
           s = (s + 1) & (bigger.size() - 1))
        if (bigger[s] == kNo) {
          bigger[s] = g;
          break;
        }
    }
    table.swap(bigger);
  };
  for (uint32_t f = 0; f < nf; ++f) {
    const uint32_t o = in.face_offsets[f], n = in.face_size(f);
    loop.clear();
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t v = vmap[in.face_vertices[o + i]];
      if (loop.empty() || loop.back().v != v) loop.push_back({v, o + i});
    }
    while (loop.size() > 1 && loop.back().v == loop.front().v) loop.pop_back();
    const size_t before = F.count();
    scratch.clear();
    for (const Corner& c : loop) scratch.push_back(c.v);
    if (loop.size() >= 3 && repeated_vertex(scratch, sorted) == kNoRepeat) {
      add_face(F, f, loop.data(), loop.size());
    } else if (loop.size() >= 3 && split_pinched(F, f, loop, stack, at) > 0) {
      ++r.split_faces;
    }
    if (F.count() == before) ++r.degenerate_faces;
    // Check what this face added: drop zero-area and duplicate loops.
    size_t keep = before;
    for (size_t g = before; g < F.count(); ++g) {
      const uint32_t go = F.offsets[g], gn = F.offsets[g + 1] - go;
      const bool degenerate = area2(P, &F.verts[go], gn) <= min_area2;
      sorted.assign(F.verts.begin() + go, F.verts.begin() + go + gn);
      std::sort(sorted.begin(), sorted.end());
      bool duplicate = false;
      size_t slot = hash_of(sorted.data(), gn) & (table.size() - 1);
      if (!degenerate)
        for (;; slot = (slot + 1) & (table.size() - 1)) {
          const uint32_t h = table[slot];
          if (h == kNo) break;
          const uint32_t ho = F.offsets[h], hn = F.offsets[h + 1] - ho;
          if (hn == gn && std::equal(sorted.begin(), sorted.end(), &sorted_verts[ho])) {
            duplicate = true;
            break;
          }
        }
      r.degenerate_faces += degenerate;
      r.duplicate_faces += duplicate;
      if (degenerate || duplicate) continue;
      // Keep: move loop g to position `keep` (it only ever moves down within this face's loops).
      const uint32_t ko = F.offsets[keep];
      std::copy(F.verts.begin() + go, F.verts.begin() + go + gn, F.verts.begin() + ko);
      std::copy(F.src_corner.begin() + go, F.src_corner.begin() + go + gn,
                F.src_corner.begin() + ko);
      F.offsets[keep + 1] = ko + gn;
      sorted_verts.resize(ko);
      sorted_verts.insert(sorted_verts.end(), sorted.begin(), sorted.end());
      table[slot] = static_cast<uint32_t>(keep);
      ++keep;
      if (2 * ++stored > table.size()) grow();
    }
    F.offsets.resize(keep + 1);
    F.verts.resize(F.offsets.back());
    F.src_corner.resize(F.offsets.back());
    F.src_face.resize(keep);
  }

  // 4-5. Orientation and manifold fans; vertices are numbered by their input vertex, copies
  // appended.
  std::vector<uint32_t> source(nv);
  for (uint32_t v = 0; v < nv; ++v) source[v] = v;
  for (int pass = 0; pass < 4; ++pass)
    if (!orient_and_split(F, source, P, center, r)) break;

  // Output vertices: the used ones in order of their input vertex, each followed by its copies.
  const size_t ids = source.size();
  std::vector<uint32_t> start(nv + 1, 0), out_id(ids, kNo);
  std::vector<uint8_t> used(ids, 0);
  for (const uint32_t v : F.verts) used[v] = 1;
  for (size_t i = 0; i < ids; ++i) start[source[i] + 1] += used[i];
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  for (size_t i = 0; i < ids; ++i)
    if (used[i]) out_id[i] = start[source[i]]++;
  size_t sources_kept = 0;
  for (size_t i = 0; i < nv; ++i) sources_kept += used[i];
  r.unreferenced_vertices = nv - r.welded_vertices - sources_kept;

  Mesh out;
  out.tags = in.tags;
  const size_t nout = start[nv];
  out.positions.resize(3 * nout);
  const bool colors = !in.colors.empty();
  if (colors) out.colors.resize(4 * nout);
  std::vector<uint32_t> out_source(nout);
  for (size_t i = 0; i < ids; ++i) {
    if (out_id[i] == kNo) continue;
    const uint32_t s = source[i], o = out_id[i];
    out_source[o] = s;
    std::copy_n(P + 3 * size_t(s), 3, &out.positions[3 * size_t(o)]);
    if (colors) std::copy_n(&in.colors[4 * size_t(s)], 4, &out.colors[4 * size_t(o)]);
  }
  out.face_offsets = F.offsets;
  out.face_vertices.resize(F.verts.size());
  for (size_t c = 0; c < F.verts.size(); ++c) out.face_vertices[c] = out_id[F.verts[c]];
  if (!in.uv_indices.empty()) {
    out.uvs = in.uvs;
    out.uv_indices.resize(F.verts.size());
    for (size_t c = 0; c < F.verts.size(); ++c) out.uv_indices[c] = in.uv_indices[F.src_corner[c]];
  }
  if (!in.normal_indices.empty()) {
    out.normals = in.normals;
    out.normal_indices.resize(F.verts.size());
    for (size_t c = 0; c < F.verts.size(); ++c)
      out.normal_indices[c] = in.normal_indices[F.src_corner[c]];
  }
  if (!in.hole_faces.empty()) {
    std::vector<uint8_t> hole(nf, 0);
    for (const uint32_t f : in.hole_faces) hole[f] = 1;
    for (size_t g = 0; g < F.count(); ++g)
      if (hole[F.src_face[g]]) out.hole_faces.push_back(static_cast<uint32_t>(g));
  }
  if (!in.crease_edges.empty()) {
    // Creases by welded input edge, then onto every output edge over it.
    const auto key = [](uint64_t a, uint64_t b) { return std::min(a, b) << 32 | std::max(a, b); };
    std::unordered_map<uint64_t, float> sharp;
    for (size_t e = 0; e < in.crease_sharpness.size(); ++e) {
      const uint32_t a = vmap[in.crease_edges[2 * e]], b = vmap[in.crease_edges[2 * e + 1]];
      if (a == b) continue;
      float& s = sharp[key(a, b)];
      s = std::max(s, in.crease_sharpness[e]);
    }
    std::unordered_set<uint64_t> emitted;
    for (size_t f = 0; f < out.face_count(); ++f) {
      const auto v = out.face(f);
      for (size_t i = 0; i < v.size(); ++i) {
        const uint32_t a = v[i], b = v[(i + 1) % v.size()];
        const auto it = sharp.find(key(out_source[a], out_source[b]));
        if (it == sharp.end() || !emitted.insert(key(a, b)).second) continue;
        out.crease_edges.insert(out.crease_edges.end(), {std::min(a, b), std::max(a, b)});
        out.crease_sharpness.push_back(it->second);
      }
    }
  }
  if (!in.corner_vertices.empty()) {
    std::unordered_map<uint32_t, float> sharp;
    for (size_t i = 0; i < in.corner_vertices.size(); ++i) {
      float& s = sharp[vmap[in.corner_vertices[i]]];
      s = std::max(s, in.corner_sharpness[i]);
    }
    for (uint32_t o = 0; o < nout; ++o)
      if (const auto it = sharp.find(out_source[o]); it != sharp.end()) {
        out.corner_vertices.push_back(o);
        out.corner_sharpness.push_back(it->second);
      }
  }
  if (report) *report = r;
  return out;
}

}  // namespace limn
