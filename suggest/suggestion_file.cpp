// The suggestion file and `pandora accept`: the scene file changes only here, only in the pose
// fields of the accepted cameras, after a backup.
#include "suggest/suggestion_file.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "analysis/scene/scene_text.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "analysis/util/json_reader.h"
#include "analysis/util/output_transaction.h"
#include "analysis/util/sha256.h"
#include "analysis/util/units.h"
#include "suggest/ptz_suggest.h"
#include "suggest/suggest.h"

namespace pandora {
namespace {

using json = nlohmann::json;
using ordered_json = nlohmann::ordered_json;
using scene_text::Clean;
using scene_text::IdOf;
using scene_text::MetresPerUnit;
using scene_text::Number;
using scene_text::ParseOrdered;
using scene_text::ReadJsonText;

json Finite(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json MetricsJson(const Metrics& m) {
  json j{
      {"objective", Finite(m.objective)},
      {"coverage_k", m.coverage_k},
      {"coverage2", m.coverage2},
      {"sigma_max_mm",
       {{"p50", Finite(m.sigma_p50)}, {"p90", Finite(m.sigma_p90)}, {"p95", Finite(m.sigma_p95)}}},
      {"sigma_max_mean_mm", Finite(m.sigma_mean)},
      {"untriangulable", m.untriangulable},
      {"min_resolution_px_per_m", Finite(m.min_resolution)}};
  if (m.n1) j["n1"] = {{"coverage_k", m.n1->coverage_k}, {"worst_camera", m.n1->worst_camera}};
  if (m.calibration)
    j["calibration"] = {{"weakest_shared", m.calibration->weakest},
                        {"weakest_link", {m.calibration->weakest_a, m.calibration->weakest_b}},
                        {"tree_shared", m.calibration->tree_total},
                        {"components", m.calibration->components},
                        {"uncalibratable", m.calibration->uncalibratable},
                        {"poses", m.calibration->poses}};
  return j;
}

json PoseJson(const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.linear());
  const Vec3 p = pose.translation();
  return json{{"position", {p.x(), p.y(), p.z()}}, {"quaternion", {q.w(), q.x(), q.y(), q.z()}}};
}

// A pose {"position": [x, y, z], "quaternion": [w, x, y, z]} (normalised).
Eigen::Isometry3d ReadPose(const JsonNode& node) {
  node.ExpectObject("a pose {\"position\", \"quaternion\"}");
  const Vec3 p = node.Get("position").Numbers(3);
  const JsonNode q = node.Get("quaternion");
  const Eigen::VectorXd w = q.Numbers(4);
  Eigen::Quaterniond quat(w[0], w[1], w[2], w[3]);
  if (!(quat.norm() > 0.5)) q.Fail("not a unit quaternion");
  quat.normalize();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = quat.toRotationMatrix();
  pose.translation() = p;
  return pose;
}

// A coordinate in file units: the multiple of `step` when it is one (within 1e-6 of a step).
double OnGrid(double v, double step) {
  if (step > 0) {
    const double k = std::round(v / step);
    if (std::abs(v / step - k) < 1e-6) return Clean(k * step);
  }
  return Clean(v);
}

ordered_json Array(const Vec3& v) {
  return ordered_json::array({Number(v.x()), Number(v.y()), Number(v.z())});
}

std::optional<Vec3> FileVec3(const ordered_json& cam, const char* key) {
  if (!cam.contains(key)) return std::nullopt;
  const ordered_json& a = cam[key];
  if (!a.is_array() || a.size() != 3) return std::nullopt;
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!a[i].is_number()) return std::nullopt;
    v[i] = a[i].get<double>();
  }
  return v;
}

// Angle of the rotation between a and b, radians (accurate near 0, unlike acos of the trace).
double AngleRad(const Mat3& a, const Mat3& b) {
  const Eigen::Quaterniond q(Mat3(a.transpose() * b));
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

}  // namespace

