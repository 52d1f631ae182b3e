#include "app/output.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "app/commands.h"
#include "validation/print.h"

namespace pandora::app {

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), active_(enabled && isatty(STDERR_FILENO)) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Update(double fraction) {
  if (!active_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (fraction < 1.0 && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  const int width = 30;
  const int filled = static_cast<int>(fraction * width + 0.5);
  std::fprintf(stderr, "\r%s [%s%s] %3d%%", label_.c_str(), std::string(filled, '#').c_str(),
               std::string(width - filled, ' ').c_str(), static_cast<int>(fraction * 100 + 0.5));
  std::fflush(stderr);
}

void ProgressBar::Finish() {
  if (!active_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  std::fprintf(stderr, "\r%*s\r", static_cast<int>(label_.size()) + 40, "");
  std::fflush(stderr);
}

std::pair<int, int> ParseImageSize(const std::string& option, const std::string& text) {
  const std::string hint = "e.g. " + option + " 1280x720";
  const std::size_t x = text.find_first_of("xX");
  auto side = [&](const std::string& part) {
    char* end = nullptr;
    errno = 0;
    const long v = part.empty() ? 0 : std::strtol(part.c_str(), &end, 10);
    if (part.empty() || *end != '\0' || errno != 0 || v < 1 || v > 16384)
      throw InputError(
          option, "", "expected WIDTHxHEIGHT in pixels, 1 to 16384 each, got '" + text + "'", hint);
    return static_cast<int>(v);
  };
  if (x == std::string::npos)
    throw InputError(option, "", "expected WIDTHxHEIGHT in pixels, got '" + text + "'", hint);
  const int w = side(text.substr(0, x)), h = side(text.substr(x + 1));
  if (static_cast<long long>(w) * h > 64LL * 1024 * 1024)
    throw InputError(option, "",
                     "'" + text + "' is " +
                         std::to_string(static_cast<long long>(w) * h / 1000000) +
                         " Mpx; at most 64 Mpx (about 40 bytes per pixel with the float layers)",
                     hint);
  return {w, h};
}

std::shared_ptr<const session::Study> LoadStudyWithVoxelSize(const std::string& scene_path,
                                                             double voxel_size) {
  return session::Study::Load(scene_path, [&](Scene& scene) {
    if (!std::isnan(voxel_size))
      scene.study.voxel_size = CheckPositiveOption("--voxel-size", voxel_size, "metres");
  });
}

Scene LoadSceneAtSample(const std::string& path, int time_sample, std::string* label) {
  Scene scene = LoadScene(path);
  if (scene.Animated()) {
    const std::vector<TimeSample> samples = scene.TimeSamples();
    const int k = time_sample < 0 ? 0 : time_sample;
    if (k >= static_cast<int>(samples.size()))
      throw InputError(
          "--time-sample", "",
          Format("the scene has %zu time samples (0 to %zu)", samples.size(), samples.size() - 1));
    if (label) *label = samples[k].label;
    Scene at = SceneAtSample(scene, samples[k]);
    at.path = scene.path;
    at.sha256 = scene.sha256;
    scene = std::move(at);
  } else if (time_sample > 0) {
    throw InputError("--time-sample", "", "the scene does not move: it has one time (0)");
  }
  PrintFiducials(&scene);
  return scene;
}

const Rig& FindRigOption(const Scene& scene, const std::string& name) {
  try {
    return scene.FindRig(name);
  } catch (const InputError& e) {
    throw InputError("--rig", "", e.reason(), e.hint());
  }
}

void AddSceneInputs(OutputTransaction& transaction, const Scene& scene) {
  for (const auto& [path, kind] : scene.InputFiles()) transaction.AddInput(path, kind);
}

}  // namespace pandora::app
