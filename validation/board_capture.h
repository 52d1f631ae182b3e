#pragma once
/// \file board_capture.h
/// A ChArUco board waved through the study region and captured by every camera of a rig, as a
/// calibration tool would take it (docs/validation.md): at each of the calibration simulation's
/// poses (analysis/rig/calibration.h) the views its rules keep are rendered where the board shows
/// (validation/synth.h), OpenCV finds the corners (validation/detect.h), and each detection is
/// paired with its exact pixel. Shared by `pandora validate` (triangulation against the predicted
/// covariance) and its calibration study (validation/calibrate.h). Light header (no OpenCV).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analysis/rig/calibration.h"
#include "analysis/scene/scene.h"
#include "validation/synth.h"

namespace pandora {

/// One corner found in one view.
struct BoardObservation {
  int pose = 0, camera = 0, id = 0;                 ///< Pose index, rig index, FiducialCorners' id.
  Vec2 found = Vec2::Zero(), truth = Vec2::Zero();  ///< Detected and exact pixel.
  /// Its view's residual RMS per coordinate; 0 for a view of fewer than 6 detections (too few to
  /// tell).
  double view_sigma = 0;
  int window = 0;  ///< The detector's window half-width (Detection::window; 0: none).
  /// The shape of its error covariance (Detection::shape; identity: isotropic).
  Eigen::Matrix2d shape = Eigen::Matrix2d::Identity();
};

/// One view's detections for a picture: pose, camera, the window's image, found and truth (in the
/// window's pixels).
struct BoardViewSample {
  int pose = -1, camera = -1;
  SynthImage image;
  std::vector<Vec2> found, truth;
};

struct BoardCaptureOptions {
  SynthOptions synth;  ///< The images; the noise's seed is derived from `seed`, pose and camera.
  std::uint64_t seed = 1;
  /// A detection farther than this from its exact projection is a misdetection (counted, not
  /// used), pixels; so is one beyond 5 robust sigmas of its view (kViewOutlierSigmas).
  double outlier_px = 1.5;
  /// Views of boards partly hidden by the scene too (ChArUco detects what shows); false: only
  /// views of the whole board, the calibration simulation's rule for "seen".
  bool partial_views = true;
};
inline constexpr double kViewOutlierSigmas = 5.0;
/// The validation boards' marker edge over square edge. OpenCV's chessboard corner refinement
/// needs a window clear of the markers (detect.h); at 0.75 a 30-pixel square leaves windows of
/// half-width 2-3 pixels, whose corners err 3-10x more than at 5 (0.29 px RMS at 2, 0.03 at 5 on
/// the trauma room); at 0.6 the same square leaves 5.
inline constexpr double kCharucoMarkerRatio = 0.6;

struct BoardCapture {
  int poses = 0;                               ///< Poses rendered.
  std::int64_t views = 0;                      ///< (pose, camera) pairs rendered.
  std::int64_t expected = 0;                   ///< Corner views the truth says a camera images.
  std::int64_t misdetected = 0;                ///< Detections rejected (see BoardCaptureOptions).
  std::vector<BoardObservation> observations;  ///< The detections kept, by pose then camera.
  std::vector<double> view_sigma;              ///< Per view of >= 6 detections, its residual RMS.
  double render_seconds = 0, detect_seconds = 0;  ///< Summed over threads.
  BoardViewSample sample;                         ///< The view with the most detections.
};

/// The median of `v` (the mean of the middle two for an even count; 0 when empty).
double SampleMedian(std::vector<double> v);

/// The misdetection limit for detections whose absolute coordinate residuals are `coordinates`:
/// kViewOutlierSigmas robust sigmas (1.4826 x their median), and at least 0.05 px.
double OutlierLimitPx(std::vector<double> coordinates);

/// The world point of the board's pattern-frame point `xy` (metres) at `pose`.
Vec3 BoardPoint(const CalibrationPose& pose, const Vec2& xy);

/// The options a board study shares (`pandora validate`, with or without --calibration): throws
/// InputError naming --poses, --square or --squares when out of range.
void CheckBoardStudyOptions(int poses, double square_m, int squares_x, int squares_y);

/// A ChArUco board of `squares_x` x `squares_y` squares of `square_m` (0: sized so that its
/// markers' cells span about `cell_pixels` at the median distance from the rig's enabled cameras to
/// the region's centre through their median focal length, rounded to 5 mm), markers
/// kCharucoMarkerRatio of a square, a margin of half a square in whole texels; DICT_4X4_50, or
/// DICT_6X6_250 when the scene prints DICT_4X4_50 markers of its own.
Fiducial SizedCharucoBoard(const Scene& scene, const Rig& rig, int squares_x, int squares_y,
                           double square_m, double cell_pixels, const std::string& name);

/// Renders and detects `board` at every pose of `poses` in every enabled camera of `rig` (`caster`
/// over scene.AllTriangles(), as the poses were sampled with) whose
/// view `rules` keep (TestBoard: seen, or partly hidden by the scene when options.partial_views),
/// when the truth says it images at least 4 corners. A corner whose neighbouring squares are not
/// all visible (at an occluding edge) is left out of both truth and detections. `progress` (may be
/// empty) is called after each pose with (done, total).
BoardCapture CaptureBoard(const Scene& scene, const RayCaster& caster, const Rig& rig,
                          const Fiducial& board, const std::vector<CalibrationPose>& poses,
                          const CalibrationBoard& rules, const BoardCaptureOptions& options,
                          const std::function<void(int, int)>& progress = {});

}  // namespace pandora
