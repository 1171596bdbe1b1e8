// Region builds: a large cage's patch table built in batches of faces, each isolated with the rings
// around it, and joined (the same table as one build, less memory at its peak).
#include "patch_builder.hpp"

namespace limn {

using namespace patch_detail;

namespace {

// Region builds (cages of many faces): the cage is cut into regions of about `batch` faces,
// grown breadth-first so they stay compact, and each region is isolated on its own sub-cage:
// the region's faces (role 2: their patches are emitted), two rings of faces around them (role
// 1: refined where they want to be, since the region's patches need their transition bits and
// the rings those refinements make) and one more ring (role 0: context, never refined for its
// own sake, so that every vertex of a role-1 face has its whole ring and is classified as in the
// whole cage). Everything a region's patches use depends only on the faces within one ring of
// it (the support of a face's limit surface), so the patches and their points equal the whole
// cage's; the working memory is a region's instead of a whole level's. Each region's pruned
// table is appended level by level with its ids shifted; the points of a patch are rebased onto
// the final level offsets once every region is in. Points used by patches of two regions are
// computed by both (a thin seam).
constexpr uint32_t kDefaultBatch = 16384;
constexpr int kTrustedRings = 2, kContextRings = 1;

// One region on its way through the pipeline: cut, isolated, merged.
struct Region {
  uint32_t index = 0;
  size_t region_faces = 0;         // faces[0, region_faces) are the region's own (role 2)
  std::vector<uint32_t> faces;     // cage faces of the sub-cage, the region's first
  std::vector<uint32_t> vertices;  // cage vertex of each sub-cage vertex
  std::vector<uint8_t> roles, depth;
  std::vector<uint8_t> sharp_corners;  // replayed builds: per sub-cage vertex
  std::vector<uint32_t> ptex;          // replayed builds: the cage's first ptex face of each face
  Mesh mesh;                           // the sub-cage (dropped once isolated)
  PatchTable table;
  PatchStats stats;
};

class RegionBuilder {
 public:
  RegionBuilder(const Mesh& cage, const PatchOptions& o, std::span<const uint8_t> depth,
                const Replay* replay = nullptr)
      : cage_(cage), o_(o), depth_(depth), replay_(replay) {
    const size_t nf = cage.face_count(), nv = cage.vertex_count();
    vertex_faces(cage, vertex_face_offsets_, vertex_faces_);  // all the regions need of it
    // Crease tags by edge; each must be an edge of some face, as in the whole-cage build.
    for (size_t i = 0; i < cage.crease_sharpness.size(); ++i) {
      const uint32_t a = cage.crease_edges[2 * i], b = cage.crease_edges[2 * i + 1];
      Crease& c = creases_[edge_key(a, b)];
      c.sharpness = std::min(cage.crease_sharpness[i], kInf);  // a later tag wins
    }
    if (!creases_.empty()) {
      for (uint32_t f = 0; f < nf; ++f) {
        const std::span<const uint32_t> vs = cage.face(f);
        for (size_t j = 0; j < vs.size(); ++j)
          if (const auto it = creases_.find(edge_key(vs[j], vs[(j + 1) % vs.size()]));
              it != creases_.end())
            it->second.on_face = true;
      }
      for (size_t i = 0; i < cage.crease_sharpness.size(); ++i) {
        const uint32_t a = cage.crease_edges[2 * i], b = cage.crease_edges[2 * i + 1];
        if (!creases_[edge_key(a, b)].on_face)
          throw InputError(
              fmt::format("crease tag {} names vertices {} and {}, which share no edge", i, a, b));
      }
    }
    if (!cage.corner_vertices.empty()) corner_sharpness_.assign(nv, 0.0f);
    for (size_t i = 0; i < cage.corner_vertices.size(); ++i)  // a later tag wins
      corner_sharpness_[cage.corner_vertices[i]] = std::min(cage.corner_sharpness[i], kInf);
    face_state_.assign(nf, 0);
    for (const uint32_t f : cage.hole_faces) face_state_[f] |= kHole;
    vertex_local_.assign(nv, kNone);
    out_.options = o.subdiv;
    out_.ptex_of_face = ptex_offsets(cage);
    out_.ptex_count = out_.ptex_of_face.back();
  }

