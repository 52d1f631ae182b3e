#pragma once
// What the translation units of `import pandora` share, one per library the module exposes:
// scene_bindings.cpp (scene, rigs, and the helpers below), fields_bindings.cpp (fields, evaluate,
// point queries), render_bindings.cpp (render), suggest_bindings.cpp (suggestions, accept, PTZ,
// save); pandora_module.cpp calls their Bind* functions. Included only there.
//
// pybind11's STL and Eigen casters are included here so that every binding file converts the same
// types the same way (a file without them would bind a std::vector or a matrix as an opaque type).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/util/error.h"
#include "app/session/session.h"
#include "app/session/study.h"
#include "volume/fields.h"

namespace pandora::python {

namespace py = pybind11;

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A loaded scene: the study (scene, text, ray caster) shared by the rigs and fields made from it.
struct PyScene {
  std::shared_ptr<const session::Study> study;
  const Scene& scene() const { return study->scene(); }
};

// A rig the script edits: a session on one of the file's rigs (edits with undo, saved only on
// save() or accept, with a backup). Copies of the Python object share the session.
struct PyRig {
  std::shared_ptr<const session::Study> study;
  std::shared_ptr<session::Session> session;

  const Rig& rig() const { return session->rig().rig(); }
  int Index(const std::string& id) const {
    const int c = rig().FindCamera(id);
    if (c < 0)
      throw InputError(study->scene().path, "",
                       "no camera '" + id + "' in rig '" + rig().name + "'");
    return c;
  }
  std::vector<int> Indices(const std::vector<std::string>& ids) const {
    if (ids.empty()) throw InputError("{ids}", "", "name at least one camera");
    std::vector<int> out;
    for (const std::string& id : ids) out.push_back(Index(id));
    return out;
  }
};

// Evaluated fields (evaluate()) with what write() records beside the grids.
struct PyFields {
  std::shared_ptr<const session::Study> study;
  std::shared_ptr<Fields> fields;
  std::vector<std::string> names;
  nlohmann::json summary;
  std::string rig_name, rig_json;  // the rig evaluated (metadata of write())
};

// ---- Helpers (scene_bindings.cpp)
// ----------------------------------------------------------------

py::array_t<double> Vec3Array(const Vec3& v);

// (N, 3) metres -> points; InputError("points", "[i]") for a non-finite one.
std::vector<Vec3> Points(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& points);

// Refuses (InputError) an output `path` that is one of the scene's input files (the scene, a mesh).
void RefuseInputPath(const Scene& scene, const std::string& path, const std::string& what);

// A JSON text as Python objects (json.loads).
py::object JsonToPython(const std::string& text);

// ---- Bindings, in the order pandora_module.cpp calls them
// ----------------------------------------

// pandora.Scene and load_scene() (scene_bindings.cpp).
void BindScene(py::module_& m);

// pandora.Rig: the editable rig, returned for the suggestion bindings that extend it
// (scene_bindings.cpp).
py::class_<PyRig> BindRig(py::module_& m);

// pandora.Fields: evaluated grids as sparse or dense arrays, and write() (fields_bindings.cpp).
void BindFields(py::module_& m);

// evaluate(): the fields for a rig (fields_bindings.cpp).
void BindEvaluate(py::module_& m);

// visibility() and covariance() at given points (fields_bindings.cpp).
void BindPointQueries(py::module_& m);

// render(): the projective-light render as a numpy array (render_bindings.cpp).
void BindRender(py::module_& m);

// Binds pandora.suggest, suggest_ptz_preset, suggest_ptz_tour, accept, the Suggestion class and
// the Rig's PTZ and save methods (suggest_bindings.cpp).
void BindSuggest(py::module_& m, py::class_<PyRig>& rig);

}  // namespace pandora::python
