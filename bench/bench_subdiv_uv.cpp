// Uniform subdivision with one UV channel, limn beside OpenSubdiv 3.5, each case in its own
// child process (time and peak resident set; isolated.hpp):
//   osd:       Far::TopologyRefinerFactory with one face-varying channel + RefineUniform +
//              PrimvarRefiner::Interpolate and InterpolateFaceVarying level by level (its
//              leanest way to a level's points and UVs), single-threaded;
//   limn full: refine_uniform with the channel (every level, its stencils and its face-varying
//              stencils kept) + the last level's positions and UVs;
//   limn lean: subdivide_uniform (only the last level kept; carries the UVs);
//   osd tables: the same kept as tables: StencilTableFactory's last-level stencils over the cage,
//              vertex and face-varying, applied (what limn full is measured against).
// And the same three without the channel, so the UVs' own cost shows. Models: the car and BigGuy
// (their own UVs) and the 800k-quad terrain (planar UVs cut by a seam down the middle). Modes:
// OpenSubdiv's default (linear all) and "none" (smooth UVs, the most work).
// Then feature-adaptive builds at depth 3 without the channel, with linear UVs and with smooth ones
// (osd_adaptive, limn_adaptive).
// Times are the best of five runs below half a second.
// Usage: limn_bench_subdiv_uv [--cap-gb N] [--adaptive-only]
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "isolated.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/refine.hpp"
#include "osd_bench.hpp"

namespace {

using namespace OpenSubdiv::OPENSUBDIV_VERSION;

template <int N>
struct Value {
  float x[N] = {};
  void Clear(void* = nullptr) {
    for (float& v : x) v = 0;
  }
  void AddWithWeight(const Value& p, float w) {
    for (int k = 0; k < N; ++k) x[k] += w * p.x[k];
  }
};

size_t osd_run(const limn::Mesh& m, int level, limn::FVarInterpolation mode, bool uv) {
  const std::unique_ptr<Far::TopologyRefiner> r = limn::bench::osd_refiner(m, uv, mode);
  Far::TopologyRefiner::UniformOptions uo(level);
  uo.fullTopologyInLastLevel = false;
  r->RefineUniform(uo);
  std::vector<Value<3>> p(m.vertex_count()), pn;
  for (size_t v = 0; v < m.vertex_count(); ++v)
    p[v] = {{m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]}};
  std::vector<Value<2>> t(m.uvs.size() / 2), tn;
  for (size_t i = 0; i < t.size(); ++i) t[i] = {{m.uvs[2 * i], m.uvs[2 * i + 1]}};
  const Far::PrimvarRefiner pr(*r);
  for (int k = 1; k <= level; ++k) {
    pn.assign(size_t(r->GetLevel(k).GetNumVertices()), {});
    pr.Interpolate(k, p, pn);
    p.swap(pn);
    if (!uv) continue;
    tn.assign(size_t(r->GetLevel(k).GetNumFVarValues(0)), {});
    pr.InterpolateFaceVarying(k, t, tn, 0);
    t.swap(tn);
  }
  return p.size() + (uv ? t.size() : 0);
}

