// The GPU side of the patch table: tessellation shaders evaluating limn's patches.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "core/timer.hpp"
#include "draw_ranges.hpp"
#include "gl_util.hpp"
#include "limn/mesh/morton.hpp"
#include "limn/mesh/topology.hpp"
#include "limn/render/draw.hpp"
#include "limn/subdiv/tessellate.hpp"
#include "material_shader.hpp"
#include "shaders.hpp"

namespace limn {

namespace {

// Per-patch data, std430: the cage line of each patch edge (a cage edge, or past the cage edges
// a cage face for edges inside one), level | boundary << 8 | transition << 12 | type << 16 |
// crease edge << 18 | depth << 20, the crease's sharpness, the ptex face and the patch's origin
// there (u | v << 16).
struct PatchInfo {
  uint32_t keys[4];
  uint32_t bits;
  float sharpness;
  uint32_t ptex, ptex_uv;
};
static_assert(sizeof(PatchInfo) == 32);

// The bits of PatchInfo (and UvPatch) that give a patch's shape: boundary, type, crease edge.
uint32_t shape_bits(const PatchParam& p) {
  return uint32_t(p.boundary & 0xF) << 8 | uint32_t(p.type) << 16 |
         uint32_t(p.crease_edge & 3) << 18;
}

std::string with_header(int cvs, const char* a, const char* b = "", const char* c = "",
                        const char* d = "") {
  return fmt::format("#version 450 core\n#define CVS {}\n{}{}{}{}", cvs, a, b, c, d);
}

// What line_rates keeps between draws: per cage face a ball holding every point its patches are
// made from (the vertices of the faces around its corners, each within half that face's
// perimeter of the corner; subdivision only averages them), view-independent; blocks of faces
// near each other with a ball holding theirs, so a view tests blocks before faces; and what the
// last view set, so the next one clears only that and uploads only the range that changed.
struct RateScratch {
  std::vector<float> ball;          // per cage face: centre x, y, z, radius
  std::vector<uint32_t> order;      // the faces by block (Morton order of their centres)
  std::vector<float> block_ball;    // per block of kBlock faces in `order`: centre, radius
  std::vector<uint8_t> face_seen;   // per cage face: may be in view
  std::vector<uint32_t> seen_list;  // the faces that may be in view
  std::vector<uint32_t> edge_stamp, vertex_stamp;  // == stamp: rated / projected this view
  std::vector<double> vertex_xy;                   // projected vertices (x, y; NaN: behind)
  std::vector<uint32_t> set;  // entries of the rates the last view made nonzero
  uint32_t stamp = 0;
  size_t dirty_lo = 0, dirty_hi = 0;  // the rates' entries changed by the last call
};
constexpr size_t kBlock = 64;

void face_balls(const Mesh& cage, RateScratch& scratch) {
  const size_t nf = cage.face_count();
  auto pos = [&](uint32_t v) { return &cage.positions[3 * size_t(v)]; };
  auto dist = [](const float* a, const float* b) {
    return std::sqrt(double(a[0] - b[0]) * (a[0] - b[0]) + double(a[1] - b[1]) * (a[1] - b[1]) +
                     double(a[2] - b[2]) * (a[2] - b[2]));
  };
  std::vector<float> reach(cage.vertex_count(), 0.0f);
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t b = cage.face_offsets[f], n = cage.face_size(f);
    double half = 0;
    for (uint32_t c = 0; c < n; ++c)
      half += dist(pos(cage.face_vertices[b + c]), pos(cage.face_vertices[b + (c + 1) % n]));
    half *= 0.5;
    for (uint32_t c = 0; c < n; ++c) {
      float& r = reach[cage.face_vertices[b + c]];
      r = std::max(r, float(half));
    }
  }
  scratch.ball.assign(4 * nf, 0.0f);
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t b = cage.face_offsets[f], n = cage.face_size(f);
    float* centre = &scratch.ball[4 * f];
    for (uint32_t c = 0; c < n; ++c)
      for (int k = 0; k < 3; ++k) centre[k] += pos(cage.face_vertices[b + c])[k] / float(n);
    double radius = 0;
    for (uint32_t c = 0; c < n; ++c) {
      const uint32_t v = cage.face_vertices[b + c];
      radius = std::max(radius, dist(centre, pos(v)) + double(reach[v]));
    }
    centre[3] = float(1.01 * radius + 1e-6);
  }
  // Blocks: the faces in the Morton order of their centres (10 bits per axis over the cage's
  // box), kBlock at a time, each block's ball holding its faces' balls.
  const Box box = bounding_box(cage);
  std::vector<std::pair<uint32_t, uint32_t>> code(nf);
  for (size_t f = 0; f < nf; ++f) {
    uint32_t q[3];
    for (int k = 0; k < 3; ++k) {
      const float ext = box.max[k] - box.min[k];
      const float t = ext > 0 ? (scratch.ball[4 * f + size_t(k)] - box.min[k]) / ext : 0.0f;
      q[k] = uint32_t(std::clamp(t, 0.0f, 1.0f) * 1023.0f);
    }
    code[f] = {uint32_t(morton3(q[0], q[1], q[2])), uint32_t(f)};
  }
  std::sort(code.begin(), code.end());
  scratch.order.resize(nf);
  for (size_t i = 0; i < nf; ++i) scratch.order[i] = code[i].second;
  const size_t nb = (nf + kBlock - 1) / kBlock;
  scratch.block_ball.assign(4 * nb, 0.0f);
  for (size_t b = 0; b < nb; ++b) {
    const size_t first = b * kBlock, last = std::min(nf, first + kBlock);
    double c[3] = {0, 0, 0};
    for (size_t i = first; i < last; ++i)
      for (int k = 0; k < 3; ++k) c[k] += scratch.ball[4 * size_t(scratch.order[i]) + size_t(k)];
    for (double& x : c) x /= double(last - first);
    double r = 0;
    for (size_t i = first; i < last; ++i) {
      const float* fb = &scratch.ball[4 * size_t(scratch.order[i])];
      r = std::max(r, std::sqrt((fb[0] - c[0]) * (fb[0] - c[0]) + (fb[1] - c[1]) * (fb[1] - c[1]) +
                                (fb[2] - c[2]) * (fb[2] - c[2])) +
                          double(fb[3]));
    }
    float* bb = &scratch.block_ball[4 * b];
    for (int k = 0; k < 3; ++k) bb[k] = float(c[k]);
    bb[3] = float(1.001 * r + 1e-6);
  }
  scratch.face_seen.assign(nf, 0);
  scratch.seen_list.clear();
  scratch.edge_stamp.clear(), scratch.vertex_stamp.clear();
}

