// The jobs of the CLI on meshes in memory (apps/common/jobs.hpp), with the GIL released while
// they run. limn/__init__.py wraps them with keyword arguments and result classes.
#include <pybind11/stl.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "jobs.hpp"
#include "limn/mesh/repair.hpp"
#include "reports.hpp"

namespace limn::py_bind {

void bind_jobs(py::module_& m) {
  m.def(
      "_simplify",
      [](const Mesh& mesh, std::optional<size_t> proxies, std::optional<double> target_error,
         size_t max_proxies, const std::string& method, const std::string& seeding, uint64_t seed,
         bool no_fill, size_t iterations, size_t teleports, double split_threshold, bool polygons,
         std::optional<size_t> distance) {
        jobs::SimplifyJob job;
        job.proxies = proxies;
        job.target_error = target_error;
        job.max_proxies = max_proxies;
        job.method = method;
        job.seeding = seeding;
        job.seed = seed;
        job.no_fill = no_fill;
        job.iterations = iterations;
        job.teleports = teleports;
        job.split_threshold = split_threshold;
        job.polygons = polygons;
        job.distance = distance;
        jobs::check(job, jobs::Names::python);
        jobs::SimplifyOutcome out;
        {
          py::gil_scoped_release unlocked;
          out = jobs::simplify(mesh, job, "mesh");
        }
        SimplifiedMesh& s = out.result.output;
        const auto faces_in = py::ssize_t(out.result.labels.size());
        const auto faces_out = py::ssize_t(s.face_cluster.size());
        const auto vertices_out = py::ssize_t(s.vertex_source.size());
        return py::make_tuple(std::move(s.mesh), owned(std::move(out.result.labels), {faces_in}),
                              owned(std::move(s.face_cluster), {faces_out}),
                              owned(std::move(s.vertex_source), {vertices_out}),
                              to_python(out.report));
      },
      py::arg("mesh"), py::arg("proxies"), py::arg("target_error"), py::arg("max_proxies"),
      py::arg("method"), py::arg("seeding"), py::arg("seed"), py::arg("no_fill"),
      py::arg("iterations"), py::arg("teleports"), py::arg("split_threshold"), py::arg("polygons"),
      py::arg("distance"));
  m.def(
      "_subdivide_uniform",
      [](const Mesh& cage, int level, bool limit) {
        jobs::UniformOutcome out;
        {
          py::gil_scoped_release unlocked;
          out = jobs::subdivide_uniform(cage, level, limit, "mesh", jobs::Names::python);
        }
        return py::make_tuple(std::move(out.mesh), to_python(out.report));
      },
      py::arg("cage"), py::arg("level"), py::arg("limit"));
  m.def(
      "_unwrap",
      [](const Mesh& mesh, double max_stretch, int size, std::optional<double> texels_per_unit,
         int tiles, int padding) {
        jobs::UnwrapJob job;
        job.max_stretch = max_stretch;
        job.size = size;
        job.texels_per_unit = texels_per_unit;
        job.tiles = tiles;
        job.padding = padding;
        jobs::check(job, jobs::Names::python);
        jobs::UnwrapOutcome out;
        {
          py::gil_scoped_release unlocked;
          out = jobs::unwrap(mesh, job, "mesh");
        }
        UnwrapResult& r = out.result;
        const auto faces = py::ssize_t(r.face_chart.size());
        const auto charts = py::ssize_t(r.chart_tile.size());
        return py::make_tuple(std::move(r.mesh), owned(std::move(r.face_chart), {faces}),
                              owned(std::move(r.chart_tile), {charts}), to_python(out.report));
      },
      py::arg("mesh"), py::arg("max_stretch"), py::arg("size"), py::arg("texels_per_unit"),
      py::arg("tiles"), py::arg("padding"));
  m.def(
      "_repair",
      [](const Mesh& soup, double weld_tolerance) {
        RepairOptions o;
        o.weld_tolerance = weld_tolerance;
        RepairReport report;
        Mesh out;
        {
          py::gil_scoped_release unlocked;
          out = repair_mesh(soup, o, &report);  // InputError for what validate_soup refuses
        }
        return py::make_tuple(std::move(out), to_python(reports::repair_json(report)));
      },
      py::arg("mesh"), py::arg("weld_tolerance"));
}

}  // namespace limn::py_bind
