#pragma once
/// \file output.h
/// Output helpers for the command-line tool: atomic file writes, output folders, progress bar.

#include <chrono>
#include <mutex>
#include <string>

namespace pandora::app {

/// Creates `dir` (and parents) if needed and checks that a file can be created in it. Throws
/// InputError (file = dir) otherwise.
void PrepareOutputDir(const std::string& dir);

/// Writes `text` to `path` + ".tmp", then renames it to `path`. Throws InputError on failure.
void WriteFileAtomically(const std::string& path, const std::string& text);

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
