// Per-camera intrinsic calibration by OpenCV for the calibration study (validation/calibrate.h):
// cv::calibrateCamera (Brown-Conrady; k3 held at 0 for a lens the design calls pinhole) or
// cv::fisheye::calibrate (from the design's nominal focal length), as a user would calibrate each
// camera from its own board views. OpenCV stays in this file.
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "validation/calibrate_internal.h"

namespace pandora::calibration_internal {
namespace {

Eigen::Isometry3d FromRodrigues(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) T.linear()(i, j) = R.at<double>(i, j);
    T.translation()[i] = tvec.at<double>(i);
  }
  return T;
}

void CalibrateFisheye(const Intrinsics& truth, const std::vector<std::vector<cv::Point3d>>& object,
                      const std::vector<std::vector<cv::Point2d>>& image, IntrinsicResult* out) {
  cv::Matx33d K(truth.fx, 0, 0.5 * (truth.width - 1), 0, truth.fx, 0.5 * (truth.height - 1), 0, 0,
                1);
  cv::Vec4d D(0, 0, 0, 0);
  std::vector<cv::Mat> rvecs, tvecs;
  const int flags = cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW |
                    cv::fisheye::CALIB_USE_INTRINSIC_GUESS;
  out->rms_px = cv::fisheye::calibrate(
      object, image, cv::Size(truth.width, truth.height), K, D, rvecs, tvecs, flags,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12));
  out->intrinsics = truth;
  out->intrinsics.fx = K(0, 0), out->intrinsics.fy = K(1, 1);
  out->intrinsics.cx = K(0, 2), out->intrinsics.cy = K(1, 2);
  out->intrinsics.model = LensModel::kFisheye;
  out->intrinsics.k1 = D[0], out->intrinsics.k2 = D[1], out->intrinsics.k3 = D[2];
  out->intrinsics.k4 = D[3], out->intrinsics.p1 = out->intrinsics.p2 = 0;
  for (std::size_t v = 0; v < rvecs.size(); ++v)
    out->camera_from_board.push_back(FromRodrigues(rvecs[v], tvecs[v]));
}

void CalibrateBrownConrady(const Intrinsics& truth,
                           const std::vector<std::vector<cv::Point3f>>& object,
                           const std::vector<std::vector<cv::Point2f>>& image,
                           IntrinsicResult* out) {
  cv::Mat K, D, std_intrinsics, std_extrinsics, per_view;
  std::vector<cv::Mat> rvecs, tvecs;
  const int flags = truth.model == LensModel::kPinhole ? cv::CALIB_FIX_K3 : 0;
  out->rms_px = cv::calibrateCamera(
      object, image, cv::Size(truth.width, truth.height), K, D, rvecs, tvecs, std_intrinsics,
      std_extrinsics, per_view, flags,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12));
  out->intrinsics = truth;
  out->intrinsics.model = LensModel::kBrownConrady;
  out->intrinsics.fx = K.at<double>(0, 0), out->intrinsics.fy = K.at<double>(1, 1);
  out->intrinsics.cx = K.at<double>(0, 2), out->intrinsics.cy = K.at<double>(1, 2);
  const auto d = [&](int i) { return i < static_cast<int>(D.total()) ? D.at<double>(i) : 0.0; };
  out->intrinsics.k1 = d(0), out->intrinsics.k2 = d(1), out->intrinsics.p1 = d(2);
  out->intrinsics.p2 = d(3), out->intrinsics.k3 = d(4), out->intrinsics.k4 = 0;
  for (int i = 0; i < 4 && i < static_cast<int>(std_intrinsics.total()); ++i)
    out->std_px[i] = std_intrinsics.at<double>(i);
  for (std::size_t v = 0; v < rvecs.size(); ++v)
    out->camera_from_board.push_back(FromRodrigues(rvecs[v], tvecs[v]));
}

}  // namespace

IntrinsicResult CalibrateIntrinsics(const Intrinsics& truth,
                                    const std::vector<ViewCorners>& views) {
  IntrinsicResult out;
  try {
    if (truth.model == LensModel::kFisheye) {
      std::vector<std::vector<cv::Point3d>> object(views.size());
      std::vector<std::vector<cv::Point2d>> image(views.size());
      for (std::size_t v = 0; v < views.size(); ++v)
        for (std::size_t i = 0; i < views[v].board_xy.size(); ++i) {
          object[v].emplace_back(views[v].board_xy[i].x(), views[v].board_xy[i].y(), 0.0);
          image[v].emplace_back(views[v].pixels[i].x(), views[v].pixels[i].y());
        }
      CalibrateFisheye(truth, object, image, &out);
    } else {
      std::vector<std::vector<cv::Point3f>> object(views.size());
      std::vector<std::vector<cv::Point2f>> image(views.size());
      for (std::size_t v = 0; v < views.size(); ++v)
        for (std::size_t i = 0; i < views[v].board_xy.size(); ++i) {
          object[v].emplace_back(static_cast<float>(views[v].board_xy[i].x()),
                                 static_cast<float>(views[v].board_xy[i].y()), 0.0f);
          image[v].emplace_back(static_cast<float>(views[v].pixels[i].x()),
                                static_cast<float>(views[v].pixels[i].y()));
        }
      CalibrateBrownConrady(truth, object, image, &out);
    }
    out.ok = std::isfinite(out.rms_px) && out.camera_from_board.size() == views.size();
  } catch (const cv::Exception& e) {
    out.ok = false;
    out.error = e.what();
  }
  return out;
}

}  // namespace pandora::calibration_internal
