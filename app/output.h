#pragma once
/// \file output.h
/// Output helpers for the command-line tool: output folders, progress bar (atomic writes live in
/// analysis/atomic_file.h).

#include <chrono>
#include <mutex>
#include <string>
#include <utility>

#include "analysis/atomic_file.h"
#include "analysis/scene.h"

namespace pandora::app {

/// Creates `dir` (and parents) if needed and checks that a file can be created in it. Throws
/// InputError (file = dir) otherwise.
void PrepareOutputDir(const std::string& dir);

/// Throws InputError(out, "", ...) when `out` is the scene file or any file the scene was loaded
/// from (mesh files, textures): outputs never replace a user's inputs. `what` names the output in
/// the message ("--out", "--json").
void RefuseToOverwriteInputs(const Scene& scene, const std::string& out, const std::string& what);

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