std::string SuggestionToJson(const Suggestion& s, const Scene& scene, const Rig& rig,
                             const SuggestOptions& options) {
  json j;
  j["pandora_suggestion"] = 1;
  std::error_code ec;
  const std::string absolute =
      std::filesystem::absolute(scene.path, ec).lexically_normal().string();
  j["scene"] = {{"path", ec ? scene.path : absolute}, {"sha256", scene.sha256}};
  j["rig"] = rig.name;
  j["improved"] = s.improved;
  j["message"] = s.message;
  j["objective"] = {{"name", ObjectiveName(s.objective)},
                    {"higher_is_better", ObjectiveHigherIsBetter(s.objective)},
                    {"before", Finite(s.before.objective)},
                    {"after", Finite(s.after.objective)}};
  j["target_points"] = s.target_points;
  j["metrics"] = {{"before", MetricsJson(s.before)}, {"after", MetricsJson(s.after)}};
  if (s.unsnapped) j["metrics"]["unsnapped"] = MetricsJson(*s.unsnapped);
  j["snap"] = {{"move_m", options.snap_move}, {"rotate_deg", options.snap_rotate_deg}};
  j["clearance_m"] = options.clearance;
  json cams = json::array();
  for (std::size_t c = 0; c < s.cameras.size(); ++c) {
    const CameraChange& ch = s.cameras[c];
    const CameraLimits& l = options.limits.size() == 1 ? options.limits[0] : options.limits[c];
    static const char* kinds[] = {"free", "plane", "line", "box"};
    json limits = {{"max_move_m", l.max_move},
                   {"max_rotate_deg", l.max_rotate_deg},
                   {"mount", kinds[static_cast<int>(l.mount.kind)]}};
    if (l.max_hfov_deg > 0) limits["hfov_range_deg"] = {l.min_hfov_deg, l.max_hfov_deg};
    json cj = {{"id", ch.id},
               {"index", ch.index},
               {"before", PoseJson(ch.before)},
               {"after", PoseJson(ch.after)},
               {"move_m", ch.move_m},
               {"rotate_deg", ch.rotate_deg},
               {"hfov_deg", {{"before", ch.hfov_before_deg}, {"after", ch.hfov_after_deg}}},
               {"surface_distance_m",
                {{"before", Finite(ch.surface_distance_before)},
                 {"after", Finite(ch.surface_distance_after)}}},
               {"limits", limits}};
    if (ch.focal_scale != 1.0) {
      const Intrinsics& k = rig.cameras[ch.index].model.intrinsics();
      cj["after"]["focal_px"] = {k.fx * ch.focal_scale, k.fy * ch.focal_scale};
    }
    if (!ch.note.empty()) cj["note"] = ch.note;
    cams.push_back(cj);
  }
  j["cameras"] = cams;
  j["solver"] = {
      {"iterations", s.iterations},
      {"outer_iterations", s.outer_iterations},
      {"evaluations", s.evaluations},
      {"screening_evaluations", s.screened},
      {"screening_best_objective", s.screened > 0 ? Finite(s.screened_objective) : json(nullptr)},
      {"seconds", s.seconds}};
  json trace = json::array();
  for (const TracePoint& t : s.trace)
    trace.push_back({t.seconds, t.evaluations, Finite(t.objective)});
  j["trace"] = {{"columns", {"seconds", "evaluations", "best_objective"}}, {"rows", trace}};
  return j.dump(1) + "\n";
}

