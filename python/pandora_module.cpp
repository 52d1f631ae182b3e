// `import pandora`: the module (docs/python.md). Its contents are bound one file per library:
// scene_bindings.cpp (scene, rigs), fields_bindings.cpp (fields, evaluate, point queries),
// render_bindings.cpp (render), suggest_bindings.cpp (suggestions, accept, PTZ, save). Errors are
// pandora.InputError with the same file, JSON path, reason and hint as the command line's one-line
// messages.
#include <pybind11/pybind11.h>

#include <exception>

#include "analysis/util/error.h"
#include "python/bindings.h"
#include "python/keywords.h"

using namespace pandora;
using namespace pandora::python;

namespace {

// The module docstring and pandora.InputError with its file/path/reason/hint attributes.
void BindInputError(py::module_& m) {
  m.doc() = "Pandora: multi-camera setup design (coverage, resolution and uncertainty fields)";
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& original) {
      // Options as the keyword arguments a script passes (python/keywords.h).
      const InputError e = RenameOptions(original, python::Keyword);
      py::object err = py::handle(input_error.ptr())(py::str(e.what()));
      // The parts of the one-line message, for scripts that act on them.
      err.attr("file") = e.file();
      err.attr("path") = e.json_path();
      err.attr("reason") = e.reason();
      err.attr("hint") = e.hint();
      PyErr_SetObject(input_error.ptr(), err.ptr());
    }
  });
}

}  // namespace

PYBIND11_MODULE(pandora, m) {
  BindInputError(m);
  BindScene(m);
  py::class_<PyRig> rig = BindRig(m);
  BindFields(m);
  BindEvaluate(m);
  BindPointQueries(m);
  BindRender(m);

  BindSuggest(m, rig);
}
