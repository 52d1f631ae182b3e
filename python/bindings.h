#pragma once
// What the two translation units of `import pandora` share (pandora_module.cpp: scene, rig, fields,
// queries, renders; suggest_bindings.cpp: suggestions, accept, PTZ, save). Included only there.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/util/error.h"
#include "app/session/session.h"
#include "app/session/study.h"

namespace pandora::python {

namespace py = pybind11;

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
};

py::array_t<double> Vec3Array(const Vec3& v);

// (N, 3) metres -> points; InputError("points", "[i]") for a non-finite one.
std::vector<Vec3> Points(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& points);

// Refuses (InputError) an output `path` that is one of the scene's input files (the scene, a mesh).
void RefuseInputPath(const Scene& scene, const std::string& path, const std::string& what);

// A JSON text as Python objects (json.loads).
py::object JsonToPython(const std::string& text);

// Binds pandora.suggest, suggest_ptz_preset, suggest_ptz_tour, accept, the Suggestion class and
// the Rig's PTZ and save methods (suggest_bindings.cpp).
void BindSuggest(py::module_& m, py::class_<PyRig>& rig);

}  // namespace pandora::python