// The level-0 rate of every cage line for this view: segments per cage edge (its projected
// length over `pixels_per_segment`), then per cage face the largest of its edges'. Lines that
// only border faces wholly out of view (their balls outside the view) get 1 segment: every patch
// of a face that may be seen keeps its rates, and rates stay per line, so shared edges still
// agree. The work follows what is in view (blocks of faces out of view are one test), not the
// cage: `out` keeps its zeros between views, and scratch.dirty_lo / dirty_hi say which entries
// this call changed.
void line_rates(const Mesh& cage, const Topology& topo, const Camera& camera, float pps,
                std::vector<float>& out, RateScratch& scratch) {
  const size_t ne = topo.edge_count(), nf = cage.face_count(), nv = cage.vertex_count();
  if (scratch.ball.size() != 4 * nf) face_balls(cage, scratch);
  size_t lo = SIZE_MAX, hi = 0;
  if (out.size() != ne + nf) {
    out.assign(ne + nf, 0.0f);
    scratch.set.clear();
    lo = 0, hi = ne + nf;
  }
  auto changed = [&](size_t i) { lo = std::min(lo, i), hi = std::max(hi, i + 1); };
  for (const uint32_t i : scratch.set) out[i] = 0.0f, changed(i);
  scratch.set.clear();
  for (const uint32_t f : scratch.seen_list) scratch.face_seen[f] = 0;
  scratch.seen_list.clear();
  if (scratch.edge_stamp.size() != ne) scratch.edge_stamp.assign(ne, 0);
  if (scratch.vertex_stamp.size() != nv)
    scratch.vertex_stamp.assign(nv, 0), scratch.vertex_xy.assign(2 * nv, 0.0);
  if (++scratch.stamp == 0) {  // wrapped: no entry may look current
    std::fill(scratch.edge_stamp.begin(), scratch.edge_stamp.end(), 0u);
    std::fill(scratch.vertex_stamp.begin(), scratch.vertex_stamp.end(), 0u);
    scratch.stamp = 1;
  }
  const uint32_t stamp = scratch.stamp;
  const CameraView view(camera);
  // The faces that may be in view, block by block.
  const size_t nb = scratch.block_ball.size() / 4;
  for (size_t b = 0; b < nb; ++b) {
    const float* bb = &scratch.block_ball[4 * b];
    if (view.ball_outside(bb, bb[3])) continue;
    for (size_t i = b * kBlock, last = std::min(nf, i + kBlock); i < last; ++i) {
      const uint32_t f = scratch.order[i];
      const float* ball = &scratch.ball[4 * size_t(f)];
      if (view.ball_outside(ball, ball[3])) continue;
      scratch.face_seen[f] = 1;
      scratch.seen_list.push_back(f);
    }
  }
  auto project = [&](uint32_t v) {
    double* xy = &scratch.vertex_xy[2 * size_t(v)];
    if (scratch.vertex_stamp[v] != stamp) {
      scratch.vertex_stamp[v] = stamp;
      if (!view.project(&cage.positions[3 * size_t(v)], xy[0], xy[1])) xy[0] = xy[1] = NAN;
    }
    return xy;
  };
  for (const uint32_t f : scratch.seen_list) {
    float m = 0;
    for (uint32_t c = cage.face_offsets[f]; c < cage.face_offsets[f + 1]; ++c) {
      const uint32_t e = topo.corner_edge[c];
      if (scratch.edge_stamp[e] != stamp) {
        scratch.edge_stamp[e] = stamp;
        const double* a = project(topo.edge_vertices[2 * size_t(e)]);
        const double* b = project(topo.edge_vertices[2 * size_t(e) + 1]);
        // Reaching behind the eye: as fine as it goes.
        out[e] = std::isnan(a[0]) || std::isnan(b[0])
                     ? 1e6f
                     : float(std::hypot(a[0] - b[0], a[1] - b[1]) / double(pps));
        scratch.set.push_back(e), changed(e);
      }
      m = std::max(m, out[e]);
    }
    out[ne + f] = m;
    scratch.set.push_back(uint32_t(ne + f)), changed(ne + f);
  }
  scratch.dirty_lo = lo == SIZE_MAX ? 0 : lo, scratch.dirty_hi = lo == SIZE_MAX ? 0 : hi;
}

}  // namespace

