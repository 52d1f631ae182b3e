#pragma once
/// \file calibration_spec.h
/// The scene file's "study.calibration" section (docs/scene-format.md): which calibration target
/// (a wand's single marker or a planar board) is simulated through the study region, and how. The
/// simulation itself is analysis/rig/calibration.h.

#include <cstdint>

namespace pandora {

/// A planar calibration board (checkerboard or ChArUco): `squares_x` x `squares_y` squares of edge
/// `square_m`, printed on its front face (+z of the board frame). The detector needs every grid
/// corner: the (squares_x + 1) x (squares_y + 1) corners of the squares, the board's 4 outer
/// corners and its (squares_x - 1) x (squares_y - 1) inner corners included.
struct CalibrationBoard {
  int squares_x = 7, squares_y = 5;
  double square_m = 0.04;  ///< Metres.
  /// Largest angle (degrees) between the board's normal and the direction from its centre to the
  /// camera centre, in (0, 90).
  double tilt_max_deg = 60;
  /// Smallest projected square edge, pixels: every edge between two neighbouring grid corners must
  /// project (distortion included) to at least this many pixels.
  double min_px_per_square = 8;
};

/// What to simulate: the scene file's "study.calibration".
struct CalibrationSpec {
  enum class Target { kWand, kBoard };
  /// How a board's orientation is drawn. kTowardCamera: the person turns the board to a camera that
  /// sees its centre (chosen uniformly among those), tilted from facing it exactly by an angle
  /// uniform in solid angle within tilt_max_deg, turned in its plane uniformly; when no camera sees
  /// the centre, a uniform normal. kUniform: a uniformly random rotation (normal uniform on the
  /// sphere, uniform turn in the plane).
  enum class Orientation { kTowardCamera, kUniform };
  Target target = Target::kWand;
  int samples = 2000;  ///< Poses.
  std::uint64_t seed = 1;
  int min_shared = 20;  ///< Poses two cameras must share to link them in the graph.
  Orientation orientation = Orientation::kTowardCamera;
  CalibrationBoard board;  ///< Used when target == kBoard.
};

/// "wand" or "board"; "toward_camera" or "uniform".
inline const char* CalibrationTargetName(CalibrationSpec::Target target) {
  return target == CalibrationSpec::Target::kWand ? "wand" : "board";
}
inline const char* CalibrationOrientationName(CalibrationSpec::Orientation orientation) {
  return orientation == CalibrationSpec::Orientation::kTowardCamera ? "toward_camera" : "uniform";
}

}  // namespace pandora
