#pragma once
// The calibration study's two numerical stages (validation/calibrate.h), each in its own
// translation unit so that OpenCV and Ceres headers stay apart: per-camera intrinsics by OpenCV
// (calibrate_opencv.cpp) and the rig's bundle adjustment by Ceres (calibrate_bundle.cpp).

#include <array>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"

namespace pandora::calibration_internal {

/// One view of the board by one camera: the corners' board-frame points and their detections.
struct ViewCorners {
  int pose = 0;
  std::vector<Vec2> board_xy, pixels;
  double sigma_px = 1;  ///< The view's pixel noise (the adjustment's weight).
};

struct IntrinsicResult {
  bool ok = false;
  std::string error;  ///< OpenCV's message when it threw.
  Intrinsics intrinsics;
  double rms_px = 0;
  std::array<double, 4> std_px{};  ///< OpenCV's standard deviations of fx fy cx cy (0: none).
  std::vector<Eigen::Isometry3d> camera_from_board;  ///< Per view given.
};

/// Calibrates one camera from its views with the lens model its design names (`truth.model`:
/// Brown-Conrady with k3 held at 0 for a pinhole, all five for Brown-Conrady, OpenCV's fisheye
/// model from the nominal focal length truth.fx for a fisheye). Only truth's model, size and
/// nominal focal length are read.
IntrinsicResult CalibrateIntrinsics(const Intrinsics& truth, const std::vector<ViewCorners>& views);

/// A camera in the bundle adjustment.
struct BundleCamera {
  LensModel design = LensModel::kPinhole;  ///< Which coefficients are free (as above).
  Intrinsics intrinsics;                   ///< Start, then the result.
  Eigen::Isometry3d camera_from_world = Eigen::Isometry3d::Identity();
  bool fixed_pose = false;  ///< The gauge.
  /// Out: the adjustment's own standard deviations (its covariance at the solution, the
  /// residuals weighted by their views' noise): fx fy cx cy (pixels), the rotation (degrees, the
  /// RMS of the angle-axis error's norm) and the centre (mm, the RMS of the position error's
  /// norm); NaN where the covariance could not be computed, 0 for the held pose.
  std::array<double, 4> std_px{};
  double rotation_sd_deg = 0, position_sd_mm = 0;
};

/// A view in the adjustment: camera and pose indices into the adjustment's vectors.
struct BundleView {
  int camera = 0, pose = 0;
  const ViewCorners* corners = nullptr;
};

struct BundleResult {
  bool converged = false;
  int iterations = 0;
  double rms_px = 0;  ///< Final reprojection RMS per coordinate, pixels.
  std::int64_t residuals = 0;
  std::string message;
};

/// Refines every camera's intrinsics and pose (but the fixed ones') and every board pose
/// (world_from_board) to the least-squares reprojection of `views`, each residual weighted by its
/// view's noise.
BundleResult BundleAdjust(std::vector<BundleCamera>* cameras,
                          std::vector<Eigen::Isometry3d>* world_from_board,
                          const std::vector<BundleView>& views);

/// The projection the adjustment uses, for a camera-frame point (OpenCV's Brown-Conrady and
/// fisheye models, as CameraModel's); false behind a pinhole camera.
bool ProjectWithIntrinsics(const Intrinsics& k, const Vec3& p_camera, Vec2* pixel);

}  // namespace pandora::calibration_internal