// The same job kept as tables for animated cages, OpenSubdiv's way: StencilTableFactory (the last
// level's stencils over the cage, vertex and face-varying) after RefineUniform, then applied.
size_t osd_tables(const limn::Mesh& m, int level, limn::FVarInterpolation mode, bool uv) {
  const std::unique_ptr<Far::TopologyRefiner> r = limn::bench::osd_refiner(m, uv, mode);
  Far::TopologyRefiner::UniformOptions uo(level);
  uo.fullTopologyInLastLevel = false;
  r->RefineUniform(uo);
  Far::StencilTableFactory::Options so;
  so.generateIntermediateLevels = false;
  so.generateOffsets = true;
  std::unique_ptr<const Far::StencilTable> st(Far::StencilTableFactory::Create(*r, so));
  std::vector<Value<3>> p(m.vertex_count()), pn(size_t(st->GetNumStencils()));
  for (size_t v = 0; v < m.vertex_count(); ++v)
    p[v] = {{m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]}};
  st->UpdateValues(p.data(), pn.data());
  size_t n = pn.size();
  if (uv) {
    so.interpolationMode = Far::StencilTableFactory::INTERPOLATE_FACE_VARYING;
    so.fvarChannel = 0;
    std::unique_ptr<const Far::StencilTable> ft(Far::StencilTableFactory::Create(*r, so));
    std::vector<Value<2>> t(m.uvs.size() / 2), tn(size_t(ft->GetNumStencils()));
    for (size_t i = 0; i < t.size(); ++i) t[i] = {{m.uvs[2 * i], m.uvs[2 * i + 1]}};
    ft->UpdateValues(t.data(), tn.data());
    n += tn.size();
  }
  return n;
}

size_t limn_full(const limn::Mesh& m, int level, limn::FVarInterpolation mode, bool uv) {
  limn::SubdivOptions o = limn::subdiv_options(m);
  o.face_varying = mode;
  const limn::FaceVaryingInput in{m.uv_indices, m.uvs.size() / 2};
  const limn::UniformRefinement r = limn::refine_uniform(m, level, o, {&in, uv ? 1u : 0u});
  const size_t n = r.positions(m, level).size() / 3;
  return n + (uv ? r.face_varying[0].values(m.uvs.data(), 2, level).size() / 2 : 0);
}

// Feature-adaptive builds with the UV channel: OpenSubdiv's RefineAdaptive + PatchTableFactory
// (Gregory-basis end caps, generateFVarTables) and the UVs of every adaptive level; linear UVs
// take its default legacy linear face-varying patches, smooth ones (mode "none") its non-linear
// face-varying patches and their local points. limn: build_patches and the patch points; linear
// UVs need nothing more (evaluate_linear_face_varying reads the cage's), smooth ones
// build_face_varying_patches and the channel's points.
size_t osd_adaptive(const limn::Mesh& m, int depth, bool uv, bool smooth) {
  const std::unique_ptr<Far::TopologyRefiner> r = limn::bench::osd_refiner(
      m, uv, smooth ? limn::FVarInterpolation::none : limn::FVarInterpolation::all);
  Far::PatchTableFactory::Options po(depth);
  po.SetEndCapType(Far::PatchTableFactory::Options::ENDCAP_GREGORY_BASIS);
  po.generateFVarTables = uv;
  po.generateFVarLegacyLinearPatches = !smooth;
  r->RefineAdaptive(po.GetRefineAdaptiveOptions());
  std::unique_ptr<Far::PatchTable> table(Far::PatchTableFactory::Create(*r, po));
  std::unique_ptr<const Far::StencilTable> st;
  {
    Far::StencilTableFactory::Options so2;
    so2.generateOffsets = true;
    so2.generateIntermediateLevels = true;
    st.reset(Far::StencilTableFactory::Create(*r, so2));
  }
  size_t n = table->GetNumPatchesTotal();
  if (uv) {
    const Far::StencilTable* local = table->GetLocalPointFaceVaryingStencilTable(0);
    const size_t refined = size_t(r->GetNumFVarValuesTotal(0));
    std::vector<Value<2>> t(refined + (local ? size_t(local->GetNumStencils()) : 0));
    for (size_t i = 0; i < m.uvs.size() / 2; ++i) t[i] = {{m.uvs[2 * i], m.uvs[2 * i + 1]}};
    const Far::PrimvarRefiner pr(*r);
    Value<2>* src = t.data();
    for (int k = 1; k <= r->GetMaxLevel(); ++k) {
      Value<2>* dst = src + r->GetLevel(k - 1).GetNumFVarValues(0);
      pr.InterpolateFaceVarying(k, src, dst, 0);
      src = dst;
    }
    if (local && local->GetNumStencils() > 0) local->UpdateValues(t.data(), t.data() + refined);
    n += t.size();
  }
  return n + size_t(st->GetNumStencils());
}

