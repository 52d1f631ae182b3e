#pragma once
/// \file print.h
/// The printed pixels of the scene's fiducials (analysis/scene/fiducial.h), drawn by OpenCV's own
/// ArUco code: cv::aruco::drawMarker for a marker, CharucoBoard::draw for a ChArUco board, and
/// black squares for a checkerboard. Light header: OpenCV stays inside print.cpp.

#include "analysis/scene/scene.h"

namespace pandora {

/// The print of one fiducial: FiducialTextureSize's texels, white, the pattern drawn inside the
/// margin and the 1-texel ring (row 0 at the top seen from the front).
PrintedPattern PrintFiducial(const Fiducial& fiducial);

/// Fills Material::printed of every fiducial of `scene` (its own material). Idempotent.
void PrintFiducials(Scene* scene);

}  // namespace pandora