std::string ReplacePoses(const std::string& text, const std::string& scene_path,
                         const std::string& rig_name, const std::vector<PoseUpdate>& poses,
                         std::vector<std::string>* notes) {
  ordered_json root = ParseOrdered(text, scene_path);
  const double mpu = MetresPerUnit(root, scene_path);
  std::size_t rig_index = 0;
  ordered_json* rig = &scene_text::FindRig(
      root, scene_path, rig_name, "the scene file no longer matches the suggestion", &rig_index);
  ordered_json& cameras = (*rig)["cameras"];
  for (const PoseUpdate& update : poses) {
    bool found = false;
    for (std::size_t c = 0; c < cameras.size(); ++c) {
      ordered_json& cam = cameras[c];
      if (!cam.is_object() || !cam.contains("id") || IdOf(cam["id"]) != update.id) continue;
      found = true;
      const std::string where =
          "$.rigs[" + std::to_string(rig_index) + "].cameras[" + std::to_string(c) + "]";
      if (!cam.contains("position"))
        throw InputError(scene_path, where, "the camera has no position");
      Vec3 p = update.pose.translation() / mpu;  // file units
      const double step = update.snap_move / mpu;
      for (int i = 0; i < 3; ++i) p[i] = OnGrid(p[i], step);
      const Mat3 R = update.pose.linear();
      // The orientation in the camera's own form.
      ordered_json orientation = ordered_json::object();
      const std::optional<Vec3> p0 = FileVec3(cam, "position"), t0 = FileVec3(cam, "look_at");
      if (cam.contains("look_at") && p0 && t0 && (*t0 - *p0).norm() > 0) {
        const double distance = (*t0 - *p0).norm();
        Vec3 target = p + distance * R.col(2);
        for (int i = 0; i < 3; ++i) target[i] = Clean(target[i]);
        const std::optional<Vec3> up0 = FileVec3(cam, "up");
        const Vec3 up = up0.value_or(Vec3::UnitZ());
        orientation["look_at"] = Array(target);
        const auto kept = LookAt(p * mpu, target * mpu, up);
        if (kept && AngleRad(kept->linear(), R) <= 1e-9) {
          if (up0) orientation["up"] = cam["up"];
        } else {
          // The roll look_at cannot express with this up: any up in the camera's own vertical plane
          // (its up direction -y and its optical axis) can. Of those, the one nearest the world's
          // +z (its projection on that plane), which reads best; the camera's up where +z is
          // perpendicular to it.
          const Vec3 u = -R.col(1), f = R.col(2);
          Vec3 own = u;
          if (u.z() > 1e-6) own = (u.z() * u + f.z() * f).normalized();
          for (int i = 0; i < 3; ++i) own[i] = Clean(own[i]);
          orientation["up"] = Array(own);
          if (notes) {
            char line[200];
            std::snprintf(
                line, sizeof line,
                "%s: the suggestion also turns the camera %.3g deg about its optical axis "
                "(a roll the old 'up' cannot express): 'up' is now [%.6g, %.6g, %.6g]",
                update.id.c_str(), kept ? AngleRad(kept->linear(), R) * kDegPerRad : 0.0, own.x(),
                own.y(), own.z());
            notes->push_back(line);
          }
        }
      } else if (cam.contains("euler_deg")) {
        const Vec3 ypr = YawPitchRollDeg(R);
        orientation["euler_deg"] = ordered_json::object({{"yaw", Number(Clean(ypr.x()))},
                                                         {"pitch", Number(Clean(ypr.y()))},
                                                         {"roll", Number(Clean(ypr.z()))}});
      } else {
        const Eigen::Quaterniond q(R);
        orientation["quaternion"] = {q.w(), q.x(), q.y(), q.z()};
      }
      ordered_json rebuilt = ordered_json::object();
      for (auto it = cam.begin(); it != cam.end(); ++it) {
        const std::string& key = it.key();
        if (key == "position") {
          rebuilt["position"] = Array(p);
          for (auto o = orientation.begin(); o != orientation.end(); ++o)
            rebuilt[o.key()] = o.value();
        } else if (key == "look_at" || key == "up" || key == "quaternion" || key == "euler_deg") {
          continue;
        } else if (update.focal_px && (key == "hfov_deg" || key == "focal_px" || key == "lens")) {
          rebuilt["focal_px"] = {update.focal_px->x(), update.focal_px->y()};
        } else {
          rebuilt[key] = it.value();
        }
      }
      cam = std::move(rebuilt);
    }
    if (!found)
      throw InputError(scene_path, "$.rigs[" + std::to_string(rig_index) + "].cameras",
                       "no camera '" + update.id + "' in rig '" + rig_name + "'",
                       "the scene file no longer matches the suggestion");
  }
  return scene_text::DumpLike(root, text);
}

