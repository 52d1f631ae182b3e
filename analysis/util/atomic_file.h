#pragma once
/// \file atomic_file.h
/// Outputs are written to a temporary name and renamed, so a reader never sees half a file and a
/// failed run never clobbers the previous result.

#include <string>

#include "analysis/util/output_transaction.h"

namespace pandora {

/// The temporary name used while `path` is being written: `path` + ".tmp-" + the process id.
std::string TemporaryPath(const std::string& path);

/// Flushes TemporaryPath(path) to disk and renames it to `path` (atomic on one file system). On
/// failure (the temporary is missing or empty, a full disk) removes the temporary file and throws
/// InputError naming `path`. Several outputs that belong together go through an OutputTransaction
/// (output_transaction.h) instead.
void CommitTemporary(const std::string& path);

/// Writes `text` to TemporaryPath(path) (every write checked, flushed to disk), then commits it.
/// When `path` exists, the new file keeps its mode. Throws InputError naming `path` on failure,
/// leaving `path` unchanged.
void WriteFileAtomically(const std::string& path, const std::string& text);

/// An exclusive advisory lock (flock) on the folder that holds `path`, held while the object
/// lives: every Pandora command that rewrites a user's file (accept, rig, import-rig, the viewer's
/// Save, Python's save and accept) takes it around its check-and-replace, so two writers of one
/// file run one after the other and the second sees the first's result. Waits for another holder
/// (at most `timeout_s`, then throws InputError naming `path`).
class FolderLock {
 public:
  explicit FolderLock(const std::string& path, double timeout_s = 60.0);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace pandora