// Patches of faces out of view that draw() draws rather than split a run of patches in view.
constexpr size_t kCullGap = 8;

struct PatchDrawer::Impl {
  const Mesh* cage = nullptr;
  Topology topo;
  size_t regular = 0, gregory = 0, point_floats = 0;
  uint32_t max_index = 0;
  // The drawing programs (regular, end caps) of each combination of options, compiled at its
  // first use: bit 0 an octree texture, bit 1 outlines, bit 2 depth colours, bit 3 UVs, bit 4 a
  // material.
  std::array<std::array<gl::Program, 2>, 32> programs;
  std::string vs16, vs20, tc16, tc20, te16, te20;
  gl::Buffer ptex_uvs;    // 4 UVs per ptex face when the cage has linear UVs
  gl::Buffer uv_patches;  // smooth UVs: per patch its face-varying patch (UvPatch)
  size_t uv_patches_cap = 0;
  bool has_uvs = false, smooth_uvs = false;
  gl::Program regular_capture, gregory_capture;  // transform feedback, no rasterisation
  gl::Buffer points, regular_cvs, gregory_cvs, infos, lines;
  size_t points_cap = 0, lines_cap = 0, regular_cap = 0, gregory_cap = 0, infos_cap = 0;
  gl::VertexArray vao;
  gl::DrawQueries queries;
  gl::Framebuffer capture_fbo;
  gl::Renderbuffer capture_rb;
  std::vector<float> rates;
  RateScratch rate_scratch;
  std::vector<uint32_t> patch_face;  // cage face of each patch (regular, then end caps)
  std::vector<DrawRange> ranges;     // this pass's draw calls
  Box bounds;
  // Patches per draw call. llvmpipe (Mesa 22.3) mixes up the tessellation of patches whose
  // levels differ once a draw holds more than about 60 patches (every patch still evaluated, but
  // with another patch's data): draws of 32 patches stay clear of it; real GPUs draw all at once.
  size_t chunk = SIZE_MAX;

