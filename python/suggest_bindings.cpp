// `import pandora`, suggest and accept (docs/python.md): camera nudges (the same options and checks
// as `pandora suggest`), PTZ preset and tour suggestions, accept into the scene file (the same code
// as `pandora accept`: backup, read-back check), and the rig's PTZ settings and save().
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/motion.h"
#include "analysis/scene/ptz.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/input_file.h"
#include "analysis/util/units.h"
#include "app/commands.h"
#include "app/session/camera_edits.h"
#include "app/suggest_options.h"
#include "python/bindings.h"
#include "suggest/ptz_suggest.h"
#include "suggest/suggest.h"
#include "suggest/suggestion_file.h"
#include "suggest/suggestion_text.h"
#include "volume/ptz_fields.h"

namespace pandora::python {
namespace {

// A suggestion for the rig it was made on (camera nudges or a PTZ controller change).
struct PySuggestion {
  std::shared_ptr<const session::Study> study;
  std::shared_ptr<session::Session> session;
  std::string kind;  // "cameras", "ptz_preset", "ptz_tour"
  std::string json;  // the suggestion file's text
  bool improved = false;
  std::string message;
  bool from_unsaved_rig = false;  // the rig had edits the scene file lacks when it was made
  std::optional<Suggestion> cameras;
  std::optional<PtzPresetSuggestion> preset;
  std::optional<PtzTourSuggestion> tour;
  int ptz_camera = -1, ptz_preset = -1;
};

// A number for every selected camera, or a list of them in `cameras` order.
std::vector<double> NumberOrList(const py::handle& value, const char* name) {
  if (py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value))
    return {value.cast<double>()};
  try {
    return value.cast<std::vector<double>>();
  } catch (const py::cast_error&) {
    throw InputError(name, "", "expected a number or a list of numbers (one per selected camera)");
  }
}

// A value for every selected camera, or {id: value}; `convert` turns one Python value into T.
template <typename T, typename F>
std::vector<app::ForCamera<T>> PerCameraEntries(const py::object& value, F convert) {
  std::vector<app::ForCamera<T>> out;
  if (value.is_none()) return out;
  if (py::isinstance<py::dict>(value)) {
    for (const auto& [id, v] : value.cast<py::dict>())
      out.push_back({py::str(id).cast<std::string>(), convert(v)});
  } else {
    out.push_back({"", convert(value)});
  }
  return out;
}

// `n` numbers from a Python sequence, or InputError(name, reason).
std::vector<double> Numbers(const py::handle& v, std::size_t n, const char* name,
                            const char* reason) {
  std::vector<double> x;
  try {
    x = v.cast<std::vector<double>>();
  } catch (const py::cast_error&) {
  }
  if (x.size() != n) throw InputError(name, "", reason);
  return x;
}

Vec3 Vector3(const py::handle& v, const char* name) {
  const std::vector<double> x = Numbers(v, 3, name, "expected three numbers (a direction, metres)");
  return Vec3(x[0], x[1], x[2]);
}

Aabb Box(const py::handle& v, const char* name) {
  const char* reason = "expected a box as (min corner, max corner), metres";
  if (!py::isinstance<py::sequence>(v) || py::len(v) != 2) throw InputError(name, "", reason);
  const py::sequence corners = py::reinterpret_borrow<py::sequence>(v);
  const std::vector<double> lo = Numbers(corners[0], 3, name, reason);
  const std::vector<double> hi = Numbers(corners[1], 3, name, reason);
  Aabb box;
  box.min = Vec3(lo[0], lo[1], lo[2]);
  box.max = Vec3(hi[0], hi[1], hi[2]);
  return box;
}

std::array<double, 2> Range(const py::handle& v, const char* name) {
  const std::vector<double> x = Numbers(v, 2, name, "expected (min, max) degrees");
  return {x[0], x[1]};
}

py::dict MetricsDict(const Metrics& m) {
  py::dict d;
  d["objective"] = m.objective;
  d["coverage_k"] = m.coverage_k;
  d["coverage2"] = m.coverage2;
  d["sigma_p50_mm"] = m.sigma_p50;
  d["sigma_p90_mm"] = m.sigma_p90;
  d["sigma_p95_mm"] = m.sigma_p95;
  d["sigma_mean_mm"] = m.sigma_mean;
  d["untriangulable"] = m.untriangulable;
  d["min_resolution_px_per_m"] = m.min_resolution;
  if (m.n1) {
    d["n1_coverage_k"] = m.n1->coverage_k;
    d["n1_worst_camera"] = m.n1->worst_camera;
  }
  if (m.calibration) d["calibration_weakest"] = m.calibration->weakest;
  return d;
}

Eigen::Matrix4d Matrix(const Eigen::Isometry3d& pose) { return pose.matrix(); }

// The target points of a suggestion: the study region's or a named region's, and/or surfaces.
std::vector<TargetPoint> Targets(const Scene& scene, int points,
                                 const std::vector<std::string>& surfaces, bool with_region,
                                 const std::string& region_name, std::uint64_t seed) {
  if (points < 1 || points > 1000000) throw InputError("points", "", "must be in [1, 1000000]");
  return app::SampleTargetsInRegion(scene, "target_region", region_name, points, surfaces,
                                    with_region, seed);
}

// Applies a suggestion to its rig in memory as one undo step: `subset` (the accepted cameras of a
// camera suggestion) or the PTZ preset / tour.
void ApplyInMemory(PySuggestion& s, const Suggestion* subset) {
  if (subset) {
    s.session->ApplySuggestion(*subset);
    return;
  }
  const Camera& c = s.session->rig().rig().cameras.at(s.ptz_camera);
  auto head = std::make_shared<PtzHead>(*c.ptz);
  std::string label;
  if (s.preset) {
    if (c.ptz->presets.at(s.ptz_preset).state.pan_deg != s.preset->before.pan_deg ||
        c.ptz->presets.at(s.ptz_preset).state.tilt_deg != s.preset->before.tilt_deg ||
        c.ptz->presets.at(s.ptz_preset).state.focal != s.preset->before.focal)
      throw InputError(s.study->scene().path, "",
                       "preset '" + s.preset->preset + "' changed since the suggestion",
                       "ask for a new suggestion");
    head->presets.at(s.ptz_preset).state = s.preset->after;
    label = "suggested preset " + s.preset->preset;
  } else {
    if (c.ptz->tour.size() != s.tour->after.size())
      throw InputError(s.study->scene().path, "", "the tour changed since the suggestion",
                       "ask for a new suggestion");
    head->tour.clear();
    for (int stop : s.tour->after) head->tour.push_back(c.ptz->tour.at(stop));
    label = "suggested tour order";
  }
  Camera after = c;
  after.ptz = std::move(head);
  s.session->rig().Apply({label, {{s.ptz_camera, c, after}}});
}

py::dict AcceptDict(const AcceptResult& r) {
  py::dict d;
  d["scene_path"] = r.scene_path;
  d["backup_path"] = r.backup_path;
  d["accepted"] = r.accepted;
  d["notes"] = r.notes;
  return d;
}

// Accepts suggestion file text through AcceptSuggestion (the `pandora accept` code) from a private
// temporary file, removed afterwards.
AcceptResult AcceptText(const std::string& text, const AcceptOptions& options) {
  namespace fs = std::filesystem;
  std::random_device rd;
  const fs::path dir = fs::temp_directory_path() /
                       ("pandora-accept-" + std::to_string(rd()) + "-" + std::to_string(rd()));
  fs::create_directory(dir);
  const std::string path = (dir / "suggestion.json").string();
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{dir};
  WriteFileAtomically(path, text);
  try {
    return AcceptSuggestion(path, options);
  } catch (const InputError& e) {
    if (e.file() != path) throw;
    throw InputError("suggestion", e.json_path(), e.reason(), e.hint());
  }
}

// ---- PTZ settings of a rig camera, and save ---------------------------------------------------
// Rig.ptz(), Rig.set_ptz() and Rig.save().
void BindPtzSettings(py::class_<PyRig>& rig) {
  rig.def(
         "ptz",
         [](const PyRig& r, const std::string& id) {
           const Camera& c = r.rig().cameras[r.Index(id)];
           if (!c.ptz) throw InputError("ptz", "", "camera '" + id + "' has no PTZ head");
           const PtzHead& h = *c.ptz;
           const Intrinsics& k = c.model.intrinsics();
           auto hfov = [&](double f) { return HfovFromFocal(f, k.width, k.model) * 180 / kPi; };
           py::dict d;
           d["pan_deg"] = h.current.pan_deg;
           d["tilt_deg"] = h.current.tilt_deg;
           d["hfov_deg"] = hfov(h.current.focal);
           d["pan_range_deg"] = py::make_tuple(h.pan_min_deg, h.pan_max_deg);
           d["tilt_range_deg"] = py::make_tuple(h.tilt_min_deg, h.tilt_max_deg);
           d["hfov_range_deg"] = py::make_tuple(hfov(h.focal_max), hfov(h.focal_min));
           d["pivot"] = Vec3Array(h.home.translation());
           py::list presets;
           for (const PtzPreset& p : h.presets) {
             py::dict q;
             q["name"] = p.name;
             q["pan_deg"] = p.state.pan_deg;
             q["tilt_deg"] = p.state.tilt_deg;
             q["hfov_deg"] = hfov(p.state.focal);
             presets.append(q);
           }
           d["presets"] = presets;
           py::list tour;
           for (const PtzTourStop& s : h.tour) {
             py::dict q;
             q["preset"] = h.presets[s.preset].name;
             q["dwell_s"] = s.dwell_s;
             tour.append(q);
           }
           d["tour"] = tour;
           return d;
         },
         py::arg("id"), "A PTZ camera's setting (pan, tilt, hfov), ranges, presets and tour.")
      .def(
          "set_ptz",
          [](PyRig& r, const std::string& id, std::optional<double> pan_deg,
             std::optional<double> tilt_deg, std::optional<double> hfov_deg,
             const std::string& preset) {
            // The session's typed edit (app/session/camera_edits.h), as the viewer's "ptz".
            session::PtzEdit edit{r.Index(id), preset, pan_deg.value_or(NAN),
                                  tilt_deg.value_or(NAN), hfov_deg.value_or(NAN)};
            r.session->rig().Apply(session::MakeEdit(r.rig(), edit).edit);
          },
          py::arg("id"), py::arg("pan_deg") = py::none(), py::arg("tilt_deg") = py::none(),
          py::arg("hfov_deg") = py::none(), py::arg("preset") = "",
          "Points PTZ camera `id` (a preset's setting, then the given angles; clamped to its "
          "ranges). One undo step.")
      .def(
          "recentre",
          [](PyRig& r, const std::string& id) {
            const int c = r.Index(id);
            r.session->rig().Apply(
                session::MakeEdit(r.rig(), session::RecentreEdit{c, r.study->scene().path,
                                                                 r.session->CameraJsonPath(c)})
                    .edit);
          },
          py::arg("id"),
          "Makes PTZ camera `id`'s current view its home (pan and tilt 0; presets and ranges "
          "shifted). One undo step.")
      .def(
          "save",
          [](PyRig& r, bool force) {
            const session::SaveResult s = r.session->Save(force);
            py::dict d;
            d["scene_path"] = s.scene_path;
            d["backup_path"] = s.backup_path;
            d["saved"] = s.saved;
            d["notes"] = s.notes;
            return d;
          },
          py::arg("force") = false,
          "Writes the edited cameras' poses and zooms (PTZ: pan, tilt, zoom) into the scene file, "
          "keeping "
          "the previous file as a backup; refuses when the file changed since it was loaded "
          "(unless force).");
}

// ---- Suggestions -----------------------------------------------------------------------------
// pandora.Suggestion: its measures, save(), apply() and accept().
void BindSuggestion(py::module_& m) {
  py::class_<PySuggestion>(m, "Suggestion",
                           "A suggestion: look at it, apply it to the rig, save it, or accept it.")
      .def_property_readonly("kind", [](const PySuggestion& s) { return s.kind; })
      .def_property_readonly("improved", [](const PySuggestion& s) { return s.improved; })
      .def_property_readonly("message", [](const PySuggestion& s) { return s.message; })
      .def_property_readonly(
          "before",
          [](const PySuggestion& s) -> py::object {
            if (s.cameras) return MetricsDict(s.cameras->before);
            return JsonToPython(s.json)["ptz"]["before"];
          },
          "The exact measures at the start (camera nudges) or the PTZ measures before.")
      .def_property_readonly("after",
                             [](const PySuggestion& s) -> py::object {
                               if (s.cameras) return MetricsDict(s.cameras->after);
                               return JsonToPython(s.json)["ptz"]["after"];
                             })
      .def_property_readonly(
          "cameras",
          [](const PySuggestion& s) {
            py::list out;
            if (!s.cameras) return out;
            for (const CameraChange& c : s.cameras->cameras) {
              py::dict d;
              d["id"] = c.id;
              d["before"] = Matrix(c.before);
              d["after"] = Matrix(c.after);
              d["move_m"] = c.move_m;
              d["rotate_deg"] = c.rotate_deg;
              d["hfov_before_deg"] = c.hfov_before_deg;
              d["hfov_after_deg"] = c.hfov_after_deg;
              d["note"] = c.note;
              out.append(d);
            }
            return out;
          },
          "Per selected camera: world_from_camera 4x4 before and after, the move, the turn, the "
          "zoom.")
      .def(
          "to_dict", [](const PySuggestion& s) { return JsonToPython(s.json); },
          "The suggestion file, as a dict.")
      .def("__str__", [](const PySuggestion& s) { return s.message; })
      .def(
          "save",
          [](const PySuggestion& s, const std::string& path) {
            RefuseInputPath(s.study->scene(), path, "the suggestion file");
            WriteFileAtomically(path, s.json);
          },
          py::arg("path"),
          "Writes the suggestion file (`pandora accept PATH` takes it), atomically.")
      .def(
          "apply",
          [](PySuggestion& s) {
            if (!s.improved)
              throw InputError("apply", "",
                               "the suggestion offers no improvement; nothing to apply");
            ApplyInMemory(s, s.cameras ? &*s.cameras : nullptr);
          },
          "Applies the suggestion to the rig in memory (one undo step); nothing is written.")
      .def(
          "accept",
          [](PySuggestion& s, std::vector<std::string> cameras, bool force) {
            const Scene& scene = s.study->scene();
            if (!s.improved)
              throw InputError(scene.path, "",
                               "the suggestion offers no improvement; nothing to accept");
            if (s.from_unsaved_rig)
              throw InputError(scene.path, "",
                               "the suggestion was made on a rig with unsaved edits",
                               "apply() it and save() the rig, which writes those edits too");
            if (!s.session->rig().Unsaved().empty())
              throw InputError(scene.path, "", "the rig has unsaved edits since the suggestion",
                               "save() or undo() them first");
            AcceptOptions options;
            options.cameras = cameras;
            options.force = force;
            // In memory first (refused when a camera moved since), then the file; a failure undoes
            // both.
            Suggestion accepted;
            if (s.cameras) {
              accepted = *s.cameras;
              if (!cameras.empty()) {
                accepted.cameras.clear();
                for (const CameraChange& c : s.cameras->cameras)
                  for (const std::string& id : cameras)
                    if (c.id == id) accepted.cameras.push_back(c);
              }
            }
            const std::int64_t version = s.session->rig().version();
            if (!s.cameras || !accepted.cameras.empty())
              ApplyInMemory(s, s.cameras ? &accepted : nullptr);
            AcceptResult result;
            try {
              result = AcceptText(s.json, options);
            } catch (...) {
              if (s.session->rig().version() != version) s.session->rig().Undo();
              throw;
            }
            s.session->MarkSaved(ReadInputFile(result.scene_path, 64u << 20, "scene file"));
            return AcceptDict(result);
          },
          py::arg("cameras") = std::vector<std::string>{}, py::arg("force") = false,
          "Writes the suggestion into the scene file as `pandora accept` does (backup, read-back "
          "check) and "
          "applies it to the rig; `cameras`: only these ids (camera nudges).");
}

// suggest(): camera nudges, as `pandora suggest`.
void BindSuggestCameras(py::module_& m) {
  m.def(
      "suggest",
      [](const PyScene& sc, PyRig& r, std::vector<std::string> cameras,
         const std::string& objective, int points, std::vector<std::string> target_surfaces,
         bool with_region, bool over_time, const py::object& max_move,
         const py::object& max_rotate_deg, const py::object& hfov_range, const py::object& rail,
         const py::object& plane, const py::object& mount_box,
         const std::vector<py::object>& keep_out, double clearance, double snap_move,
         double snap_rotate_deg, int outer_iterations, std::uint64_t seed) {
        const Scene& scene = sc.scene();
        if (r.study != sc.study) throw InputError("rig", "", "the rig belongs to another scene");
        if (cameras.empty())
          throw InputError("cameras", "", "which cameras may move?", "give cameras=[ids]");
        app::SuggestRequest a;
        a.cameras = cameras;
        a.objective = objective;
        a.points = points;
        a.target_surfaces = target_surfaces;
        a.with_region = with_region;
        a.over_time = over_time;
        a.clearance = clearance;
        a.snap_move = snap_move;
        a.snap_rotate_deg = snap_rotate_deg;
        a.outer_iterations = outer_iterations;
        a.seed = seed;
        a.max_move = NumberOrList(max_move, "{max_move}");
        a.max_rotate_deg = NumberOrList(max_rotate_deg, "{max_rotate_deg}");
        a.hfov_range = PerCameraEntries<std::array<double, 2>>(
            hfov_range, [](const py::handle& v) { return Range(v, "{hfov_range}"); });
        a.rail =
            PerCameraEntries<Vec3>(rail, [](const py::handle& v) { return Vector3(v, "{rail}"); });
        a.plane = PerCameraEntries<Vec3>(plane,
                                         [](const py::handle& v) { return Vector3(v, "{plane}"); });
        a.mount_box = PerCameraEntries<Aabb>(
            mount_box, [](const py::handle& v) { return Box(v, "{mount_box}"); });
        for (const py::object& box : keep_out) a.keep_out.push_back(Box(box, "{keep_out}"));
        const std::shared_ptr<app::SuggestProblem> problem = app::PrepareSuggest(a, scene, r.rig());
        PySuggestion out;
        out.study = sc.study;
        out.session = r.session;
        out.kind = "cameras";
        out.from_unsaved_rig = !r.session->rig().Unsaved().empty();
        {
          py::gil_scoped_release release;
          out.cameras = r.session->Suggest(problem->targets, problem->options);
        }
        out.improved = out.cameras->improved;
        out.message = out.cameras->message;
        out.json = SuggestionToJson(*out.cameras, scene, r.rig(), problem->options);
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("cameras"), py::arg("objective") = "coverage2",
      py::arg("points") = 1500, py::arg("target_surfaces") = std::vector<std::string>{},
      py::arg("with_region") = false, py::arg("over_time") = false,
      py::arg("max_move") = py::float_(0.3), py::arg("max_rotate_deg") = py::float_(10.0),
      py::arg("hfov_range") = py::none(), py::arg("rail") = py::none(),
      py::arg("plane") = py::none(), py::arg("mount_box") = py::none(),
      py::arg("keep_out") = std::vector<py::object>{}, py::arg("clearance") = 0.1,
      py::arg("snap_move") = 0.0, py::arg("snap_rotate_deg") = 0.0, py::arg("outer_iterations") = 4,
      py::arg("seed") = 1,
      "Nudges the `cameras` of `rig` within the limits to improve `objective` over target points, "
      "as "
      "`pandora suggest` does (docs/suggest.md). Per-camera limits: a value for all, a list in "
      "`cameras` "
      "order, or for hfov_range / rail / plane / mount_box a dict {id: value}.");
}

// suggest_ptz_preset() and suggest_ptz_tour().
void BindSuggestPtz(py::module_& m) {
  auto ptz_common = [](const PyScene& sc, PyRig& r, const char* option, const std::string& id,
                       int points, const std::string& target_region,
                       const std::vector<std::string>& surfaces, bool with_region,
                       std::uint64_t seed, int* camera, std::vector<Vec3>* xyz) {
    if (r.study != sc.study) throw InputError("rig", "", "the rig belongs to another scene");
    *camera = app::PtzCameraOption(r.rig(), option, id);
    for (const TargetPoint& t :
         Targets(sc.scene(), points, surfaces, with_region, target_region, seed))
      xyz->push_back(t.p);
  };

  m.def(
      "suggest_ptz_preset",
      [ptz_common](const PyScene& sc, PyRig& r, const std::string& camera,
                   const std::string& preset, int points, const std::string& target_region,
                   std::vector<std::string> target_surfaces, bool with_region, std::uint64_t seed) {
        int c = -1;
        std::vector<Vec3> xyz;
        ptz_common(sc, r, "camera", camera, points, target_region, target_surfaces, with_region,
                   seed, &c, &xyz);
        const PtzHead& head = *r.rig().cameras[c].ptz;
        int p = -1;
        std::string names;
        for (std::size_t i = 0; i < head.presets.size(); ++i) {
          names += (names.empty() ? "" : ", ") + head.presets[i].name;
          if (head.presets[i].name == preset) p = int(i);
        }
        if (p < 0)
          throw InputError("preset", "", "camera '" + camera + "' has no preset '" + preset + "'",
                           "its presets: " + names);
        PySuggestion out;
        out.study = sc.study;
        out.session = r.session;
        out.kind = "ptz_preset";
        out.from_unsaved_rig = !r.session->rig().Unsaved().empty();
        out.ptz_camera = c;
        out.ptz_preset = p;
        {
          py::gil_scoped_release release;
          const VisibilityTester tester(r.rig().cameras, sc.study->caster(),
                                        sc.scene().ContentBounds().diagonal());
          out.preset = SuggestPtzPreset(tester, c, p, xyz, sc.scene().study.ptz.min_px_per_m);
        }
        out.improved = out.preset->improved();
        out.message = camera + " preset " + preset + ": sees " +
                      std::to_string(out.preset->seen_before) + " -> " +
                      std::to_string(out.preset->seen_after) + " of " +
                      std::to_string(out.preset->points) + " target points";
        out.json = PtzPresetSuggestionToJson(*out.preset, sc.scene(), r.rig());
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("camera"), py::arg("preset"),
      py::arg("points") = 1500, py::arg("target_region") = "",
      py::arg("target_surfaces") = std::vector<std::string>{}, py::arg("with_region") = false,
      py::arg("seed") = 1,
      "The pan, tilt and zoom of a PTZ camera's preset that see the most target points at the "
      "study's "
      "PTZ density target (docs/ptz.md); `target_region`: one of study.regions.");

  m.def(
      "suggest_ptz_tour",
      [ptz_common](const PyScene& sc, PyRig& r, const std::string& camera,
                   const std::string& objective, int points, const std::string& target_region,
                   std::vector<std::string> target_surfaces, bool with_region, std::uint64_t seed) {
        const std::optional<TourObjective> tour = TourObjectiveFromName(objective);
        if (!tour)
          throw InputError("objective", "", "unknown tour objective '" + objective + "'",
                           "use mean or max");
        int c = -1;
        std::vector<Vec3> xyz;
        ptz_common(sc, r, "camera", camera, points, target_region, target_surfaces, with_region,
                   seed, &c, &xyz);
        if (r.rig().cameras[c].ptz->tour.size() < 3)
          throw InputError(
              "camera", "",
              "camera '" + camera + "' has fewer than 3 tour stops: every order is the same cycle");
        PySuggestion out;
        out.study = sc.study;
        out.session = r.session;
        out.kind = "ptz_tour";
        out.from_unsaved_rig = !r.session->rig().Unsaved().empty();
        out.ptz_camera = c;
        {
          py::gil_scoped_release release;
          const std::unique_ptr<SurfaceDistance> surfaces = PtzSweptOccluders(sc.scene(), r.rig());
          const VisibilityTester tester(r.rig().cameras, sc.study->caster(),
                                        sc.scene().ContentBounds().diagonal(), surfaces.get());
          out.tour = SuggestPtzTour(tester, c, xyz, sc.scene().study.ptz.min_px_per_m, *tour);
        }
        out.improved = out.tour->improved();
        char line[256];
        std::snprintf(line, sizeof line,
                      "%s tour: longest gap %.2f -> %.2f s, mean longest gap %.2f -> %.2f s",
                      camera.c_str(), out.tour->gap_max_before, out.tour->gap_max_after,
                      out.tour->gap_mean_before, out.tour->gap_mean_after);
        out.message = line;
        out.json = PtzTourSuggestionToJson(*out.tour, sc.scene(), r.rig());
        return out;
      },
      py::arg("scene"), py::arg("rig"), py::arg("camera"), py::arg("objective") = "mean",
      py::arg("points") = 1500, py::arg("target_region") = "",
      py::arg("target_surfaces") = std::vector<std::string>{}, py::arg("with_region") = false,
      py::arg("seed") = 1,
      "The order of a PTZ camera's tour stops that minimises the mean (or max) longest unwatched "
      "gap.");
}

// accept(): a saved suggestion file into its scene file.
void BindAccept(py::module_& m) {
  m.def(
      "accept",
      [](const std::string& path, std::vector<std::string> cameras, bool force) {
        AcceptOptions options;
        options.cameras = cameras;
        options.force = force;
        return AcceptDict(AcceptSuggestion(path, options));
      },
      py::arg("path"), py::arg("cameras") = std::vector<std::string>{}, py::arg("force") = false,
      "`pandora accept PATH`: writes a saved suggestion file into its scene file (backup kept).");
}

}  // namespace

void BindSuggest(py::module_& m, py::class_<PyRig>& rig) {
  BindPtzSettings(rig);
  BindSuggestion(m);
  BindSuggestCameras(m);
  BindSuggestPtz(m);
  BindAccept(m);
}

}  // namespace pandora::python
