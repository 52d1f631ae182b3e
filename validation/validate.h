#pragma once
/// \file validate.h
/// Predicted against measured (`pandora validate`, docs/validation.md): a ChArUco board is waved
/// through the study region (the calibration simulation's poses, analysis/rig/calibration.h); each
/// camera's synthetic image of it (validation/synth.h) goes through OpenCV's detector
/// (validation/detect.h); every corner found in two or more cameras is triangulated (Ceres, the
/// known cameras) and its error against the truth compared with the covariance Pandora predicts at
/// that point for the same cameras (J^-1, analysis/geometry/uncertainty.h), at the pixel noise the
/// detections themselves show (their residuals against the exact projections). Light header.

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "validation/board_capture.h"
#include "validation/synth.h"

namespace pandora {

struct ValidateOptions {
  int poses = 60;          ///< Board poses (>= 1).
  std::uint64_t seed = 1;  ///< Of the poses (and, plus one, of the image noise).
  int squares_x = 5, squares_y = 4;
  /// The board's square, metres; 0: sized so that its markers' cells span about 5 pixels at the
  /// median distance from the cameras to the region's centre (kBoardCellPixels).
  double square_m = 0;
  SynthOptions synth;  ///< Default: 4x4 samples, 0.5 px blur, noise 2 levels.
  /// A detection farther than this from its exact projection is a misdetection (counted, not
  /// used), pixels.
  double outlier_px = 1.5;
  int min_bin = 50;  ///< Corners per bin of predicted sigma (>= 2).
  /// Each detection's pixel noise in the prediction. kView: its view's residual RMS (views of
  /// fewer than 6 detections: theirs pooled). kCorner: the residual RMS of every detection with
  /// its detector window size (Detection::window) times the scale its view's residuals show
  /// (small views: the scale of theirs pooled), so that corners of one view differ as their
  /// windows do.
  enum class NoiseModel { kView, kCorner };
  NoiseModel noise_model = NoiseModel::kCorner;
  /// The views used: as a calibration tool would keep them (CalibrationBoard's rules, the whole
  /// board in the image): turned at most this far from facing the camera, degrees, ...
  double tilt_max_deg = 60;
  /// ... and every square at least this many pixels.
  double min_px_per_square = 12;
  ValidateOptions() {
    synth.blur_px = 0.5;
    synth.noise = 2.0;
  }
  /// Throws InputError naming the option.
  void Check() const;
};
/// The validation board's marker cells at the median camera distance, pixels (its square: 40).
inline constexpr double kBoardCellPixels = 4.0;

/// One triangulated corner.
struct ValidatedPoint {
  int pose = 0, id = 0;
  Vec3 truth = Vec3::Zero(), estimate = Vec3::Zero();
  std::vector<int> cameras;  ///< Rig indices of the detections used.
  /// Predicted covariance's eigenvalues (m^2, largest first) and eigenvectors (columns, same
  /// order).
  Vec3 variances = Vec3::Zero();
  Mat3 axes = Mat3::Identity();
  double angle_deg = 0;  ///< Largest triangulation angle among its cameras.
  /// The error along each predicted axis in units of its predicted sigma (N(0, 1) if the
  /// prediction holds). The prediction takes each detection's pixel noise from its view's
  /// residuals (ValidateResult::view_sigma).
  Vec3 whitened = Vec3::Zero();
  /// The same against the prediction with one pixel noise for every camera (sigma_px, the design's
  /// assumption), along that prediction's own axes.
  Vec3 whitened_one_sigma = Vec3::Zero();
  double sigma_max() const { return std::sqrt(variances[0]); }
};

/// One bin of points.
struct ValidateBin {
  std::string label;  ///< "0.21-0.35 mm" or "5-10 deg".
  int points = 0;
  /// Measured / predicted RMS along each principal axis: sqrt(mean(whitened_i^2)).
  Vec3 ratio = Vec3::Zero();
  Vec3 ratio_one_sigma = Vec3::Zero();  ///< ... of whitened_one_sigma.
  /// RMS of the error along each principal axis and the predicted RMS (sqrt of the mean
  /// variance), millimetres.
  Vec3 measured_mm = Vec3::Zero(), predicted_mm = Vec3::Zero();
  double skew_major = 0;  ///< Skewness of the whitened major-axis errors.
  double median_cameras = 0, median_angle_deg = 0;
};

struct ValidateResult {
  int poses = 0;                 ///< Poses rendered.
  double square_m = 0;           ///< The board's square.
  std::string board;             ///< "5 x 4 squares of 120 mm, DICT_4X4_50 markers of 90 mm".
  std::int64_t views = 0;        ///< (pose, camera) pairs rendered.
  std::int64_t expected = 0;     ///< Corner views the truth says a camera images.
  std::int64_t detected = 0;     ///< ... that OpenCV found within outlier_px.
  std::int64_t misdetected = 0;  ///< Detections farther than outlier_px from the truth.
  double sigma_px = 0;           ///< RMS per coordinate of the detections' residuals.
  /// Per view (pose, camera) used: the RMS per coordinate of its residuals, the pixel noise of its
  /// detections in the prediction (for a view of fewer than 6 detections: small_view_sigma).
  std::vector<double> view_sigma;
  /// The pooled RMS of the detections in views of fewer than 6 (their noise in the prediction;
  /// 0 when fewer than 6 such detections: sigma_px then).
  double small_view_sigma = 0;
  /// kCorner: the residual RMS per detector window half-width (pixels), and the small views'
  /// pooled scale of it (1: as the window sizes say); empty and 0 otherwise.
  std::map<int, double> window_sigma;
  double corner_noise_scale = 0;
  Vec2 mean_residual = Vec2::Zero();  ///< Their mean (a detector's bias), pixels.
  /// Every detection kept, with its noise in the prediction (view_sigma).
  std::vector<BoardObservation> observations;
  std::vector<ValidatedPoint> points;
  std::vector<ValidateBin> sigma_bins;  ///< By predicted sigma_max, equal counts.
  std::vector<ValidateBin> angle_bins;  ///< By triangulation angle.
  ValidateBin all;
  double render_seconds = 0, detect_seconds = 0, total_seconds = 0;
  std::vector<std::string> notes;
  /// Detections of one view for a picture (the view with the most).
  using Sample = BoardViewSample;
  Sample sample;
};

/// Runs the study on `rig` in `scene` (the scene at one time sample: static). `progress` (may be
/// empty) is called after each pose with (done, total).
ValidateResult RunValidation(const Scene& scene, const Rig& rig, const ValidateOptions& options,
                             const std::function<void(int, int)>& progress = {});

/// The points split into bins of at least min_bin by predicted sigma_max (at most 6, equal
/// counts), and by triangulation angle (0-5, 5-10, 10-20, 20-45, 45-180 degrees; bins with fewer
/// than 2 points left out); `all` over every point.
void BinValidatedPoints(ValidateResult* result, int min_bin);

}  // namespace pandora