  const std::array<gl::Program, 2>& programs_for(const DrawOptions& o);
  // The face-varying patches of smooth UVs under the patches of `table`, uploaded.
  void upload_uv_patches(const PatchTable& table);
  // The rates of this view, uploaded where they changed.
  void update_rates(const Camera& camera, float pixels_per_segment) {
    line_rates(*cage, topo, camera, pixels_per_segment, rates, rate_scratch);
    const size_t bytes = rates.size() * sizeof(float);
    if (!lines.get() || bytes > lines_cap) {
      gl::upload(lines, lines_cap, rates.data(), bytes);
    } else if (rate_scratch.dirty_hi > rate_scratch.dirty_lo) {
      const size_t lo = rate_scratch.dirty_lo, n = rate_scratch.dirty_hi - lo;
      glNamedBufferSubData(lines.get(), GLintptr(lo * sizeof(float)), GLsizeiptr(n * sizeof(float)),
                           rates.data() + lo);
    }
  }
};

const std::array<gl::Program, 2>& PatchDrawer::Impl::programs_for(const DrawOptions& o) {
  const bool uvs = o.uv_checker > 0 && has_uvs;
  const int flags = (o.texture ? 1 : 0) | (o.outline ? 2 : 0) | (o.depth_colors ? 4 : 0) |
                    (uvs ? 8 : 0) | (o.material ? 16 : 0);
  std::array<gl::Program, 2>& p = programs[size_t(flags)];
  if (p[0].get()) return p;
  const std::string defines =
      fmt::format("{}{}{}{}", o.outline ? "#define OUTLINE\n" : "",
                  o.depth_colors ? "#define DEPTH_COLORS\n" : "", uvs ? "#define UVS\n" : "",
                  o.material ? "#define MATERIAL\n" : "");
  const std::string fs = with_header(16, defines.c_str(), shaders::patch_info, shaders::shade,
                                     o.texture ? shaders::octree : shaders::no_octree) +
                         (o.material ? detail::material_glsl() : std::string()) +
                         shaders::patch_frag;
  // With UVs the evaluation stages compute them too (a define ahead of patch_eval).
  const char* uv_define = smooth_uvs ? "#define SMOOTH_UVS\n" : "#define UVS\n";
  const std::string te_regular = uvs ? with_header(16, uv_define, shaders::patch_info,
                                                   shaders::patch_eval, shaders::patch_regular_tese)
                                     : te16;
  const std::string te_gregory = uvs ? with_header(20, uv_define, shaders::patch_info,
                                                   shaders::patch_eval, shaders::patch_gregory_tese)
                                     : te20;
  p[0] = gl::program("regular patches", {{GL_VERTEX_SHADER, vs16},
                                         {GL_TESS_CONTROL_SHADER, tc16},
                                         {GL_TESS_EVALUATION_SHADER, te_regular},
                                         {GL_FRAGMENT_SHADER, fs}});
  p[1] = gl::program("end caps", {{GL_VERTEX_SHADER, vs20},
                                  {GL_TESS_CONTROL_SHADER, tc20},
                                  {GL_TESS_EVALUATION_SHADER, te_gregory},
                                  {GL_FRAGMENT_SHADER, fs}});
  return p;
}

