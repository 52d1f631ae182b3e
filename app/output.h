#pragma once
/// \file output.h
/// Output helpers for the command-line tool: image sizes, the progress bar, and the inputs every
/// command's OutputTransaction (analysis/util/output_transaction.h) must not overwrite.

#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "analysis/scene/scene.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "analysis/util/output_transaction.h"
#include "app/session/study.h"

namespace pandora::app {

/// The study of `scene_path` with `--voxel-size` applied when given (not NaN; checked positive):
/// what analyze and the field benches open.
std::shared_ptr<const session::Study> LoadStudyWithVoxelSize(const std::string& scene_path,
                                                             double voxel_size);

/// `pandora synth` and `validate`: the scene file at time sample `time_sample` (-1: the first of an
/// animated scene; a static scene has only 0) with its fiducials printed; `label` (if given)
/// receives the sample's label (empty for a static scene). InputError naming --time-sample.
Scene LoadSceneAtSample(const std::string& path, int time_sample, std::string* label = nullptr);

/// scene.FindRig(name), an unknown name blamed on --rig.
const Rig& FindRigOption(const Scene& scene, const std::string& name);

/// Registers every file `scene` was read from (Scene::InputFiles) as an input of `transaction`, so
/// that no output replaces the scene file, a mesh file or a texture.
void AddSceneInputs(OutputTransaction& transaction, const Scene& scene);

/// Parses an image size "WxH" for the option `option` (e.g. "--size"): each side 1 to 16384 and at
/// most 64 Mpx in all (a render keeps about 40 bytes per pixel with its layers, more for a camera's
/// own view and contours). Throws InputError naming the option otherwise.
std::pair<int, int> ParseImageSize(const std::string& option, const std::string& text);

/// A one-line progress bar on stderr, drawn only when stderr is a terminal. Thread-safe; redraws at
/// most ten times a second.
class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled = true);
  ~ProgressBar();
  void Update(double fraction);
  void Finish();

 private:
  std::string label_;
  bool active_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_;
  bool finished_ = false;
};

}  // namespace pandora::app
