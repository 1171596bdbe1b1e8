#include "common.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <filesystem>

#include <sstream>

namespace limn::cli {

MeshFormat parse_format_option(const std::string& value, const char* option) {
  if (value.empty()) return MeshFormat::automatic;
  const MeshFormat f = format_from_name(value);
  if (f == MeshFormat::automatic)
    throw InputError(
        fmt::format("{}: unknown format '{}' (obj, ply, off, stl, gltf, glb)", option, value));
  return f;
}

WriteOptions output_options(const std::string& out, const std::string& to, bool ascii) {
  WriteOptions w;
  w.format = parse_format_option(to, "--to");
  w.ascii = ascii;
  const MeshFormat f = w.format == MeshFormat::automatic ? format_from_path(out) : w.format;
  if (f == MeshFormat::automatic)
    throw InputError(
        fmt::format("{}: cannot tell the output format from the extension (use "
                    ".obj, .ply, .off, .stl or .glb, or --to)",
                    out));
  if (f == MeshFormat::gltf)
    throw InputError(
        fmt::format("{}: writing .gltf is not supported (limn writes binary glTF: use .glb)", out));
  return w;
}

Mesh read_input(const std::string& path, const std::string& format, bool weld,
                size_t* dropped_degenerate, const char* format_option) {
  ReadOptions r;
  r.format = parse_format_option(format, format_option);
  r.weld = weld;
  r.dropped_degenerate = dropped_degenerate;
  return read_mesh(path, r);
}

void add_weld_flag(CLI::App& cmd, bool& weld) {
  cmd.add_flag("--weld", weld,
               "glTF input: merge the vertices glTF splits at UV/normal seams into one cage "
               "vertex (needed to subdivide or simplify a glTF mesh as one surface)");
}

void add_repair_flags(CLI::App& cmd, RepairFlags& repair) {
  cmd.add_flag("--repair", repair.on,
               "Repair the mesh first, as `limn repair` does (weld, drop degenerate and duplicate "
               "faces, orient, split non-manifold edges and vertices); counts on stderr and in "
               "--json");
  cmd.add_option("--weld-tolerance", repair.tolerance,
                 "With --repair: weld vertices closer than this fraction of the bounding-box "
                 "diagonal (0: only equal positions)")
      ->check(CLI::Range(0.0, 0.1));
}

Mesh read_soup(const std::string& path, ReadOptions r, size_t& dropped) {
  r.soup = true;
  r.dropped_degenerate = &dropped;
  return read_mesh(path, r);
}

Mesh repair_input(const Mesh& soup, size_t dropped, const std::string& path, double tolerance,
                  RepairReport& report) {
  if (soup.face_count() == 0) throw InputError(fmt::format("{}: no faces to repair", path));
  RepairOptions options;
  options.weld_tolerance = tolerance;
  Mesh out = repair_mesh(soup, options, &report);
  report.degenerate_faces += dropped;  // STL and glTF drop theirs while reading
  if (out.face_count() == 0)
    throw InputError(fmt::format("{}: nothing left after repair: all {} faces are degenerate", path,
                                 soup.face_count() + dropped));
  fmt::print(stderr, "limn: repair {}: {}\n", path, repair_summary(report));
  return out;
}

Mesh read_input(const std::string& path, const std::string& format, bool weld,
                const RepairFlags& repair, nlohmann::json& report) {
  if (!repair.on) {
    report = nullptr;
    return read_input(path, format, weld);
  }
  ReadOptions r;
  r.format = parse_format_option(format, "--format");
  r.weld = weld;
  size_t dropped = 0;
  const Mesh soup = read_soup(path, r, dropped);
  RepairReport counts;
  Mesh out = repair_input(soup, dropped, path, repair.tolerance, counts);
  report = repair_json(counts);
  return out;
}

std::string repair_summary(const RepairReport& r) {
  std::vector<std::string> parts;
  const auto add = [&](size_t n, const char* one, const char* many) {
    if (n) parts.push_back(fmt::format("{} {}", n, n == 1 ? one : many));
  };
  add(r.welded_vertices, "vertex welded", "vertices welded");
  add(r.degenerate_faces, "degenerate face dropped", "degenerate faces dropped");
  add(r.split_faces, "pinched face split", "pinched faces split");
  add(r.duplicate_faces, "duplicate face dropped", "duplicate faces dropped");
  add(r.flipped_faces, "face flipped", "faces flipped");
  add(r.non_manifold_edges, "non-manifold edge cut", "non-manifold edges cut");
  add(r.unorientable_edges, "unorientable edge cut", "unorientable edges cut");
  add(r.split_vertices, "vertex copy added", "vertex copies added");
  add(r.unreferenced_vertices, "unreferenced vertex dropped", "unreferenced vertices dropped");
  const std::string pieces = fmt::format("{} piece{} ({} closed)", r.components,
                                         r.components == 1 ? "" : "s", r.closed_components);
  if (parts.empty()) return "nothing to repair; " + pieces;
  return fmt::format("{}; {}", fmt::join(parts, ", "), pieces);
}

nlohmann::json write_output(const Mesh& mesh, const std::string& path,
                            std::vector<std::string> lost, const WriteOptions& opt) {
  MeshFormat format = opt.format;
  if (format == MeshFormat::automatic) format = format_from_path(path);
  for (std::string& d : dropped_attributes(mesh, format))
    if (std::find(lost.begin(), lost.end(), d) == lost.end()) lost.push_back(std::move(d));
  write_mesh(mesh, path, opt);
  if (!lost.empty())
    fmt::print(stderr, "limn: warning: {}: dropped {} (not carried to this output)\n", path,
               fmt::join(lost, ", "));
  return nlohmann::json(lost);
}

std::string stats_text(const MeshStats& s) {
  std::string arity, valence;
  for (auto [k, n] : s.faces_by_arity) arity += fmt::format(" {}-gons: {}", k, n);
  for (auto [k, n] : s.valence_histogram) valence += fmt::format(" {}:{}", k, n);
  std::string out;
  out += fmt::format("vertices        {} ({} unreferenced)\n", s.vertices, s.unreferenced_vertices);
  out +=
      fmt::format("faces           {} ({})\n", s.faces, arity.empty() ? "none" : arity.substr(1));
  out += fmt::format("edges           {} ({} boundary, {} non-manifold)\n", s.edges,
                     s.boundary_edges, s.non_manifold_edges);
  out += fmt::format("boundary loops  {}\n", s.boundary_loops);
  out += fmt::format("components      {}\n", s.components);
  out += fmt::format("euler char.     {}\n", s.euler_characteristic);
  out += fmt::format("genus           {}\n",
                     s.genus >= 0 ? std::to_string(s.genus) : std::string("n/a (non-manifold)"));
  out += fmt::format("non-manifold    {} edges, {} vertices\n", s.non_manifold_edges,
                     s.non_manifold_vertices);
  out += fmt::format("orientation     {}\n",
                     s.inconsistent_edges == 0
                         ? std::string("consistent")
                         : fmt::format("{} inconsistent edges", s.inconsistent_edges));
  out += fmt::format("degenerate      {} zero-area faces\n", s.degenerate_faces);
  out +=
      fmt::format("extraordinary   {} vertices; valences{}\n", s.extraordinary_vertices, valence);
  out +=
      fmt::format("tags            {} crease edges ({} infinitely sharp), {} corners, {} holes\n",
                  s.crease_edges, s.infinitely_sharp_creases, s.corner_vertices, s.hole_faces);
  if (!s.bbox.empty())
    out += fmt::format(
        "bbox            [{:.6g} {:.6g} {:.6g}] - [{:.6g} {:.6g} {:.6g}] (diag {:.6g})\n",
        s.bbox.min[0], s.bbox.min[1], s.bbox.min[2], s.bbox.max[0], s.bbox.max[1], s.bbox.max[2],
        s.bbox.diagonal());
  const std::string uvs =
      s.has_uvs ? fmt::format("{} values, {} seam edges", s.uv_values, s.uv_seam_edges) : "no";
  out += fmt::format("attributes      normals: {}, uvs: {}, colours: {}\n",
                     s.has_normals ? "yes" : "no", uvs, s.has_colors ? "yes" : "no");
  return out;
}

std::vector<float> parse_numbers(const std::string& s, const char* option) {
  std::vector<float> v;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stof(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError(fmt::format("{} {}: '{}' is not a number", option, s, item));
    }
  }
  return v;
}

void check_writable_folder(const std::string& path, const char* what) {
  const std::filesystem::path dir = std::filesystem::absolute(path).parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw InputError(fmt::format("{}: the {} folder {} does not exist", path, what, dir.string()));
}

}  // namespace limn::cli
