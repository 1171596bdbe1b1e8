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

#include <algorithm>

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

// The channel's mesh (see the file comment); `source` gets each of its vertices' value index.
Mesh channel_mesh(const Mesh& cage, const SubdivOptions& o, const FaceVaryingInput& channel,
                  std::vector<uint32_t>& source, std::vector<uint8_t>& sharp_corners) {
  RefinedLevel L0;
  const Adj adj = cage_level(cage, o, L0);
  FVarState s = fvar_cage_state(o, L0, adj, channel.corner_values, channel.value_count);
  Mesh m;
  m.positions.assign(3 * s.value_count(), 0.0f);
  sharp_corners.assign(s.value_count(), 0);
  m.face_offsets = cage.face_offsets;
  m.face_vertices = s.corner_value;
  for (uint32_t f = 0; f < L0.face_count(); ++f)
    if (L0.face_hole[f]) m.hole_faces.push_back(f);
  const LevelRef l{L0, adj};
  for (uint32_t c = 0; c < L0.face_vertices.size(); ++c) {
    const uint32_t e = adj.corner_edge[c];
    const float x = L0.edge_sharpness[e];
    if (x > 0.0f && adj.edge_face_count(e) == 2 && !(s.edge[e] & kFvEdgeMismatch))
      m.crease_edges.insert(m.crease_edges.end(), {s.corner_value[c], s.corner_value[l.next(c)]}),
          m.crease_sharpness.push_back(x);
  }
  for (uint32_t v = 0; v < L0.vertex_count(); ++v) {
    float dependent = L0.vertex_sharpness[v];  // what a value pinned by its sibling follows
    for (uint32_t k = adj.veo[v]; k < adj.veo[v + 1]; ++k)
      if (const float x = L0.edge_sharpness[adj.ve[k]]; x < kInf)
        dependent = std::max(dependent, x);
    // Only mismatched values can be sharp for it (every value of a non-manifold vertex is).
    const bool non_manifold = s.offsets[v + 1] > s.offsets[v] &&
                              (s.tag[s.offsets[v]] & kFvMismatch) &&
                              cage_vertex_non_manifold(adj, v);
    for (uint32_t x = s.offsets[v]; x < s.offsets[v + 1]; ++x) {
      const uint8_t t = s.tag[x];
      sharp_corners[x] = non_manifold;
      float sharpness = L0.vertex_sharpness[v];
      if (t & kFvDepSharp) {
        sharpness = dependent;
      } else if ((t & kFvMismatch) && !(t & kFvSemiSharp)) {
        sharpness = t & kFvCrease ? 0.0f : kInf;
      }
      if (sharpness > 0.0f) m.corner_vertices.push_back(x), m.corner_sharpness.push_back(sharpness);
    }
  }
  source = std::move(s.source);
  return m;
}

// Components [k0, k0 + kn) (kn <= 3) of the channel's values as the points of its table, and
// those points pushed through it (PatchTable::points).
std::vector<float> channel_points(const FaceVaryingPatches& patches, const float* values, size_t w,
                                  size_t k0, size_t kn) {
  const size_t nv = patches.source.size();
  std::vector<float> cage_points(3 * nv, 0.0f);
  for (size_t x = 0; x < nv; ++x)
    for (size_t k = 0; k < kn; ++k)
      cage_points[3 * x + k] = values[size_t(patches.source[x]) * w + k0 + k];
  return patches.table.points(cage_points);
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
  const Mesh m = channel_mesh(cage, options.subdiv, channel, out.source, replay.sharp_corners);
  PatchOptions po = options;
  po.subdiv.boundary = BoundaryInterpolation::edge_only;
  po.depth = 12;  // only a bound: the vertex table's refinement is replayed
  refined_faces(table, replay);
  out.table = build_replayed(m, po, replay);
  return out;
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
    evaluate_patches(t, channel_points(patches, values, w, k0, kn), at, p.data(),
                     du ? pu.data() : nullptr, dv ? pv.data() : nullptr);
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
      evaluate_grids(t, channel_points(patches, values, w, k0, kn), n, p.data(),
                     du ? pu.data() : nullptr, dv ? pv.data() : nullptr);
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