size_t limn_adaptive(const limn::Mesh& m, int depth, bool smooth) {
  limn::PatchOptions po;
  po.subdiv = limn::subdiv_options(m);
  po.subdiv.face_varying = smooth ? limn::FVarInterpolation::none : limn::FVarInterpolation::all;
  po.depth = depth;
  const limn::PatchTable t = limn::build_patches(m, po);
  size_t n = t.patch_count() + t.points(m.positions).size() / 3;
  if (smooth) {
    const limn::FaceVaryingInput in{m.uv_indices, m.uvs.size() / 2};
    const limn::FaceVaryingPatches f = limn::build_face_varying_patches(m, t, in, po);
    n += f.table.patch_count() + f.points(m.uvs.data(), 2).size() / 3;
  }
  return n;
}

// `m` carries only what is measured: UVs or nothing (the lean path carries whatever it has).
size_t limn_lean(const limn::Mesh& m, int level, limn::FVarInterpolation mode) {
  limn::SubdivOptions o = limn::subdiv_options(m);
  o.face_varying = mode;
  const limn::Mesh out = limn::subdivide_uniform(m, level, o);
  return out.vertex_count() + out.uvs.size() / 2;
}

// Planar UVs over the terrain, cut by a seam down the middle: faces right of it see the
// middle column's vertices at UVs of their own.
void terrain_uvs(limn::Mesh& m) {
  const limn::Box b = limn::bounding_box(m);
  const float mid = 0.5f * (b.min[0] + b.max[0]);
  const size_t nv = m.vertex_count();
  std::vector<uint32_t> second(nv, UINT32_MAX);
  for (size_t v = 0; v < nv; ++v)
    m.uvs.insert(m.uvs.end(), {(m.positions[3 * v] - b.min[0]) / (b.max[0] - b.min[0]),
                               (m.positions[3 * v + 1] - b.min[1]) / (b.max[1] - b.min[1])});
  for (size_t f = 0; f < m.face_count(); ++f) {
    float cx = 0;
    for (uint32_t v : m.face(f)) cx += m.positions[3 * size_t(v)] / float(m.face_size(f));
    for (uint32_t v : m.face(f)) {
      const bool on_seam =
          std::fabs(m.positions[3 * size_t(v)] - mid) < 1e-4f * (b.max[0] - b.min[0]);
      uint32_t id = v;
      if (on_seam && cx > mid) {
        if (second[v] == UINT32_MAX) {
          second[v] = uint32_t(m.uvs.size() / 2);
          m.uvs.insert(m.uvs.end(), {m.uvs[2 * v] + 0.01f, m.uvs[2 * v + 1]});
        }
        id = second[v];
      }
      m.uv_indices.push_back(id);
    }
  }
}

// A case's mesh: the procedural terrain with its seamed UVs, or a shared model (false when the
// shared models are absent).
bool load(const std::string& name, limn::Mesh& m) {
  if (name == "terrain") {
    m = limn::make_shape("terrain");
    terrain_uvs(m);
    return true;
  }
  const std::filesystem::path path = std::filesystem::path(LIMN_SHARED_MODELS) / name;
  if (!std::filesystem::exists(path)) return false;
  m = limn::read_mesh(path);
  return true;
}

