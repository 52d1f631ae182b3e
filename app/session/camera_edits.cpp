// Camera edits under the PTZ rule (app/session/camera_edits.h).
#include "app/session/camera_edits.h"

#include <cstdio>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/pose.h"
#include "analysis/rig/rig_check.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "app/session/ptz_edit.h"

namespace pandora::session {
namespace {

// The focal length in pixels that gives `camera` the horizontal field of view `hfov_deg` (checked:
// in (0, 360), under 180 for a pinhole or Brown-Conrady lens).
double FocalForHfov(const Camera& camera, double hfov_deg) {
  if (!(hfov_deg > 0 && hfov_deg < 360))
    throw InputError("{hfov_deg}", "", "must be in (0, 360) degrees");
  const Intrinsics& k = camera.model.intrinsics();
  if (k.model != LensModel::kFisheye && hfov_deg >= 180)
    throw InputError("{hfov_deg}", "", "a pinhole or Brown-Conrady lens sees less than 180 degrees",
                     "camera '" + camera.id + "' has a " + LensModelName(k.model) + " lens");
  return FocalFromHfov(hfov_deg * kRadPerDeg, k.width, k.model);
}

// `k` at resolution `width` x `height`: the same rays through the image's edges (pixel edges at
// -0.5 and width - 0.5 scale).
void Resize(Intrinsics& k, int width, int height) {
  const double sx = double(width) / k.width, sy = double(height) / k.height;
  k.fx *= sx;
  k.fy *= sy;
  k.cx = (k.cx + 0.5) * sx - 0.5;
  k.cy = (k.cy + 0.5) * sy - 0.5;
  k.width = width;
  k.height = height;
}

// `k` with lens model `to`: the nominal field of view kept across a change of projection, the
// coefficients reset.
void ChangeModel(Intrinsics& k, LensModel to, const std::string& id) {
  if ((to == LensModel::kFisheye) != (k.model == LensModel::kFisheye)) {
    const double hfov = HfovFromFocal(k.fx, k.width, k.model);
    if (to != LensModel::kFisheye && !(hfov < kPi))
      throw InputError("", "",
                       "camera '" + id + "' sees " +
                           std::to_string(int(std::lround(hfov * kDegPerRad))) + " degrees; a " +
                           LensModelName(to) + " lens sees less than 180",
                       "narrow its field of view (hfov) first");
    const double fx = FocalFromHfov(hfov, k.width, to);
    k.fy *= fx / k.fx;
    k.fx = fx;
  }
  k.model = to;
  k.k1 = k.k2 = k.p1 = k.p2 = k.k3 = k.k4 = 0;
}

// `camera` with `edit`'s lens applied, checked.
void ApplyLens(Camera& camera, const LensEdit& edit, bool lens_changed) {
  Intrinsics k = camera.model.intrinsics();
  if (camera.ptz && (edit.width > 0 || (edit.model && *edit.model != k.model)))
    throw InputError("", "",
                     "camera '" + camera.id +
                         "' is a PTZ camera: its zoom range is in pixels of its resolution and "
                         "lens, which the viewer does not convert",
                     "change its resolution or lens model in the scene file");
  if (edit.width > 0) Resize(k, edit.width, edit.height);
  if (edit.model) ChangeModel(k, *edit.model, camera.id);
  double* c[6] = {&k.k1, &k.k2, &k.p1, &k.p2, &k.k3, &k.k4};
  for (int i = 0; i < 6; ++i) {
    if (std::isnan(edit.coefficients[i])) continue;
    const std::string name = kLensCoefficientNames[i];
    if (!LensHasCoefficient(k.model, i))
      throw InputError("{" + name + "}", "",
                       "camera '" + camera.id + "' has a " + LensModelName(k.model) +
                           " lens, which has no coefficient " + name,
                       k.model == LensModel::kPinhole
                           ? "give \"model\": \"brown_conrady\" or \"fisheye\" with it"
                           : "fisheye: k1 k2 k3 k4; brown_conrady: k1 k2 p1 p2 k3");
    *c[i] = edit.coefficients[i];
  }
  camera.model = CameraModel(k);
  if (lens_changed && k.model != LensModel::kPinhole) {
    // A lens that folds back inside the image: part of it no ray reaches.
    const LensCoverage lc = ComputeLensCoverage(camera.model);
    if (lc.domain_ends_inside_image) {
      char share[32];
      std::snprintf(share, sizeof share, "%.1f", 100 * lc.unreachable_fraction);
      throw InputError("", "",
                       "camera '" + camera.id + "': this " + LensModelName(k.model) +
                           " distortion folds back inside the image (its valid domain ends "
                           "there; " +
                           share + " % of the pixels would see nothing)",
                       "use smaller coefficients");
    }
  }
}

}  // namespace

std::string EditLabel(const Rig& rig, const std::string& verb, const std::vector<int>& cameras) {
  return verb + " " +
         (cameras.size() == 1 ? rig.cameras[cameras[0]].id
                              : std::to_string(cameras.size()) + " cameras");
}

CameraEditResult MakeCameraEdit(const Rig& rig, const std::vector<int>& cameras,
                                const std::string& label,
                                const std::function<void(Camera&)>& change) {
  CameraEditResult out;
  out.edit.label = label;
  for (int c : cameras) {
    CameraEdit ce{c, rig.cameras[c], rig.cameras[c]};
    change(ce.after);
    if (ce.before.ptz && ce.after.ptz == ce.before.ptz &&
        (ce.after.world_from_camera.matrix() != ce.before.world_from_camera.matrix() ||
         ce.after.model.intrinsics().fx != ce.before.model.intrinsics().fx)) {
      bool clamped = false;
      ce.after = PtzFollow(ce.before, ce.after, &clamped);
      out.ptz_camera = c;
      out.clamped = clamped;
    }
    out.edit.changes.push_back(std::move(ce));
  }
  return out;
}

CameraEditResult MakeEdit(const Rig& rig, const AimEdit& e) {
  if (!e.position.allFinite()) throw InputError("{position}", "", "not a finite position");
  if (!e.look_at.allFinite()) throw InputError("{look_at}", "", "not a finite position");
  const auto pose = LookAt(e.position, e.look_at, e.up);
  if (!pose)
    throw InputError("{look_at}", "", "look_at equals the position, or up is parallel to the view");
  return MakeCameraEdit(rig, {e.camera}, "move " + rig.cameras[e.camera].id,
                        [&](Camera& cam) { cam.world_from_camera = *pose; });
}

CameraEditResult MakeEdit(const Rig& rig, const PoseEdit& e) {
  if (!e.position.allFinite()) throw InputError("{position}", "", "not finite");
  if (!e.rotation.allFinite()) throw InputError("{rotation}", "", "not finite");
  if ((e.rotation.transpose() * e.rotation - Mat3::Identity()).norm() > 1e-9 ||
      e.rotation.determinant() < 0)
    throw InputError("{rotation}", "",
                     "not a rotation matrix (orthonormal to 1e-9, determinant +1)");
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = e.rotation;
  pose.translation() = e.position;
  return MakeCameraEdit(rig, {e.camera}, "move " + rig.cameras[e.camera].id,
                        [&](Camera& cam) { cam.world_from_camera = pose; });
}

CameraEditResult MakeEdit(const Rig& rig, const OrientEdit& e) {
  if (!e.ypr_deg.allFinite()) throw InputError("{ypr_deg}", "", "not finite");
  if (std::abs(e.ypr_deg.y()) > 90)
    throw InputError("{ypr_deg}", "", "the pitch lies in [-90, 90] degrees");
  const Mat3 r = RotationFromYawPitchRollDeg(e.ypr_deg);
  return MakeCameraEdit(rig, {e.camera}, EditLabel(rig, "turn", {e.camera}),
                        [&](Camera& cam) { cam.world_from_camera.linear() = r; });
}

CameraEditResult MakeEdit(const Rig& rig, const ZoomEdit& e) {
  return MakeCameraEdit(rig, e.cameras, EditLabel(rig, "zoom", e.cameras), [&](Camera& cam) {
    Intrinsics k = cam.model.intrinsics();
    const double fx = FocalForHfov(cam, e.hfov_deg);
    k.fy *= fx / k.fx;
    k.fx = fx;
    cam.model = CameraModel(k);
  });
}

CameraEditResult MakeEdit(const Rig& rig, const LensEdit& e) {
  if (e.width != 0 || e.height != 0) {
    if (e.width < 1 || e.height < 1 || e.width > 65536 || e.height > 65536)
      throw InputError("{resolution}", "", "expected whole numbers of pixels from 1 to 65536");
  }
  bool any_coefficient = false;
  for (int i = 0; i < 6; ++i) {
    if (std::isnan(e.coefficients[i])) continue;
    any_coefficient = true;
    if (!std::isfinite(e.coefficients[i]))
      throw InputError("{" + std::string(kLensCoefficientNames[i]) + "}", "", "not finite");
  }
  if (e.width == 0 && !e.model && !any_coefficient)
    throw InputError("", "", "nothing to change",
                     "give a resolution, a lens model or coefficients (k1 k2 p1 p2 k3 k4)");
  const bool lens_changed = e.model.has_value() || any_coefficient;
  return MakeCameraEdit(rig, e.cameras, EditLabel(rig, "lens", e.cameras),
                        [&](Camera& cam) { ApplyLens(cam, e, lens_changed); });
}

CameraEditResult MakeEdit(const Rig& rig, const RangeEdit& e) {
  if (!std::isnan(e.near) && !(std::isfinite(e.near) && e.near >= 0))
    throw InputError("{near}", "", "must be zero or positive metres");
  return MakeCameraEdit(rig, e.cameras, EditLabel(rig, "range", e.cameras), [&](Camera& cam) {
    const double near = std::isnan(e.near) ? cam.near : e.near;
    const double far = std::isnan(e.far) ? cam.far : e.far;
    if (!(far > near))
      throw InputError("{far}", "",
                       "camera '" + cam.id + "': far (" + std::to_string(far) +
                           " m) must be greater than near (" + std::to_string(near) + " m)");
    cam.near = near;
    cam.far = far;
  });
}

CameraEditResult MakeEdit(const Rig& rig, const ColorEdit& e) {
  for (int i = 0; i < 3; ++i)
    if (!(e.color[i] >= 0 && e.color[i] <= 1))
      throw InputError("{color}", "", "colour components are linear RGB in [0, 1]");
  return MakeCameraEdit(rig, e.cameras, EditLabel(rig, "colour", e.cameras),
                        [&](Camera& cam) { cam.color = e.color; });
}

CameraEditResult MakeEdit(const Rig& rig, const EnableEdit& e) {
  return MakeCameraEdit(rig, e.cameras, EditLabel(rig, e.enabled ? "enable" : "disable", e.cameras),
                        [&](Camera& cam) { cam.enabled = e.enabled; });
}

CameraEditResult MakeEdit(const Rig& rig, const PtzEdit& e) {
  const Camera& cam = rig.cameras[e.camera];
  if (!cam.ptz)
    throw InputError("", "", "camera '" + cam.id + "' has no pan-tilt-zoom head",
                     "pan, tilt and zoom apply to a camera with a \"ptz\" block (docs/ptz.md)");
  PtzState want = cam.ptz->current;
  if (!e.preset.empty()) {
    std::string names;
    const PtzPreset* found = nullptr;
    for (const PtzPreset& p : cam.ptz->presets) {
      if (p.name == e.preset) found = &p;
      names += (names.empty() ? "" : ", ") + p.name;
    }
    if (!found)
      throw InputError("{preset}", "", "camera '" + cam.id + "' has no preset '" + e.preset + "'",
                       names.empty() ? "it has no presets" : "presets: " + names);
    want = found->state;
  }
  if (!std::isnan(e.pan_deg)) {
    if (!std::isfinite(e.pan_deg)) throw InputError("{pan_deg}", "", "not a finite angle");
    want.pan_deg = e.pan_deg;
  }
  if (!std::isnan(e.tilt_deg)) {
    if (!std::isfinite(e.tilt_deg)) throw InputError("{tilt_deg}", "", "not a finite angle");
    want.tilt_deg = e.tilt_deg;
  }
  if (!std::isnan(e.hfov_deg)) want.focal = FocalForHfov(cam, e.hfov_deg);
  CameraEditResult out =
      MakeCameraEdit(rig, {e.camera}, EditLabel(rig, "pan/tilt/zoom", {e.camera}),
                     [&](Camera& x) { x = WithPtzState(x, want); });
  const PtzState got = ClampPtzState(*cam.ptz, want);
  out.ptz_camera = e.camera;
  out.clamped = std::abs(got.tilt_deg - want.tilt_deg) > 1e-9 ||
                std::abs(got.focal - want.focal) > 1e-9 * want.focal ||
                (!cam.ptz->ContinuousPan() && std::abs(got.pan_deg - want.pan_deg) > 1e-9);
  return out;
}

CameraEditResult MakeEdit(const Rig& rig, const RecentreEdit& e) {
  return MakeCameraEdit(rig, {e.camera}, EditLabel(rig, "re-centre", {e.camera}),
                        [&](Camera& x) { x = RecentredPtz(x, e.file, e.json_path); });
}

}  // namespace pandora::session
