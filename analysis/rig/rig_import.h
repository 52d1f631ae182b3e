#pragma once
/// \file rig_import.h
/// `pandora import-rig` (issue 14; docs/tool-chain.md): a calibrated rig read from OpenCV YAML or a
/// COLMAP text model is written into the scene file (backup first), and compared with the design.
/// No JSON types in this header.

#include <string>
#include <vector>

#include "analysis/scene/scene.h"

namespace pandora {

struct RigImportOptions {
  std::string scene;   ///< The scene file, rewritten.
  std::string format;  ///< "opencv" or "colmap".
  std::string from;    ///< The YAML file, or the COLMAP model's folder.
  std::string rig;     ///< The design rig; without `as`, the rig written (replaced by id, or new).
  std::string as;      ///< When given: a new rig of this name (the design stays as it was).
};

/// One imported camera against the design camera of the same id.
struct RigImportDifference {
  std::string id;
  bool in_design = false;
  double moved_m = 0;                     ///< Distance between the centres, metres.
  double turned_deg = 0;                  ///< Angle of the relative rotation, degrees.
  double fx_design = 0, fx_imported = 0;  ///< Focal lengths, pixels.
};

struct RigImportResult {
  std::string scene_path, backup_path;
  std::string rig_written;  ///< The rig's name in the file.
  bool new_rig = false;
  std::vector<RigImportDifference> differences;  ///< One per imported camera, in import order.
};

/// Reads the calibrated rig (`format`, `from`): InputError naming that file, the line and field.
Rig ReadCalibratedRig(const std::string& format, const std::string& from,
                      const std::string& rig_name);

/// The scene file text with `imported` written: as a new rig named `target` (appended to "rigs")
/// when `new_rig`, else into the rig `target`, each camera found by id (InputError when one is not
/// there, or is a PTZ camera) keeping its other keys and order: position and quaternion (its
/// orientation key's place), resolution, focal_px (its focal key's place), principal_point and
/// distortion (removed for a pinhole). Positions in the file's units; numbers with 17 digits.
std::string WriteRigIntoSceneText(const std::string& scene_text, const std::string& scene_path,
                                  const Rig& imported, const std::string& target, bool new_rig);

/// The whole import: reads the rig, writes the scene file with a backup (checked first: the new
/// text loads and its rig has the imported poses to 1e-9 and intrinsics bit for bit), and compares
/// with the design rig. Throws InputError leaving every file as it was.
RigImportResult ImportRig(const RigImportOptions& options);

}  // namespace pandora
