// limn.Mesh: limn::Mesh with its flat arrays as numpy views, and the mesh files.
#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.hpp"
#include "bindings.hpp"
#include "limn/io/mesh_io.hpp"
#include "limn/mesh/shapes.hpp"
#include "limn/mesh/topology.hpp"
#include "reports.hpp"

namespace limn::py_bind {

namespace {

// One of Mesh's arrays: its member, row width (0: one value a row) and whether it holds indices.
template <class T>
struct Attribute {
  const char* name;
  std::vector<T> Mesh::*member;
  size_t cols;
  const char* doc;
};

const Attribute<float> kFloatAttributes[] = {
    {"positions", &Mesh::positions, 3, "(n, 3) float32: xyz per vertex"},
    {"normals", &Mesh::normals, 3, "(q, 3) float32: normals, indexed by normal_indices"},
    {"uvs", &Mesh::uvs, 2, "(t, 2) float32: texture coordinates, indexed by uv_indices"},
    {"colors", &Mesh::colors, 4, "(n, 4) float32: RGBA in [0, 1] per vertex, or empty"},
    {"crease_sharpness", &Mesh::crease_sharpness, 0, "(k,) float32: sharpness per crease edge"},
    {"corner_sharpness", &Mesh::corner_sharpness, 0, "(c,) float32: sharpness per corner vertex"},
};
const Attribute<uint32_t> kIndexAttributes[] = {
    {"face_offsets", &Mesh::face_offsets, 0,
     "(m + 1,) uint32: face f spans corners [face_offsets[f], face_offsets[f + 1])"},
    {"face_vertices", &Mesh::face_vertices, 0, "(corners,) uint32: vertex per corner"},
    {"normal_indices", &Mesh::normal_indices, 0, "(corners,) uint32: normal per corner, or empty"},
    {"uv_indices", &Mesh::uv_indices, 0, "(corners,) uint32: uv per corner, or empty"},
    {"crease_edges", &Mesh::crease_edges, 2, "(k, 2) uint32: vertex pairs of crease edges"},
    {"corner_vertices", &Mesh::corner_vertices, 0, "(c,) uint32: vertices tagged as corners"},
    {"hole_faces", &Mesh::hole_faces, 0, "(h,) uint32: faces tagged as holes"},
};

// Sets one array and checks the whole mesh; on a failed check the mesh is left as it was.
template <class T>
void assign(Mesh& m, std::vector<T> Mesh::*member, std::vector<T> values) {
  std::swap(m.*member, values);
  try {
    validate(m);
  } catch (...) {
    std::swap(m.*member, values);
    throw;
  }
}

// Faces from a (m, k) integer array, or from a sequence of sequences of any lengths.
void set_faces(Mesh& m, py::handle faces) {
  py::array a = py::array::ensure(faces);
  if (a && a.ndim() == 2 && (a.dtype().kind() == 'i' || a.dtype().kind() == 'u')) {
    const size_t k = size_t(a.shape(1));
    if (k < 3) throw InputError(fmt::format("faces: {} corners per face, at least 3 needed", k));
    m.face_vertices = indices(a, "faces", k);
    m.face_offsets.resize(size_t(a.shape(0)) + 1);
    for (size_t f = 0; f < m.face_offsets.size(); ++f) m.face_offsets[f] = uint32_t(f * k);
    return;
  }
  if (!py::isinstance<py::sequence>(faces))
    throw py::type_error("faces: expected an (m, k) integer array or a sequence of faces");
  m.face_offsets = {0};
  m.face_vertices.clear();
  for (py::object face : py::reinterpret_borrow<py::sequence>(faces)) {  // owns each item
    const std::vector<uint32_t> f = indices(face, "faces", 0);
    m.face_vertices.insert(m.face_vertices.end(), f.begin(), f.end());
    m.face_offsets.push_back(uint32_t(m.face_vertices.size()));
  }
}

Mesh from_arrays(py::handle positions, py::handle faces, py::handle offsets, py::handle uvs,
                 py::handle uv_indices, py::handle normals, py::handle normal_indices,
                 py::handle colors, py::handle crease_edges, py::handle crease_sharpness,
                 py::handle corner_vertices, py::handle corner_sharpness, py::handle hole_faces) {
  Mesh m;
  m.positions = floats(positions, "positions", 3);
  if (!offsets.is_none()) {
    m.face_vertices = indices(faces, "faces", 0);
    m.face_offsets = indices(offsets, "offsets", 0);
  } else {
    set_faces(m, faces);
  }
  const auto opt_floats = [](py::handle h, const char* what, size_t cols) {
    return h.is_none() ? std::vector<float>{} : floats(h, what, cols);
  };
  const auto opt_indices = [](py::handle h, const char* what, size_t cols) {
    return h.is_none() ? std::vector<uint32_t>{} : indices(h, what, cols);
  };
  m.uvs = opt_floats(uvs, "uvs", 2);
  m.uv_indices = opt_indices(uv_indices, "uv_indices", 0);
  m.normals = opt_floats(normals, "normals", 3);
  m.normal_indices = opt_indices(normal_indices, "normal_indices", 0);
  m.colors = opt_floats(colors, "colors", 4);
  m.crease_edges = opt_indices(crease_edges, "crease_edges", 2);
  m.crease_sharpness = opt_floats(crease_sharpness, "crease_sharpness", 0);
  m.corner_vertices = opt_indices(corner_vertices, "corner_vertices", 0);
  m.corner_sharpness = opt_floats(corner_sharpness, "corner_sharpness", 0);
  m.hole_faces = opt_indices(hole_faces, "hole_faces", 0);
  validate(m);
  return m;
}

MeshFormat format_arg(const std::optional<std::string>& format) {
  if (!format) return MeshFormat::automatic;
  const MeshFormat f = format_from_name(*format);
  if (f == MeshFormat::automatic)
    throw InputError(fmt::format("format '{}': expected obj, ply, off, stl, gltf or glb", *format));
  return f;
}

}  // namespace

void bind_mesh(py::module_& m) {
  py::class_<Mesh> mesh(m, "Mesh", R"(A polygon mesh as flat arrays (limn::Mesh).

Faces of any arity are stored as offsets + one vertex index per corner. Every array property is a
numpy view of the mesh's own memory (no copy; the view keeps the mesh alive): edit values in place
through it, or assign a new array to a property (copied and checked). Build one with
Mesh.from_arrays or read_mesh.)");
  mesh.def(py::init<>(), "An empty mesh.")
      .def_static("from_arrays", &from_arrays, py::arg("positions"), py::arg("faces"),
                  py::kw_only(), py::arg("offsets") = py::none(), py::arg("uvs") = py::none(),
                  py::arg("uv_indices") = py::none(), py::arg("normals") = py::none(),
                  py::arg("normal_indices") = py::none(), py::arg("colors") = py::none(),
                  py::arg("crease_edges") = py::none(), py::arg("crease_sharpness") = py::none(),
                  py::arg("corner_vertices") = py::none(), py::arg("corner_sharpness") = py::none(),
                  py::arg("hole_faces") = py::none(),
                  R"(A mesh from arrays (copied).

positions: (n, 3) numbers. faces: an (m, k) integer array (every face k corners), a sequence of
faces of any sizes, or with `offsets` the flat corner list (face f is
faces[offsets[f]:offsets[f + 1]]). Optional: uvs (t, 2) with uv_indices (one per corner),
normals (q, 3) with normal_indices, colors (n, 4) RGBA in [0, 1], crease_edges (k, 2) with
crease_sharpness (k,), corner_vertices with corner_sharpness, hole_faces.
Raises InputError for out-of-range indices, faces repeating a vertex, NaNs or wrong shapes;
TypeError for arrays of non-numbers.)")
      .def_property_readonly("vertex_count", &Mesh::vertex_count, "Vertices (positions rows).")
      .def_property_readonly("face_count", &Mesh::face_count, "Faces.")
      .def_property_readonly("corner_count", &Mesh::corner_count,
                             "Corners: one per face vertex (face_vertices entries).")
      .def_property_readonly(
          "faces",
          [](py::object self) -> py::object {
            Mesh& me = self.cast<Mesh&>();
            const size_t k = me.face_count() ? me.face_size(0) : 3;
            for (size_t f = 0; f < me.face_count(); ++f)
              if (me.face_size(f) != k)
                throw InputError(
                    "faces: the mesh mixes face sizes; use face_offsets and face_vertices");
            return view(me.face_vertices, k, self);
          },
          "(m, k) uint32 view of the corners when every face has k corners (InputError when "
          "sizes are mixed: use face_offsets and face_vertices)")
      .def(
          "copy", [](const Mesh& me) { return Mesh(me); }, "A deep copy.")
      .def(
          "vertex_normals",
          [](const Mesh& me) {
            std::vector<float> n = vertex_normals(me);
            const auto rows = py::ssize_t(n.size() / 3);
            return owned(std::move(n), {rows, 3});
          },
          "Area-weighted unit vertex normals, (n, 3) float32 (zero for unreferenced vertices).")
      .def("__repr__", [](const Mesh& me) {
        return fmt::format("<limn.Mesh: {} vertices, {} faces{}{}{}>", me.vertex_count(),
                           me.face_count(), me.uv_indices.empty() ? "" : ", uvs",
                           me.normal_indices.empty() ? "" : ", normals",
                           me.colors.empty() ? "" : ", colors");
      });
  for (const Attribute<float>& a : kFloatAttributes)
    mesh.def_property(
        a.name, [a](py::object self) { return view(self.cast<Mesh&>().*a.member, a.cols, self); },
        [a](Mesh& me, py::handle v) { assign(me, a.member, floats(v, a.name, a.cols)); }, a.doc);
  for (const Attribute<uint32_t>& a : kIndexAttributes)
    mesh.def_property(
        a.name, [a](py::object self) { return view(self.cast<Mesh&>().*a.member, a.cols, self); },
        [a](Mesh& me, py::handle v) { assign(me, a.member, indices(v, a.name, a.cols)); }, a.doc);

  m.def(
      "read_mesh",
      [](const std::filesystem::path& path, std::optional<std::string> format, bool weld,
         bool soup) {
        ReadOptions r;
        r.format = format_arg(format);
        r.weld = weld;
        r.soup = soup;
        py::gil_scoped_release unlocked;
        return read_mesh(path, r);
      },
      py::arg("path"), py::kw_only(), py::arg("format") = py::none(), py::arg("weld") = false,
      py::arg("soup") = false,
      R"(Reads a mesh file: OBJ (with OpenSubdiv tags), PLY, OFF, STL, glTF/GLB.

format: 'obj', 'ply', 'off', 'stl', 'gltf', 'glb' (default: by extension, then content).
weld: glTF only, merge the vertices glTF splits at UV and normal seams. soup: OBJ/PLY/OFF keep
faces that repeat a vertex (for repair). Raises InputError with the file's one-line message.)");
  m.def(
      "_write_mesh",
      [](const Mesh& me, const std::string& path, std::optional<std::string> format, bool ascii) {
        WriteOptions w;
        w.format = format ? format_arg(format) : format_from_path(path);
        w.ascii = ascii;
        if (w.format == MeshFormat::automatic)
          throw InputError(fmt::format(
              "{}: cannot tell the output format from the extension (.obj, .ply, .off, .stl, "
              ".glb)",
              path));
        std::vector<std::string> dropped = dropped_attributes(me, w.format);
        py::gil_scoped_release unlocked;
        write_mesh(me, path, w);
        return dropped;
      },
      py::arg("mesh"), py::arg("path"), py::arg("format") = py::none(), py::arg("ascii") = false);
  m.def(
      "shape",
      [](const std::string& name, uint64_t seed) {
        py::gil_scoped_release unlocked;
        return make_shape(name, seed);
      },
      py::arg("name"), py::kw_only(), py::arg("seed") = 1,
      "`limn shape NAME`: a built-in procedural cage (see shape_names()). InputError for an "
      "unknown name.");
  m.def("shape_names", &shape_names, "The names shape() accepts.");
  m.def(
      "_info",
      [](const Mesh& me) {
        nlohmann::json j;
        {
          py::gil_scoped_release unlocked;
          j = reports::stats_json(analyze(me, build_topology(me)));
        }
        return to_python(j);
      },
      py::arg("mesh"));
}

}  // namespace limn::py_bind
