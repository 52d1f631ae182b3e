#pragma once
/// \file calibrate.h
/// Calibration end to end (`pandora validate --calibration`, docs/validation.md): the board of the
/// scene's "study.calibration" (or a ChArUco board sized from the rig) is waved through the region
/// at the calibration simulation's poses and captured by every camera (validation/board_capture.h);
/// each camera's intrinsics are calibrated from its views by OpenCV (cv::calibrateCamera, or
/// cv::fisheye::calibrate for a fisheye lens), the rig's extrinsics and the intrinsics together by
/// a Ceres bundle adjustment over the shared board views, one camera held at its design pose (the
/// gauge; the board's size fixes the scale); the result is compared with the truth and with
/// Pandora's feasibility verdict (analysis/rig/calibration.h): a camera it calls uncalibratable
/// must fail, and the weakest links should give the largest errors. Light header (no OpenCV, no
/// Ceres).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analysis/rig/calibration.h"
#include "analysis/scene/scene.h"
#include "validation/board_capture.h"

namespace pandora {

struct CalibrateOptions {
  int poses = 200;         ///< Board poses rendered (>= 1).
  std::uint64_t seed = 1;  ///< Of the poses (and, plus one, of the image noise).
  /// The board when the scene's study has no board calibration: squares_x x squares_y squares of
  /// square_m (0: sized so that a marker cell spans kCalibrationCellPixels at the median distance).
  int squares_x = 7, squares_y = 5;
  double square_m = 0;
  SynthOptions synth;        ///< Default: 3x3 samples, 0.5 px blur, noise 2 levels.
  double outlier_px = 1.5;   ///< As BoardCaptureOptions.
  int min_view_corners = 8;  ///< Corners a view needs to count for a camera (>= 6).
  int min_views = 5;         ///< Views a camera needs for its intrinsics (>= 3).
  /// Partly hidden boards too (a ChArUco calibration tool uses them); false: only the views the
  /// feasibility simulation counts (the whole board seen), so that its verdict is what is tested.
  bool partial_views = false;
  /// A linked camera counts as calibrated when its pixels of the board corners it saw are within
  /// this RMS of the true camera's (CameraCalibration::world_rms_px: what triangulation uses);
  /// its lens map over the whole image is checked against the same bound apart (map_within_bound:
  /// the simulation does not ask whether the views cover the image), pixels.
  double bound_px = 1.0;
  CalibrateOptions() {
    synth.samples = 3;
    synth.blur_px = 0.5;
    synth.noise = 2.0;
  }
  /// Throws InputError naming the option.
  void Check() const;
};
/// The calibration board's marker cells at the median camera distance, pixels (its square: 40).
inline constexpr double kCalibrationCellPixels = 4.0;

/// One camera's calibration against its truth.
struct CameraCalibration {
  std::string id;
  bool enabled = true;
  int views = 0, corners = 0;  ///< Views of >= min_view_corners detections, and their corners.
  /// Pandora's verdict from the feasibility simulation (the scene's spec, or 2000 poses of this
  /// board): poses it predicts the camera observes, whether it is calibratable, and its link
  /// strength: the smallest shared count on its path to the reference camera in the maximum
  /// spanning forest (0 when not connected; the reference itself: its observed poses).
  std::int64_t predicted_observed = 0, link_strength = 0;
  bool predicted_calibratable = false;
  /// "calibrated" (within CalibrateOptions::bound_px), or why not: "too few views (n of m)",
  /// "calibration failed", "not linked to the rig", "out of bounds (...)".
  std::string status;
  bool intrinsics_ok = false, linked = false;
  bool calibrated = false;          ///< status == "calibrated".
  bool map_within_bound = false;    ///< map_rms_px <= CalibrateOptions::bound_px.
  bool reference = false;           ///< The camera held at its design pose (the gauge).
  Intrinsics truth, opencv, final;  ///< OpenCV's per-camera result and the bundle adjustment's.
  double opencv_rms_px = 0;         ///< cv::calibrateCamera's reprojection RMS.
  /// The final estimate's own standard deviations of fx, fy, cx, cy (pixels): the bundle
  /// adjustment's covariance for a linked camera, OpenCV's for one calibrated alone (0 for a
  /// fisheye, whose OpenCV calibration states none); NaN when the covariance is rank deficient.
  double std_fx = 0, std_fy = 0, std_cx = 0, std_cy = 0;
  /// OpenCV's per-camera standard deviations of fx and cx (its own estimate), pixels.
  double opencv_std_fx = 0, opencv_std_cx = 0;
  /// The adjustment's standard deviations of the pose: rotation (degrees) and centre (mm, RMS of
  /// the position error's norm); 0 for the held camera.
  double rotation_sd_deg = 0, position_sd_mm = 0;
  /// The final model's pixel for each pixel's true ray, against the pixel: RMS and max over a
  /// 32 x 24 grid across the image, and RMS over the detections' true pixels (the footprint
  /// the board covered).
  double map_rms_px = 0, map_max_px = 0, map_footprint_rms_px = 0;
  double rotation_error_deg = 0, position_error_mm = 0;  ///< Extrinsics against the truth.
  /// The calibrated camera (final intrinsics and pose) against the true one on the world points
  /// it imaged (the board corners it saw): RMS of the pixel differences. Pose and intrinsics
  /// errors that compensate each other (a principal point shift against a small turn) cancel
  /// here, as they do for triangulation; the map_* values above do not. NaN when not linked.
  double world_rms_px = 0;
  int shared_views = 0;  ///< Views of poses another linked camera also used.
};

struct CalibrationStudy {
  std::string board;     ///< "9 x 7 squares of 60 mm, DICT_4X4_50 markers of 45.0 mm".
  CalibrationSpec spec;  ///< The simulation the verdict comes from.
  CalibrationResult predicted;
  BoardCapture capture;
  std::vector<CameraCalibration> cameras;  ///< Rig order.
  int reference = -1;
  double ba_rms_px = 0;  ///< The bundle adjustment's final reprojection RMS.
  int ba_iterations = 0;
  std::int64_t ba_residuals = 0;  ///< Corner detections in the adjustment.
  /// The verdict's check: every camera Pandora calls uncalibratable failed (not calibrated within
  /// the bound), every one it calls calibratable succeeded.
  bool verdict_holds = false;
  /// Spearman's rank correlation between the calibrated cameras' link strength and position error
  /// (negative: weaker links, larger errors); NaN with fewer than 3 such cameras.
  double link_error_correlation = 0;
  double calibrate_seconds = 0, total_seconds = 0;
  std::vector<std::string> notes;
};

/// Runs the study on `rig` in `scene` (static). `progress` as CaptureBoard's.
CalibrationStudy RunCalibrationStudy(const Scene& scene, const Rig& rig,
                                     const CalibrateOptions& options,
                                     const std::function<void(int, int)>& progress = {});

/// Spearman's rank correlation of x and y (average ranks on ties); NaN when fewer than 3 pairs or
/// either is constant.
double SpearmanCorrelation(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace pandora
