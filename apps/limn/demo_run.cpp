// limn demo's work, in the GL module (gl_commands.hpp): the whole workflow on built-in shapes, no
// input files needed: every procedural cage analysed as `limn info` does; a cage's adaptive limit
// surface with a depth per vertex chosen for a near and a far camera, drawn on the GPU with depth
// colours; scripted paint strokes into an octree texture, baked and rendered; the painted surface
// simplified by VSA into a few polygons, its partition rendered. Writes PNGs, meshes and a Markdown
// + JSON report.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>

#include "gl_commands.hpp"
#include "limn/atlas/unwrap.hpp"
#include "limn/atlas/uv_metrics.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/file.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/paint/bake.hpp"
#include "limn/paint/brush.hpp"
#include "limn/paint/file.hpp"
#include "limn/render/draw.hpp"
#include "limn/render/gl_context.hpp"
#include "limn/render/image.hpp"
#include "limn/simplify/vsa.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/tessellate.hpp"
#include "limn/version.hpp"

namespace limn::cli {

namespace {

struct DemoShape {
  const char* name;
  const char* what;
  bool export_mesh;  // the 800k-quad cages are analysed, not exported (tens of MB each)
};

constexpr int kWidth = 960, kHeight = 600;

// A camera looking at `target` from direction `dir` at `distance`.
Camera look(const float target[3], const double dir[3], double distance) {
  Camera c;
  c.width = kWidth, c.height = kHeight;
  c.fovy_deg = 40.0f;
  const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  for (int k = 0; k < 3; ++k)
    c.target[k] = target[k], c.eye[k] = float(target[k] + distance * dir[k] / len);
  c.up[0] = 0, c.up[1] = 0, c.up[2] = 1;
  return c;
}

// The whole cage from above one side, filling the picture.
Camera overview(const Mesh& cage) {
  const Box b = bounding_box(cage);
  const float centre[3] = {(b.min[0] + b.max[0]) / 2, (b.min[1] + b.max[1]) / 2,
                           (b.min[2] + b.max[2]) / 2};
  const double dir[3] = {0.8, -1.5, 1.1};
  return fit_camera(look(centre, dir, b.diagonal()), cage.positions);
}

void save_image(RenderTarget& target, const std::filesystem::path& path) {
  write_png(path, target.width(), target.height(), target.read_rgba());
}

// A colour per cluster, spread around the hue circle so neighbours differ.
std::vector<float> cluster_colors(std::span<const uint32_t> face_cluster) {
  std::vector<float> out(3 * face_cluster.size());
  for (size_t f = 0; f < face_cluster.size(); ++f) {
    const double h = std::fmod(double(face_cluster[f]) * 0.618033988749895, 1.0) * 6.0;
    const double x = 1.0 - std::abs(std::fmod(h, 2.0) - 1.0);
    const double rgb[6][3] = {{1, x, 0}, {x, 1, 0}, {0, 1, x}, {0, x, 1}, {x, 0, 1}, {1, 0, x}};
    for (int k = 0; k < 3; ++k) out[3 * f + size_t(k)] = float(0.35 + 0.55 * rgb[int(h) % 6][k]);
  }
  return out;
}

// A closed stroke around the z axis at z = height: for each of `bins` angles, among the surface
// vertices in the angle's wedge within `band` of the height, the one farthest from the axis
// (`outer`) or nearest it. A height crosses a torus on two rings; the stroke keeps to one
// instead of jumping between them (dabs between the rings would miss the surface).
std::vector<float> ring_stroke(const Mesh& m, float height, float band, bool outer,
                               int bins = 180) {
  std::vector<std::pair<float, uint32_t>> best(size_t(bins), {INFINITY, kNone});
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    const float* p = &m.positions[3 * size_t(v)];
    if (!(std::abs(p[2] - height) < band)) continue;
    const float r = std::hypot(p[0], p[1]);
    const double a = std::atan2(double(p[1]), double(p[0])) + 3.14159265358979323846;
    const size_t bin = std::min(size_t(bins) - 1, size_t(a / (2 * 3.14159265358979323846) * bins));
    const float key = outer ? -r : r;
    if (key < best[bin].first) best[bin] = {key, v};
  }
  std::vector<float> xyz;
  for (const auto& [d, v] : best)
    if (v != kNone)
      xyz.insert(xyz.end(), &m.positions[3 * size_t(v)], &m.positions[3 * size_t(v)] + 3);
  // Closed: back to the first point, so the stroke's dabs also cover the seam between them.
  if (xyz.size() >= 6) xyz.insert(xyz.end(), xyz.begin(), xyz.begin() + 3);
  return xyz;
}

constexpr float kWhite[4] = {1, 1, 1, 1};

// The workflow's first step: the adaptive surface seen from two cameras (a hierarchy once, then a
// view change only selects).
void workflow_surface(const std::filesystem::path& dir, std::string& md, nlohmann::json& j,
                      Stopwatch& sw, GlContext* gl, std::unique_ptr<RenderTarget>& target,
                      const Mesh& cage, const PatchOptions& po) {
  fmt::print(stderr, "adaptive surface: patch hierarchy to depth {} ...", po.depth);
  std::fflush(stderr);
  const PatchHierarchy h = build_patch_hierarchy(cage, po);
  VertexErrorModel model = vertex_error_model(cage, po.subdiv);
  measure_vertex_errors(cage, h, model);
  const std::vector<float> points = h.table.points(cage.positions);
  const double t_hierarchy = sw.lap();
  fmt::print(stderr, " {} nodes ({:.0f} ms)\n", h.node_count(), t_hierarchy);
  if (gl) target = std::make_unique<RenderTarget>(kWidth, kHeight, 4);
  md +=
      "| camera | patches | deepest level | select ms | GPU ms | image "
      "|\n|---|---:|---:|---:|---:|---|\n";
  // Far: the whole torus. Near: close to its valence-8 vertex, looking along its normal.
  const std::vector<float> vn = vertex_normals(cage);
  uint32_t star = 0, most = 0;
  {
    std::vector<uint32_t> valence(cage.vertex_count(), 0);
    for (const uint32_t v : cage.face_vertices) ++valence[v];
    for (uint32_t v = 0; v < cage.vertex_count(); ++v)
      if (valence[v] > most) most = valence[v], star = v;
  }
  const double star_dir[3] = {vn[3 * star] + 0.3, vn[3 * star + 1] - 0.4, vn[3 * star + 2] + 0.3};
  const Camera cameras[2] = {overview(cage), look(&cage.positions[3 * size_t(star)], star_dir,
                                                  0.12 * bounding_box(cage).diagonal())};
  for (int ci = 0; ci < 2; ++ci) {
    const char* name = ci ? "near" : "far";
    const Camera& cam = cameras[ci];
    DepthOptions d;
    d.tolerance_px = 0.5f;
    d.max_depth = po.depth;
    const std::vector<uint8_t> depth = select_depths(cage, model, cam, d);
    const PatchTable sel = select_patches(h, depth);
    const double t_select = sw.lap();
    int deepest = 0;
    for (const auto* params : {&sel.regular_params, &sel.gregory_params})
      for (const PatchParam& p : *params) deepest = std::max(deepest, int(p.level));
    const std::string file = fmt::format("surface-{}.png", name);
    double gpu_ms = 0;
    if (gl) {
      PatchDrawer drawer(cage, sel, points);
      target->begin(kWhite);
      DrawOptions o;
      o.depth_colors = o.outline = true;
      gpu_ms = drawer.draw(cam, o).gpu_ms;
      save_image(*target, dir / file);
    }
    fmt::print(stderr, "adaptive surface, {} camera: {} patches, deepest level {}\n", name,
               sel.patch_count(), deepest);
    md += fmt::format("| {} | {} | {} | {:.2f} | {:.1f} | {} |\n", name, sel.patch_count(), deepest,
                      t_select, gpu_ms, gl ? fmt::format("![{0}]({0})", file) : "-");
    j["surface"][name] = {{"patches", sel.patch_count()},
                          {"deepest_level", deepest},
                          {"select_ms", t_select},
                          {"gpu_ms", gpu_ms},
                          {"image", file}};
  }
  sw.lap();
}

// The second: a dense tessellation of the surface painted by scripted strokes into an octree
// texture, baked and drawn. Returns the tessellation.
Mesh workflow_paint(const std::filesystem::path& dir, std::string& md, nlohmann::json& j,
                    Stopwatch& sw, GlContext* gl, RenderTarget* target, const Mesh& cage,
                    const PatchOptions& po) {
  PatchOptions fixed = po;
  fixed.depth = 2;
  const PatchTable table = build_patches(cage, fixed);
  TessellateOptions to;
  to.factor = 6;
  to.normals = false;
  const Mesh dense = tessellate_patches(cage, table, table.points(cage.positions), to);
  write_mesh(dense, dir / "torus-limit.obj");
  fmt::print(stderr, "paint: {} triangles ...", dense.face_count());
  std::fflush(stderr);
  const PaintSurface surface(dense);
  MaterialTexture texture =
      MaterialTexture::from_color(OctreeTexture::create(surface, pack_rgba8(235, 235, 225, 255)));
  const Box box = bounding_box(dense);
  const float extent = box.diagonal();
  MaterialPainter painter(texture, surface);
  // Each stroke carries a material: red metal, matte blue, a raised green ridge, gold.
  struct Stroke {
    float height;  // fraction of the height from the bottom
    bool outer;    // the ring farther from the axis
    float color[4];
    float radius;                       // fraction of the diagonal
    float roughness, metallic, relief;  // channels; < 0: not painted
  };
  const Stroke strokes[] = {{0.99f, true, {0.85f, 0.15f, 0.1f, 1}, 0.035f, 0.25f, 1.0f, -1},
                            {0.5f, true, {0.1f, 0.35f, 0.85f, 1}, 0.05f, 0.9f, -1, -1},
                            {0.5f, false, {0.15f, 0.65f, 0.3f, 1}, 0.03f, -1, -1, 1.0f},
                            {0.2f, true, {0.95f, 0.7f, 0.1f, 1}, 0.03f, 0.35f, 1.0f, -1}};
  size_t dabs = 0;
  for (const Stroke& s : strokes) {
    Brush b;
    std::copy(s.color, s.color + 4, b.color);
    b.radius = s.radius * extent;
    b.hardness = 0.6f;
    b.depth = 9;
    const float values[3] = {s.roughness, s.metallic, s.relief};
    for (int k = 0; k < kMaterialChannels; ++k)
      if (values[k] >= 0) b.material[k] = {true, values[k], BlendMode::mix, 0.9f};
    const float z = box.min[2] + s.height * (box.max[2] - box.min[2]);
    const std::vector<float> xyz = ring_stroke(dense, z, 0.02f * extent, s.outer);
    if (xyz.empty()) continue;
    painter.begin(b);
    painter.stroke_world(xyz);
    dabs += painter.end().dabs;
  }
  save_lot(texture, dir / "torus.lot");
  Mesh painted = dense;
  painted.colors = bake_vertex_colors(texture.color, dense);
  write_mesh(painted, dir / "torus-painted.glb");
  const OctreeTextureStats ts = texture.color.stats();
  const size_t rmh_bytes = texture.rmh ? texture.rmh->stats().bytes : 0;
  const double t_paint = sw.lap();
  fmt::print(stderr, " {} dabs, {} texels, {:.1f} bytes per texel ({:.0f} ms)\n", dabs,
             ts.painted_samples, ts.bytes_per_painted_texel, t_paint);
  md += fmt::format(
      "\nPaint: four scripted strokes ({} dabs), each carrying a material (red metal, matte blue, "
      "a raised green ridge, gold), into adaptive octree textures (no UVs), leaves down to level "
      "9 only under the brush: base colour {} painted texels, {} bytes ({:.1f} per painted "
      "texel), max depth {}; roughness, metallic and height {} bytes; the colour baked to vertex "
      "colours ([torus-painted.glb](torus-painted.glb), texture [torus.lot](torus.lot)). {:.0f} "
      "ms.\n\n",
      dabs, ts.painted_samples, ts.bytes, ts.bytes_per_painted_texel, ts.max_depth, rmh_bytes,
      t_paint);
  if (gl) {
    // The limit surface drawn by the tessellation shaders, shaded per fragment by the material
    // looked up on the GPU (no baking, no UVs).
    const std::vector<float> table_points = table.points(cage.positions);
    PatchDrawer drawer(cage, table, table_points);
    GpuOctreeTexture gpu_texture(texture.color);
    std::optional<GpuOctreeTexture> gpu_rmh;
    if (texture.rmh) gpu_rmh.emplace(*texture.rmh);
    DrawOptions o;
    o.texture = &gpu_texture;
    o.material = gpu_rmh ? &*gpu_rmh : nullptr;
    o.height_scale = texture.height_scale;
    target->begin(kWhite);
    drawer.draw(overview(cage), o);
    save_image(*target, dir / "painted.png");
    md += "![painted](painted.png)\n\n";
  }
  j["paint"] = {{"dabs", dabs},
                {"painted_texels", ts.painted_samples},
                {"bytes", ts.bytes},
                {"material_bytes", rmh_bytes},
                {"max_depth", ts.max_depth},
                {"ms", t_paint}};
  sw.lap();

  // The paint out to a standard texture: an automatic atlas on a lighter tessellation of the same
  // surface, the texture baked into it, a GLB whose material carries it.
  TessellateOptions light = to;
  light.factor = 2;
  const Mesh coarse = tessellate_patches(cage, table, table.points(cage.positions), light);
  fmt::print(stderr, "atlas: {} triangles ...", coarse.face_count());
  std::fflush(stderr);
  UnwrapOptions uo;
  uo.size = 512;
  const UnwrapResult atlas = unwrap_mesh(coarse, uo, "torus");
  const MaterialImages baked = bake_material(texture, atlas.mesh, uo.size, uo.size, 8, {}, true);
  GlbTextures material;
  material.base_color_png = encode_png(baked.base_color);
  material.metallic_roughness_png = encode_png(baked.metallic_roughness);
  material.normal_png = encode_png(baked.normal);
  material.metallic = material.roughness = 1;  // the texture's values as they are
  std::string glb;
  write_glb(atlas.mesh, material, glb);
  const std::vector<uint8_t> layout = uv_layout_image(atlas.mesh, atlas.face_chart, uo.size);
  write_png(dir / "torus-atlas.png", uo.size, uo.size, layout);
  const std::vector<std::pair<std::filesystem::path, std::string>> files = {
      {dir / "torus-basecolor.png", material.base_color_png},
      {dir / "torus-metallic-roughness.png", material.metallic_roughness_png},
      {dir / "torus-normal.png", material.normal_png},
      {dir / "torus-height.png", encode_png16(baked.height)},
      {dir / "torus-textured.glb", glb}};
  write_files_atomic(files);
  write_mesh(atlas.mesh, dir / "torus-atlas.obj");
  const UnwrapStats& us = atlas.stats;
  const double t_atlas = sw.lap();
  fmt::print(stderr, " {} charts, {:.1f}% used, stretch {:.4f} ({:.0f} ms)\n", us.charts,
             100 * us.utilization, us.stretch_l2, t_atlas);
  md += fmt::format(
      "Atlas and bake: the surface tessellated more lightly ({} triangles) and unwrapped into {} "
      "charts on a {}x{} atlas ({:.1f}% of it used with {}-texel gutters, Sander stretch L2 "
      "{:.4f}); the material baked into it: base colour, roughness (green) and metalness (blue) "
      "packed as glTF wants them, a normal map of the height (and the height itself, 16-bit: "
      "[torus-height.png](torus-height.png)), all carried by the material of "
      "[torus-textured.glb](torus-textured.glb) (mesh with its UVs: "
      "[torus-atlas.obj](torus-atlas.obj)). {:.0f} ms.\n\n"
      "| atlas (a colour per chart) | base colour | metallic-roughness | normal map |\n"
      "|---|---|---|---|\n"
      "| ![atlas](torus-atlas.png) | ![baked](torus-basecolor.png) | "
      "![metallic-roughness](torus-metallic-roughness.png) | ![normal](torus-normal.png) |\n\n",
      coarse.face_count(), us.charts, uo.size, uo.size, 100 * us.utilization, uo.padding,
      us.stretch_l2, t_atlas);
  j["atlas"] = {
      {"triangles", coarse.face_count()}, {"charts", us.charts},         {"size", uo.size},
      {"utilization", us.utilization},    {"stretch_l2", us.stretch_l2}, {"ms", t_atlas}};
  return dense;
}

// The third: the painted surface simplified back to a few polygons.
void workflow_simplify(const std::filesystem::path& dir, std::string& md, nlohmann::json& j,
                       Stopwatch& sw, GlContext* gl, RenderTarget* target, const Mesh& cage,
                       const Mesh& dense) {
  VsaOptions vo;
  vo.proxies = 40;
  vo.meshing.polygons = true;
  fmt::print(stderr, "simplify: {} faces to {} proxies ...", dense.face_count(), vo.proxies);
  std::fflush(stderr);
  const VsaResult r = simplify_vsa(dense, vo, "torus-limit");
  write_mesh(r.output.mesh, dir / "torus-simplified.obj");
  const double t_simplify = sw.lap();
  fmt::print(stderr, " {} polygons ({:.0f} ms)\n", r.output.mesh.face_count(), t_simplify);
  md += fmt::format(
      "Simplify: variational shape approximation (greedy optimiser) of the {} triangles into {} "
      "clusters, E = {:.4g}, meshed as {} polygons ([torus-simplified.obj](torus-simplified.obj)). "
      "{:.0f} ms.\n\n",
      dense.face_count(), r.stats.clusters, r.stats.energy, r.output.mesh.face_count(), t_simplify);
  if (gl) {
    const Camera cam = overview(cage);
    MeshDrawer partition(dense, cluster_colors(r.labels));
    target->begin(kWhite);
    partition.draw(cam, DrawOptions{});
    save_image(*target, dir / "partition.png");
    MeshDrawer simplified(r.output.mesh, cluster_colors(r.output.face_cluster), true);
    target->begin(kWhite);
    DrawOptions o;
    o.outline = true;
    simplified.draw(cam, o);
    save_image(*target, dir / "simplified.png");
    md +=
        "| partition | polygons |\n|---|---|\n| ![partition](partition.png) | "
        "![simplified](simplified.png) |\n\n";
  }
  j["simplify"] = {{"faces", dense.face_count()},
                   {"clusters", r.stats.clusters},
                   {"energy", r.stats.energy},
                   {"polygons", r.output.mesh.face_count()},
                   {"ms", t_simplify}};
}

// The workflow on the procedural torus (extraordinary vertices of valence 3, 5, 6 and 8).
void workflow(const std::filesystem::path& dir, std::string& md, nlohmann::json& report) {
  Stopwatch sw;
  const Mesh cage = make_shape("torus");
  md += fmt::format(
      "\n## The workflow on the `torus` cage ({} quads)\n\n"
      "Adaptive limit surface (per-vertex depth from the camera, 0.5 px tolerance), drawn on the "
      "GPU with tessellation shaders; colours show each patch's refinement level (blue shallow, "
      "red deep), lines the patch outlines. The near camera looks at the valence-{} vertex.\n\n",
      cage.face_count(), 8);
  nlohmann::json j;
  std::unique_ptr<GlContext> gl;
  try {
    gl = std::make_unique<GlContext>();
  } catch (const std::exception& e) {
    fmt::print(stderr, "demo: no OpenGL, images skipped ({})\n", e.what());
    md += fmt::format("No OpenGL context ({}): images skipped.\n\n", e.what());
  }
  std::unique_ptr<RenderTarget> target;  // made by the first step, once timed
  PatchOptions po;
  po.subdiv = subdiv_options(cage);
  po.depth = 10;
  workflow_surface(dir, md, j, sw, gl.get(), target, cage, po);
  const Mesh dense = workflow_paint(dir, md, j, sw, gl.get(), target.get(), cage, po);
  workflow_simplify(dir, md, j, sw, gl.get(), target.get(), cage, dense);
  if (gl) j["renderer"] = gl->renderer();
  report["workflow"] = j;
}

}  // namespace

