#pragma once
/// \file camera_edits.h
/// Camera edits as every front end makes them: the viewer's actions, Python's Rig methods. One rule
/// is inside, not in a front end: a PTZ camera's base stays level and its head turns, so a pose or
/// a zoom asked of it moves the pivot by the centre's move and becomes pan, tilt and zoom within
/// the head's ranges (PtzFollow, app/session/ptz_edit.h; docs/ptz.md).
///
/// MakeCameraEdit is the rule over any change; the typed edits below check their values and build
/// their change with it. An error about a value names its field as `{field}` (analysis/util/
/// error.h), which each front end writes as its own key; an error about a camera (a PTZ camera's
/// lens, a distortion that folds back) has no file and names the camera in its reason.

#include <array>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/scene/scene.h"
#include "app/session/editable_rig.h"

namespace pandora::session {

/// An undo step over some cameras, and what the PTZ rule did.
struct CameraEditResult {
  Edit edit;
  int ptz_camera = -1;   ///< The last PTZ camera that followed its head (rig index), -1 if none.
  bool clamped = false;  ///< A head's range limited it.
};

/// `change` applied to a copy of each of `cameras` (rig indices), under the PTZ rule: a PTZ camera
/// whose pose or focal length `change` altered (its head left as it was) follows its head.
CameraEditResult MakeCameraEdit(const Rig& rig, const std::vector<int>& cameras,
                                const std::string& label,
                                const std::function<void(Camera&)>& change);

/// Camera `camera` placed at `position` looking at `look_at`, `up` giving the image's up
/// (metres, world frame). Errors: {position} or {look_at} not finite; {look_at} equal to the
/// position or {up} parallel to the view.
struct AimEdit {
  int camera = -1;
  Vec3 position = Vec3::Zero(), look_at = Vec3::UnitX(), up = Vec3::UnitZ();
};

/// Camera `camera` with centre `position` (metres) and world_from_camera rotation `rotation`.
/// Errors: {position} or {rotation} not finite, {rotation} not a rotation (orthonormal to 1e-9,
/// determinant +1).
struct PoseEdit {
  int camera = -1;
  Vec3 position = Vec3::Zero();
  Mat3 rotation = Mat3::Identity();
};

/// Camera `camera` turned to yaw, pitch and roll `ypr_deg` (the scene file's euler_deg). Errors:
/// {ypr_deg} not finite, or a pitch outside [-90, 90].
struct OrientEdit {
  int camera = -1;
  Vec3 ypr_deg = Vec3::Zero();
};

/// `cameras` zoomed to horizontal field of view `hfov_deg` (fy / fx kept). Errors: {hfov_deg}
/// outside (0, 360), or 180 and over for a pinhole or Brown-Conrady lens.
struct ZoomEdit {
  std::vector<int> cameras;
  double hfov_deg = 0;
};

/// `cameras`' resolution (the same rays through the image's edges), lens model (the nominal field
/// of view kept across a change of projection; the coefficients reset) and distortion coefficients
/// (kLensCoefficientNames' order; NaN: unchanged). Errors: {resolution} not whole pixels in
/// 1..65536; {k1}..{k4} not finite, or a coefficient the lens has not; nothing to change; a PTZ
/// camera's resolution or model (its zoom range is in its pixels); a lens seeing 180 degrees or
/// more made pinhole; a distortion folding back inside the image.
struct LensEdit {
  std::vector<int> cameras;
  int width = 0, height = 0;  ///< 0: unchanged.
  std::optional<LensModel> model;
  std::array<double, 6> coefficients{NAN, NAN, NAN, NAN, NAN, NAN};
};

/// `cameras`' working range in metres (NaN: unchanged; far may be infinite). Errors: {near} not
/// finite or negative, {far} NaN-free but not above near.
struct RangeEdit {
  std::vector<int> cameras;
  double near = NAN, far = NAN;
};

/// `cameras`' colour (linear RGB in [0, 1]). Errors: {color} outside.
struct ColorEdit {
  std::vector<int> cameras;
  Vec3 color = Vec3::Ones();
};

/// `cameras` switched on or off (an undo step; Session::Save does not write it).
struct EnableEdit {
  std::vector<int> cameras;
  bool enabled = true;
};

/// PTZ camera `camera` set to preset `preset` (when not empty), then to the given angles (NaN:
/// kept), clamped to its head's ranges (CameraEditResult::clamped). Errors: the camera has no head;
/// {preset} unknown; {pan_deg}, {tilt_deg} not finite; {hfov_deg} outside (0, 360), or 180 and
/// over for a pinhole or Brown-Conrady lens.
struct PtzEdit {
  int camera = -1;
  std::string preset;
  double pan_deg = NAN, tilt_deg = NAN, hfov_deg = NAN;
};

/// PTZ camera `camera`'s home made its current view (RecentredPtz; `file` and `json_path` name
/// the camera in its errors).
struct RecentreEdit {
  int camera = -1;
  std::string file, json_path;
};

/// The edits, labelled as the viewer's undo list shows them ("move ID", "zoom 3 cameras").
CameraEditResult MakeEdit(const Rig& rig, const AimEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const PoseEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const OrientEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const ZoomEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const LensEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const RangeEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const ColorEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const EnableEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const PtzEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const RecentreEdit& edit);

/// An edit's undo label: the verb and the camera's id, or the number of cameras ("zoom 3 cameras").
std::string EditLabel(const Rig& rig, const std::string& verb, const std::vector<int>& cameras);

}  // namespace pandora::session