// Runs one case (small ones, taking milliseconds, as the best of five fresh processes) and
// prints its row; OpenSubdiv's row comes first and is kept in `osd` for the ratios.
void row(const std::string& label, int level, const char* uv, const std::string& who,
         const std::function<size_t()>& fn, double cap_gb, limn::bench::Outcome& osd) {
  limn::bench::Outcome o = limn::bench::run_isolated(fn, cap_gb);
  for (int rep = 1; rep < (o.ms < 500 ? 5 : 1); ++rep) {
    const limn::bench::Outcome again = limn::bench::run_isolated(fn, cap_gb);
    if (again.ok && again.ms < o.ms) o.ms = again.ms;
  }
  const bool peer = who.starts_with("osd");
  if (peer) osd = o;
  std::string note = o.why;
  if (o.ok && osd.ok && !peer)
    note = fmt::format("time {:.2f}x, memory {:.2f}x", osd.ms / o.ms, osd.peak_mb / o.peak_mb);
  fmt::print("{:<10} {:<5} {:<6} {:<12} {:>10} {:>9.1f} {:>9.0f}  {}\n", label, level, uv, who,
             o.points, o.ms, o.peak_mb, note);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  double cap_gb = 22;
  bool uniform = true;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--cap-gb" && i + 1 < argc) cap_gb = std::atof(argv[++i]);
    if (std::string(argv[i]) == "--adaptive-only") uniform = false;
  }
  std::vector<std::pair<std::string, int>> cases = {
      {"osd/catmark_car.obj", 3}, {"quads/bigguy.obj", 3}, {"terrain", 2}};
  fmt::print("{:<10} {:<5} {:<6} {:<12} {:>10} {:>9} {:>9}  {}\n", "model", "level", "uv", "who",
             "values", "ms", "peak MB", "OpenSubdiv/limn");
  for (const auto& [name, level] : cases) {
    if (!uniform) break;
    limn::Mesh m;
    if (!load(name, m)) continue;
    // Only positions, tags and the UVs go in (BigGuy's normals would be a second channel).
    m.normals.clear(), m.normal_indices.clear(), m.colors.clear();
    limn::Mesh plain = m;
    plain.uvs.clear(), plain.uv_indices.clear();
    const std::string label = std::filesystem::path(name).stem().string();
    for (const auto& [mode_name, mode, uv] :
         {std::tuple{"-", limn::FVarInterpolation::all, false},
          std::tuple{"all", limn::FVarInterpolation::all, true},
          std::tuple{"none", limn::FVarInterpolation::none, true}}) {
      limn::bench::Outcome osd;
      limn::bench::Outcome osd_table;
      for (const char* who : {"osd", "limn lean", "osd tables", "limn full"}) {
        const std::string w = who;
        const auto fn = [&, mode = mode, uv = uv]() -> size_t {
          if (w == "osd") return osd_run(m, level, mode, uv);
          if (w == "osd tables") return osd_tables(m, level, mode, uv);
          if (w == "limn full") return limn_full(m, level, mode, uv);
          return limn_lean(uv ? m : plain, level, mode);
        };
        // The lean path against PrimvarRefiner, the tables against Far's stencil tables.
        const bool tables = w == "osd tables" || w == "limn full";
        row(label, level, mode_name, who, fn, cap_gb, tables ? osd_table : osd);
      }
    }
  }
  // Adaptive: depth 3 (OpenSubdiv's default isolation is 2-4 for drawing).
  fmt::print("\n{:<10} {:<5} {:<6} {:<12} {:>10} {:>9} {:>9}  {}\n", "model", "depth", "uv", "who",
             "count", "ms", "peak MB", "OpenSubdiv/limn");
  for (const std::string name : {"osd/catmark_car.obj", "quads/bigguy.obj", "terrain"}) {
    limn::Mesh m;
    if (!load(name, m)) continue;
    m.normals.clear(), m.normal_indices.clear(), m.colors.clear();
    const std::string label = std::filesystem::path(name).stem().string();
    for (const auto& [uv, smooth] : {std::pair{false, false}, {true, false}, {true, true}}) {
      limn::bench::Outcome osd;
      for (const char* who : {"osd", "limn"}) {
        const std::string w = who;
        const auto fn = [&, uv = uv, smooth = smooth]() -> size_t {
          return w == "osd" ? osd_adaptive(m, 3, uv, smooth) : limn_adaptive(m, 3, smooth);
        };
        row(label, 3, !uv ? "-" : smooth ? "none" : "linear", who, fn, cap_gb, osd);
      }
    }
  }
  return 0;
}
