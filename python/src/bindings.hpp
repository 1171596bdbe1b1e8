// The pieces of the _limn extension (module.cpp puts them together).
#pragma once

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>

namespace limn::py_bind {

namespace py = pybind11;

/// A JSON report as Python objects (dict, list, str, int, float, bool, None).
py::object to_python(const nlohmann::json& j);

void bind_mesh(py::module_& m);     ///< Mesh, read_mesh, _write_mesh, _info
void bind_jobs(py::module_& m);     ///< _simplify, _subdivide_uniform, _repair
void bind_render(py::module_& m);   ///< _render_mesh, read_png, _write_png
void bind_paint(py::module_& m);    ///< Texture, load_texture, _paint, _bake_*
void bind_subdiv(py::module_& m);   ///< StencilTable, _stencils
void bind_patches(py::module_& m);  ///< PatchTable, patches

}  // namespace limn::py_bind
