// `pandora import-rig`: a calibrated rig into the scene file (analysis/rig/rig_import.h).
#include "analysis/rig/rig_import.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>

#include "analysis/rig/rig_formats.h"
#include "analysis/scene/scene_text.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

using scene_text::ordered_json;
namespace fs = std::filesystem;

double MetresPerUnit(const ordered_json& root) {
  if (!root.is_object() || !root.contains("units") || !root["units"].is_string()) return 1.0;
  const std::string u = root["units"].get<std::string>();
  if (u == "cm") return 0.01;
  if (u == "mm") return 0.001;
  if (u == "in") return 0.0254;
  if (u == "ft") return 0.3048;
  return 1.0;
}

// A number as a person writes it where that is exact: whole numbers as integers, no -0; every
// other value with the digits that read back to the same double.
ordered_json J(double v) {
  if (v == std::floor(v) && std::abs(v) < 9e15) return static_cast<std::int64_t>(v);
  return v;
}

ordered_json Pair(double a, double b) { return ordered_json::array({J(a), J(b)}); }

ordered_json DistortionJson(const Intrinsics& k) {
  ordered_json d = ordered_json::object();
  if (k.model == LensModel::kBrownConrady) {
    d["model"] = "brown_conrady";
    d["k1"] = J(k.k1), d["k2"] = J(k.k2), d["p1"] = J(k.p1), d["p2"] = J(k.p2), d["k3"] = J(k.k3);
  } else {
    d["model"] = "fisheye";
    d["k1"] = J(k.k1), d["k2"] = J(k.k2), d["k3"] = J(k.k3), d["k4"] = J(k.k4);
  }
  return d;
}

// The pose and lens keys of `camera` in the file's form, in the order a new camera has them.
std::vector<std::pair<std::string, ordered_json>> CameraKeys(const Camera& camera, double mpu) {
  const Intrinsics& k = camera.model.intrinsics();
  const Vec3 p = camera.center() / mpu;
  Eigen::Quaterniond q(camera.world_from_camera.linear());
  q.normalize();
  std::vector<std::pair<std::string, ordered_json>> keys = {
      {"position", ordered_json::array({J(p.x()), J(p.y()), J(p.z())})},
      {"quaternion", ordered_json::array({J(q.w()), J(q.x()), J(q.y()), J(q.z())})},
      {"resolution", ordered_json::array({k.width, k.height})},
      {"focal_px", Pair(k.fx, k.fy)},
      {"principal_point", Pair(k.cx, k.cy)}};
  if (k.model != LensModel::kPinhole) keys.emplace_back("distortion", DistortionJson(k));
  return keys;
}

bool SameIntrinsics(const Intrinsics& a, const Intrinsics& b) {
  return a.width == b.width && a.height == b.height && a.model == b.model && a.fx == b.fx &&
         a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && a.k1 == b.k1 && a.k2 == b.k2 &&
         a.p1 == b.p1 && a.p2 == b.p2 && a.k3 == b.k3 && a.k4 == b.k4;
}

double AngleDeg(const Mat3& a, const Mat3& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / kPi;
}

}  // namespace

Rig ReadCalibratedRig(const std::string& format, const std::string& from,
                      const std::string& rig_name) {
  constexpr std::uint64_t kMaxBytes = 64ull << 20;
  if (format == "opencv") {
    const std::string text = ReadInputFile(from, kMaxBytes, "OpenCV YAML file");
    Rig rig = ParseOpenCvYaml(text, from);
    rig.name = rig_name;
    return rig;
  }
  if (format == "colmap") {
    std::error_code ec;
    if (!fs::is_directory(from, ec))
      throw InputError(from, "", "not a folder",
                       "{from} colmap takes the model's folder (cameras.txt, images.txt)");
    const std::string cameras = (fs::path(from) / "cameras.txt").string();
    const std::string images = (fs::path(from) / "images.txt").string();
    return ParseColmap(ReadInputFile(cameras, kMaxBytes, "COLMAP cameras file"), cameras,
                       ReadInputFile(images, kMaxBytes, "COLMAP images file"), images, rig_name);
  }
  throw InputError("{from}", "", "unknown format '" + format + "'", "opencv or colmap");
}

