// Camera edits under the PTZ rule (app/session/camera_edits.h).
#include "app/session/camera_edits.h"

#include "analysis/geometry/camera.h"
#include "analysis/util/error.h"
#include "app/session/ptz_edit.h"

namespace pandora::session {

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

}  // namespace pandora::session
