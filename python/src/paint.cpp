// Octree textures for Python: paint (the CLI's stroke scripts), lookups at arrays of points,
// .lot files, baking, and the texture in renders.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <optional>

#include "arrays.hpp"
#include "bindings.hpp"
#include "jobs.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/file.hpp"
#include "limn/paint/bake.hpp"
#include "limn/paint/file.hpp"
#include "limn/paint/lookup.hpp"
#include "limn/paint/material.hpp"
#include "limn/paint/surface.hpp"
#include "limn/paint/undo.hpp"
#include "reports.hpp"

namespace limn::py_bind {

namespace {

// Points (n, 3) and optional normals (n, 3) for lookups.
struct Queries {
  std::vector<float> p, n;
  size_t count = 0;
};
Queries queries(py::handle points, py::handle normals) {
  Queries q;
  q.p = floats(points, "points", 3);
  q.count = q.p.size() / 3;
  if (!normals.is_none()) {
    q.n = floats(normals, "normals", 3);
    if (q.n.size() != q.p.size())
      throw InputError(fmt::format("normals: {} rows for {} points", q.n.size() / 3, q.count));
  }
  return q;
}

// A painting session: the surface's BVH built once, a texture and its undo history, so strokes
// can be added call by call and undone (what the viewer does for an artist).
struct Painter {
  Mesh mesh;
  std::unique_ptr<PaintSurface> surface;
  MaterialTexture texture;
  PaintHistory history;
  int depth = 10;
  MaterialDefaults defaults;
};

MaterialDefaults defaults_arg(const std::array<float, 3>& d) {
  const MaterialDefaults out{d[0], d[1], d[2]};
  try {
    rmh_background(out);
  } catch (const InputError& e) {
    throw InputError(fmt::format("channel_defaults: {}", e.what()));
  }
  return out;
}

float height_scale_arg(float s) {
  if (!(s > 0 && std::isfinite(s)))
    throw InputError(fmt::format("height_scale {}: must be a positive number", s));
  return s;
}

py::array image_array(Image img) {
  return owned(std::move(img.rgba), {py::ssize_t(img.height), py::ssize_t(img.width), 4});
}

Image image_arg(const py::array_t<uint8_t, py::array::c_style | py::array::forcecast>& a,
                const char* name) {
  if (a.ndim() != 3 || a.shape(2) != 4)
    throw InputError(fmt::format("{}: expected shape (h, w, 4) uint8 (RGBA)", name));
  Image img;
  img.height = int(a.shape(0)), img.width = int(a.shape(1));
  img.rgba.assign(a.data(), a.data() + a.size());
  return img;
}

// A new texture's background colour, checked (RGBA in [0, 1]).
Rgba8 background_arg(const std::array<float, 4>& background) {
  for (float c : background)
    if (!(c >= 0 && c <= 1)) throw InputError("background: components must be numbers in [0, 1]");
  return rgba8_from_float(background.data());
}

}  // namespace

void bind_paint(py::module_& m) {
  py::class_<MaterialTexture> tex(m, "Texture", R"(An adaptive octree texture (limn paint): a
material on a surface without UVs, deep only where detail was painted: base colour, and roughness,
metallic and height once a brush painted them (an RMH texture beside the colour one). Made by
paint() or load_texture().)");
  tex.def(
         "save",
         [](const MaterialTexture& t, const std::filesystem::path& path) {
           if (path.extension() != ".lot")
             throw InputError(
                 fmt::format("{}: the texture file name must end in .lot", path.string()));
           py::gil_scoped_release unlocked;
           save_lot(t, path);
         },
         py::arg("path"), "Writes the texture as a .lot file, atomically.")
      .def_property_readonly(
          "stats", [](const MaterialTexture& t) { return to_python(reports::material_json(t)); },
          "`limn paint --stats --json`: nodes, bricks, leaves, samples, bytes, bytes per painted "
          "texel, the cube, the height scale, and 'rmh' (the material channels' texture: its "
          "counts and defaults; None when no channel was painted).")
      .def_property_readonly(
          "has_channels", [](const MaterialTexture& t) { return t.rmh.has_value(); },
          "Whether roughness, metallic or height were ever painted (an RMH texture exists).")
      .def_property_readonly(
          "channel_defaults",
          [](const MaterialTexture& t) {
            const MaterialDefaults d = t.defaults();
            return py::make_tuple(d.roughness, d.metallic, d.height);
          },
          "(roughness, metallic, height) where they were not painted.")
      .def_property(
          "height_scale", [](const MaterialTexture& t) { return t.height_scale; },
          [](MaterialTexture& t, float s) { t.height_scale = height_scale_arg(s); },
          "Model units that height 1 stands for (bump shading, normal maps).")
      .def_property_readonly(
          "background",
          [](const MaterialTexture& mat) {
            const Rgba8 c = mat.color.background();
            return py::make_tuple(channel(c, 0), channel(c, 1), channel(c, 2), channel(c, 3));
          },
          "RGBA8 of unpainted surface, as a tuple of 0-255 ints.")
      .def(
          "nearest",
          [](const MaterialTexture& mat, py::handle points, py::handle normals) {
            const OctreeTexture& t = mat.color;
            const Queries q = queries(points, normals);
            std::vector<uint32_t> rgba(q.count);
            std::vector<uint8_t> found(q.count);
            {
              py::gil_scoped_release unlocked;
              OctreeSampler sampler(t);
              sampler.nearest_batch(q.p.data(), q.n.empty() ? nullptr : q.n.data(), q.count,
                                    rgba.data(), found.data());
            }
            std::vector<uint8_t> bytes(4 * q.count);
            for (size_t i = 0; i < q.count; ++i)
              for (int k = 0; k < 4; ++k) bytes[4 * i + size_t(k)] = uint8_t(channel(rgba[i], k));
            return py::make_tuple(
                owned(std::move(bytes), {py::ssize_t(q.count), 4}),
                owned(std::move(found), {py::ssize_t(q.count)}).attr("astype")("bool"));
          },
          py::arg("points"), py::arg("normals") = py::none(),
          R"(Nearest lookups: (colors (n, 4) uint8, found (n,) bool) at (n, 3) points.

normals (n, 3), optional: which side of a two-sided leaf to read (see limn/paint/lookup.hpp);
found is False where no leaf with a sample facing the normal holds the point (colour: the
background).)")
      .def(
          "filtered",
          [](const MaterialTexture& mat, py::handle points, py::handle normals, float footprint) {
            const OctreeTexture& t = mat.color;
            if (!(footprint >= 0 && std::isfinite(footprint)))
              throw InputError(fmt::format("footprint {}: must be a number >= 0", footprint));
            const Queries q = queries(points, normals);
            std::vector<float> rgba(4 * q.count);
            std::vector<uint8_t> found(q.count);
            {
              py::gil_scoped_release unlocked;
              OctreeSampler sampler(t);
              sampler.filtered_batch(q.p.data(), q.n.empty() ? nullptr : q.n.data(), q.count,
                                     footprint, rgba.data(), found.data());
            }
            return py::make_tuple(
                owned(std::move(rgba), {py::ssize_t(q.count), 4}),
                owned(std::move(found), {py::ssize_t(q.count)}).attr("astype")("bool"));
          },
          py::arg("points"), py::arg("normals") = py::none(), py::arg("footprint") = 0.0f,
          R"(Filtered lookups: (rgba (n, 4) float32 straight in [0, 1], found (n,) bool).

Trilinear over the leaves around each point (what the renderer shows); footprint (world units):
wider than a leaf blends the mip levels it spans.)")
      .def(
          "channels",
          [](const MaterialTexture& mat, py::handle points, py::handle normals, float footprint) {
            if (!(footprint >= 0 && std::isfinite(footprint)))
              throw InputError(fmt::format("footprint {}: must be a number >= 0", footprint));
            const Queries q = queries(points, normals);
            std::vector<float> out(3 * q.count);
            {
              py::gil_scoped_release unlocked;
              const MaterialDefaults d = mat.defaults();
              if (!mat.rmh) {
                for (size_t i = 0; i < q.count; ++i)
                  out[3 * i] = d.roughness, out[3 * i + 1] = d.metallic, out[3 * i + 2] = d.height;
              } else {
                std::vector<float> rgba(4 * q.count);
                std::vector<uint8_t> found(q.count);
                OctreeSampler sampler(*mat.rmh);
                sampler.filtered_batch(q.p.data(), q.n.empty() ? nullptr : q.n.data(), q.count,
                                       footprint, rgba.data(), found.data());
                for (size_t i = 0; i < q.count; ++i) {
                  const float none[4] = {0, 0, 0, 0};
                  const auto v =
                      material_value(found[i] ? &rgba[4 * i] : none, mat.rmh->background());
                  for (size_t k = 0; k < 3; ++k) out[3 * i + k] = v[k];
                }
              }
            }
            return owned(std::move(out), {py::ssize_t(q.count), 3});
          },
          py::arg("points"), py::arg("normals") = py::none(), py::arg("footprint") = 0.0f,
          R"(Material channels: (n, 3) float32 roughness, metallic, height at (n, 3) points, filtered
as `filtered` is, over the defaults where nothing was painted.)");

  py::class_<Painter>(m, "Painter", R"(A painting session on one mesh: strokes call by call into one
texture, each undoable (undo/redo), the surface's BVH built once.)")
      .def(py::init([](const Mesh& mesh, const MaterialTexture* texture,
                       std::array<float, 4> background, int depth,
                       std::array<float, 3> channel_defaults) {
             jobs::check_paint_depth(depth, jobs::Names::python);
             const Rgba8 bg = background_arg(background);
             auto p = std::make_unique<Painter>();
             p->defaults = defaults_arg(channel_defaults);
             py::gil_scoped_release unlocked;
             p->mesh = mesh;
             p->surface = std::make_unique<PaintSurface>(p->mesh);
             p->texture = texture
                              ? *texture
                              : MaterialTexture::from_color(OctreeTexture::create(*p->surface, bg));
             p->depth = depth;
             return p;
           }),
           py::arg("mesh"), py::kw_only(), py::arg("texture") = py::none(),
           py::arg("background") = std::array<float, 4>{0, 0, 0, 0}, py::arg("depth") = 10,
           py::arg("channel_defaults") = std::array<float, 3>{0.5f, 0.0f, 0.5f},
           "Starts a session on `mesh`: a new texture with `background` (RGBA in [0, 1]), or a "
           "copy of `texture`; `depth` for strokes that give none; `channel_defaults` "
           "(roughness, metallic, height) where they are not painted, once a stroke paints one.")
      .def(
          "_run",
          [](Painter& p, const std::string& strokes_json, const std::string& name) {
            const StrokeScript script = parse_strokes(strokes_json, name, p.depth);
            ScriptResult r;
            {
              py::gil_scoped_release unlocked;
              r = run_strokes(p.texture, *p.surface, script, p.history, p.defaults);
            }
            size_t dabs = 0, changed = 0;
            for (const StrokeStats& st : r.strokes) dabs += st.dabs, changed += st.samples_changed;
            return to_python({{"strokes", r.strokes.size()},
                              {"dabs", dabs},
                              {"samples_changed", changed},
                              {"undos", r.undos},
                              {"redos", r.redos}});
          },
          py::arg("strokes_json"), py::arg("name"))
      .def(
          "undo",
          [](Painter& p) {
            py::gil_scoped_release unlocked;
            return p.history.undo(p.texture);
          },
          "Undoes the last stroke or fill; False when there is nothing to undo.")
      .def(
          "redo",
          [](Painter& p) {
            py::gil_scoped_release unlocked;
            return p.history.redo(p.texture);
          },
          "Redoes the last undone stroke; False when there is nothing to redo.")
      .def_property_readonly(
          "undo_count", [](const Painter& p) { return p.history.undo_count(); },
          "Strokes and fills undo() can take back.")
      .def_property_readonly(
          "redo_count", [](const Painter& p) { return p.history.redo_count(); },
          "Undone strokes redo() can bring back.")
      .def_property_readonly(
          "texture",
          [](const Painter& p) {
            MaterialTexture copy = p.texture;
            copy.color.compact();
            if (copy.rmh) copy.rmh->compact();
            return copy;
          },
          "The texture as painted so far (a compact copy: the session goes on).");
  m.def(
      "load_texture",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release unlocked;
        return load_lot(path);
      },
      py::arg("path"), "Reads a .lot texture; InputError naming the file when it is not one.");
  m.def(
      "_paint",
      [](const Mesh& mesh, const std::string& strokes_json, const std::string& name, int depth,
         std::array<float, 4> background, const MaterialTexture* start,
         std::array<float, 3> channel_defaults, std::optional<float> height_scale) {
        jobs::check_paint_depth(depth, jobs::Names::python);
        const Rgba8 bg = background_arg(background);
        const MaterialDefaults defaults = defaults_arg(channel_defaults);
        if (height_scale) height_scale_arg(*height_scale);
        const StrokeScript script = parse_strokes(strokes_json, name, depth);
        std::optional<MaterialTexture> first;
        if (start) first = *start;  // a copy: the caller's texture stays as it was
        jobs::PaintOutcome out;
        {
          py::gil_scoped_release unlocked;
          out = jobs::paint(mesh, script, bg, std::move(first), defaults);
        }
        if (height_scale) out.texture.height_scale = *height_scale;
        nlohmann::json report = std::move(out.report);
        report["depth"] = depth;
        return py::make_tuple(std::move(out.texture), to_python(report));
      },
      py::arg("mesh"), py::arg("strokes_json"), py::arg("name"), py::arg("depth"),
      py::arg("background"), py::arg("texture"), py::arg("channel_defaults"),
      py::arg("height_scale"));
  m.def(
      "_bake_vertex_colors",
      [](const MaterialTexture& mat, const Mesh& mesh, bool nearest) {
        const OctreeTexture& t = mat.color;
        BakeOptions o;
        o.filtered = !nearest;
        std::vector<float> colors;
        {
          py::gil_scoped_release unlocked;
          check_texture_fits(t, mesh, "texture", "mesh");
          colors = bake_vertex_colors(t, mesh, o);
        }
        const auto n = py::ssize_t(colors.size() / 4);
        return owned(std::move(colors), {n, 4});
      },
      py::arg("texture"), py::arg("mesh"), py::arg("nearest"));
  m.def(
      "_bake_uv_image",
      [](const MaterialTexture& mat, const Mesh& mesh, int width, int height, int gutter,
         bool nearest, int udim, bool normal_map) {
        if (gutter < 0 || gutter > 1024) throw InputError("gutter: must be 0-1024 pixels");
        if (udim < 1001 || udim > 1100)
          throw InputError(fmt::format("udim {}: must be 1001-1100", udim));
        BakeOptions o;
        o.filtered = !nearest;
        o.tile = udim - 1001;
        MaterialImages img;
        {
          py::gil_scoped_release unlocked;
          check_texture_fits(mat.color, mesh, "texture", "mesh");
          img = bake_material(mat, mesh, width, height, gutter, o, normal_map);
        }
        py::dict out;
        out["base_color"] = image_array(std::move(img.base_color));
        out["metallic_roughness"] = img.metallic_roughness.rgba.empty()
                                        ? py::object(py::none())
                                        : image_array(std::move(img.metallic_roughness));
        out["height"] = img.height.values.empty()
                            ? py::object(py::none())
                            : py::object(owned(std::move(img.height.values),
                                               {py::ssize_t(height), py::ssize_t(width)}));
        out["normal"] =
            img.normal.rgba.empty() ? py::object(py::none()) : image_array(std::move(img.normal));
        return out;
      },
      py::arg("texture"), py::arg("mesh"), py::arg("width"), py::arg("height"), py::arg("gutter"),
      py::arg("nearest"), py::arg("udim"), py::arg("normal_map"));
  m.def(
      "udim_tiles",
      [](const Mesh& mesh) {
        std::vector<int> tiles = uv_tiles(mesh);
        for (int& t : tiles) t += 1001;
        return tiles;
      },
      py::arg("mesh"),
      "The UDIM tiles (1001, 1002, ...) that hold the mesh's UV triangles, ascending. InputError "
      "when the mesh has no UVs, or a triangle reaches into two tiles or lies outside u, v in "
      "[0, 10].");
  m.def(
      "_write_glb",
      [](const Mesh& mesh, const std::filesystem::path& path,
         std::optional<py::array_t<uint8_t, py::array::c_style | py::array::forcecast>> base_color,
         std::optional<py::array_t<uint8_t, py::array::c_style | py::array::forcecast>>
             metallic_roughness,
         std::optional<py::array_t<uint8_t, py::array::c_style | py::array::forcecast>> normal,
         float metallic, float roughness) {
        GlbTextures textures;
        textures.metallic = metallic, textures.roughness = roughness;
        Image img[3];
        if (base_color) img[0] = image_arg(*base_color, "base_color");
        if (metallic_roughness) img[1] = image_arg(*metallic_roughness, "metallic_roughness");
        if (normal) img[2] = image_arg(*normal, "normal");
        py::gil_scoped_release unlocked;
        if (base_color) textures.base_color_png = encode_png(img[0]);
        if (metallic_roughness) textures.metallic_roughness_png = encode_png(img[1]);
        if (normal) textures.normal_png = encode_png(img[2]);
        std::string bytes;
        write_glb(mesh, textures, bytes);
        write_file_atomic(path, bytes);
      },
      py::arg("mesh"), py::arg("path"), py::arg("base_color"), py::arg("metallic_roughness"),
      py::arg("normal"), py::arg("metallic"), py::arg("roughness"));
  m.def(
      "_write_png16",
      [](const std::filesystem::path& path,
         py::array_t<uint16_t, py::array::c_style | py::array::forcecast> image) {
        if (image.ndim() != 2) throw InputError("image: expected shape (h, w) uint16");
        Image16 img;
        img.height = int(image.shape(0)), img.width = int(image.shape(1));
        if (img.width < 1 || img.height < 1) throw InputError("image: empty");
        img.values.assign(image.data(), image.data() + image.size());
        py::gil_scoped_release unlocked;
        write_file_atomic(path, encode_png16(img));
      },
      py::arg("path"), py::arg("image"));
}

}  // namespace limn::py_bind
