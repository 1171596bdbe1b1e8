// The _limn extension: limn's meshes and jobs for Python (the package in python/limn wraps it).
#include "bindings.hpp"
#include "limn/mesh/mesh.hpp"
#include "limn/version.hpp"

namespace limn::py_bind {

py::object to_python(const nlohmann::json& j) {
  // Reports are small (a few hundred values): through Python's own parser is exact and simple.
  // Held for the process's life: never destroyed after the interpreter is gone.
  static const py::object* loads = new py::object(py::module_::import("json").attr("loads"));
  return (*loads)(j.dump());
}

}  // namespace limn::py_bind

PYBIND11_MODULE(_limn, m) {
  namespace py = pybind11;
  m.doc() = "limn's compiled core; use the limn package.";
  m.attr("__version__") = limn::version();
  // Bad input: ValueError subclasses with limn's one-line messages. The exception types are
  // never released (a static py::exception would be, after the interpreter is gone).
  static PyObject* input_error =
      (new py::exception<limn::InputError>(m, "InputError", PyExc_ValueError))->ptr();
  static PyObject* repairable =
      (new py::exception<limn::RepairableError>(m, "RepairableError", input_error))->ptr();
  py::setattr(input_error, "__doc__",
              py::str("Bad input (a malformed file, an out-of-range index, a NaN, a bad "
                      "option): limn's one-line message naming the file or array and the "
                      "problem."));
  py::setattr(repairable, "__doc__",
              py::str("Bad input that limn.repair fixes: a face repeating a vertex, a "
                      "non-manifold edge, faces that disagree on orientation, duplicate faces."));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const limn::RepairableError& e) {
      PyErr_SetString(repairable, e.what());
    } catch (const limn::InputError& e) {
      PyErr_SetString(input_error, e.what());
    }
  });
  limn::py_bind::bind_mesh(m);
  limn::py_bind::bind_jobs(m);
  limn::py_bind::bind_subdiv(m);
  limn::py_bind::bind_patches(m);
  limn::py_bind::bind_paint(m);  // before render, whose functions take a Texture
  limn::py_bind::bind_render(m);
}
