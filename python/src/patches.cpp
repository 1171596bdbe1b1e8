// Feature-adaptive patch tables for Python: limit evaluation at (ptex face, u, v) arrays with
// derivatives, and watertight tessellation, as `limn subdivide --adaptive` makes them.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <memory>
#include <optional>

#include "arrays.hpp"
#include "bindings.hpp"
#include "jobs.hpp"
#include "limn/paint/material.hpp"
#include "limn/subdiv/depth.hpp"
#include "limn/subdiv/patches.hpp"
#include "limn/subdiv/refine.hpp"
#include "limn/subdiv/tessellate.hpp"
#include "render_job.hpp"

namespace limn::py_bind {

namespace {

// Every patch of a cage down to a depth, with its measured errors (what `limn subdivide
// --adaptive --tolerance PX --errors measured` builds once for all views).
struct Hierarchy {
  Mesh cage;
  PatchHierarchy hierarchy;
  VertexErrorModel model;
  std::vector<float> points;
  int max_depth = 0;
};

// A table with the cage it was built from and its points, ready to evaluate. A selection from a
// hierarchy (`from`) reads the hierarchy's cage and points, shared by every selection: nothing
// is copied per view, and a pose set through one selection is every selection's.
struct Patches {
  PatchTable table;
  std::unique_ptr<PatchMap> map;
  std::shared_ptr<Hierarchy> from;
  Mesh own_cage;  // a table of its own (patches()): its cage and points
  std::vector<float> own_points;