  PatchTable run(uint32_t batch, PatchStats* stats) {
    const size_t nf = cage_.face_count();
    size_t seed = 0, emitted = 0;
    uint32_t next = 0;
    // Regions are cut and merged in order (so the table does not depend on the thread count) and
    // isolated in parallel, a few in flight at a time (their memory stays bounded).
    const size_t tokens = 2 * size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    tbb::parallel_pipeline(
        tokens,
        // Shared pointers, so regions in flight are freed when a stage throws.
        tbb::make_filter<void, std::shared_ptr<Region>>(
            tbb::filter_mode::serial_in_order,
            [&](tbb::flow_control& fc) -> std::shared_ptr<Region> {
              while (seed < nf && (face_state_[seed] & kDone)) ++seed;
              if (seed == nf) {
                fc.stop();
                return nullptr;
              }
              auto r = std::make_shared<Region>();
              r->index = next++;
              grow(uint32_t(seed), batch, *r);
              extract(*r);
              return r;
            }) &
            tbb::make_filter<std::shared_ptr<Region>, std::shared_ptr<Region>>(
                tbb::filter_mode::parallel,
                [&](std::shared_ptr<Region> r) {
                  isolate_region(*r);
                  return r;
                }) &
            tbb::make_filter<std::shared_ptr<Region>, void>(
                tbb::filter_mode::serial_in_order, [&](const std::shared_ptr<Region>& r) {
                  emitted += r->region_faces;
                  merge(*r, stats);
                  if (emitted < nf) reserve(emitted, nf, r->region_faces);
                }));
    finish(stats);
    return std::move(out_);
  }

 private:
  // The region from `seed` (breadth-first over faces sharing a vertex) and its rings.
  void grow(uint32_t seed, uint32_t batch, Region& r) {
    std::vector<uint32_t>& faces = r.faces;
    auto add = [&](uint32_t f, uint8_t role) {
      face_state_[f] |= kCut;
      faces.push_back(f);
      r.roles.push_back(role);
    };
    const uint32_t* fv = cage_.face_vertices.data();
    auto around = [&](uint32_t f, auto&& visit) {
      for (uint32_t c = cage_.face_offsets[f]; c < cage_.face_offsets[f + 1]; ++c) {
        const uint32_t v = fv[c];
        for (uint32_t k = vertex_face_offsets_[v]; k < vertex_face_offsets_[v + 1]; ++k)
          visit(vertex_faces_[k]);
      }
    };
    add(seed, 2);
    face_state_[seed] |= kDone;
    for (size_t head = 0; head < faces.size() && faces.size() < batch; ++head)
      around(faces[head], [&](uint32_t g) {
        if (faces.size() < batch && !(face_state_[g] & (kCut | kDone))) {
          add(g, 2);
          face_state_[g] |= kDone;
        }
      });
    r.region_faces = faces.size();
    size_t begin = 0;
    for (int ring = 0; ring < kTrustedRings + kContextRings; ++ring) {
      const size_t end = faces.size();
      const uint8_t role = ring < kTrustedRings ? 1 : 0;
      for (size_t i = begin; i < end; ++i)
        around(faces[i], [&](uint32_t g) {
          if (!(face_state_[g] & kCut)) add(g, role);
        });
      begin = end;
    }
  }

  // The sub-cage: the region's faces and rings over their own vertices, with the cage's tags.
  void extract(Region& r) {
    Mesh& m = r.mesh;
    m.tags = cage_.tags;
    const std::vector<uint32_t>& faces = r.faces;
    std::vector<uint32_t>& verts = r.vertices;
    const uint32_t* fv = cage_.face_vertices.data();
    for (size_t i = 0; i < faces.size(); ++i) {
      const uint32_t f = faces[i];
      for (uint32_t c = cage_.face_offsets[f]; c < cage_.face_offsets[f + 1]; ++c) {
        const uint32_t v = fv[c];
        if (vertex_local_[v] == kNone) {
          vertex_local_[v] = uint32_t(verts.size());
          verts.push_back(v);
        }
        m.face_vertices.push_back(vertex_local_[v]);
      }
      m.face_offsets.push_back(uint32_t(m.face_vertices.size()));
      if (face_state_[f] & kHole) m.hole_faces.push_back(uint32_t(i));
    }
    if (!creases_.empty())
      for (const uint32_t f : faces) {  // every vertex has its id now
        const std::span<const uint32_t> vs = cage_.face(f);
        for (size_t j = 0; j < vs.size(); ++j) {
          const uint32_t a = vs[j], b = vs[(j + 1) % vs.size()];
          const auto it = creases_.find(edge_key(a, b));
          if (it == creases_.end() || it->second.region == r.index) continue;
          it->second.region = r.index;
          m.crease_edges.insert(m.crease_edges.end(), {vertex_local_[a], vertex_local_[b]});
          m.crease_sharpness.push_back(it->second.sharpness);
        }
      }
    m.positions.resize(3 * verts.size());
    for (size_t i = 0; i < verts.size(); ++i) {
      std::copy_n(&cage_.positions[3 * size_t(verts[i])], 3, &m.positions[3 * i]);
      if (corner_sharpness_.empty()) continue;
      if (const float x = corner_sharpness_[verts[i]]; x > 0.0f) {
        m.corner_vertices.push_back(uint32_t(i));
        m.corner_sharpness.push_back(x);
      }
    }
    if (!depth_.empty())
      for (const uint32_t v : verts) r.depth.push_back(depth_[v]);
    if (replay_) {
      for (const uint32_t f : faces) r.ptex.push_back(out_.ptex_of_face[f]);
      if (!replay_->sharp_corners.empty())
        for (const uint32_t v : verts) r.sharp_corners.push_back(replay_->sharp_corners[v]);
    }
    for (const uint32_t f : faces) face_state_[f] &= uint8_t(~kCut);
    for (const uint32_t v : verts) vertex_local_[v] = kNone;
  }

