#pragma once
/// \file autosave.h
/// A viewer's autosave: the cameras edited since the last save, written beside the scene file after
/// every edit, so that a crash loses nothing; read back at the next start (docs/viewer.md,
/// "Autosave and recovery"). The scene file itself is never written here: only Session::Save does,
/// with a backup, when the person saves.
///
/// The file, "<scene>.autosave.json" in the scene's folder:
///     {"pandora_autosave": 1, "scene": "<path>", "scene_sha256": "<hex>", "rig": "<name>",
///      "cameras": [<camera in the scene file's form, as RigToJson writes it>, ...]}
/// Only cameras that differ from the scene file are listed; with none, there is no file.

#include <optional>
#include <string>
#include <vector>

#include "app/session/session.h"

namespace pandora::session {

/// "<scene_path>.autosave.json".
std::string AutosavePath(const std::string& scene_path);

/// Writes the session's unsaved cameras to `path` (atomically), or removes `path` when there are
/// none. Throws InputError (file `path`) when it cannot be written.
void WriteAutosave(const Session& session, const std::string& path);

/// An autosave read back.
struct Autosave {
  std::string rig;
  /// The scene file changed since the autosave was written (its sha256 differs): recovering would
  /// apply the edits to another file's cameras, so RecoverAutosave refuses.
  bool stale = false;
  std::vector<Camera> cameras;  ///< As saved; ids are the rig's.
};

/// Reads `path`: nullopt when there is no such file; InputError naming the file and JSON path when
/// it is damaged (not JSON, wrong version, a camera that fails the scene file's checks, an id the
/// study's rig lacks).
std::optional<Autosave> ReadAutosave(const std::string& path, const Study& study);

/// Applies an autosave to the session's rig as one undo step ("recover autosave (N cameras)") and
/// returns the ids recovered. Throws InputError when it is stale or for another rig.
std::vector<std::string> RecoverAutosave(Session& session, const Autosave& autosave,
                                         const std::string& path);

}  // namespace pandora::session