std::string ReplacePtzHeads(const std::string& text, const std::string& scene_path,
                            const std::string& rig_name, const std::vector<PtzHeadUpdate>& heads) {
  ordered_json root = ParseOrdered(text, scene_path);
  std::size_t rig_index = 0;
  ordered_json* rig = &scene_text::FindRig(
      root, scene_path, rig_name, "the scene file no longer matches the session", &rig_index);
  if (!rig->contains("cameras") || !(*rig)["cameras"].is_array())
    throw InputError(scene_path, "$.rigs[" + std::to_string(rig_index) + "].cameras", "no cameras",
                     "the scene file no longer matches the session");
  ordered_json& cameras = (*rig)["cameras"];
  for (const PtzHeadUpdate& u : heads) {
    std::size_t c = 0;
    while (c < cameras.size() &&
           !(cameras[c].is_object() && cameras[c].contains("id") && IdOf(cameras[c]["id"]) == u.id))
      ++c;
    const std::string where =
        "$.rigs[" + std::to_string(rig_index) + "].cameras[" + std::to_string(c) + "]";
    if (c == cameras.size())
      throw InputError(scene_path, "$.rigs[" + std::to_string(rig_index) + "].cameras",
                       "no camera '" + u.id + "' in rig '" + rig_name + "'",
                       "the scene file no longer matches the session");
    ordered_json& cam = cameras[c];
    if (!cam.contains("ptz") || !cam["ptz"].is_object())
      throw InputError(scene_path, where, "camera '" + u.id + "' has no \"ptz\" block in the file",
                       "the scene file no longer matches the session");
    const PtzHead& a = u.before;
    const PtzHead& b = u.after;
    auto hfov = [&](double f) {
      return Number(Clean(HfovFromFocal(f, u.lens.width, u.lens.model) / kRadPerDeg));
    };
    // A value that changed: written (a default that stays left out stays out).
    auto set = [](ordered_json& obj, const char* key, double now, double before,
                  double default_value) {
      if (now == before) return;
      if (now == default_value && !obj.contains(key)) return;
      obj[key] = Number(Clean(now));
    };
    // The zoom: the camera's own lens key.
    if (b.current.focal != a.current.focal) {
      if (cam.contains("hfov_deg")) {
        cam["hfov_deg"] = hfov(b.current.focal);
      } else {
        ordered_json rebuilt = ordered_json::object();
        for (auto it = cam.begin(); it != cam.end(); ++it) {
          if (it.key() == "focal_px" || it.key() == "lens")
            rebuilt["focal_px"] = {u.lens.fx, u.lens.fy};
          else
            rebuilt[it.key()] = it.value();
        }
        cam = std::move(rebuilt);
      }
    }
    ordered_json& head = cam["ptz"];
    set(head, "pan_deg", b.current.pan_deg, a.current.pan_deg, 0.0);
    set(head, "tilt_deg", b.current.tilt_deg, a.current.tilt_deg, 0.0);
    if (b.pan_min_deg != a.pan_min_deg || b.pan_max_deg != a.pan_max_deg)
      head["pan_range_deg"] =
          ordered_json::array({Number(Clean(b.pan_min_deg)), Number(Clean(b.pan_max_deg))});
    if (b.tilt_min_deg != a.tilt_min_deg || b.tilt_max_deg != a.tilt_max_deg)
      head["tilt_range_deg"] =
          ordered_json::array({Number(Clean(b.tilt_min_deg)), Number(Clean(b.tilt_max_deg))});
    if (b.home.linear() != a.home.linear() && !head.contains("pan_axis")) {
      // The reader's default (analysis/scene/scene.cpp ReadPtz): +z for a level image x axis, else
      // home's up.
      const Mat3& R = b.home.linear();
      const Vec3 fallback = std::abs(R(2, 0)) <= 1e-9 ? Vec3::UnitZ() : Vec3(-R.col(1));
      if ((fallback - b.pan_axis).norm() > 1e-12) {
        Vec3 axis = b.pan_axis;
        for (int i = 0; i < 3; ++i) axis[i] = Clean(axis[i]);
        head["pan_axis"] = Array(axis);
      }
    }
    if (b.presets.size() != a.presets.size())
      throw InputError(scene_path, where + ".ptz.presets",
                       "the session changed the number of presets, which saving does not write");
    if (!b.presets.empty()) {
      if (!head.contains("presets") || !head["presets"].is_array() ||
          head["presets"].size() != b.presets.size())
        throw InputError(scene_path, where + ".ptz.presets",
                         "the file's presets are not the session's",
                         "the scene file no longer matches the session");
      for (std::size_t i = 0; i < b.presets.size(); ++i) {
        ordered_json& p = head["presets"][i];
        const std::string at = where + ".ptz.presets[" + std::to_string(i) + "]";
        if (!p.is_object() || !p.contains("name") || p["name"] != b.presets[i].name)
          throw InputError(scene_path, at,
                           "not the preset '" + b.presets[i].name + "' the session has",
                           "the scene file no longer matches the session");
        set(p, "pan_deg", b.presets[i].state.pan_deg, a.presets[i].state.pan_deg, 0.0);
        set(p, "tilt_deg", b.presets[i].state.tilt_deg, a.presets[i].state.tilt_deg, 0.0);
        // Without hfov_deg a preset takes the camera's zoom: keep its own when that changes.
        if (!p.contains("hfov_deg") && b.current.focal != a.current.focal)
          p["hfov_deg"] = hfov(b.presets[i].state.focal);
      }
    }
  }
  return scene_text::DumpLike(root, text);
}