  // Touches nothing shared: regions are isolated in parallel.
  void isolate_region(Region& r) const {
    const auto t0 = std::chrono::steady_clock::now();
    {
      Builder b(r.mesh, o_, r.depth);
      b.set_roles(r.roles);
      if (replay_) {
        b.set_replay(replay_, r.ptex);
        b.set_sharp_corners(r.sharp_corners);
      }
      b.set_stats(&r.stats);
      SparseRefinement s = isolate(r.mesh, o_, b);
      b.build(r.table, s, &r.stats);
    }
    r.stats.refine_ms = ms_since(t0) - r.stats.patches_ms;
    r.mesh = Mesh{};
  }

  // Appends src's rows' weights to dst (shared: src's pool after dst's, each region's rows keep
  // their own copy of a row they share with another region's).
  static void append_weights(const StencilTable& src, StencilTable& dst) {
    const uint32_t at = uint32_t(dst.weights.size());
    for (size_t i = 0; i < src.size(); ++i) dst.weight_offsets.push_back(at + src.weight_start(i));
    dst.weights.insert(dst.weights.end(), src.weights.begin(), src.weights.end());
  }

  // Appends a region's table: level-k rows after the earlier regions' (ids shifted by their
  // counts), patch points as ids within their level (rebased in finish()).
  void merge(const Region& r, PatchStats* stats) {
    const PatchTable& t = r.table;
    const PatchStats& ps = r.stats;
    const std::vector<uint32_t>& verts = r.vertices;
    const std::vector<uint32_t>& faces = r.faces;
    const size_t nl = t.level_offsets.size() - 1;
    if (out_.level_stencils.size() < nl - 1) out_.level_stencils.resize(nl - 1);
    if (count_.size() < nl) count_.resize(nl, 0);
    const std::vector<uint32_t> base(count_);  // this region's first id in each level
    for (size_t k = 1; k < nl; ++k) {
      const StencilTable& src = t.level_stencils[k - 1];
      StencilTable& dst = out_.level_stencils[k - 1];
      const uint32_t shift = uint32_t(dst.indices.size());
      for (size_t i = 1; i < src.offsets.size(); ++i) dst.offsets.push_back(shift + src.offsets[i]);
      if (k == 1) {
        for (const uint32_t p : src.indices) dst.indices.push_back(verts[p]);
      } else {
        for (const uint32_t p : src.indices) dst.indices.push_back(base[k - 1] + p);
      }
      append_weights(src, dst);
      count_[k] += uint32_t(src.size());
    }
    // A level-k patch's points are all level-k points.
    auto local = [&](uint32_t p, uint32_t k) {
      if (p < t.level_offsets[k] || p >= t.level_offsets[k + 1])
        throw std::logic_error("patches: a region's patch reads another level");
      return k == 0 ? verts[p] : base[k] + (p - t.level_offsets[k]);
    };
    auto place = [&](PatchParam pp) {
      const uint32_t f = faces[pp.base_face];
      pp.ptex = out_.ptex_of_face[f] + (pp.ptex - t.ptex_of_face[pp.base_face]);
      pp.base_face = f;
      return pp;
    };
    for (size_t i = 0; i < t.regular_params.size(); ++i) {
      const PatchParam& pp = t.regular_params[i];
      for (size_t j = 16 * i; j < 16 * i + 16; ++j)
        out_.regular_points.push_back(local(t.regular_points[j], pp.level));
      out_.regular_params.push_back(place(pp));
    }
    // End-cap points: corner rows after the earlier regions' corner rows, face rows after
    // theirs (marked kCapRef until finish()); a row's level is its end caps' (all of a cap's
    // points are of its level).
    const StencilTable &g = t.gregory_stencils, &gf = t.gregory_face_stencils;
    StencilTable &dg = out_.gregory_stencils, &dgf = out_.gregory_face_stencils;
    const uint32_t cap_base = t.level_offsets.back(), face_base = cap_base + uint32_t(g.size());
    const uint32_t corner_shift = uint32_t(dg.size()), face_shift = uint32_t(dgf.size());
    corner_level_.resize(corner_shift + g.size(), 0);
    face_level_.resize(face_shift + gf.size(), 0);
    for (size_t i = 0; i < t.gregory_params.size(); ++i) {
      const uint8_t k = t.gregory_params[i].level;
      for (size_t j = 20 * i; j < 20 * i + 20; ++j) {
        const uint32_t p = t.gregory_points[j];
        if (p < cap_base) throw std::logic_error("patches: an end cap reads a refined point");
        if (p < face_base) {
          corner_level_[corner_shift + p - cap_base] = k;
          out_.gregory_points.push_back(corner_shift + (p - cap_base));
        } else {
          face_level_[face_shift + p - face_base] = k;
          out_.gregory_points.push_back(kCapRef | (face_shift + (p - face_base)));
        }
      }
      out_.gregory_params.push_back(place(t.gregory_params[i]));
    }
    auto append = [&](const StencilTable& src, StencilTable& dst, const uint8_t* level) {
      const uint32_t shift = uint32_t(dst.indices.size());
      for (size_t row = 0; row < src.size(); ++row) {
        for (uint32_t j = src.offsets[row]; j < src.offsets[row + 1]; ++j) {
          const uint32_t p = src.indices[j];
          dst.indices.push_back(p >= cap_base ? kCapRef | (corner_shift + (p - cap_base))
                                              : local(p, level[row]));
        }
        dst.offsets.push_back(shift + src.offsets[row + 1]);
      }
      append_weights(src, dst);
    };
    append(g, dg, corner_level_.data() + corner_shift);  // data(): the arrays may be empty
    append(gf, dgf, face_level_.data() + face_shift);
    if (stats) {
      for (auto [to, from] : {std::pair{&stats->regular_by_level, &ps.regular_by_level},
                              std::pair{&stats->gregory_by_level, &ps.gregory_by_level}}) {
        if (to->size() < from->size()) to->resize(from->size(), 0);
        for (size_t k = 0; k < from->size(); ++k) (*to)[k] += (*from)[k];
      }
      stats->patches_ms += ps.patches_ms;
      stats->refine_ms += ps.refine_ms;
    }
  }

