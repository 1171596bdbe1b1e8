#include "reports.hpp"

namespace limn::reports {

nlohmann::json stats_json(const MeshStats& s) {
  using nlohmann::json;
  json arity = json::object(), valence = json::object();
  for (auto [k, n] : s.faces_by_arity) arity[std::to_string(k)] = n;
  for (auto [k, n] : s.valence_histogram) valence[std::to_string(k)] = n;
  json j = {
      {"vertices", s.vertices},
      {"referenced_vertices", s.referenced_vertices},
      {"unreferenced_vertices", s.unreferenced_vertices},
      {"faces", s.faces},
      {"faces_by_arity", arity},
      {"corners", s.corners},
      {"edges", s.edges},
      {"boundary_edges", s.boundary_edges},
      {"boundary_loops", s.boundary_loops},
      {"components", s.components},
      {"euler_characteristic", s.euler_characteristic},
      {"genus", s.genus >= 0 ? json(s.genus) : json(nullptr)},
      {"closed", s.boundary_edges == 0},
      {"manifold", s.non_manifold_edges == 0 && s.non_manifold_vertices == 0},
      {"non_manifold_edges", s.non_manifold_edges},
      {"non_manifold_vertices", s.non_manifold_vertices},
      {"consistently_oriented", s.inconsistent_edges == 0},
      {"inconsistent_edges", s.inconsistent_edges},
      {"degenerate_faces", s.degenerate_faces},
      {"extraordinary_vertices", s.extraordinary_vertices},
      {"valence_histogram", valence},
      {"crease_edges", s.crease_edges},
      {"infinitely_sharp_crease_edges", s.infinitely_sharp_creases},
      {"corner_vertices", s.corner_vertices},
      {"hole_faces", s.hole_faces},
      {"surface_area", s.surface_area},
      {"has_normals", s.has_normals},
      {"has_uvs", s.has_uvs},
      {"uv_values", s.uv_values},
      {"uv_seam_edges", s.uv_seam_edges},
      {"has_colors", s.has_colors},
  };
  if (s.bbox.empty()) {
    j["bbox"] = nullptr;
  } else {
    j["bbox"] = {{"min", {s.bbox.min[0], s.bbox.min[1], s.bbox.min[2]}},
                 {"max", {s.bbox.max[0], s.bbox.max[1], s.bbox.max[2]}},
                 {"diagonal", s.bbox.diagonal()}};
  }
  return j;
}

nlohmann::json repair_json(const RepairReport& r) {
  return {{"welded_vertices", r.welded_vertices},
          {"degenerate_faces", r.degenerate_faces},
          {"split_faces", r.split_faces},
          {"duplicate_faces", r.duplicate_faces},
          {"flipped_faces", r.flipped_faces},
          {"non_manifold_edges", r.non_manifold_edges},
          {"unorientable_edges", r.unorientable_edges},
          {"split_vertices", r.split_vertices},
          {"unreferenced_vertices", r.unreferenced_vertices},
          {"components", r.components},
          {"closed_components", r.closed_components}};
}

nlohmann::json texture_json(const OctreeTexture& t) {
  const OctreeTextureStats s = t.stats();
  return {
      {"nodes", s.nodes},
      {"general_nodes", s.general_nodes},
      {"bricks", s.bricks},
      {"leaves", s.leaf_cells},
      {"double_sided_leaves", s.double_cells},
      {"samples", s.samples},
      {"painted_samples", s.painted_samples},
      {"max_depth", s.max_depth},
      {"leaves_at_max_depth", s.leaves_at_depth},
      {"bytes", s.bytes},
      {"pool_words", s.pool_words},
      {"free_words", s.free_words},
      {"free_blocks", t.free_blocks().size()},
      {"bytes_per_painted_texel", s.bytes_per_painted_texel},
      {"cube", {{"origin", {t.origin()[0], t.origin()[1], t.origin()[2]}}, {"size", t.size()}}}};
}

nlohmann::json material_json(const MaterialTexture& m) {
  nlohmann::json j = texture_json(m.color);
  j["height_scale"] = m.height_scale;
  if (!m.rmh) {
    j["rmh"] = nullptr;
    return j;
  }
  const MaterialDefaults d = m.defaults();
  nlohmann::json r = texture_json(*m.rmh);
  r.erase("cube");
  r["defaults"] = {{"roughness", d.roughness}, {"metallic", d.metallic}, {"height", d.height}};
  j["rmh"] = std::move(r);
  return j;
}

nlohmann::json simplify_json(const Mesh& input, const VsaOptions& options, const VsaResult& r) {
  using nlohmann::json;
  const VsaStats& st = r.stats;
  const MeshingStats& ms = r.output.stats;
  const double diag = bounding_box(input).diagonal();
  size_t triangles = 0, polygons = 0;
  for (size_t f = 0; f < r.output.mesh.face_count(); ++f)
    ++(r.output.mesh.face_size(f) == 3 ? triangles : polygons);
  return {{"method", options.method == VsaMethod::lloyd ? "lloyd" : "greedy"},
          {"seeding", options.seeding.method == SeedingMethod::random ? "random" : "curvature"},
          {"proxies_requested", options.proxies},
          {"target_error", options.target_error > 0 ? json(options.target_error) : json(nullptr)},
          {"clusters", st.clusters},
          {"clusters_seeded", st.seeded},
          {"clusters_for_components", st.component_clusters},
          {"clusters_split", st.split_clusters},
          {"teleports", st.teleports},
          {"clusters_split_for_meshing", ms.cluster_splits},
          {"energy", st.energy},
          {"energy_per_area", st.total_area > 0 ? st.energy / st.total_area : 0.0},
          {"energy_unit_diagonal", diag > 0 ? st.energy / (diag * diag) : 0.0},
          {"surface_area", st.total_area},
          {"input_faces", input.face_count()},
          {"input_vertices", input.vertex_count()},
          {"output_vertices", r.output.mesh.vertex_count()},
          {"output_faces", r.output.mesh.face_count()},
          {"output_triangles", triangles},
          {"output_polygons", polygons},
          {"meshing",
           {{"split_threshold", options.meshing.split_threshold},
            {"anchors", ms.anchors},
            {"forced_anchors", ms.forced_anchors},
            {"chains", ms.chains},
            {"forced_chain_splits", ms.forced_splits},
            {"bridges", ms.bridges},
            {"polygons_written", ms.polygons},
            {"polygons_triangulated", ms.triangulated},
            {"clusters_fanned", ms.fans}}},
          {"greedy",
           {{"moves", st.greedy.moves},
            {"evaluations", st.greedy.evaluations},
            {"rounds", st.greedy.rounds},
            {"local_connectivity_checks", st.greedy.local_checks},
            {"searched_connectivity_checks", st.greedy.search_checks},
            {"refused_disconnecting", st.greedy.refused_disconnect},
            {"refused_search_budget", st.greedy.refused_budget}}},
          {"lloyd_iterations", st.lloyd.iterations}};
}

nlohmann::json distance_json(const SurfaceDistance& d) {
  return {{"hausdorff", d.hausdorff},
          {"rms", d.rms_to_reference},
          {"max_output_to_input", d.max_to_reference},
          {"max_input_to_output", d.max_from_reference},
          {"samples", d.samples},
          {"relative_to", "input bounding-box diagonal"}};
}

nlohmann::json simplify_timings_json(const VsaStats& st) {
  return {{"prepare", st.prepare_ms},
          {"seeding", st.seeding_ms},
          {"optimisation", st.optimise_ms},
          {"meshing", st.meshing_ms}};
}

}  // namespace limn::reports
