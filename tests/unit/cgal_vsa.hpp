// CGAL 5.5's Variational_shape_approximation run on a limn mesh: the peer the simplify layer is
// compared with (tests: energy oracle; bench: speed). L21 metric (CGAL's default plane proxy),
// hierarchical seeding, a fixed number of Lloyd iterations, then CGAL's own meshing.
#pragma once

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Variational_shape_approximation.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <iterator>
#include <stdexcept>
#include <vector>

#include "limn/mesh/mesh.hpp"

namespace limn::test {

struct CgalVsaResult {
  std::vector<uint32_t> labels;  ///< proxy per face, in limn's face order
  size_t proxies = 0;
  double seeding_ms = 0, iterations_ms = 0, meshing_ms = 0;
  std::vector<std::array<std::size_t, 3>> triangles;  ///< CGAL's output triangles (anchors)
  size_t anchors = 0;
  bool manifold = false;  ///< what extract_mesh says of its output
};

/// A copy of `m` scaled about the origin so its bounding-box diagonal is 1 (E then compares with
/// the figures in ../shared/design/vsa.md).
inline Mesh unit_diagonal(const Mesh& m) {
  Mesh out = m;
  const Box b = bounding_box(m);
  const double d = b.diagonal();
  for (float& x : out.positions) x = static_cast<float>(double(x) / d);
  return out;
}

/// Runs CGAL VSA on a triangle mesh. `mesh_output` false skips extract_mesh.
inline CgalVsaResult run_cgal_vsa(const Mesh& m, size_t proxies, size_t iterations,
                                  bool mesh_output = true) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using SM = CGAL::Surface_mesh<Kernel::Point_3>;
  using Vpm = boost::property_map<SM, boost::vertex_point_t>::type;
  using Approx = CGAL::Variational_shape_approximation<SM, Vpm>;
  using Metric = Approx::Error_metric;
  namespace VSA = CGAL::Surface_mesh_approximation;
  auto ms = [] {
    return std::chrono::duration<double, std::milli>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  };
  SM sm;
  std::vector<SM::Vertex_index> vi;
  vi.reserve(m.vertex_count());
  for (size_t v = 0; v < m.vertex_count(); ++v)
    vi.push_back(sm.add_vertex(
        Kernel::Point_3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2])));
  for (size_t f = 0; f < m.face_count(); ++f) {
    const auto fv = m.face(f);
    if (fv.size() != 3) throw std::invalid_argument("CGAL VSA needs triangles");
    if (sm.add_face(vi[fv[0]], vi[fv[1]], vi[fv[2]]) == SM::null_face())
      throw std::invalid_argument("CGAL Surface_mesh refused a face");
  }
  Vpm vpm = get(boost::vertex_point, sm);
  Metric metric(sm, vpm);
  Approx approx(sm, vpm, metric);
  CgalVsaResult r;
  double t = ms();
  approx.initialize_seeds(
      CGAL::parameters::seeding_method(VSA::HIERARCHICAL).max_number_of_proxies(proxies));
  r.seeding_ms = ms() - t;
  t = ms();
  approx.run(iterations);
  r.iterations_ms = ms() - t;
  if (mesh_output) {
    t = ms();
    r.manifold = approx.extract_mesh(CGAL::parameters::default_values());
    approx.indexed_triangles(std::back_inserter(r.triangles));
    r.meshing_ms = ms() - t;
    std::vector<Kernel::Point_3> anchors;
    approx.anchor_points(std::back_inserter(anchors));
    r.anchors = anchors.size();
  }
  r.proxies = approx.number_of_proxies();
  auto fpm = sm.add_property_map<SM::Face_index, std::size_t>("f:limn_proxy", 0).first;
  approx.proxy_map(fpm);
  r.labels.resize(m.face_count());
  for (SM::Face_index f : sm.faces()) r.labels[size_t(f)] = static_cast<uint32_t>(fpm[f]);
  return r;
}

}  // namespace limn::test
