// limn demo: the workflow on built-in shapes, no input files needed. Grows with each layer; today
// it builds every procedural cage, analyses it as `limn info` does, subdivides the small cages to
// their limit surface, exports viewable meshes and writes a Markdown + JSON report.
#include <fmt/format.h>

#include <filesystem>

#include "common.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/subdiv/refine.hpp"
#include "limn/version.hpp"

namespace limn::cli {

namespace {

struct DemoShape {
  const char* name;
  const char* what;
  bool export_mesh;  // the 800k-quad cages are analysed, not exported (tens of MB each)
};

}  // namespace

void add_demo(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("demo", "Run the limn workflow on built-in shapes and write a report");
  struct Opts {
    std::string dir = "limn-demo";
    bool quick = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("-o,--output", o->dir, "Output folder (created if missing)");
  cmd->add_flag("--quick", o->quick, "Use the small variants of the 800k-quad shapes");
  cmd->add_flag("--json", o->json, "Print the report as one JSON object too");
  cmd->callback([o] {
    namespace fs = std::filesystem;
    const fs::path dir(o->dir);
    std::error_code ec;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
      throw InputError(fmt::format("{}: exists and is not a folder", o->dir));
    fs::create_directories(dir, ec);
    if (ec)
      throw std::runtime_error(fmt::format("{}: cannot create folder: {}", o->dir, ec.message()));

    const std::vector<DemoShape> shapes = {
        {"cube", "unit cube, 6 quads", true},
        {"torus", "quad torus with extraordinary vertices of valence 3, 5, 6, 8", true},
        {"cage", "open box with sharp and semi-sharp creases, corners, a hole and a boundary",
         true},
        {o->quick ? "terrain-small" : "terrain",
         "terrain height field with scattered extraordinary vertices", o->quick},
        {o->quick ? "torus-dense-small" : "torus-dense",
         "torus-like cage, about one extraordinary vertex in ten", o->quick},
    };
    Stopwatch total;
    nlohmann::json report = {{"limn", version()}, {"shapes", nlohmann::json::array()}};
    std::string md = fmt::format(
        "# limn demo report\n\nlimn {}. Every shape is built procedurally (no input files), then "
        "analysed as `limn info` does: adjacency, manifoldness, orientation, boundary loops, "
        "genus and the extraordinary vertices that adaptive subdivision will isolate.\n\n"
        "| shape | vertices | faces | edges | extraordinary | valences | boundary loops | genus | "
        "build ms | adjacency ms | output "
        "|\n|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---|\n",
        version());
    for (size_t i = 0; i < shapes.size(); ++i) {
      const DemoShape& s = shapes[i];
      fmt::print(stderr, "[{}/{}] {}: building ...", i + 1, shapes.size(), s.name);
      std::fflush(stderr);
      Stopwatch sw;
      const Mesh mesh = make_shape(s.name);
      const double t_build = sw.lap();
      fmt::print(stderr, " {} faces, analysing ...", mesh.face_count());
      std::fflush(stderr);
      const Topology topo = build_topology(mesh);
      const double t_topo = sw.lap();
      const MeshStats st = analyze(mesh, topo);
      const double t_analyze = sw.lap();
      std::string out = "-";
      if (s.export_mesh) {
        // OBJ keeps the subdivision tags; GLB opens in any viewer.
        for (const char* ext : {".obj", ".glb"})
          write_mesh(mesh, dir / (std::string(s.name) + ext));
        out = fmt::format("[{0}.obj]({0}.obj), [{0}.glb]({0}.glb)", s.name);
      }
      fmt::print(stderr, " done ({:.0f} ms)\n", sw.ms());
      std::string valences;
      for (auto [k, n] : st.valence_histogram) valences += fmt::format("{}:{} ", k, n);
      md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {:.1f} | {:.1f} | {} |\n",
                        s.name, st.vertices, st.faces, st.edges, st.extraordinary_vertices,
                        valences, st.boundary_loops, st.genus, t_build, t_topo, out);
      nlohmann::json j = stats_json(st);
      j["shape"] = s.name;
      j["description"] = s.what;
      j["timings_ms"] = {{"build", t_build}, {"topology", t_topo}, {"analysis", t_analyze}};
      report["shapes"].push_back(j);
    }
    // Subdivision: the small cages, uniformly refined and pushed to the limit surface.
    md +=
        "\n## Subdivision surfaces\n\nUniform Catmull-Clark refinement with OpenSubdiv's rules "
        "(creases, corners, boundaries, holes), points pushed to the limit with limit normals.\n\n"
        "| cage | level | faces | refine ms | limit ms | output |\n|---|---:|---:|---:|---:|---|\n";
    for (const char* name : {"cube", "torus", "cage"}) {
      const int level = 3;
      fmt::print(stderr, "subdivide {} to level {} ...", name, level);
      std::fflush(stderr);
      Stopwatch sw;
      const Mesh cage = make_shape(name);
      const UniformRefinement r = refine_uniform(cage, level, subdiv_options(cage));
      const std::vector<float> pts = r.positions(cage, level);
      const double t_refine = sw.lap();
      const LimitStencils ls = limit_stencils(r, level);
      Mesh surface;
      surface.positions.resize(pts.size());
      std::vector<float> t1(pts.size()), t2(pts.size());
      apply_stencils(ls.position, pts.data(), surface.positions.data(), 3);
      apply_stencils(ls.tangent1, pts.data(), t1.data(), 3);
      apply_stencils(ls.tangent2, pts.data(), t2.data(), 3);
      surface.normals = normals_from_tangents(t1, t2);
      const double t_limit = sw.lap();
      const RefinedLevel& L = r.levels.back();
      for (size_t f = 0; f < L.face_count(); ++f)
        if (!L.face_hole[f])
          surface.add_face(
              std::span<const uint32_t>(L.face_vertices.data() + L.face_offsets[f], 4));
      surface.normal_indices = surface.face_vertices;
      const std::string file = fmt::format("{}-limit-L{}.glb", name, level);
      write_mesh(surface, dir / file);
      fmt::print(stderr, " {} faces ({:.0f} ms)\n", surface.face_count(), sw.ms());
      md += fmt::format("| {} | {} | {} | {:.1f} | {:.1f} | [{}]({}) |\n", name, level,
                        surface.face_count(), t_refine, t_limit, file, file);
      report["subdivision"].push_back({{"cage", name},
                                       {"level", level},
                                       {"faces", surface.face_count()},
                                       {"output", file},
                                       {"timings_ms", {{"refine", t_refine}, {"limit", t_limit}}}});
    }
    md += "\nShapes:\n\n";
    for (const auto& s : shapes) md += fmt::format("- `{}`: {}\n", s.name, s.what);
    md += fmt::format("\nTotal time {:.0f} ms.\n", total.ms());
    report["total_ms"] = total.ms();
    write_file_atomic(dir / "report.md", md);
    write_file_atomic(dir / "report.json", report.dump(2) + "\n");
    fmt::print(stderr, "wrote {}\n", (dir / "report.md").string());
    if (o->json) fmt::print("{}\n", report.dump(2));
  });
}

}  // namespace limn::cli
