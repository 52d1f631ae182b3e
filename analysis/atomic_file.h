#pragma once
/// \file atomic_file.h
/// Outputs are written to a temporary name and renamed, so a reader never sees half a file and a
/// failed run never clobbers the previous result.

#include <string>

namespace pandora {

/// The temporary name used while `path` is being written: `path` + ".tmp-" + the process id.
std::string TemporaryPath(const std::string& path);

/// Renames TemporaryPath(path) to `path` (atomic on one file system). On failure removes the
/// temporary file and throws InputError naming `path`.
void CommitTemporary(const std::string& path);

/// Writes `text` to TemporaryPath(path), then commits it. Throws InputError on failure, leaving
/// neither file changed.
void WriteFileAtomically(const std::string& path, const std::string& text);

}  // namespace pandora