  const Mesh& cage() const { return from ? from->cage : own_cage; }
  const std::vector<float>& points() const { return from ? from->points : own_points; }
  // Sets new cage positions and the patch points from them (same vertex count).
  void pose(std::vector<float> positions) {
    Mesh& c = from ? from->cage : own_cage;
    c.positions = std::move(positions);
    if (from)
      from->points = from->hierarchy.table.points(c.positions);
    else
      own_points = table.points(c.positions);
  }
};

// The camera a view's depths are chosen for, with the options every depth selection checks.
Camera depth_view(const Mesh& cage, int width, int height,
                  const std::optional<std::array<float, 7>>& camera, float tolerance) {
  if (width < 1 || height < 1 || width > 32768 || height > 32768)
    throw InputError(fmt::format("resolution {}x{}: each side must be 1-32768", width, height));
  if (!(tolerance > 0 && std::isfinite(tolerance)))
    throw InputError(fmt::format("tolerance {}: must be a positive number of pixels", tolerance));
  return jobs::view_camera(cage, width, height, camera_arg(camera));
}

std::vector<uint8_t> depths_arg(py::handle depths, size_t vertices, const char* what) {
  std::vector<uint8_t> out;
  for (uint32_t d : indices(depths, what, 0, 17)) out.push_back(uint8_t(d));
  if (out.size() != vertices)
    throw InputError(fmt::format("{}: {} entries for {} vertices", what, out.size(), vertices));
  return out;
}

}  // namespace

void bind_patches(py::module_& m) {
  py::class_<Patches>(m, "PatchTable", R"(A feature-adaptive patch table over a cage (limn
subdivide --adaptive): regular B-spline patches where the surface is regular, end caps around
extraordinary vertices isolated to their depth. Evaluates the limit surface exactly.)")
      .def_property_readonly(
          "regular_count", [](const Patches& p) { return p.table.regular_params.size(); },
          "Regular (B-spline) patches.")
      .def_property_readonly(
          "gregory_count", [](const Patches& p) { return p.table.gregory_params.size(); },
          "End caps (Gregory patches) around extraordinary vertices at their depth.")
      .def_property_readonly(
          "ptex_count", [](const Patches& p) { return p.table.ptex_count; },
          "Ptex faces: one per cage quad, one per corner of other faces.")
      .def_property_readonly(
          "point_count", [](const Patches& p) { return p.points().size() / 3; },
          "Control points the patches read (cage, refined and end-cap points).")
      .def_property_readonly(
          "ptex_of_face",
          [](py::object self) { return view(self.cast<Patches&>().table.ptex_of_face, 0, self); },
          "(faces + 1,) uint32: the first ptex face of each cage face")
      .def(
          "update",
          [](Patches& p, py::handle positions) {
            std::vector<float> cage = floats(positions, "positions", 3);
            if (cage.size() != p.cage().positions.size())
              throw InputError(fmt::format("positions: {} rows, the cage has {}", cage.size() / 3,
                                           p.cage().vertex_count()));
            py::gil_scoped_release unlocked;
            p.pose(std::move(cage));
          },
          py::arg("positions"),
          "New cage positions (an animated cage): the patch points again, nothing refined. For "
          "a selection, the hierarchy's points: every selection from it sees the new pose.")
      .def(
          "evaluate",
          [](const Patches& p, py::handle ptex, py::handle u, py::handle v) {
            const std::vector<uint32_t> faces = indices(ptex, "ptex", 0, p.table.ptex_count);
            const std::vector<float> us = floats(u, "u", 0), vs = floats(v, "v", 0);
            if (us.size() != faces.size() || vs.size() != faces.size())
              throw InputError("ptex, u and v: expected arrays of one length");
            for (size_t i = 0; i < us.size(); ++i)
              if (!(us[i] >= 0 && us[i] <= 1 && vs[i] >= 0 && vs[i] <= 1))
                throw InputError(
                    fmt::format("u, v: ({}, {}) at {} is outside [0, 1]", us[i], vs[i], i));
            const size_t n = faces.size();
            std::vector<float> pos(3 * n), du(3 * n), dv(3 * n);
            {
              py::gil_scoped_release unlocked;
              std::vector<PatchCoord> coords(n);
              for (size_t i = 0; i < n; ++i) coords[i] = p.map->find(faces[i], us[i], vs[i]);
              evaluate_patches(p.table, p.points(), coords, pos.data(), du.data(), dv.data());
            }
            const auto rows = py::ssize_t(n);
            return py::make_tuple(owned(std::move(pos), {rows, 3}), owned(std::move(du), {rows, 3}),
                                  owned(std::move(dv), {rows, 3}));
          },
          py::arg("ptex"), py::arg("u"), py::arg("v"),
          R"(Limit positions and first derivatives (per ptex unit) at (ptex, u, v) arrays:
(positions, du, dv), each (n, 3) float32. u, v in [0, 1].)")
      .def(
          "_render",
          [](const Patches& p, int width, int height, int samples, std::array<float, 4> background,
             std::optional<std::array<float, 7>> camera, bool wireframe, bool depth_colors,
             int tess, float tess_px, const MaterialTexture* texture, bool nearest) {
            check_image(width, height, samples);
            if (tess < 0 || tess > 32) throw InputError(fmt::format("tess {}: must be 1-32", tess));
            if (!(tess_px > 0 && std::isfinite(tess_px)))
              throw InputError(
                  fmt::format("tess_px {}: must be a positive number of pixels", tess_px));
            jobs::MeshRender r;
            r.width = width, r.height = height, r.samples = samples;
            std::copy(background.begin(), background.end(), r.background);
            r.camera = camera_arg(camera);
            r.wireframe = wireframe, r.depth_colors = depth_colors;
            r.factor = tess, r.pixels_per_segment = tess_px;
            r.texture = texture ? &texture->color : nullptr, r.nearest = nearest;
            r.rmh = texture && texture->rmh ? &*texture->rmh : nullptr;
            r.height_scale = texture ? texture->height_scale : 0.0f;
            jobs::RenderedImage image;
            {
              py::gil_scoped_release unlocked;
              image = jobs::render_patches(p.cage(), p.table, p.points(), r, "mesh",
                                           jobs::Names::python);
            }
            return py::make_tuple(owned(std::move(image.rgba), {height, width, 4}),
                                  to_python(image.report));
          },
          py::arg("width"), py::arg("height"), py::arg("samples"), py::arg("background"),
          py::arg("camera"), py::arg("wireframe"), py::arg("depth_colors"), py::arg("tess"),
          py::arg("tess_px"), py::arg("texture"), py::arg("nearest"))
      .def(
          "tessellate",
          [](const Patches& p, int tess, bool normals) {
            if (tess < 1 || tess > 64) throw InputError(fmt::format("tess {}: must be 1-64", tess));
            TessellateOptions o;
            o.factor = tess;
            o.normals = normals;
            py::gil_scoped_release unlocked;
            return tessellate_patches(p.cage(), p.table, p.points(), o);
          },
          py::arg("tess") = 4, py::arg("normals") = true,
          "A watertight mesh of the limit surface: `tess` segments per patch edge (1-64), with "
          "limit normals (what `limn subdivide --adaptive --tess N` writes).");
  m.def(
      "patches",
      [](const Mesh& cage, int depth, py::handle vertex_depth) {
        if (depth < 0 || depth > 12) throw InputError(fmt::format("depth {}: must be 0-12", depth));
        std::vector<uint8_t> vdepth;
        if (!vertex_depth.is_none()) {
          for (uint32_t d : indices(vertex_depth, "vertex_depth", 0, 17))
            vdepth.push_back(uint8_t(d));
          if (vdepth.size() != cage.vertex_count())
            throw InputError(fmt::format("vertex_depth: {} entries for {} vertices", vdepth.size(),
                                         cage.vertex_count()));
        }
        auto p = std::make_unique<Patches>();
        {
          py::gil_scoped_release unlocked;
          p->own_cage = cage;
          PatchOptions o;
          o.subdiv = subdiv_options(cage);
          o.depth = depth;
          p->table = build_patches(cage, o, vdepth);
          p->own_points = p->table.points(cage.positions);
          p->map = std::make_unique<PatchMap>(p->table);
        }
        return p;
      },
      py::arg("mesh"), py::kw_only(), py::arg("depth") = 3, py::arg("vertex_depth") = py::none(),
      R"(The feature-adaptive patch table of a cage: every extraordinary vertex (and sharp
feature) isolated `depth` times (0-12), or each vertex to its own depth (vertex_depth: one per
cage vertex, 0-16, capped by depth). InputError for cages limn cannot subdivide.)");

  py::class_<Hierarchy, std::shared_ptr<Hierarchy>>(m, "PatchHierarchy", R"(Every patch a cage can
need down to max_depth, with each vertex's errors measured on it: views then choose depths and
select their patches without refining again.)")
      .def_property_readonly(
          "max_depth", [](const Hierarchy& h) { return h.max_depth; },
          "The depth the hierarchy goes down to (the cap of every selection).")
      .def(
          "_select_depths",  // limn/__init__.py wraps it as select_depths
          [](const Hierarchy& h, int width, int height, std::optional<std::array<float, 7>> camera,
             float tolerance, py::handle previous) {
            const Camera cam = depth_view(h.cage, width, height, camera, tolerance);
            std::vector<uint8_t> prev;
            if (!previous.is_none()) prev = depths_arg(previous, h.cage.vertex_count(), "previous");
            DepthOptions d;
            d.tolerance_px = tolerance;
            d.max_depth = h.max_depth;
            std::vector<uint8_t> depths;
            {
              py::gil_scoped_release unlocked;
              depths = select_depths(h.cage, h.model, cam, d, prev);
            }
            const auto n = py::ssize_t(depths.size());
            return owned(std::move(depths), {n});
          },
          py::arg("width"), py::arg("height"), py::arg("camera"), py::arg("tolerance"),
          py::arg("previous"))
      .def(
          "select",
          [](const std::shared_ptr<Hierarchy>& h, py::handle vertex_depth) {
            const std::vector<uint8_t> vdepth =
                depths_arg(vertex_depth, h->cage.vertex_count(), "vertex_depth");
            auto p = std::make_unique<Patches>();
            {
              py::gil_scoped_release unlocked;
              p->table = select_patches(h->hierarchy, vdepth);
              p->map = std::make_unique<PatchMap>(p->table);
              p->from = h;
            }
            return p;
          },
          py::arg("vertex_depth"),
          "The patches of a depth per cage vertex (select_depths' result), as a PatchTable.");
  m.def(
      "_patch_hierarchy",
      [](const Mesh& cage, int max_depth) {
        if (max_depth < 0 || max_depth > 12)
          throw InputError(fmt::format("max_depth {}: must be 0-12", max_depth));
        auto h = std::make_shared<Hierarchy>();
        py::gil_scoped_release unlocked;
        h->cage = cage;
        h->max_depth = max_depth;
        PatchOptions o;
        o.subdiv = subdiv_options(cage);
        o.depth = max_depth;
        h->model = vertex_error_model(cage, o.subdiv);
        h->hierarchy = build_patch_hierarchy(cage, o);
        measure_vertex_errors(cage, h->hierarchy, h->model);
        h->points = h->hierarchy.table.points(cage.positions);
        return h;
      },
      py::arg("mesh"), py::arg("max_depth"));
  m.def(
      "_estimate_depths",
      [](const Mesh& cage, int width, int height, std::optional<std::array<float, 7>> camera,
         float tolerance, int max_depth) {
        const Camera cam = depth_view(cage, width, height, camera, tolerance);
        if (max_depth < 0 || max_depth > 16)
          throw InputError(fmt::format("max_depth {}: must be 0-16", max_depth));
        DepthOptions d;
        d.tolerance_px = tolerance;
        d.max_depth = max_depth;
        std::vector<uint8_t> depths;
        {
          py::gil_scoped_release unlocked;
          depths = select_depths(cage, vertex_error_model(cage, subdiv_options(cage)), cam, d);
        }
        const auto n = py::ssize_t(depths.size());
        return owned(std::move(depths), {n});
      },
      py::arg("mesh"), py::arg("width"), py::arg("height"), py::arg("camera"), py::arg("tolerance"),
      py::arg("max_depth"));
}

}  // namespace limn::py_bind
