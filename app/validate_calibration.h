#pragma once
// `pandora validate --calibration` (docs/validation.md): the calibration study's outputs.
#include <string>

#include "analysis/scene/scene.h"
#include "validation/calibrate.h"

namespace pandora::app {

/// Runs validation/calibrate.h's study of `rig` in `scene` (read from `scene_path`) and writes
/// calibration.md and calibration_cameras.csv into `out` in one transaction; prints the Markdown
/// unless `quiet`. Returns 0.
int RunValidateCalibration(const std::string& scene_path, const Scene& scene, const Rig& rig,
                           const CalibrateOptions& options, const std::string& out, bool quiet);

}  // namespace pandora::app