  // Room for the whole table at the rate of the regions merged so far, once a tenth of the cage
  // is in (the first region alone misjudges features that are few and far between: a rate off
  // by more than the margin doubled an array late, a copy beside the old one at the build's
  // peak); until then the arrays double while they are small. Afterwards an array is given room
  // again only when the next regions might not fit, as late as possible, when the rate is known
  // best. The room is held to the end: it is part of the build's peak.
  void reserve(size_t emitted, size_t faces, size_t last_region) {
    if (10 * emitted < faces) return;
    const double scale = double(faces) / double(emitted);
    const bool first = !reserved_;
    reserved_ = true;
    auto grow = [&](auto& v) {
      const double want = double(v.size()) * scale;
      const double next = 2.0 * double(v.size()) * double(last_region) / double(emitted);
      if (first ? double(v.capacity()) < 1.05 * want
                : double(v.capacity()) < double(v.size()) + next)
        v.reserve(size_t(1.05 * want + next) + 64);
    };
    for (StencilTable& st : out_.level_stencils)
      grow(st.offsets), grow(st.indices), grow(st.weight_offsets);
    for (StencilTable* g : {&out_.gregory_stencils, &out_.gregory_face_stencils})
      grow(g->offsets), grow(g->indices), grow(g->weight_offsets);
    grow(out_.regular_points), grow(out_.regular_params);
    grow(out_.gregory_points), grow(out_.gregory_params);
  }

