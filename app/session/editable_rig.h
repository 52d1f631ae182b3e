#pragma once
/// \file editable_rig.h
/// A rig being edited: every change is an Edit (a command holding each touched camera before and
/// after), applied, undone and redone as a whole; per-camera versions tell incremental consumers
/// (fields, renderers) which cameras changed. Not thread-safe: the session's owner edits, and jobs
/// take copies of rig().

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/scene/scene.h"

namespace pandora::session {

/// One camera's state before and after an edit.
struct CameraEdit {
  int index = 0;  ///< In the rig.
  Camera before, after;
};

/// A user action: one or more cameras changed together (a drag, a suggestion accepted in memory).
struct Edit {
  std::string label;  ///< For menus: "move c03", "accept suggestion (3 cameras)".
  std::vector<CameraEdit> changes;
};

class EditableRig {
 public:
  explicit EditableRig(Rig rig);

  const Rig& rig() const { return rig_; }
  /// Bumps on every Apply, Undo and Redo.
  std::int64_t version() const { return version_; }
  /// Bumps when camera `index` changes (also by undo and redo).
  std::int64_t camera_version(int index) const { return camera_versions_.at(index); }

  /// Applies `edit` (each change's `before` must be the camera as it is now: a stale edit throws
  /// std::logic_error), pushes it on the undo stack and clears the redo stack.
  void Apply(Edit edit);
  /// Continues the last edit instead of adding one: `edit`'s cameras must be the last edit's (same
  /// indices, same order) and each `before` the camera as it is now; the last edit keeps its own
  /// `before` states and takes `edit`'s `after` states (std::logic_error otherwise). A drag or a
  /// gamepad gesture stays one undo step while the rig, its versions and the fields follow every
  /// step. Clears the redo stack.
  void Amend(const Edit& edit);
  /// Whether Amend would accept an edit of `cameras` (indices, in order) now.
  bool CanAmend(const std::vector<int>& cameras) const;
  bool Undo();  ///< False when there is nothing to undo.
  bool Redo();  ///< False when there is nothing to redo.
  bool can_undo() const { return !undo_.empty(); }
  bool can_redo() const { return !redo_.empty(); }
  std::string undo_label() const { return undo_.empty() ? "" : undo_.back().label; }
  std::string redo_label() const { return redo_.empty() ? "" : redo_.back().label; }

  /// Index of the camera with id `id`, or -1.
  int Find(const std::string& id) const;

  // Edits of one camera, each one undo step.
  void SetPose(int index, const Eigen::Isometry3d& world_from_camera);
  void SetEnabled(int index, bool enabled);
  void SetIntrinsics(int index, const Intrinsics& intrinsics);
  /// Several poses (and focal lengths) at once, by camera id, as one undo step: a suggestion
  /// applied in memory. Throws InputError(file, "", ...) for an id the rig lacks.
  struct Pose {
    std::string id;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    double focal_scale = 1.0;  ///< fx and fy times this (a zoom), 1: unchanged.
  };
  void SetPoses(const std::vector<Pose>& poses, const std::string& label, const std::string& file);

  /// Cameras that differ from the rig as last saved (or as loaded).
  std::vector<int> Unsaved() const;
  const Rig& saved() const { return saved_; }
  void MarkSaved() { saved_ = rig_; }

 private:
  void Set(const std::vector<CameraEdit>& changes, bool forward);
  Rig rig_, saved_;
  std::int64_t version_ = 0;
  std::vector<std::int64_t> camera_versions_;
  std::vector<Edit> undo_, redo_;
};

}  // namespace pandora::session