PatchDrawer::PatchDrawer(const Mesh& cage, const PatchTable& table, std::span<const float> points)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.cage = &cage;
  m.topo = build_topology(cage);
  // Linear UVs (the default mode) need only each ptex face's corners; smooth ones their
  // face-varying patches, made with the patches (upload_patches).
  m.has_uvs = !cage.uv_indices.empty();
  m.smooth_uvs = m.has_uvs && table.options.face_varying != FVarInterpolation::all;
  upload_patches(table);
  if (m.has_uvs && !m.smooth_uvs) {
    const FaceVaryingInput in{cage.uv_indices, cage.uvs.size() / 2};
    const std::vector<float> uv = ptex_corner_values(cage, in, cage.uvs.data(), 2);
    m.ptex_uvs = gl::buffer(uv.data(), uv.size() * sizeof(float));
  }
  m.vs16 = with_header(16, shaders::patch_vert), m.vs20 = with_header(20, shaders::patch_vert);
  m.tc16 = with_header(16, shaders::patch_info, shaders::patch_tesc),
  m.tc20 = with_header(20, shaders::patch_info, shaders::patch_tesc);
  m.te16 = with_header(16, shaders::patch_info, shaders::patch_eval, shaders::patch_regular_tese);
  m.te20 = with_header(20, shaders::patch_info, shaders::patch_eval, shaders::patch_gregory_tese);
  m.programs_for(DrawOptions{});  // the default programs, so that shader errors show here
  // The tessellation stages alone, their position, (s, t) and patch captured by transform
  // feedback (interleaved: 3 + 2 floats, then the patch as a float-bit uint).
  const auto varyings = {"t_pos", "t_uv", "t_patch"};
  m.regular_capture = gl::program("regular patches (capture)",
                                  {{GL_VERTEX_SHADER, m.vs16},
                                   {GL_TESS_CONTROL_SHADER, m.tc16},
                                   {GL_TESS_EVALUATION_SHADER, m.te16}},
                                  varyings);
  m.gregory_capture = gl::program("end caps (capture)",
                                  {{GL_VERTEX_SHADER, m.vs20},
                                   {GL_TESS_CONTROL_SHADER, m.tc20},
                                   {GL_TESS_EVALUATION_SHADER, m.te20}},
                                  varyings);
  GLuint n = 0;
  glCreateVertexArrays(1, &n);
  m.vao = gl::VertexArray(n);
  if (std::string(reinterpret_cast<const char*>(glGetString(GL_RENDERER))).find("llvmpipe") !=
      std::string::npos)
    m.chunk = 32;
  set_points(points);
  gl::check("PatchDrawer");
}

PatchDrawer::~PatchDrawer() = default;

namespace {

// patch_eval.glsl's UvPatch (std430: 20 vec2, then 8 bytes).
struct UvPatch {
  float cv[40];
  uint32_t bits;
  float sharpness;
};
static_assert(sizeof(UvPatch) == 168);

}  // namespace

// The face-varying patch under each patch (regular, then end caps), found by its place: both
// tables cover the same squares of the same ptex faces.
void PatchDrawer::Impl::upload_uv_patches(const PatchTable& table) {
  const Mesh& c = *cage;
  const FaceVaryingInput in{c.uv_indices, c.uvs.size() / 2};
  PatchOptions po;
  po.subdiv = table.options;
  const FaceVaryingPatches fv = build_face_varying_patches(c, table, in, po);
  const std::vector<float> uv = fv.points(c.uvs.data(), 2);
  // Each vertex patch's face-varying patch is the one at the same place (the two tables list
  // their patches in different orders): matched through the face-varying places, sorted.
  using Place = std::tuple<uint32_t, uint8_t, uint16_t, uint16_t>;
  auto place = [](const PatchParam& p) { return Place(p.ptex, p.depth, p.u, p.v); };
  const size_t nr = fv.table.regular_params.size();
  auto param = [&](size_t i) -> const PatchParam& {
    return i < nr ? fv.table.regular_params[i] : fv.table.gregory_params[i - nr];
  };
  std::vector<std::pair<Place, uint32_t>> places(fv.table.patch_count());
  for (size_t i = 0; i < places.size(); ++i) places[i] = {place(param(i)), uint32_t(i)};
  std::sort(places.begin(), places.end());
  std::vector<UvPatch> out;
  out.reserve(table.patch_count());
  for (const auto* params : {&table.regular_params, &table.gregory_params})
    for (const PatchParam& p : *params) {
      const auto it = std::lower_bound(places.begin(), places.end(), std::pair(place(p), 0u));
      if (it == places.end() || it->first != place(p))
        throw std::logic_error("render: a patch without its face-varying patch");
      const size_t i = it->second;
      const bool cap = i >= nr;
      const uint32_t* pts =
          cap ? &fv.table.gregory_points[20 * (i - nr)] : &fv.table.regular_points[16 * i];
      UvPatch& u = out.emplace_back();
      for (int j = 0; j < (cap ? 20 : 16); ++j)
        u.cv[2 * j] = uv[3 * size_t(pts[j])], u.cv[2 * j + 1] = uv[3 * size_t(pts[j]) + 1];
      u.bits = shape_bits(param(i));
      u.sharpness = param(i).sharpness;
    }
  gl::upload(uv_patches, uv_patches_cap, out.data(), out.size() * sizeof(UvPatch));
}

