#pragma once
/// \file atomic_file.h
/// Outputs are written to a temporary name and renamed, so a reader never sees half a file and a
/// failed run never clobbers the previous result.

#include <string>

#include "analysis/output_transaction.h"

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

}  // namespace pandora