  void finish(PatchStats* stats) {
    PatchTable& t = out_;
    t.level_offsets.assign(1, 0);
    t.level_offsets.push_back(uint32_t(cage_.vertex_count()));
    for (size_t k = 1; k < count_.size(); ++k) {
      if (uint64_t(t.level_offsets.back()) + count_[k] >= kNone)
        throw InputError("patches: more than 2^32 points");
      t.level_offsets.push_back(t.level_offsets.back() + count_[k]);
    }
    for (size_t i = 0; i < t.regular_params.size(); ++i) {
      const uint32_t shift = t.level_offsets[t.regular_params[i].level];
      if (t.regular_params[i].level > 0)
        for (size_t j = 16 * i; j < 16 * i + 16; ++j) t.regular_points[j] += shift;
    }
    for (StencilTable* g : {&t.gregory_stencils, &t.gregory_face_stencils}) {
      const std::vector<uint8_t>& level = g == &t.gregory_stencils ? corner_level_ : face_level_;
      for (size_t r = 0; r < g->size(); ++r)
        if (level[r] > 0)
          for (uint32_t j = g->offsets[r]; j < g->offsets[r + 1]; ++j)
            if (!(g->indices[j] & kCapRef)) g->indices[j] += t.level_offsets[level[r]];
    }
    resolve_cap_points(t);
    if (stats) {
      stats->regular_by_level.resize(t.level_offsets.size() - 1, 0);
      stats->gregory_by_level.resize(t.level_offsets.size() - 1, 0);
      stats->points = t.point_count();
    }
  }

  static uint64_t edge_key(uint32_t a, uint32_t b) {
    return a < b ? uint64_t(a) << 32 | b : uint64_t(b) << 32 | a;
  }
  struct Crease {
    float sharpness = 0;
    uint32_t region = kNone;  // the last region that took it
    bool on_face = false;
  };

  const Mesh& cage_;
  PatchOptions o_;
  std::span<const uint8_t> depth_;
  const Replay* replay_;
  std::vector<uint32_t> vertex_face_offsets_, vertex_faces_;
  std::unordered_map<uint64_t, Crease> creases_;
  std::vector<float> corner_sharpness_;  // per cage vertex when any is tagged (a later tag wins)
  // Per cage face: kDone once a region has taken it as its own, kCut while in the region being
  // cut, kHole for a hole.
  static constexpr uint8_t kDone = 1, kCut = 2, kHole = 4;
  std::vector<uint8_t> face_state_;
  std::vector<uint32_t> vertex_local_;              // kNone outside the region being cut
  std::vector<uint32_t> count_{0};                  // points per level so far
  bool reserved_ = false;                           // room made for the whole table
  std::vector<uint8_t> corner_level_, face_level_;  // level of each merged end-cap row
  PatchTable out_;
};

}  // namespace

namespace patch_detail {

PatchTable build_replayed(const Mesh& cage, const PatchOptions& options, const Replay& replay) {
  const size_t nf = cage.face_count();
  const uint32_t batch = options.batch_faces ? options.batch_faces : kDefaultBatch;
  if (options.batch_faces ? nf > batch : nf > 2 * size_t(batch)) {
    validate(cage, "cage");
    RegionBuilder rb(cage, options, {}, &replay);
    return rb.run(batch, nullptr);
  }
  Builder b(cage, options, {});
  b.set_replay(&replay);
  b.set_sharp_corners(replay.sharp_corners);
  SparseRefinement r = isolate(cage, options, b);
  PatchTable out;
  b.build(out, r, nullptr);
  return out;
}

}  // namespace patch_detail

PatchTable build_patches(const Mesh& cage, const PatchOptions& options,
                         std::span<const uint8_t> vertex_depth, PatchStats* stats) {
  check_depth(options);
  if (!vertex_depth.empty() && vertex_depth.size() != cage.vertex_count())
    throw InputError(fmt::format("patches: {} vertex depths for {} vertices", vertex_depth.size(),
                                 cage.vertex_count()));
  const auto t0 = std::chrono::steady_clock::now();
  if (stats) *stats = {};
  const size_t nf = cage.face_count();
  const uint32_t batch = options.batch_faces ? options.batch_faces : kDefaultBatch;
  if (options.batch_faces ? nf > batch : nf > 2 * size_t(batch)) {
    validate(cage, "cage");
    RegionBuilder rb(cage, options, vertex_depth);
    return rb.run(batch, stats);  // the stats' times: summed over the regions (thread time)
  }
  Builder b(cage, options, vertex_depth);
  b.set_stats(stats);
  SparseRefinement r = isolate(cage, options, b);
  PatchTable out;
  b.build(out, r, stats);
  // Patches are emitted while the refinement runs: refine_ms is the rest.
  if (stats) stats->refine_ms = ms_since(t0) - stats->patches_ms;
  return out;
}

}  // namespace limn
