// Headless images as numpy arrays (the render layer through apps/common/render_job), and PNGs.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <cmath>

#include "arrays.hpp"
#include "bindings.hpp"
#include "limn/render/image.hpp"
#include "render_job.hpp"

namespace limn::py_bind {

std::optional<Camera> camera_arg(const std::optional<std::array<float, 7>>& camera) {
  if (!camera) return std::nullopt;
  const std::array<float, 7>& c = *camera;
  for (float x : c)
    if (!std::isfinite(x)) throw InputError("camera: not finite");
  if (!(c[6] > 0 && c[6] < 180))
    throw InputError(fmt::format("camera: fovy_deg {} must be in (0, 180)", c[6]));
  Camera cam;
  for (int k = 0; k < 3; ++k) cam.eye[k] = c[size_t(k)], cam.target[k] = c[size_t(k) + 3];
  cam.fovy_deg = c[6];
  return cam;
}

void check_image(int width, int height, int samples) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InputError(fmt::format("resolution {}x{}: each side must be 1-16384", width, height));
  if (samples < 1 || samples > 16)
    throw InputError(fmt::format("samples {}: must be 1-16", samples));
}

void bind_render(py::module_& m) {
  m.def(
      "_render_mesh",
      [](const Mesh& mesh, int width, int height, int samples, std::array<float, 4> background,
         std::optional<std::array<float, 7>> camera, bool flat, bool wireframe, float uv_checker,
         const MaterialTexture* texture, bool nearest) {
        check_image(width, height, samples);
        if (!(uv_checker >= 0 && uv_checker <= 1024))
          throw InputError(fmt::format("uv_checker {}: squares per UV unit, 0-1024", uv_checker));
        jobs::MeshRender r;
        r.width = width, r.height = height, r.samples = samples;
        std::copy(background.begin(), background.end(), r.background);
        r.camera = camera_arg(camera);
        r.flat = flat, r.wireframe = wireframe, r.uv_checker = uv_checker;
        r.texture = texture ? &texture->color : nullptr, r.nearest = nearest;
        r.rmh = texture && texture->rmh ? &*texture->rmh : nullptr;
        r.height_scale = texture ? texture->height_scale : 0.0f;
        jobs::RenderedImage image;
        {
          py::gil_scoped_release unlocked;
          image = jobs::render_mesh(mesh, r, "mesh", jobs::Names::python);
        }
        return py::make_tuple(owned(std::move(image.rgba), {height, width, 4}),
                              to_python(image.report));
      },
      py::arg("mesh"), py::arg("width"), py::arg("height"), py::arg("samples"),
      py::arg("background"), py::arg("camera"), py::arg("flat"), py::arg("wireframe"),
      py::arg("uv_checker"), py::arg("texture"), py::arg("nearest"));
  m.def(
      "read_png",
      [](const std::filesystem::path& path) {
        int w = 0, h = 0;
        std::vector<uint8_t> rgba;
        {
          py::gil_scoped_release unlocked;
          rgba = read_png(path, w, h);
        }
        return owned(std::move(rgba), {h, w, 4});
      },
      py::arg("path"), "A PNG as an (h, w, 4) uint8 array, rows top to bottom.");
  m.def(
      "_write_png",
      [](const std::filesystem::path& path,
         py::array_t<uint8_t, py::array::c_style | py::array::forcecast> image) {
        if (image.ndim() != 3 || image.shape(2) != 4)
          throw InputError("image: expected shape (h, w, 4) uint8 (RGBA)");
        const int h = int(image.shape(0)), w = int(image.shape(1));
        std::span<const uint8_t> px(image.data(), size_t(image.size()));
        py::gil_scoped_release unlocked;
        write_png(path, w, h, px);
      },
      py::arg("path"), py::arg("image"));
}

}  // namespace limn::py_bind
