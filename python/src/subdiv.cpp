// Stencil tables for Python: cage points to a refinement level's (or its limit's) in one pass,
// for animated cages (apply again to new cage positions, no rebuild).
#include <fmt/format.h>
#include <pybind11/numpy.h>

#include <algorithm>

#include "arrays.hpp"
#include "bindings.hpp"
#include "jobs.hpp"
#include "limn/subdiv/refine.hpp"

namespace limn::py_bind {

namespace {

struct Stencils {
  StencilTable table;
  size_t sources = 0;  ///< points a table reads: its largest index + 1
};

Stencils stencils_for(const Mesh& cage, int level, bool limit) {
  const UniformRefinement r = refine_uniform(cage, level, subdiv_options(cage));
  Stencils s;
  if (level == 0) {  // the identity over the cage
    for (uint32_t v = 0; v < cage.vertex_count(); ++v) {
      s.table.indices.push_back(v);
      s.table.weights.push_back(1.0f);
      s.table.offsets.push_back(v + 1);
    }
  } else {
    s.table = cage_stencils(r, level);
  }
  if (limit) s.table = compose_stencils(limit_stencils(r, level).position, s.table);
  for (uint32_t i : s.table.indices) s.sources = std::max<size_t>(s.sources, size_t(i) + 1);
  return s;
}

}  // namespace

void bind_subdiv(py::module_& m) {
  py::class_<Stencils>(m, "StencilTable", R"(Weights that turn a cage's points into the points of
a refinement level (or of its limit surface) in one pass: row i is
sum(weights[k] * points[indices[k]] for k in offsets[i]:offsets[i + 1]).)")
      .def_property_readonly(
          "size", [](const Stencils& s) { return s.table.size(); },
          "Points the table makes (rows).")
      .def_property_readonly(
          "source_count", [](const Stencils& s) { return s.sources; },
          "Points the table reads (the cage's vertices it uses).")
      .def_property_readonly(
          "offsets",
          [](py::object self) { return view(self.cast<Stencils&>().table.offsets, 0, self); },
          "(size + 1,) uint32: row i spans entries offsets[i]:offsets[i + 1]")
      .def_property_readonly(
          "indices",
          [](py::object self) { return view(self.cast<Stencils&>().table.indices, 0, self); },
          "(entries,) uint32: the source point of each entry")
      .def_property_readonly(
          "weights",
          [](py::object self) { return view(self.cast<Stencils&>().table.weights, 0, self); },
          "(entries,) float32: the weight of each entry")
      .def(
          "apply",
          [](const Stencils& s, py::handle points) {
            py::array a = py::array::ensure(points);
            if (!a || a.ndim() != 2 || a.shape(1) < 1 || a.shape(1) > 16)
              throw InputError("points: expected an (n, c) array of numbers, 1 <= c <= 16");
            const size_t channels = size_t(a.shape(1));
            const std::vector<float> in = floats(a, "points", channels);
            if (in.size() / channels < s.sources)
              throw InputError(fmt::format("points: {} rows, the table reads {}",
                                           in.size() / channels, s.sources));
            std::vector<float> out(s.table.size() * channels);
            {
              py::gil_scoped_release unlocked;
              apply_stencils(s.table, in.data(), out.data(), int(channels));
            }
            const auto rows = py::ssize_t(s.table.size());
            return owned(std::move(out), {rows, py::ssize_t(channels)});
          },
          py::arg("points"),
          "The table applied to (n, c) float data per cage point (positions, colours, ...): "
          "(size, c) float32. Sums in double; parallel.");
  m.def(
      "_stencils",
      [](const Mesh& cage, int level, bool limit) {
        Stencils s;
        jobs::UniformOutcome refined;
        {
          py::gil_scoped_release unlocked;
          refined = jobs::subdivide_uniform(cage, level, limit, "mesh", jobs::Names::python);
          s = stencils_for(cage, level, limit);
        }
        return py::make_tuple(std::move(s), std::move(refined.mesh));
      },
      py::arg("cage"), py::arg("level"), py::arg("limit"));
}

}  // namespace limn::py_bind
