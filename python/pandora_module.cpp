// `import pandora`: the scene, its rigs, field evaluation, per-point visibility and covariance, and
// renders as numpy arrays (docs/python.md). Errors are pandora.InputError with the same file, JSON
// path, reason and hint as the command line's one-line messages.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/session/analyze.h"
#include "app/session/camera_edits.h"
#include "app/session/study.h"
#include "python/bindings.h"
#include "python/keywords.h"
#include "render/render.h"
#include "volume/fields.h"
#include "volume/fields_vdb.h"
#include "volume/ptz_fields.h"
#include "volume/summary.h"
#include "volume/vdb_io.h"

using namespace pandora;
using namespace pandora::python;

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

}  // namespace pandora::python

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct PyFields {
  std::shared_ptr<const session::Study> study;
  std::shared_ptr<Fields> fields;
  std::vector<std::string> names;
  nlohmann::json summary;
  std::string rig_name, rig_json;  // the rig evaluated (metadata of write())
};

std::string VoxelText(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.12g", v);
  return b;
}

openvdb::FloatGrid::ConstPtr FloatGrid(const PyFields& f, const std::string& name) {
  const Fields::Impl& g = f.fields->impl();
  if (auto grid = g.Float(name)) return grid;
  if (auto it = g.extra.find(name); it != g.extra.end()) return it->second;
  return nullptr;
}

double SigmaOf(const Scene& scene, const Camera& c) {
  return c.pixel_sigma > 0 ? c.pixel_sigma : scene.study.pixel_sigma;
}

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
  return rig;
}

// pandora.Fields: evaluated grids as sparse or dense arrays, and write().
void BindFields(py::module_& m) {
  py::class_<PyFields>(m, "Fields",
                       "Evaluated fields over the study region (sparse OpenVDB grids).")
      .def_property_readonly("names", [](const PyFields& f) { return f.names; })
      .def_property_readonly(
          "summary",
          [](const PyFields& f) {
            return py::module_::import("json").attr("loads")(f.summary.dump());
          },
          "summary.json of this evaluation, as a dict.")
      .def(
          "sparse",
          [](const PyFields& f, const std::string& name) {
            // Active voxels: (ijk (N, 3) int32, centres (N, 3) metres, values (N,)).
            const Fields::Impl& g = f.fields->impl();
            std::vector<openvdb::Coord> ijk;
            std::vector<double> values;
            if (name == "coverage" && g.coverage) {
              ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int v) {
                ijk.push_back(c);
                values.push_back(v);
              });
            } else if (auto grid = FloatGrid(f, name)) {
              ForEachActiveVoxel(*grid, [&](const openvdb::Coord& c, float v) {
                ijk.push_back(c);
                values.push_back(v);
              });
            } else {
              throw InputError("sparse", "", "no field '" + name + "' was evaluated");
            }
            const std::size_t n = ijk.size();
            py::array_t<int> idx({n, std::size_t(3)});
            py::array_t<double> xyz({n, std::size_t(3)});
            py::array_t<double> val(n);
            auto I = idx.mutable_unchecked<2>();
            auto X = xyz.mutable_unchecked<2>();
            auto V = val.mutable_unchecked<1>();
            for (std::size_t i = 0; i < n; ++i) {
              const openvdb::Vec3d w = g.transform->indexToWorld(ijk[i]);
              for (int a = 0; a < 3; ++a) {
                I(i, a) = ijk[i][a];
                X(i, a) = w[a];
              }
              V(i) = values[i];
            }
            return py::make_tuple(idx, xyz, val);
          },
          py::arg("name"))
      .def(
          "dense",
          [](const PyFields& f, const std::string& name) {
            // The whole lattice (nx, ny, nz), NaN where the field has no value (unseen, solid,
            // outside).
            const VoxelLattice& L = f.fields->lattice;
            py::array_t<double> out(
                {std::size_t(L.dims.x()), std::size_t(L.dims.y()), std::size_t(L.dims.z())});
            auto O = out.mutable_unchecked<3>();
            for (py::ssize_t i = 0; i < O.shape(0); ++i)
              for (py::ssize_t j = 0; j < O.shape(1); ++j)
                for (py::ssize_t k = 0; k < O.shape(2); ++k) O(i, j, k) = kNaN;
            const Fields::Impl& g = f.fields->impl();
            auto put = [&](const openvdb::Coord& c, double v) {
              const openvdb::Coord& o = c;  // index (0, 0, 0) is the lattice's origin
              if (o.x() >= 0 && o.y() >= 0 && o.z() >= 0 && o.x() < L.dims.x() &&
                  o.y() < L.dims.y() && o.z() < L.dims.z())
                O(o.x(), o.y(), o.z()) = v;
            };
            if (name == "coverage" && g.coverage)
              ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int v) { put(c, v); });
            else if (auto grid = FloatGrid(f, name))
              ForEachActiveVoxel(*grid, [&](const openvdb::Coord& c, float v) { put(c, v); });
            else
              throw InputError("dense", "", "no field '" + name + "' was evaluated");
            return out;
          },
          py::arg("name"))
      .def(
          "write",
          [](const PyFields& f, const std::string& path) {
            const Scene& scene = f.study->scene();
            RefuseInputPath(scene, path, "fields.vdb");
            const std::map<std::string, std::string> meta{
                {"units", "m"},
                {"tool", "pandora (python)"},
                {"scene_file", scene.path},
                {"scene_sha256", scene.sha256},
                {"rig_name", f.rig_name},
                {"rig", f.rig_json},
                {"voxel_size_m", VoxelText(scene.study.voxel_size)}};
            py::gil_scoped_release release;
            WriteFieldsVdb(*f.fields, path, meta);
          },
          py::arg("path"),
          "Writes the grids as `pandora analyze` writes fields.vdb (atomically; never over an "
          "input).");
}

