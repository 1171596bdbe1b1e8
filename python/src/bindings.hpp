// The pieces of the _limn extension (module.cpp puts them together).
#pragma once

#include <pybind11/pybind11.h>

#include <array>
#include <nlohmann/json.hpp>
#include <optional>

#include "limn/subdiv/depth.hpp"

namespace limn::py_bind {

namespace py = pybind11;

/// A JSON report as Python objects (dict, list, str, int, float, bool, None).
py::object to_python(const nlohmann::json& j);

/// A camera given as (ex, ey, ez, tx, ty, tz, fovy_deg), checked (finite, 0 < fovy < 180);
/// none stays none (the mesh framed, jobs::view_camera).
std::optional<Camera> camera_arg(const std::optional<std::array<float, 7>>& camera);
/// InputError unless the image is 1-16384 pixels a side and samples 1-16.
void check_image(int width, int height, int samples);

void bind_mesh(py::module_& m);     ///< Mesh, read_mesh, _write_mesh, _info
void bind_jobs(py::module_& m);     ///< _simplify, _subdivide_uniform, _repair
void bind_render(py::module_& m);   ///< _render_mesh, read_png, _write_png
void bind_paint(py::module_& m);    ///< Texture, load_texture, _paint, _bake_*
void bind_subdiv(py::module_& m);   ///< StencilTable, _stencils
void bind_patches(py::module_& m);  ///< PatchTable, patches

}  // namespace limn::py_bind
