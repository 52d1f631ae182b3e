// `import pandora`, the scene and its rigs (docs/python.md): load_scene(), pandora.Scene, and
// pandora.Rig with its edits (move, set_pose, set_enabled, undo, redo); and the helpers the binding
// files share (python/bindings.h).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <tuple>
#include <utility>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/session/camera_edits.h"
#include "app/session/session.h"
#include "app/session/study.h"
#include "python/bindings.h"

namespace pandora::python {

py::array_t<double> Vec3Array(const Vec3& v) {
  py::array_t<double> a(3);
  for (int i = 0; i < 3; ++i) a.mutable_at(i) = v[i];
  return a;
}

std::vector<Vec3> Points(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& points) {
  if (points.ndim() != 2 || points.shape(1) != 3)
    throw InputError("points", "", "expected an array of shape (N, 3), metres");
  std::vector<Vec3> out(points.shape(0));
  auto r = points.unchecked<2>();
  for (py::ssize_t i = 0; i < points.shape(0); ++i) {
    out[i] = Vec3(r(i, 0), r(i, 1), r(i, 2));
    if (!out[i].allFinite())
      throw InputError("points", "[" + std::to_string(i) + "]", "not a finite point");
  }
  return out;
}

py::object JsonToPython(const std::string& text) {
  return py::module_::import("json").attr("loads")(text);
}

// An output path that is one of the scene's input files (the scene, a mesh, ...) is refused.
void RefuseInputPath(const Scene& scene, const std::string& path, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(path, ec);
  for (const auto& [input, kind] : scene.InputFiles()) {
    std::error_code e2;
    if (!ec && out == fs::weakly_canonical(input, e2))
      throw InputError(path, "", what + " would replace the " + kind + " " + input,
                       "write it somewhere else");
  }
}

// pandora.Scene and load_scene().
void BindScene(py::module_& m) {
  py::class_<PyScene>(m, "Scene", "A scene file, loaded and checked, with its ray caster.")
      .def_property_readonly("path", [](const PyScene& s) { return s.scene().path; })
      .def_property_readonly("rigs",
                             [](const PyScene& s) {
                               std::vector<std::string> names;
                               for (const Rig& r : s.scene().rigs) names.push_back(r.name);
                               return names;
                             })
      .def_property_readonly("voxel_size",
                             [](const PyScene& s) { return s.scene().study.voxel_size; })
      .def_property_readonly("region",
                             [](const PyScene& s) {
                               const Aabb& b = s.scene().study.region.box;
                               return py::make_tuple(Vec3Array(b.min), Vec3Array(b.max));
                             })
      .def(
          "rig",
          [](const PyScene& s, const std::string& name, const std::vector<std::string>& disable) {
            session::SessionOptions o;
            o.rig = name;
            o.rig_option = "rig";
            o.disable = disable;
            o.disable_option = "disable";
            o.fields.fields = {"coverage"};
            o.fields.scene_path = s.scene().path;
            o.incremental = false;
            return PyRig{s.study, std::make_shared<session::Session>(s.study, std::move(o))};
          },
          py::arg("name") = "", py::arg("disable") = std::vector<std::string>{},
          "The rig `name` (the first by default) to edit: moves are undoable and reach the scene "
          "file "
          "only through save() or an accepted suggestion. `disable`: camera ids left out (not an "
          "edit).");

  m.def(
      "load_scene", [](const std::string& path) { return PyScene{session::Study::Load(path)}; },
      py::arg("path"),
      "Reads and checks a scene file (meshes, rigs, study); raises pandora.InputError.");
}

// The session's typed edits beyond the pose (app/session/camera_edits.h), as the viewer makes them.
void BindTypedEdits(py::class_<PyRig>& rig) {
  rig.def(
         "orient",
         [](PyRig& r, const std::string& id, double yaw_deg, double pitch_deg, double roll_deg) {
           r.session->rig().Apply(
               session::MakeEdit(
                   r.rig(), session::OrientEdit{r.Index(id), Vec3(yaw_deg, pitch_deg, roll_deg)})
                   .edit);
         },
         py::arg("id"), py::arg("yaw_deg"), py::arg("pitch_deg"), py::arg("roll_deg") = 0.0,
         "Turns camera `id` to a yaw, pitch and roll in degrees (the scene file's euler_deg). One "
         "undo step; a PTZ camera's head follows.")
      .def(
          "zoom",
          [](PyRig& r, const std::vector<std::string>& ids, double hfov_deg) {
            r.session->rig().Apply(
                session::MakeEdit(r.rig(), session::ZoomEdit{r.Indices(ids), hfov_deg}).edit);
          },
          py::arg("ids"), py::arg("hfov_deg"),
          "Zooms cameras `ids` to a horizontal field of view in degrees (fy / fx kept). One undo "
          "step; a PTZ camera zooms within its head's range.")
      .def(
          "set_lens",
          [](PyRig& r, const std::vector<std::string>& ids,
             std::optional<std::pair<int, int>> resolution, std::optional<std::string> model,
             std::optional<double> k1, std::optional<double> k2, std::optional<double> p1,
             std::optional<double> p2, std::optional<double> k3, std::optional<double> k4) {
            session::LensEdit edit;
            edit.cameras = r.Indices(ids);
            if (resolution) std::tie(edit.width, edit.height) = *resolution;
            if (resolution && (edit.width == 0 || edit.height == 0))
              throw InputError("{resolution}", "",
                               "expected whole numbers of pixels from 1 to 65536");
            if (model) {
              edit.model = LensModelFromName(*model);
              if (!edit.model)
                throw InputError("{model}", "", "unknown lens model '" + *model + "'",
                                 "pinhole, brown_conrady or fisheye");
            }
            const std::optional<double>* c[6] = {&k1, &k2, &p1, &p2, &k3, &k4};
            for (int i = 0; i < 6; ++i)
              if (*c[i]) edit.coefficients[i] = **c[i];
            r.session->rig().Apply(session::MakeEdit(r.rig(), edit).edit);
          },
          py::arg("ids"), py::arg("resolution") = py::none(), py::arg("model") = py::none(),
          py::arg("k1") = py::none(), py::arg("k2") = py::none(), py::arg("p1") = py::none(),
          py::arg("p2") = py::none(), py::arg("k3") = py::none(), py::arg("k4") = py::none(),
          "Sets cameras `ids`' resolution (width, height: the same rays through the image's "
          "edges), lens model (pinhole, brown_conrady, fisheye: the field of view kept, the "
          "coefficients reset) and distortion coefficients, as the viewer's lens panel. One undo "
          "step.")
      .def(
          "set_range",
          [](PyRig& r, const std::vector<std::string>& ids, std::optional<double> near,
             std::optional<double> far) {
            r.session->rig().Apply(
                session::MakeEdit(r.rig(), session::RangeEdit{r.Indices(ids), near.value_or(NAN),
                                                              far.value_or(NAN)})
                    .edit);
          },
          py::arg("ids"), py::arg("near") = py::none(), py::arg("far") = py::none(),
          "Sets cameras `ids`' working range in metres (far may be math.inf). One undo step.")
      .def(
          "set_color",
          [](PyRig& r, const std::vector<std::string>& ids, const Vec3& color) {
            r.session->rig().Apply(
                session::MakeEdit(r.rig(), session::ColorEdit{r.Indices(ids), color}).edit);
          },
          py::arg("ids"), py::arg("color"),
          "Sets cameras `ids`' colour (linear RGB in [0, 1]). One undo step.");
}

// pandora.Rig: the editable rig (returned for the suggestion bindings that extend it).
py::class_<PyRig> BindRig(py::module_& m) {
  py::class_<PyRig> rig(m, "Rig",
                        "A rig of cameras being edited (undo, redo, save with a backup).");
  rig.def_property_readonly("name", [](const PyRig& r) { return r.rig().name; })
      .def_property_readonly("ids",
                             [](const PyRig& r) {
                               std::vector<std::string> ids;
                               for (const Camera& c : r.rig().cameras) ids.push_back(c.id);
                               return ids;
                             })
      .def("position",
           [](const PyRig& r, const std::string& id) {
             return Vec3Array(r.rig().cameras[r.Index(id)].center());
           })
      .def(
          "rotation",
          [](const PyRig& r, const std::string& id) -> Mat3 {
            return r.rig().cameras[r.Index(id)].world_from_camera.linear();
          },
          "world_from_camera rotation (columns: image x right, y down, optical axis).")
      .def("intrinsics",
           [](const PyRig& r, const std::string& id) {
             const Camera& c = r.rig().cameras[r.Index(id)];
             const Intrinsics& k = c.model.intrinsics();
             py::dict d;
             d["width"] = k.width;
             d["height"] = k.height;
             d["fx"] = k.fx;
             d["fy"] = k.fy;
             d["cx"] = k.cx;
             d["cy"] = k.cy;
             d["model"] = LensModelName(k.model);
             d["k"] = std::vector<double>{k.k1, k.k2, k.p1, k.p2, k.k3, k.k4};
             d["enabled"] = c.enabled;
             d["near"] = c.near;
             d["far"] = c.far;
             d["color"] = Vec3Array(c.color);
             d["ptz"] = bool(c.ptz);
             return d;
           })
      .def(
          "move",
          [](PyRig& r, const std::string& id, const Vec3& position, const Vec3& look_at,
             const Vec3& up) {
            // The session's edit, PTZ rule inside (app/session/camera_edits.h), as the viewer's.
            r.session->rig().Apply(
                session::MakeEdit(r.rig(), session::AimEdit{r.Index(id), position, look_at, up})
                    .edit);
          },
          py::arg("id"), py::arg("position"), py::arg("look_at"), py::arg("up") = Vec3(0, 0, 1),
          "Places camera `id` at `position` looking at `look_at` (metres, world frame). One undo "
          "step. A PTZ camera's head follows: its pivot moves with the centre, pan and tilt face "
          "`look_at` within the head's ranges (as in the viewer).")
      .def(
          "set_pose",
          [](PyRig& r, const std::string& id, const Vec3& position, const Mat3& rotation) {
            r.session->rig().Apply(
                session::MakeEdit(r.rig(), session::PoseEdit{r.Index(id), position, rotation})
                    .edit);
          },
          py::arg("id"), py::arg("position"), py::arg("rotation"),
          "Sets camera `id`'s centre (metres) and world_from_camera rotation (3x3). One undo step. "
          "A PTZ camera's head follows, as with move().")
      .def(
          "set_enabled",
          [](PyRig& r, const std::string& id, bool on) {
            r.session->rig().SetEnabled(r.Index(id), on);
          },
          py::arg("id"), py::arg("enabled"),
          "Switches a camera on or off (a what-if: save() does not write it).")
      .def(
          "undo", [](PyRig& r) { return r.session->rig().Undo(); },
          "Undoes the last edit; False when there is none.")
      .def(
          "redo", [](PyRig& r) { return r.session->rig().Redo(); },
          "Redoes the last undone edit; False when there is none.")
      .def_property_readonly(
          "unsaved",
          [](const PyRig& r) {
            std::vector<std::string> ids;
            for (int c : r.session->rig().Unsaved()) ids.push_back(r.rig().cameras[c].id);
            return ids;
          },
          "Ids of the cameras that differ from the scene file.");
  BindTypedEdits(rig);
  return rig;
}

}  // namespace pandora::python
