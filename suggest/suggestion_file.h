#pragma once
/// \file suggestion_file.h
/// The suggestion file (`pandora suggest --out suggestion.json`) and the accept cycle
/// (`pandora accept`): the scene file is rewritten only on accept, only the pose fields of the
/// accepted cameras change, and the previous file is kept as a backup. No JSON types in this
/// header.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/scene/ptz.h"
#include "analysis/scene/scene.h"
#include "suggest/suggest.h"

namespace pandora {

/// The suggestion as JSON text (format in docs/suggest.md): the scene file's path (absolute) and
/// SHA-256 at suggest time, the rig, the objective and metrics before/after, per camera the old and
/// new pose (position in metres, quaternion [w, x, y, z] of world_from_camera) and the change,
/// solver statistics and the trace. Infinite values are written as null.
std::string SuggestionToJson(const Suggestion& suggestion, const Scene& scene, const Rig& rig,
                             const SuggestOptions& options);

/// A pose to write: camera id, the new world_from_camera (metres) and, after a zoom, the new focal
/// lengths in pixels.
struct PoseUpdate {
  std::string id;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  std::optional<Vec2> focal_px;
  /// The suggestion's --snap-move (metres; 0: none): position coordinates within 1e-6 of a step of
  /// a multiple of it are written as that multiple (in the file's units).
  double snap_move = 0;
};

/// The scene file text with the pose of each listed camera of `rig` replaced, in the form the file
/// gives it (docs/suggest.md, "Accept"):
///  - `position` + `look_at` (+ `up`): the new position and a look_at point at the old look_at's
///    distance along the new optical axis; `up` is kept (or left out, as it was) when it reproduces
///    the new orientation to 1e-9 rad, else it is written as the direction nearest +z in the
///    camera's vertical plane (its image up direction, minus y, and its optical axis), which
///    expresses the roll the suggestion made (reported in `notes`);
///  - `position` + `euler_deg`: the new yaw, pitch and roll (scene-format angles, degrees);
///  - `position` + `quaternion`: the new quaternion [w, x, y, z].
/// Positions are in the file's units; every written number is the double nearest its 12-digit
/// decimal (no 0.30000000000000004), and coordinates on the snap grid are written as multiples of
/// the step. With `focal_px`, the focal-length key (`hfov_deg`, `focal_px` or `lens`) is replaced
/// by `focal_px` [fx, fy] at its place. Everything else keeps its order and value; the text is
/// re-serialised with the file's indentation. Throws InputError (file = scene_path) when the JSON,
/// the rig or a camera cannot be found. `notes` (may be null) receives one line per camera whose
/// `up` had to change.
std::string ReplacePoses(const std::string& scene_text, const std::string& scene_path,
                         const std::string& rig, const std::vector<PoseUpdate>& poses,
                         std::vector<std::string>* notes = nullptr);

/// A PTZ camera's head as saved (`before`, what the file says) and as edited (`after`), with the
/// camera's lens at the edited zoom.
struct PtzHeadUpdate {
  std::string id;
  PtzHead before, after;
  Intrinsics lens;
};

/// The scene file text with each listed PTZ camera's head written (docs/ptz.md, "In the viewer"):
/// the zoom in the camera's own lens key (`hfov_deg` keeps its form; `focal_px` or `lens` become
/// `focal_px` [fx, fy] at their place) and in the "ptz" block pan_deg and tilt_deg, and, where they
/// changed (a re-centre), pan_range_deg, tilt_range_deg, each preset's pan_deg and tilt_deg, and
/// pan_axis when the file leaves it out and the reader's default from the new home would differ. A
/// preset without hfov_deg (which means "the camera's zoom") gets its zoom written when the
/// camera's zoom changes. Angles are written as ReplacePoses writes numbers (12 significant
/// digits); keys that did not change keep their text, new keys go last. Call after ReplacePoses,
/// which writes the position (the pivot) and orientation (home). Throws InputError (file =
/// scene_path, the camera's JSON path) when the camera, its "ptz" block or a preset cannot be
/// found.
std::string ReplacePtzHeads(const std::string& scene_text, const std::string& scene_path,
                            const std::string& rig, const std::vector<PtzHeadUpdate>& heads);

/// A viewing station placed anew (metres, world frame): its eye and its display's centre. The
/// display keeps its orientation (its `facing` point moves with its centre).
struct StationMove {
  std::string name;
  Vec3 eye = Vec3::Zero();
  Vec3 display_center = Vec3::Zero();
};

/// The scene file text with each listed station's `eye` and `display.center` replaced (in the
/// file's units, numbers written as ReplacePoses writes them) and its `display.facing` moved by the
/// centre's displacement. Everything else keeps its order and value. Throws InputError (file =
/// scene_path) when the JSON or a station cannot be found.
std::string ReplaceStations(const std::string& scene_text, const std::string& scene_path,
                            const std::vector<StationMove>& stations);

struct AcceptOptions {
  std::vector<std::string> cameras;  ///< Ids to accept; empty: all cameras of the suggestion.
  bool force = false;                ///< Accept even when the scene file changed since.
};

struct AcceptResult {
  std::string scene_path;
  std::string backup_path;
  std::vector<std::string> accepted;  ///< Camera ids written.
  std::vector<std::string> notes;     ///< E.g. a look_at camera whose `up` changed (a roll).
};

/// Reads the suggestion file, checks it (an improvement, the scene file unchanged since: same
/// SHA-256, unless force), writes a backup of the scene file (`SCENE.bak`, or `SCENE.bak.N` with
/// the first free N), then the scene file with the accepted poses (atomically), each in its
/// camera's form (ReplacePoses). Before writing, the new text is parsed as a scene and checked: the
/// accepted cameras have the suggested poses (centres to 1e-9 of the scene size, orientations to
/// 1e-9 rad) and every other camera of every rig is unchanged. Throws InputError on any problem,
/// leaving every file as it was.
AcceptResult AcceptSuggestion(const std::string& suggestion_path, const AcceptOptions& options);

}  // namespace pandora