void PatchDrawer::upload_patches(const PatchTable& table) {
  Impl& m = *impl_;
  const Mesh& cage = *m.cage;
  if (table.ptex_of_face.size() != cage.face_count() + 1)
    throw InputError("render: the patch table was built from another cage");
  m.regular = table.regular_params.size();
  m.gregory = table.gregory_params.size();
  std::vector<PatchInfo> infos;
  infos.reserve(m.regular + m.gregory);
  m.patch_face.clear();
  m.patch_face.reserve(m.regular + m.gregory);
  const uint32_t ne = uint32_t(m.topo.edge_count());
  for (const auto* params : {&table.regular_params, &table.gregory_params})
    for (const PatchParam& pp : *params) {
      m.patch_face.push_back(pp.base_face);
      PatchInfo in{};
      const uint32_t f = pp.base_face, b = cage.face_offsets[f], n = cage.face_size(f);
      const uint32_t last = (1u << pp.depth) - 1;
      for (int e = 0; e < 4; ++e) in.keys[e] = ne + f;  // inside the cage face
      auto edge_of = [&](uint32_t corner) { return m.topo.corner_edge[b + corner % n]; };
      if (n == 4) {
        if (pp.v == 0) in.keys[0] = edge_of(0);
        if (pp.u == last) in.keys[1] = edge_of(1);
        if (pp.v == last) in.keys[2] = edge_of(2);
        if (pp.u == 0) in.keys[3] = edge_of(3);
      } else {  // corner c's quad: edge 0 on cage edge (c, c+1), edge 3 on (c-1, c)
        if (pp.v == 0) in.keys[0] = edge_of(pp.corner);
        if (pp.u == 0) in.keys[3] = edge_of(pp.corner + n - 1);
      }
      in.bits = uint32_t(pp.level) | uint32_t(pp.transition & 0xF) << 12 | shape_bits(pp) |
                uint32_t(pp.depth & 31) << 20;
      in.sharpness = pp.sharpness;
      in.ptex = pp.ptex;
      in.ptex_uv = uint32_t(pp.u) | uint32_t(pp.v) << 16;
      infos.push_back(in);
    }
  m.max_index = 0;
  for (const uint32_t p : table.regular_points) m.max_index = std::max(m.max_index, p);
  for (const uint32_t p : table.gregory_points) m.max_index = std::max(m.max_index, p);
  gl::upload(m.regular_cvs, m.regular_cap, table.regular_points.data(),
             table.regular_points.size() * 4);
  gl::upload(m.gregory_cvs, m.gregory_cap, table.gregory_points.data(),
             table.gregory_points.size() * 4);
  gl::upload(m.infos, m.infos_cap, infos.data(), infos.size() * sizeof(PatchInfo));
  if (m.smooth_uvs) m.upload_uv_patches(table);
}

void PatchDrawer::set_patches(const PatchTable& table) {
  Impl& m = *impl_;
  // Checked before anything is replaced, so a refused table leaves the drawer as it was.
  uint32_t top = 0;
  for (const auto* pts : {&table.regular_points, &table.gregory_points})
    for (const uint32_t p : *pts) top = std::max(top, p);
  if (table.patch_count() && m.point_floats / 3 <= top)
    throw InputError(fmt::format("render: {} point coordinates for patches reading point {}",
                                 m.point_floats, top));
  upload_patches(table);
  gl::check("PatchDrawer::set_patches");
}

