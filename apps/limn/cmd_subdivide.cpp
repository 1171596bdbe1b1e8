// limn subdivide: uniform Catmull-Clark refinement (adaptive patches come with the next layer).
// Without --limit it runs the lean path (subdivide_uniform): only the last level is ever kept.
#include <fmt/format.h>

#include <cmath>

#include "common.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn::cli {

void add_subdivide(CLI::App& app) {
  auto* cmd = app.add_subcommand("subdivide", "Catmull-Clark subdivision of a cage");
  struct Opts {
    std::string mesh, out, format;
    int uniform = -1;
    bool limit = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("MESH", o->mesh, "Control cage (OBJ with OpenSubdiv tags, PLY, OFF)")->required();
  cmd->add_option("-o,--output", o->out, "Output mesh (.obj, .ply, .off, .glb)")->required();
  cmd->add_option("--uniform", o->uniform, "Refine every face L times (0-8)")->required();
  cmd->add_flag("--limit", o->limit, "Push the points to the limit surface, with limit normals");
  cmd->add_option("--format", o->format, "Input format, overriding the extension");
  cmd->add_flag("--json", o->json, "Print one JSON object with counts per level and timings");
  cmd->callback([o] {
    if (o->uniform < 0 || o->uniform > 8)
      throw InputError(fmt::format("--uniform {}: level must be 0-8", o->uniform));
    if (format_from_path(o->out) == MeshFormat::automatic)
      throw InputError(fmt::format("{}: cannot tell the output format from the extension", o->out));
    Stopwatch sw;
    const Mesh cage = read_mesh(o->mesh, parse_format_option(o->format, "--format"));
    const double t_read = sw.lap();
    // Every level multiplies corners by 4 (after the first, which makes one quad per corner).
    // The lean path needs ~70 bytes per output quad; with --limit every level, its stencils and
    // the limit masks are kept (~500 bytes per quad).
    const double faces = double(cage.corner_count()) * std::pow(4.0, o->uniform - 1);
    const double cap = o->limit ? 4e7 : 3.5e8;
    if (o->uniform > 0 && faces > cap)
      throw InputError(fmt::format("{}: level {}{} would make {:.3g} faces; limn stops at {:.3g}",
                                   o->mesh, o->uniform, o->limit ? " with --limit" : "", faces,
                                   cap));
    const SubdivOptions options = subdiv_options(cage);
    Mesh out;
    nlohmann::json levels = nlohmann::json::array();
    nlohmann::json timings = {{"read", t_read}};
    if (!o->limit) {
      // Lean: only the last level is kept, stencils are applied chunk by chunk and dropped.
      SubdivideStats st;
      out = subdivide_uniform(cage, o->uniform, options, &st);
      for (size_t k = 0; k < st.levels.size(); ++k)
        levels.push_back({{"level", k},
                          {"vertices", st.levels[k].vertices},
                          {"faces", st.levels[k].faces},
                          {"edges", st.levels[k].edges},
                          {"stencil_entries", st.levels[k].stencil_entries}});
      timings["topology"] = st.topology_ms;
      timings["stencils_and_apply"] = st.stencils_ms;
      timings["output"] = st.output_ms;
    } else {
      const UniformRefinement r = refine_uniform(cage, o->uniform, options);
      timings["topology_refine_stencils"] = sw.lap();
      std::vector<float> pos = r.positions(cage, o->uniform);
      timings["apply"] = sw.lap();
      const RefinedLevel& L = r.levels.back();
      const LimitStencils ls = limit_stencils(r, o->uniform);
      std::vector<float> p(pos.size()), t1(pos.size()), t2(pos.size());
      apply_stencils(ls.position, pos.data(), p.data(), 3);
      apply_stencils(ls.tangent1, pos.data(), t1.data(), 3);
      apply_stencils(ls.tangent2, pos.data(), t2.data(), 3);
      out.normals = normals_from_tangents(t1, t2);
      out.positions = std::move(p);
      timings["limit"] = sw.lap();
      // Holes are refined for their neighbours but make no surface.
      for (size_t f = 0; f < L.face_count(); ++f) {
        if (L.face_hole[f]) continue;
        out.add_face(std::span<const uint32_t>(L.face_vertices.data() + L.face_offsets[f],
                                               L.face_offsets[f + 1] - L.face_offsets[f]));
      }
      out.normal_indices = out.face_vertices;
      // Remaining sharpness travels as OpenSubdiv tags, so the result can be refined further.
      for (size_t e = 0; e < L.edge_count(); ++e)
        if (L.edge_sharpness[e] > 0.0f) {
          out.crease_edges.insert(out.crease_edges.end(),
                                  {L.edge_vertices[2 * e], L.edge_vertices[2 * e + 1]});
          out.crease_sharpness.push_back(L.edge_sharpness[e]);
        }
      for (size_t v = 0; v < L.vertex_count(); ++v)
        if (L.vertex_sharpness[v] > 0.0f) {
          out.corner_vertices.push_back(static_cast<uint32_t>(v));
          out.corner_sharpness.push_back(L.vertex_sharpness[v]);
        }
      out.tags = cage.tags;
      for (size_t k = 0; k < r.levels.size(); ++k) {
        const RefinedLevel& l = r.levels[k];
        levels.push_back({{"level", k},
                          {"vertices", l.vertex_count()},
                          {"faces", l.face_count()},
                          {"edges", l.edge_count()},
                          {"stencil_entries", k == 0 ? 0 : r.stencils[k - 1].indices.size()}});
      }
    }
    sw.lap();
    write_mesh(out, o->out);
    timings["write"] = sw.lap();

    if (o->json) {
      nlohmann::json j = {{"input", o->mesh},
                          {"output", o->out},
                          {"level", o->uniform},
                          {"limit", o->limit},
                          {"levels", levels},
                          {"output_vertices", out.vertex_count()},
                          {"output_faces", out.face_count()},
                          {"timings_ms", timings}};
      fmt::print("{}\n", j.dump(2));
    } else {
      fmt::print("{} -> {}: level {}{}, {} vertices, {} faces ({:.1f} ms)\n", o->mesh, o->out,
                 o->uniform, o->limit ? " (limit)" : "", out.vertex_count(), out.face_count(),
                 sw.ms());
    }
  });
}

}  // namespace limn::cli
