#pragma once
/// \file output.h
/// Output helpers for the command-line tool: output folders, progress bar (atomic writes live in
/// analysis/atomic_file.h).

#include <chrono>
#include <mutex>
#include <string>

#include "analysis/atomic_file.h"

namespace pandora::app {

/// Creates `dir` (and parents) if needed and checks that a file can be created in it. Throws
/// InputError (file = dir) otherwise.
void PrepareOutputDir(const std::string& dir);

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