void PatchDrawer::set_points(std::span<const float> points) {
  Impl& m = *impl_;
  if (points.size() % 3 || (m.regular + m.gregory && points.size() / 3 <= m.max_index))
    throw InputError(fmt::format("render: {} point coordinates for patches reading point {}",
                                 points.size(), m.max_index));
  gl::upload(m.points, m.points_cap, points.data(), points.size() * sizeof(float));
  m.point_floats = points.size();
  face_balls(*m.cage, m.rate_scratch);  // the cage may have moved with its points
  m.bounds = Box{};                     // near and far planes come from the points' bounds
  for (size_t i = 0; i + 2 < points.size(); i += 3)
    for (int k = 0; k < 3; ++k)
      m.bounds.min[k] = std::min(m.bounds.min[k], points[i + size_t(k)]),
      m.bounds.max[k] = std::max(m.bounds.max[k], points[i + size_t(k)]);
}

DrawStats PatchDrawer::draw(const Camera& camera, const DrawOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  DrawStats st;
  st.patches = m.regular + m.gregory;
  if (o.factor < 0 || o.factor > 32)
    throw InputError(fmt::format("render: tessellation factor {} out of range (1-32)", o.factor));
  if (!(o.pixels_per_segment > 0)) throw InputError("render: pixels per segment must be positive");
  m.update_rates(camera, o.pixels_per_segment);
  const std::array<float, 16> vp = gl::view_projection(camera, m.bounds);
  float ramp[17 * 3];
  for (int k = 0; k < 17; ++k) depth_color(k, ramp + 3 * k);

  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glBindVertexArray(m.vao.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, m.points.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, m.infos.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, m.lines.get());
  const std::array<gl::Program, 2>& programs = m.programs_for(o);
  m.queries.begin();
  for (int pass = 0; pass < 2; ++pass) {
    const size_t count = pass ? m.gregory : m.regular;
    if (!count) continue;
    const GLuint prog = programs[size_t(pass)].get();
    const int cvs = pass ? 20 : 16;
    glUseProgram(prog);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, (pass ? m.gregory_cvs : m.regular_cvs).get());
    glUniform1ui(glGetUniformLocation(prog, "patch_base"), pass ? GLuint(m.regular) : 0u);
    glUniform1i(glGetUniformLocation(prog, "factor"), o.factor);
    glUniformMatrix4fv(glGetUniformLocation(prog, "view_proj"), 1, GL_FALSE, vp.data());
    glUniform3fv(glGetUniformLocation(prog, "eye"), 1, camera.eye);
    glUniform3fv(glGetUniformLocation(prog, "base"), 1, o.color);
    glUniform3fv(glGetUniformLocation(prog, "ramp"), 17, ramp);
    if (m.has_uvs && o.uv_checker > 0) {
      if (m.smooth_uvs)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, m.uv_patches.get());
      else
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, m.ptex_uvs.get());
      glUniform1f(glGetUniformLocation(prog, "uv_checker"), o.uv_checker);
    }
    if (o.texture) o.texture->bind(prog, o.texture_nearest ? 1 : 2);
    if (o.material) {
      o.material->bind(prog, 2, "rmh_", detail::kRmhBinding);
      glUniform1f(glGetUniformLocation(prog, "height_scale"), o.height_scale);
    }
    glPatchParameteri(GL_PATCH_VERTICES, cvs);
    // Patches whose faces are all out of view are left out.
    const std::span<const uint32_t> faces(m.patch_face.data() + (pass ? m.regular : 0), count);
    patch_draw_ranges(faces, m.rate_scratch.face_seen, kCullGap, m.chunk, m.ranges);
    for (const DrawRange& r : m.ranges)
      glDrawArrays(GL_PATCHES, GLint(r.first * size_t(cvs)), GLsizei(r.count * size_t(cvs)));
  }
  const auto [ns, prims] = m.queries.end();
  glBindVertexArray(0);
  glUseProgram(0);
  gl::check("PatchDrawer::draw");
  st.gpu_ms = double(ns) * 1e-6;
  st.triangles = prims;
  st.cpu_ms = ms_since(t0);
  return st;
}

