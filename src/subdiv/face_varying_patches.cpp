// Face-varying patches: a channel's own patches beside a vertex patch table, as OpenSubdiv's Far
// builds them when its face-varying patches are not all linear (PatchTableFactory with
// generateFVarLegacyLinearPatches off; facts, not code).
//
// The channel's topology is a mesh of its own: one vertex per value (per sibling value of a cage
// vertex, as face_varying.cpp numbers them), the cage's faces over them, boundaries where seams
// run. Its refinement equals the channel's when the tags become sharpness: a value that is
// pinned (a corner) is an infinitely sharp vertex, a crease value lies on the channel mesh's
// boundary and takes its crease rule, a semi-sharp value keeps its vertex's sharpness and the
// semi-sharp edges inside its span (so it is a corner until they decay, then a crease, blended
// as OpenSubdiv blends it), and matching values see the vertex's own topology and sharpness. So
// the vertex patch builder, told to refine exactly the faces the vertex table refined (the
// channel does not drive isolation, as in Far without considerFVarChannels), makes the channel's
// patches: regular B-spline patches where its topology is regular (with boundary edges along
// seams) and Gregory end caps where it is not, at the same level and place as each vertex patch.
// One thing the channel's mesh cannot show: a value of a non-manifold cage vertex may look
// manifold in it, yet its end-cap corners are sharp (Builder::set_sharp_corners).
#include <fmt/format.h>

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <atomic>

#include "core/parallel.hpp"
#include "face_varying.hpp"
#include "patch_builder.hpp"