// evaluate(): the fields for a rig.
void BindEvaluate(py::module_& m) {
  m.def(
      "evaluate",
      [](const PyScene& s, const PyRig& r, std::vector<std::string> fields) {
        const Scene& scene = s.scene();
        const Rig rig = r.rig();  // a copy: the evaluation runs without the GIL
        // What `pandora analyze` computes (app/session/analyze.h): the fields, then the time
        // samples, surface targets, pixel targets, DORI, warnings, calibration, N-1 and PTZ.
        session::AnalyzeOptions analysis;
        FieldOptions& o = analysis.fields;
        o.fields = fields.empty() ? scene.study.fields : fields;
        o.scene_path = scene.path;
        o.memory_budget_bytes = scene.study.memory_budget_bytes;
        PyFields out;
        out.study = s.study;
        session::RigAnalysis result;
        {
          py::gil_scoped_release release;
          session::RigFieldsAnalysis a = session::AnalyzeRig(*s.study, rig, analysis);
          out.fields = std::make_shared<Fields>(std::move(a.fields));
          result = std::move(a.analysis);
        }
        out.names = o.fields;
        for (const auto& [name, grid] : out.fields->impl().extra) out.names.push_back(name);
        out.summary = result.summary;
        out.rig_name = rig.name;
        out.rig_json = RigToJson(rig).dump();
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("fields") = std::vector<std::string>{},
      "Evaluates the fields (default: the study's) for the rig's enabled cameras, and what "
      "`pandora analyze` computes beside them (time samples, surface targets, pixel targets, DORI, "
      "warnings, calibration, N-1, PTZ reach and tours): the same summary and the same grids.");
}

// visibility() and covariance() at given points.
void BindPointQueries(py::module_& m) {
  m.def(
      "visibility",
      [](const PyScene& s, const PyRig& r,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& points) {
        const std::vector<Vec3> X = Points(points);
        const VisibilityTester tester(r.rig().cameras, s.study->caster(),
                                      s.scene().ContentBounds().diagonal());
        const std::size_t C = r.rig().cameras.size();
        py::array_t<bool> out({X.size(), C});
        auto O = out.mutable_unchecked<2>();
        for (std::size_t i = 0; i < X.size(); ++i)
          for (std::size_t c = 0; c < C; ++c)
            O(i, c) = r.rig().cameras[c].enabled && tester.Test(int(c), X[i]) == ViewResult::kSeen;
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("points"),
      "(N, C) booleans: camera c sees point i (image, range, occlusion; the field evaluation's "
      "rules).");

  m.def(
      "covariance",
      [](const PyScene& s, const PyRig& r,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& points) {
        const Scene& scene = s.scene();
        const std::vector<Vec3> X = Points(points);
        const VisibilityTester tester(r.rig().cameras, s.study->caster(),
                                      scene.ContentBounds().diagonal());
        py::array_t<double> out({X.size(), std::size_t(3), std::size_t(3)});
        auto O = out.mutable_unchecked<3>();
        for (std::size_t i = 0; i < X.size(); ++i) {
          Mat3 J = Mat3::Zero();
          int cameras = 0;
          for (std::size_t c = 0; c < r.rig().cameras.size(); ++c) {
            if (!r.rig().cameras[c].enabled) continue;
            Mat23 A;
            if (tester.Test(int(c), X[i], nullptr, &A) != ViewResult::kSeen) continue;
            const double sigma = SigmaOf(scene, r.rig().cameras[c]);
            J += A.transpose() * A / (sigma * sigma);
            ++cameras;
          }
          const StaticUncertainty u = StaticFromInformation(DecomposeInformation(J), cameras);
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) O(i, a, b) = u.triangulable ? u.covariance(a, b) : kNaN;
        }
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("points"),
      "(N, 3, 3) triangulation covariance (m^2) from the cameras that see each point; NaN where "
      "not triangulable.");
}

// render(): the projective-light render as a numpy array.
void BindRender(py::module_& m) {
  m.def(
      "render",
      [](const PyScene& s, const PyRig& r, const std::string& view, int width, int height,
         const std::string& plan) {
        const Scene& scene = s.scene();
        RenderView v;
        RenderOptions o;
        if (!plan.empty()) {
          double mpp = 0;
          const std::optional<RenderView> p =
              PlanView(scene.ContentBounds(), plan, width, height,
                       plan == "plan" ? scene.study.region.box.max.z() : kNaN, &mpp);
          if (!p)
            throw InputError("plan", "", "unknown side '" + plan + "'",
                             "use plan, north, south, east or west");
          v = *p;
          o.overlays.labels = true;
        } else {
          auto it = scene.views.find(view);
          if (view.empty() && !scene.views.empty()) it = scene.views.begin();
          if (it == scene.views.end())
            throw InputError("view", "", "no view '" + view + "' in the scene");
          v = ViewFromScene(it->second, width, height);
        }
        o.pixel_sigma = scene.study.pixel_sigma;
        Image image;
        {
          py::gil_scoped_release release;
          image = Render(scene, r.rig(), s.study->caster(), v, o);
        }
        py::array_t<float> out(
            {std::size_t(image.height), std::size_t(image.width), std::size_t(3)});
        std::copy(image.rgb.begin(), image.rgb.end(), out.mutable_data());
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("view") = "", py::arg("width") = 640,
      py::arg("height") = 400, py::arg("plan") = "",
      "The projective-light render as an (H, W, 3) float32 linear RGB array.");
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