LIMN_GL_ENTRY void limn_cli_demo(const DemoJob& job) {
  namespace fs = std::filesystem;
  const fs::path dir(job.dir);
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(fmt::format("{}: exists and is not a folder", job.dir));
  fs::create_directories(dir, ec);
  if (ec)
    throw std::runtime_error(fmt::format("{}: cannot create folder: {}", job.dir, ec.message()));

  const std::vector<DemoShape> shapes = {
      {"cube", "unit cube, 6 quads", true},
      {"torus", "quad torus with extraordinary vertices of valence 3, 5, 6, 8", true},
      {"cage", "open box with sharp and semi-sharp creases, corners, a hole and a boundary", true},
      {job.quick ? "terrain-small" : "terrain",
       "terrain height field with scattered extraordinary vertices", job.quick},
      {job.quick ? "torus-dense-small" : "torus-dense",
       "torus-like cage, about one extraordinary vertex in ten", job.quick},
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
      for (const char* ext : {".obj", ".glb"}) write_mesh(mesh, dir / (std::string(s.name) + ext));
      out = fmt::format("[{0}.obj]({0}.obj), [{0}.glb]({0}.glb)", s.name);
    }
    fmt::print(stderr, " done ({:.0f} ms)\n", sw.ms());
    std::string valences;
    for (auto [k, n] : st.valence_histogram) valences += fmt::format("{}:{} ", k, n);
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {:.1f} | {:.1f} | {} |\n", s.name,
                      st.vertices, st.faces, st.edges, st.extraordinary_vertices, valences,
                      st.boundary_loops, st.genus, t_build, t_topo, out);
    nlohmann::json j = stats_json(st);
    j["shape"] = s.name;
    j["description"] = s.what;
    j["timings_ms"] = {{"build", t_build}, {"topology", t_topo}, {"analysis", t_analyze}};
    report["shapes"].push_back(j);
  }
  workflow(dir, md, report);
  md += "\nShapes:\n\n";
  for (const auto& s : shapes) md += fmt::format("- `{}`: {}\n", s.name, s.what);
  md += fmt::format("\nTotal time {:.0f} ms.\n", total.ms());
  report["total_ms"] = total.ms();
  write_file_atomic(dir / "report.md", md);
  write_file_atomic(dir / "report.json", report.dump(2) + "\n");
  fmt::print(stderr, "wrote {}\n", (dir / "report.md").string());
  if (job.json) fmt::print("{}\n", report.dump(2));
}

}  // namespace limn::cli