namespace limn {

using namespace refine_detail;
using namespace patch_detail;

namespace {

// The faces `t` refined (every ancestor of a patch), as Replay holds them.
void refined_faces(const PatchTable& t, Replay& r) {
  r.cage.assign(t.ptex_count, 0);
  auto add = [&](const PatchParam& p) {
    if (r.keys.size() < p.level) r.keys.resize(p.level);
    if (p.level > 0) r.cage[t.ptex_of_face.at(p.base_face)] = 1;
    for (uint32_t k = 1; k < p.level; ++k) {
      const uint32_t shift = p.level - k;
      r.keys[k].push_back(face_key(p.ptex, uint32_t(p.u) >> shift, uint32_t(p.v) >> shift));
    }
  };
  for (const PatchParam& p : t.regular_params) add(p);
  for (const PatchParam& p : t.gregory_params) add(p);
  for (std::vector<uint64_t>& level : r.keys) {
    std::sort(level.begin(), level.end());
    level.erase(std::unique(level.begin(), level.end()), level.end());
  }
}

// One block's share of the channel's mesh: its vertices' values in vertex order, and the crease
// edges at them as pairs of cage corners (their values are numbered once every block is in).
struct ChannelBlock {
  std::vector<uint32_t> source;          // per value: the caller's value index
  std::vector<float> sharpness;          // per value: its corner sharpness in the channel's mesh
  std::vector<uint8_t> sharp_corner;     // per value: Replay::sharp_corners
  std::vector<uint32_t> crease_corners;  // two cage corners per crease edge
  std::vector<float> crease_sharpness;
};

// The channel's mesh (see the file comment); `source` gets each of its vertices' value index.
// Built block by block of cage vertices: a vertex's values, tags and seams depend only on the
// faces around it, so each block takes the sub-cage of the faces around its vertices, in the
// cage's order (a vertex sees its faces in the same order, and so numbers its values the same
// way), and the channel's state on it, with no adjacency of the whole cage (which costs more
// than the rest of the channel's mesh together on large cages, mostly in fresh memory).
Mesh channel_mesh(const Mesh& cage, const SubdivOptions& o, const FaceVaryingInput& channel,
                  uint32_t block, std::vector<uint32_t>& source,
                  std::vector<uint8_t>& sharp_corners) {
  validate(cage, "cage");
  check_face_varying(channel, cage.corner_count());
  const uint32_t nv = uint32_t(cage.vertex_count()), nf = uint32_t(cage.face_count());
  const uint32_t* fo = cage.face_offsets.data();
  const uint32_t* fv = cage.face_vertices.data();
  // Faces around each vertex, ascending; crease tags by vertex; corner tags (a later tag wins).
  std::vector<uint32_t> vfo, vf;
  vertex_faces(cage, vfo, vf);
  const size_t ncreases = cage.crease_sharpness.size();
  std::vector<uint32_t> cto(ncreases ? size_t(nv) + 1 : 0, 0), ct(2 * ncreases);
  if (ncreases) {
    for (const uint32_t v : cage.crease_edges) ++cto[v + 1];
    for (uint32_t v = 0; v < nv; ++v) cto[v + 1] += cto[v];
    std::vector<uint32_t> fill(cto.begin(), cto.end() - 1);
    for (size_t i = 0; i < ncreases; ++i) {
      const uint32_t a = cage.crease_edges[2 * i], b = cage.crease_edges[2 * i + 1];
      ct[fill[a]++] = uint32_t(i), ct[fill[b]++] = uint32_t(i);
      bool edge = false;  // a block sees only the tags on its sub-cage's edges: check them here
      for (uint32_t k = vfo[a]; k < vfo[a + 1] && !edge; ++k) {
        const uint32_t f = vf[k], n = fo[f + 1] - fo[f];
        for (uint32_t j = 0; j < n && !edge; ++j)
          edge = fv[fo[f] + j] == a &&
                 (fv[fo[f] + (j + 1) % n] == b || fv[fo[f] + (j + n - 1) % n] == b);
      }
      if (!edge)
        throw InputError(
            fmt::format("crease tag {} names vertices {} and {}, which share no edge", i, a, b));
    }
  }
  std::vector<float> corner_tag(cage.corner_vertices.empty() ? 0 : nv, 0.0f);
  for (size_t i = 0; i < cage.corner_vertices.size(); ++i)
    corner_tag[cage.corner_vertices[i]] = std::min(cage.corner_sharpness[i], kInf);
  std::vector<uint8_t> hole(nf, 0);
  for (const uint32_t f : cage.hole_faces) hole[f] = 1;

  Mesh m;
  m.face_offsets = cage.face_offsets;
  m.face_vertices.resize(cage.corner_count());       // a corner's place among its vertex's values
  std::vector<uint32_t> offsets(size_t(nv) + 1, 0);  // values per vertex, then their first
  const uint32_t nblocks = (nv + block - 1) / block;
  std::vector<ChannelBlock> blocks(nblocks);
  tbb::enumerable_thread_specific<std::vector<uint32_t>> locals(
      [nv] { return std::vector<uint32_t>(nv, kNone); });
  parallel_range(nblocks, 1, [&](size_t b0, size_t b1) {
    std::vector<uint32_t>& local = locals.local();
    std::vector<uint32_t> faces, verts, values, tags;
    for (size_t bi = b0; bi < b1; ++bi) {
      const uint32_t v0 = uint32_t(bi) * block, v1 = std::min(nv, v0 + block);
      faces.assign(vf.begin() + vfo[v0], vf.begin() + vfo[v1]);
      std::sort(faces.begin(), faces.end());
      faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
      if (faces.empty()) continue;
      Mesh sub;
      verts.clear(), values.clear();
      for (uint32_t i = 0; i < faces.size(); ++i) {
        const uint32_t f = faces[i];
        for (uint32_t c = fo[f]; c < fo[f + 1]; ++c) {
          if (local[fv[c]] == kNone) local[fv[c]] = uint32_t(verts.size()), verts.push_back(fv[c]);
          sub.face_vertices.push_back(local[fv[c]]);
          values.push_back(channel.corner_values[c]);
        }
        sub.face_offsets.push_back(uint32_t(sub.face_vertices.size()));
        if (hole[f]) sub.hole_faces.push_back(i);
      }
      sub.positions.assign(3 * verts.size(), 0.0f);
      if (ncreases) {
        tags.assign(ct.begin() + cto[v0], ct.begin() + cto[v1]);
        std::sort(tags.begin(), tags.end());  // in the cage's order: a later tag wins
        tags.erase(std::unique(tags.begin(), tags.end()), tags.end());
        for (const uint32_t i : tags) {
          sub.crease_edges.push_back(local[cage.crease_edges[2 * i]]);
          sub.crease_edges.push_back(local[cage.crease_edges[2 * i + 1]]);
          sub.crease_sharpness.push_back(cage.crease_sharpness[i]);
        }
      }
      if (!corner_tag.empty())
        for (uint32_t v = v0; v < v1; ++v)
          if (corner_tag[v] > 0.0f && local[v] != kNone)
            sub.corner_vertices.push_back(local[v]), sub.corner_sharpness.push_back(corner_tag[v]);

      RefinedLevel L0;
      std::vector<uint8_t> excluded;
      const Adj adj = cage_level(sub, o, L0, &excluded);
      const FVarState s = fvar_cage_state(o, L0, adj, values, channel.value_count);
      ChannelBlock& out = blocks[bi];
      for (uint32_t v = v0; v < v1; ++v) {
        const uint32_t lv = local[v];
        if (lv == kNone) continue;  // on no face: no value
        offsets[v + 1] = s.offsets[lv + 1] - s.offsets[lv];
        float dependent = L0.vertex_sharpness[lv];  // what a value pinned by its sibling follows
        for (uint32_t k = adj.veo[lv]; k < adj.veo[lv + 1]; ++k)
          if (const float x = L0.edge_sharpness[adj.ve[k]]; x < kInf)
            dependent = std::max(dependent, x);
        // Only mismatched values can be sharp for it (every value of a non-manifold vertex is).
        const bool non_manifold = s.offsets[lv + 1] > s.offsets[lv] &&
                                  (s.tag[s.offsets[lv]] & kFvMismatch) &&
                                  cage_vertex_non_manifold(adj, lv);
        for (uint32_t x = s.offsets[lv]; x < s.offsets[lv + 1]; ++x) {
          const uint8_t t = s.tag[x];
          float sharpness = L0.vertex_sharpness[lv];
          if (t & kFvDepSharp) {
            sharpness = dependent;
          } else if ((t & kFvMismatch) && !(t & kFvSemiSharp)) {
            sharpness = t & kFvCrease ? 0.0f : kInf;
          }
          out.source.push_back(s.source[x]);
          out.sharpness.push_back(sharpness);
          out.sharp_corner.push_back(non_manifold);
        }
        if (excluded[lv])
          for (uint32_t k = vfo[v]; k < vfo[v + 1]; ++k)
            std::atomic_ref<uint8_t>(hole[vf[k]]).store(1, std::memory_order_relaxed);
      }
      // Each corner at a block's vertex: its place among the vertex's values, and the crease
      // edge it starts when the channel keeps the vertex's crease there.
      const LevelRef l{L0, adj};
      for (uint32_t i = 0; i < faces.size(); ++i)
        for (uint32_t c = L0.face_offsets[i]; c < L0.face_offsets[i + 1]; ++c) {
          const uint32_t v = verts[L0.face_vertices[c]];
          if (v < v0 || v >= v1) continue;
          const uint32_t cage_corner = fo[faces[i]] + (c - L0.face_offsets[i]);
          m.face_vertices[cage_corner] = s.corner_value[c] - s.offsets[L0.face_vertices[c]];
          const uint32_t e = adj.corner_edge[c];
          const float x = L0.edge_sharpness[e];
          if (x > 0.0f && adj.edge_face_count(e) == 2 && !(s.edge[e] & kFvEdgeMismatch)) {
            const uint32_t n = l.next(c);
            out.crease_corners.insert(out.crease_corners.end(),
                                      {cage_corner, fo[faces[i]] + (n - L0.face_offsets[i])});
            out.crease_sharpness.push_back(x);
          }
        }
      for (const uint32_t v : verts) local[v] = kNone;
    }
  });
  for (uint32_t v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
  for (size_t c = 0; c < m.face_vertices.size(); ++c) m.face_vertices[c] += offsets[fv[c]];
  source.clear(), sharp_corners.clear();
  source.reserve(offsets.back()), sharp_corners.reserve(offsets.back());
  for (const ChannelBlock& b : blocks) {
    for (size_t i = 0; i < b.sharpness.size(); ++i)
      if (b.sharpness[i] > 0.0f)
        m.corner_vertices.push_back(uint32_t(source.size() + i)),
            m.corner_sharpness.push_back(b.sharpness[i]);
    source.insert(source.end(), b.source.begin(), b.source.end());
    sharp_corners.insert(sharp_corners.end(), b.sharp_corner.begin(), b.sharp_corner.end());
    for (const uint32_t c : b.crease_corners) m.crease_edges.push_back(m.face_vertices[c]);
    m.crease_sharpness.insert(m.crease_sharpness.end(), b.crease_sharpness.begin(),
                              b.crease_sharpness.end());
  }
  m.positions.assign(3 * size_t(offsets.back()), 0.0f);
  for (uint32_t f = 0; f < nf; ++f)
    if (hole[f]) m.hole_faces.push_back(f);
  return m;
}

// Copies components [k0, k0 + kn) of n results (3 floats each) into outputs of w floats each.
void scatter(size_t n, size_t w, size_t k0, size_t kn, const std::vector<float>& p,
             const std::vector<float>& pu, const std::vector<float>& pv, float* out, float* du,
             float* dv) {
  for (size_t i = 0; i < n; ++i)
    for (size_t k = 0; k < kn; ++k) {
      out[i * w + k0 + k] = p[3 * i + k];
      if (du) du[i * w + k0 + k] = pu[3 * i + k];
      if (dv) dv[i * w + k0 + k] = pv[3 * i + k];
    }
}

}  // namespace

FaceVaryingPatches build_face_varying_patches(const Mesh& cage, const PatchTable& table,
                                              const FaceVaryingInput& channel,
                                              const PatchOptions& options) {
  FaceVaryingPatches out;
  out.interpolation = options.subdiv.face_varying;
  check_face_varying(channel, cage.corner_count());
  if (out.interpolation == FVarInterpolation::all) return out;
  if (table.ptex_of_face.size() != cage.face_count() + 1)
    throw InputError("face-varying patches: the patch table was built from another cage");
  Replay replay;
  const uint32_t block = options.batch_faces ? options.batch_faces : 16384;
  const Mesh m =
      channel_mesh(cage, options.subdiv, channel, block, out.source, replay.sharp_corners);
  PatchOptions po = options;
  po.subdiv.boundary = BoundaryInterpolation::edge_only;
  po.depth = 12;  // only a bound: the vertex table's refinement is replayed
  refined_faces(table, replay);
  out.table = build_replayed(m, po, replay);
  return out;
}

std::vector<float> FaceVaryingPatches::points(const float* values, size_t width,
                                              size_t first) const {
  if (first >= width)
    throw InputError(fmt::format("face-varying points: component {} of {}", first, width));
  const size_t nv = source.size(), kn = std::min<size_t>(3, width - first);
  std::vector<float> cage_points(3 * nv, 0.0f);
  for (size_t x = 0; x < nv; ++x)
    for (size_t k = 0; k < kn; ++k)
      cage_points[3 * x + k] = values[size_t(source[x]) * width + first + k];
  return table.points(cage_points);
}

void evaluate_face_varying(const Mesh& cage, const FaceVaryingInput& channel,
                           const FaceVaryingPatches& patches, const float* values, int width,
                           std::span<const PtexCoord> coords, float* out, float* du, float* dv) {
  if (patches.interpolation == FVarInterpolation::all)
    return evaluate_linear_face_varying(cage, channel, values, width, coords, out, du, dv);
  check_face_varying(channel, cage.corner_count());
  if (width < 1 || width > 4) throw InputError("face-varying evaluation: width must be 1-4");
  const PatchTable& t = patches.table;
  const PatchMap map(t);
  std::vector<PatchCoord> at(coords.size());
  for (size_t i = 0; i < coords.size(); ++i)
    at[i] = map.find(coords[i].ptex, coords[i].u, coords[i].v);
  const size_t w = size_t(width), n = coords.size();
  // Three components at a time, as points.
  std::vector<float> p(3 * n), pu(du ? 3 * n : 0), pv(dv ? 3 * n : 0);
  for (size_t k0 = 0; k0 < w; k0 += 3) {
    const size_t kn = std::min<size_t>(3, w - k0);
    evaluate_patches(t, patches.points(values, w, k0), at, p.data(), du ? pu.data() : nullptr,
                     dv ? pv.data() : nullptr);
    scatter(n, w, k0, kn, p, pu, pv, out, du, dv);
  }
}

void evaluate_face_varying_grids(const Mesh& cage, const FaceVaryingInput& channel,
                                 const FaceVaryingPatches& patches, const float* values, int width,
                                 int n, float* out, float* du, float* dv) {
  if (n < 2 || n > 65536) throw InputError(fmt::format("face-varying grids: n = {} (2-65536)", n));
  check_face_varying(channel, cage.corner_count());
  if (width < 1 || width > 4) throw InputError("face-varying evaluation: width must be 1-4");
  uint32_t ptex_count = 0;
  for (size_t f = 0; f < cage.face_count(); ++f)
    ptex_count += cage.face_size(f) == 4 ? 1 : cage.face_size(f);
  const size_t nn = size_t(n) * size_t(n), w = size_t(width);
  if (patches.interpolation != FVarInterpolation::all) {
    // The channel's own table has the cage's ptex faces: evaluate_grids over it, three
    // components at a time.
    const PatchTable& t = patches.table;
    const size_t total = size_t(t.ptex_count) * nn;
    std::vector<float> p(3 * total), pu(du ? 3 * total : 0), pv(dv ? 3 * total : 0);
    for (size_t k0 = 0; k0 < w; k0 += 3) {
      const size_t kn = std::min<size_t>(3, w - k0);
      evaluate_grids(t, patches.points(values, w, k0), n, p.data(), du ? pu.data() : nullptr,
                     dv ? pv.data() : nullptr);
      scatter(total, w, k0, kn, p, pu, pv, out, du, dv);
    }
    return;
  }
  // Linear: blocks of ptex faces, so the coordinates stay small.
  const float step = 1.0f / float(n - 1);
  const uint32_t block = uint32_t(std::max<size_t>(1, (size_t(1) << 16) / nn));
  std::vector<PtexCoord> at;
  for (uint32_t p0 = 0; p0 < ptex_count; p0 += block) {
    const uint32_t p1 = std::min(ptex_count, p0 + block);
    at.clear();
    for (uint32_t p = p0; p < p1; ++p)
      for (size_t j = 0; j < size_t(n); ++j)
        for (size_t i = 0; i < size_t(n); ++i) at.push_back({p, float(i) * step, float(j) * step});
    const size_t o = size_t(p0) * nn * w;
    evaluate_linear_face_varying(cage, channel, values, width, at, out + o, du ? du + o : nullptr,
                                 dv ? dv + o : nullptr);
  }
}

}  // namespace limn