PatchDrawer::Capture PatchDrawer::capture(const Camera& camera, const DrawOptions& o) {
  Impl& m = *impl_;
  m.update_rates(camera, o.pixels_per_segment);
  const std::array<float, 16> vp = gl::view_projection(camera, m.bounds);
  Capture out;
  // Nothing is drawn, but a draw needs a complete framebuffer (a surfaceless context has none).
  if (!m.capture_fbo.get()) {
    GLuint f = 0, rb = 0;
    glCreateFramebuffers(1, &f);
    glCreateRenderbuffers(1, &rb);
    m.capture_fbo = gl::Framebuffer(f), m.capture_rb = gl::Renderbuffer(rb);
    glNamedRenderbufferStorage(rb, GL_RGBA8, 1, 1);
    glNamedFramebufferRenderbuffer(f, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb);
  }
  GLint previous = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, m.capture_fbo.get());
  glEnable(GL_RASTERIZER_DISCARD);
  glBindVertexArray(m.vao.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, m.points.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, m.infos.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, m.lines.get());
  for (int pass = 0; pass < 2; ++pass) {
    const size_t count = pass ? m.gregory : m.regular;
    if (!count) continue;
    const int cvs = pass ? 20 : 16;
    const GLuint prog = (pass ? m.gregory_capture : m.regular_capture).get();
    glUseProgram(prog);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, (pass ? m.gregory_cvs : m.regular_cvs).get());
    glUniform1ui(glGetUniformLocation(prog, "patch_base"), pass ? GLuint(m.regular) : 0u);
    glUniform1i(glGetUniformLocation(prog, "factor"), o.factor);
    glUniformMatrix4fv(glGetUniformLocation(prog, "view_proj"), 1, GL_FALSE, vp.data());
    glPatchParameteri(GL_PATCH_VERTICES, cvs);
    // Room for the largest tessellation of a patch: inner levels up to 2 x the rate (an edge
    // bordering finer patches), 2 triangles of 3 points per inner cell.
    const size_t rate = o.factor > 0 ? 2 * size_t(o.factor) : 64;
    const size_t per_patch = 2 * (rate + 1) * (rate + 1) * 3, floats = 6;
    const size_t batch_max =
        std::min(m.chunk, std::max<size_t>(1, (size_t(64) << 20) / (per_patch * floats * 4)));
    gl::Buffer tf;
    size_t tf_bytes = 0;
    GLuint qn = 0;
    glCreateQueries(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, 1, &qn);
    const gl::Query q(qn);
    std::vector<float> data;
    for (size_t first = 0; first < count;) {
      const size_t batch = std::min(count - first, batch_max);
      const size_t bytes = batch * per_patch * floats * 4;
      if (bytes > tf_bytes) tf = gl::buffer(nullptr, bytes, true), tf_bytes = bytes;
      glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, tf.get());
      glBeginQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, qn);
      glBeginTransformFeedback(GL_TRIANGLES);
      glDrawArrays(GL_PATCHES, GLint(first * size_t(cvs)), GLsizei(batch * size_t(cvs)));
      glEndTransformFeedback();
      glEndQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN);
      GLuint64 prims = 0;
      glGetQueryObjectui64v(qn, GL_QUERY_RESULT, &prims);
      data.resize(size_t(prims) * 3 * floats);
      glGetNamedBufferSubData(tf.get(), 0, GLsizeiptr(data.size() * 4), data.data());
      for (size_t i = 0; i < data.size(); i += floats) {
        uint32_t patch;
        std::memcpy(&patch, &data[i + 5], 4);
        out.coords.push_back({patch, data[i + 3], data[i + 4]});
        out.positions.insert(out.positions.end(), &data[i], &data[i] + 3);
      }
      first += batch;
    }
  }
  glDisable(GL_RASTERIZER_DISCARD);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, GLuint(previous));
  glBindVertexArray(0);
  glUseProgram(0);
  gl::check("PatchDrawer::capture");
  return out;
}

}  // namespace limn