std::string WriteRigIntoSceneText(const std::string& text, const std::string& scene_path,
                                  const Rig& imported, const std::string& target, bool new_rig) {
  ordered_json root = scene_text::ParseOrdered(text, scene_path);
  const double mpu = MetresPerUnit(root);
  if (new_rig) {
    if (!root.contains("rigs") || !root["rigs"].is_array())
      throw InputError(scene_path, "$.rigs", "the scene file has no rigs array");
    for (const ordered_json& r : root["rigs"])
      if (r.is_object() && r.contains("name") && r["name"] == target)
        throw InputError("{as}", "", "the scene already has a rig named '" + target + "'",
                         "choose another name, or leave {as} out to replace its cameras");
    ordered_json cameras = ordered_json::array();
    for (const Camera& camera : imported.cameras) {
      ordered_json c = ordered_json::object();
      c["id"] = camera.id;
      if (camera.name != camera.id) c["name"] = camera.name;
      for (auto& [key, value] : CameraKeys(camera, mpu)) c[key] = value;
      cameras.push_back(std::move(c));
    }
    ordered_json rig = ordered_json::object();
    rig["name"] = target;
    rig["cameras"] = std::move(cameras);
    root["rigs"].push_back(std::move(rig));
    return scene_text::DumpLike(root, text);
  }
  std::size_t rig_index = 0;
  ordered_json& rig = scene_text::FindRig(root, scene_path, target, "", &rig_index);
  const std::string rig_path = "$.rigs[" + std::to_string(rig_index) + "]";
  if (!rig.contains("cameras") || !rig["cameras"].is_array())
    throw InputError(scene_path, rig_path + ".cameras", "the rig has no cameras array");
  static const std::vector<std::string> kOrientation = {"look_at", "quaternion", "euler_deg"};
  static const std::vector<std::string> kFocal = {"hfov_deg", "focal_px", "lens"};
  for (const Camera& camera : imported.cameras) {
    ordered_json* found = nullptr;
    std::size_t index = 0;
    for (std::size_t i = 0; i < rig["cameras"].size(); ++i) {
      ordered_json& c = rig["cameras"][i];
      if (c.is_object() && c.contains("id") && scene_text::IdOf(c["id"]) == camera.id) {
        found = &c;
        index = i;
        break;
      }
    }
    if (!found)
      throw InputError(scene_path, rig_path,
                       "the imported camera '" + camera.id + "' is not in rig '" + target + "'",
                       "import as a new rig with {as} NAME, or give the cameras the design's ids");
    const std::string path = rig_path + ".cameras[" + std::to_string(index) + "]";
    if (found->contains("ptz"))
      throw InputError(scene_path, path, "camera '" + camera.id + "' is a PTZ camera",
                       "import the calibration as a new rig with {as} NAME");
    const auto keys = CameraKeys(camera, mpu);
    const auto value = [&](const std::string& k) -> const ordered_json* {
      for (const auto& [key, v] : keys)
        if (key == k) return &v;
      return nullptr;
    };
    ordered_json out = ordered_json::object();
    std::vector<std::string> written;
    const auto put = [&](const std::string& k) {
      if (const ordered_json* v = value(k)) {
        out[k] = *v;
        written.push_back(k);
      }
    };
    for (auto it = found->begin(); it != found->end(); ++it) {
      const std::string& key = it.key();
      const auto in = [&](const std::vector<std::string>& list) {
        return std::find(list.begin(), list.end(), key) != list.end();
      };
      if (key == "position" || key == "resolution" || key == "principal_point") {
        put(key);
      } else if (in(kOrientation)) {
        put("quaternion");
      } else if (in(kFocal)) {
        put("focal_px");
      } else if (key == "distortion") {
        put("distortion");
      } else if (key == "up") {
        // Only with look_at, which is replaced.
      } else {
        out[key] = it.value();
      }
    }
    for (const auto& [key, v] : keys)
      if (std::find(written.begin(), written.end(), key) == written.end()) out[key] = v;
    *found = std::move(out);
  }
  return scene_text::DumpLike(root, text);
}

RigImportResult ImportRig(const RigImportOptions& options) {
  const std::string text = scene_text::ReadJsonText(options.scene, "scene file");
  LoadOptions load;
  load.load_meshes = false;
  const Scene before = ParseScene(text, options.scene, load);
  const Rig* design = nullptr;
  for (const Rig& r : before.rigs)
    if (r.name == options.rig) design = &r;
  RigImportResult result;
  result.scene_path = options.scene;
  if (!options.as.empty()) {
    if (!design) {
      try {
        before.FindRig(options.rig);
      } catch (const InputError& e) {
        throw InputError("{rig}", "", e.reason(), e.hint());  // names the scene's rigs
      }
    }
    result.rig_written = options.as;
    result.new_rig = true;
  } else {
    result.rig_written = options.rig;
    result.new_rig = design == nullptr;
  }
  const Rig imported = ReadCalibratedRig(options.format, options.from, result.rig_written);
  const std::string new_text =
      WriteRigIntoSceneText(text, options.scene, imported, result.rig_written, result.new_rig);

  // The new text must load and hold what was imported.
  const Scene after = ParseScene(new_text, options.scene, load);
  const Rig& written = after.FindRig(result.rig_written);
  for (const Camera& c : imported.cameras) {
    const int i = written.FindCamera(c.id);
    const bool ok = i >= 0 &&
                    (written.cameras[i].center() - c.center()).norm() <=
                        1e-9 * std::max(1.0, c.center().norm()) &&
                    AngleDeg(written.cameras[i].world_from_camera.linear(),
                             c.world_from_camera.linear()) <= 1e-9 * 180 / kPi &&
                    SameIntrinsics(written.cameras[i].model.intrinsics(), c.model.intrinsics());
    if (!ok)
      throw InputError(options.scene, "",
                       "the rewritten scene does not hold camera '" + c.id + "' as imported",
                       "this is a bug; the scene file was not changed");
  }
  for (const Camera& c : imported.cameras) {
    RigImportDifference d;
    d.id = c.id;
    d.fx_imported = c.model.intrinsics().fx;
    const int i = design ? design->FindCamera(c.id) : -1;
    if (i >= 0) {
      const Camera& e = design->cameras[static_cast<std::size_t>(i)];
      d.in_design = true;
      d.moved_m = (e.center() - c.center()).norm();
      d.turned_deg = AngleDeg(e.world_from_camera.linear(), c.world_from_camera.linear());
      d.fx_design = e.model.intrinsics().fx;
    }
    result.differences.push_back(d);
  }
  std::vector<std::pair<std::string, std::string>> inputs;
  if (options.format == "colmap") {
    inputs.emplace_back((fs::path(options.from) / "cameras.txt").string(), "COLMAP cameras file");
    inputs.emplace_back((fs::path(options.from) / "images.txt").string(), "COLMAP images file");
  } else {
    inputs.emplace_back(options.from, "OpenCV YAML file");
  }
  result.backup_path = ReplaceSceneFileWithBackup(options.scene, text, new_text, inputs);
  return result;
}

}  // namespace pandora