std::string ReplaceStations(const std::string& text, const std::string& scene_path,
                            const std::vector<StationMove>& stations) {
  ordered_json root = ParseOrdered(text, scene_path);
  const double mpu = MetresPerUnit(root, scene_path);
  for (const StationMove& move : stations) {
    const std::string where = "$.stations." + move.name;
    if (!root.is_object() || !root.contains("stations") || !root["stations"].is_object() ||
        !root["stations"].contains(move.name) || !root["stations"][move.name].is_object())
      throw InputError(scene_path, where, "no viewing station '" + move.name + "'",
                       "the scene file no longer has the station the session moved");
    ordered_json& station = root["stations"][move.name];
    if (!station.contains("display") || !station["display"].is_object())
      throw InputError(scene_path, where + ".display", "the station has no display");
    ordered_json& display = station["display"];
    const std::optional<Vec3> center0 = FileVec3(display, "center"),
                              facing0 = FileVec3(display, "facing");
    if (!center0 || !facing0)
      throw InputError(scene_path, where + ".display",
                       "the display has no 'center' or 'facing' point");
    Vec3 center = move.display_center / mpu, eye = move.eye / mpu;
    Vec3 facing = *facing0 + (center - *center0);
    for (int i = 0; i < 3; ++i) {
      center[i] = Clean(center[i]);
      eye[i] = Clean(eye[i]);
      facing[i] = Clean(facing[i]);
    }
    display["center"] = Array(center);
    display["facing"] = Array(facing);
    station["eye"] = Array(eye);
  }
  return scene_text::DumpLike(root, text);
}

