#include "app/session/editable_rig.h"

#include <stdexcept>

#include "analysis/util/error.h"
#include "app/session/ptz_edit.h"

namespace pandora::session {

namespace {

bool SameCamera(const Camera& a, const Camera& b) {
  // A PTZ camera's head too: a re-centre changes its home, ranges and presets but not its pose.
  return SameCameraGeometry(a, b) && a.id == b.id && a.name == b.name && a.color == b.color &&
         SamePtzHead(a.ptz.get(), b.ptz.get());
}

}  // namespace

EditableRig::EditableRig(Rig rig)
    : rig_(std::move(rig)), saved_(rig_), camera_versions_(rig_.cameras.size(), 0) {}

void EditableRig::Set(const std::vector<CameraEdit>& changes, bool forward) {
  for (const CameraEdit& c : changes) {
    rig_.cameras.at(c.index) = forward ? c.after : c.before;
    ++camera_versions_.at(c.index);
  }
  ++version_;
}

void EditableRig::Apply(Edit edit) {
  for (const CameraEdit& c : edit.changes) {
    if (c.index < 0 || c.index >= static_cast<int>(rig_.cameras.size()))
      throw std::logic_error("edit '" + edit.label + "': no camera " + std::to_string(c.index));
    if (!SameCamera(rig_.cameras[c.index], c.before))
      throw std::logic_error("edit '" + edit.label + "': camera " + rig_.cameras[c.index].id +
                             " changed since the edit was made");
  }
  Set(edit.changes, true);
  undo_.push_back(std::move(edit));
  redo_.clear();
}

bool EditableRig::CanAmend(const std::vector<int>& cameras) const {
  if (undo_.empty() || undo_.back().changes.size() != cameras.size()) return false;
  for (std::size_t i = 0; i < cameras.size(); ++i)
    if (undo_.back().changes[i].index != cameras[i]) return false;
  return true;
}

void EditableRig::Amend(const Edit& edit) {
  std::vector<int> cameras;
  for (const CameraEdit& c : edit.changes) cameras.push_back(c.index);
  if (!CanAmend(cameras))
    throw std::logic_error("edit '" + edit.label + "': not the cameras of the last edit");
  for (const CameraEdit& c : edit.changes)
    if (!SameCamera(rig_.cameras[c.index], c.before))
      throw std::logic_error("edit '" + edit.label + "': camera " + rig_.cameras[c.index].id +
                             " changed since the edit was made");
  Set(edit.changes, true);
  for (std::size_t i = 0; i < edit.changes.size(); ++i)
    undo_.back().changes[i].after = edit.changes[i].after;
  redo_.clear();
}

bool EditableRig::Undo() {
  if (undo_.empty()) return false;
  Set(undo_.back().changes, false);
  redo_.push_back(std::move(undo_.back()));
  undo_.pop_back();
  return true;
}

bool EditableRig::Redo() {
  if (redo_.empty()) return false;
  Set(redo_.back().changes, true);
  undo_.push_back(std::move(redo_.back()));
  redo_.pop_back();
  return true;
}

int EditableRig::Find(const std::string& id) const {
  for (std::size_t c = 0; c < rig_.cameras.size(); ++c)
    if (rig_.cameras[c].id == id) return static_cast<int>(c);
  return -1;
}

void EditableRig::SetPose(int index, const Eigen::Isometry3d& world_from_camera) {
  CameraEdit c{index, rig_.cameras.at(index), rig_.cameras.at(index)};
  c.after.world_from_camera = world_from_camera;
  Apply({"move " + c.before.id, {c}});
}

void EditableRig::SetEnabled(int index, bool enabled) {
  CameraEdit c{index, rig_.cameras.at(index), rig_.cameras.at(index)};
  c.after.enabled = enabled;
  Apply({std::string(enabled ? "enable " : "disable ") + c.before.id, {c}});
}

void EditableRig::SetIntrinsics(int index, const Intrinsics& intrinsics) {
  CameraEdit c{index, rig_.cameras.at(index), rig_.cameras.at(index)};
  c.after.model = CameraModel(intrinsics);
  Apply({"lens of " + c.before.id, {c}});
}

void EditableRig::SetPoses(const std::vector<Pose>& poses, const std::string& label,
                           const std::string& file) {
  Edit edit{label, {}};
  for (const Pose& p : poses) {
    const int index = Find(p.id);
    if (index < 0)
      throw InputError(file, "", "rig '" + rig_.name + "' has no camera '" + p.id + "'",
                       "was the suggestion made for another rig or scene?");
    CameraEdit c{index, rig_.cameras[index], rig_.cameras[index]};
    c.after.world_from_camera = p.pose;
    if (p.focal_scale != 1.0) {
      Intrinsics k = c.after.model.intrinsics();
      k.fx *= p.focal_scale;
      k.fy *= p.focal_scale;
      c.after.model = CameraModel(k);
    }
    edit.changes.push_back(std::move(c));
  }
  Apply(std::move(edit));
}

std::vector<int> EditableRig::Unsaved() const {
  std::vector<int> out;
  for (std::size_t c = 0; c < rig_.cameras.size(); ++c)
    if (!SameCamera(rig_.cameras[c], saved_.cameras[c])) out.push_back(static_cast<int>(c));
  return out;
}

}  // namespace pandora::session
