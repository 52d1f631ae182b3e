#include "app/session/study.h"

#include "analysis/util/allocation_budget.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "validation/print.h"

namespace pandora::session {

std::shared_ptr<const Study> Study::Load(const std::string& path,
                                         const std::function<void(Scene&)>& adjust) {
  auto study = std::shared_ptr<Study>(new Study());
  // Read once: the parsed scene and the kept text are the same bytes (scene_.sha256 is theirs).
  study->text_ = ReadInputFile(path, InputLimits::kJsonBytes, "scene file");
  study->scene_ = ParseScene(study->text_, path);
  PrintFiducials(&study->scene_);  // the markers' and boards' pixels, OpenCV's own
  // The mesh importers (assimp) free most of what they allocated; glibc keeps it resident unless
  // asked. A 1,002,252-triangle OBJ: 434 MiB resident after its import, 71 MiB after this, for the
  // rest of the run (docs/robustness.md).
  ReleaseFreedMemory();
  if (adjust) adjust(study->scene_);
  study->caster_ = MakeEmbreeRayCaster(study->scene_.AllTriangles());
  study->solid_trees_ = std::make_unique<SolidTrees>(study->scene_);
  return study;
}

std::shared_ptr<const Study> Study::FromScene(Scene scene, std::string text) {
  auto study = std::shared_ptr<Study>(new Study());
  study->scene_ = std::move(scene);
  PrintFiducials(&study->scene_);
  study->text_ = std::move(text);
  study->caster_ = MakeEmbreeRayCaster(study->scene_.AllTriangles());
  study->solid_trees_ = std::make_unique<SolidTrees>(study->scene_);
  return study;
}

const PreparedScene& Study::prepared() const {
  std::call_once(prepared_once_,
                 [this] { prepared_ = std::make_unique<PreparedScene>(scene_, *caster_); });
  return *prepared_;
}

const Rig& Study::FindRig(const std::string& name, const std::string& option) const {
  if (scene_.rigs.empty()) throw InputError(scene_.path, "$.rigs", "the scene has no rig");
  if (name.empty()) return scene_.rigs.front();
  for (const Rig& rig : scene_.rigs)
    if (rig.name == name) return rig;
  std::string names;
  for (const Rig& rig : scene_.rigs) names += (names.empty() ? "'" : ", '") + rig.name + "'";
  if (!option.empty())
    throw InputError(option, "", "no rig named '" + name + "' in " + scene_.path,
                     "rigs in this scene: " + names);
  throw InputError(scene_.path, "$.rigs", "no rig named '" + name + "'",
                   "rigs in this scene: " + names);
}

Rig DisableCameras(Rig rig, const std::vector<std::string>& ids, const std::string& option) {
  for (const std::string& id : ids) {
    if (id.empty()) throw InputError(option, "", "an empty camera id", "e.g. " + option + " c1,c2");
    const int index = rig.FindCamera(id);
    if (index < 0)
      throw InputError(option, "", "no camera '" + id + "' in rig '" + rig.name + "'",
                       "cameras: " + rig.CameraIds());
    rig.cameras[index].enabled = false;
  }
  return rig;
}

}  // namespace pandora::session
