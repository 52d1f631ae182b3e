#pragma once
/// \file camera_edits.h
/// Camera edits as every front end makes them: the viewer's actions, Python's Rig methods. One rule
/// is inside, not in a front end: a PTZ camera's base stays level and its head turns, so a pose or
/// a zoom asked of it moves the pivot by the centre's move and becomes pan, tilt and zoom within
/// the head's ranges (PtzFollow, app/session/ptz_edit.h; docs/ptz.md).
///
/// MakeCameraEdit is the rule over any change; the typed edits below check their values (errors
/// name the option fields as `{field}`, analysis/util/error.h) and build their change with it.

#include <functional>
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

/// The edits, labelled "move ID" as the viewer's moves are.
CameraEditResult MakeEdit(const Rig& rig, const AimEdit& edit);
CameraEditResult MakeEdit(const Rig& rig, const PoseEdit& edit);

}  // namespace pandora::session