AcceptResult AcceptSuggestion(const std::string& suggestion_path, const AcceptOptions& options) {
  const json j = ReadJsonFile(suggestion_path, "suggestion file");
  const JsonNode root = JsonNode::Root(j, suggestion_path);
  if (!j.is_object() || !j.contains("pandora_suggestion"))
    root.Fail("not a suggestion file: no \"pandora_suggestion\" key",
              "is this a file written by pandora suggest?");
  root.Get("pandora_suggestion").Number();
  // A PTZ controller suggestion (a preset's setting or a tour's order; suggest/ptz_suggest.h).
  if (j.contains("kind") && j["kind"].is_string() &&
      j["kind"].get<std::string>().rfind("ptz_", 0) == 0) {
    if (!options.cameras.empty())
      throw InputError("{cameras}", "",
                       "a PTZ suggestion changes one camera's preset or tour: accept it whole",
                       "leave out {cameras}");
    AcceptResult result;
    std::string what;
    result.backup_path = AcceptPtzSuggestion(root, options.force, &result.scene_path, &what);
    result.accepted.push_back(what);
    return result;
  }
  const JsonNode scene = root.Get("scene");
  scene.ExpectObject("a scene {\"path\", \"sha256\"}");
  const std::string rig = root.Get("rig").String();
  const bool improved = root.Get("improved").Bool();
  const JsonNode cams = root.Get("cameras");
  const std::size_t camera_count = cams.ArraySize("an array of cameras");
  AcceptResult result;
  result.scene_path = scene.Get("path").String();
  const std::string scene_sha256 = scene.Get("sha256").String();
  if (!improved)
    throw InputError(suggestion_path, "$.improved",
                     "the suggestion offers no improvement; nothing to accept",
                     "run pandora suggest with other limits or cameras");
  if (root.Has("perturbed_for_benchmark") && root.Get("perturbed_for_benchmark").Bool())
    throw InputError(
        suggestion_path, "$.perturbed_for_benchmark",
        "this suggestion was made from perturbed poses ({perturb}), not the scene file's",
        "run pandora suggest without {perturb}");
  double snap_move = 0;
  if (const auto snap = root.Find("snap"))
    if (const auto move = snap->Find("move_m")) snap_move = move->NonNegative();

  std::vector<PoseUpdate> updates;
  std::map<std::string, PoseUpdate> offered;
  std::vector<std::string> order;
  for (std::size_t c = 0; c < camera_count; ++c) {
    const JsonNode cam = cams.At(c);
    cam.ExpectObject();
    const std::string id = cam.Get("id").NonEmptyString();
    const JsonNode after = cam.Get("after");
    PoseUpdate u{id, ReadPose(after), std::nullopt, snap_move};
    if (const auto f = after.Find("focal_px")) {
      const Eigen::VectorXd focal = f->Numbers(2);
      if (!(focal[0] > 0) || !(focal[1] > 0)) f->Fail("expected [fx, fy], positive");
      u.focal_px = Vec2(focal[0], focal[1]);
    }
    offered[id] = u;
    // Accepting everything leaves the cameras the search did not move as the user wrote them
    // (a move written as null, not finite, counts as a move).
    const auto unmoved = [&cam](const char* key) {
      const auto n = cam.Find(key);
      return n && n->value().is_number() && n->value().get<double>() == 0.0;
    };
    const bool moved = !(unmoved("move_m") && unmoved("rotate_deg") && !u.focal_px);
    if (moved || !options.cameras.empty()) order.push_back(id);
  }
  std::vector<std::string> chosen = options.cameras.empty() ? order : options.cameras;
  std::set<std::string> unique;
  for (const std::string& id : chosen) {
    if (!offered.count(id)) {
      std::string list;
      for (const std::string& o : order) list += (list.empty() ? "" : ", ") + o;
      throw InputError("{cameras}", "",
                       "camera '" + id + "' is not in the suggestion " + suggestion_path,
                       "it offers: " + list);
    }
    if (unique.insert(id).second) updates.push_back(offered[id]);
  }

  const std::string scene_text = ReadJsonText(result.scene_path, "scene file");
  if (Sha256Hex(scene_text) != scene_sha256 && !options.force)
    throw InputError(result.scene_path, "",
                     "the scene file changed since the suggestion was made (SHA-256 differs)",
                     "run pandora suggest again, or accept with {force}");
  const std::string new_text =
      ReplacePoses(scene_text, result.scene_path, rig, updates, &result.notes);

  // Check the new text before touching any file: the accepted poses are there, nothing else moved.
  LoadOptions lo;
  lo.load_meshes = false;
  const Scene before = ParseScene(scene_text, result.scene_path, lo);
  const Scene after = ParseScene(new_text, result.scene_path, lo);
  const double tol = 1e-9 * std::max(1.0, before.Bounds().diagonal());
  for (std::size_t r = 0; r < before.rigs.size(); ++r) {
    for (std::size_t c = 0; c < before.rigs[r].cameras.size(); ++c) {
      const Camera& a = before.rigs[r].cameras[c];
      const Camera& b = after.rigs[r].cameras[c];
      Eigen::Isometry3d expected = a.world_from_camera;
      Vec2 focal(a.model.intrinsics().fx, a.model.intrinsics().fy);
      if (before.rigs[r].name == rig && unique.count(a.id)) {
        expected = offered[a.id].pose;
        if (offered[a.id].focal_px) focal = *offered[a.id].focal_px;
      }
      const Vec2 focal_read(b.model.intrinsics().fx, b.model.intrinsics().fy);
      const bool same =
          (b.world_from_camera.translation() - expected.translation()).norm() <= tol &&
          AngleRad(b.world_from_camera.linear(), expected.linear()) <= 1e-9 &&
          (focal_read - focal).norm() <= 1e-9 * focal.norm();
      if (!same)
        throw InputError(result.scene_path,
                         "$.rigs[" + std::to_string(r) + "].cameras[" + std::to_string(c) + "]",
                         "internal check failed: the rewritten pose does not read back as intended",
                         "the scene file was not changed");
    }
  }

  const std::string backup = ReplaceSceneFileWithBackup(result.scene_path, scene_text, new_text,
                                                        {{suggestion_path, "suggestion file"}});
  result.backup_path = backup;
  for (const PoseUpdate& u : updates) result.accepted.push_back(u.id);
  return result;
}

}  // namespace pandora
