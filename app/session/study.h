#pragma once
/// \file study.h
/// A loaded study: the scene file (parsed and as text), and the ray caster built once over its
/// triangles, shared by fields, suggest and render for as long as the study is open (the session
/// layer, docs/architecture.md). Immutable after loading, so safe to share between threads.

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "render/prepared_scene.h"
#include "volume/solid_trees.h"

namespace pandora::session {

class Study {
 public:
  /// Reads the scene file once, validates it (ParseScene: InputError naming the file and JSON path
  /// on any problem), keeps its text, and builds the ray caster.
  /// `adjust` (may be empty) changes the scene before the caster is built: a command's overrides
  /// of the study (--voxel-size), checked by the caller.
  static std::shared_ptr<const Study> Load(const std::string& path,
                                           const std::function<void(Scene&)>& adjust = {});
  /// A study over a scene built in memory (tests, generated scenes); `text` may be empty (then it
  /// cannot be saved).
  static std::shared_ptr<const Study> FromScene(Scene scene, std::string text = {});

  const Scene& scene() const { return scene_; }
  /// The scene file's bytes as loaded (their SHA-256 is scene().sha256).
  const std::string& text() const { return text_; }
  const RayCaster& caster() const { return *caster_; }
  /// The search trees of the scene's solids and region mesh, built at first use and kept
  /// (volume/solid_trees.h); FieldOptions::solid_trees.
  const SolidTrees& solid_trees() const { return *solid_trees_; }
  /// The scene prepared for the renderer over the same ray caster (no second BVH), built at first
  /// use, once, thread-safely.
  const PreparedScene& prepared() const;

  /// The rig named `name`, or the first rig when `name` is empty. An unknown name throws
  /// InputError blaming `option` (e.g. "{rig}") when given, else the scene's "$.rigs".
  const Rig& FindRig(const std::string& name, const std::string& option = {}) const;

 private:
  Study() = default;
  Scene scene_;
  std::string text_;
  std::unique_ptr<RayCaster> caster_;
  std::unique_ptr<SolidTrees> solid_trees_;
  mutable std::once_flag prepared_once_;
  mutable std::unique_ptr<PreparedScene> prepared_;
};

/// `rig` with the cameras `ids` disabled, for one run (`--disable ID[,ID...]`: what the rig loses
/// when they fail; docs/failures.md). Throws InputError naming `option` for an empty id or one that
/// is not in the rig (the hint lists the rig's ids). Disabling a disabled camera is no error.
Rig DisableCameras(Rig rig, const std::vector<std::string>& ids, const std::string& option);

}  // namespace pandora::session
