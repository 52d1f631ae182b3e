#pragma once
/// \file detect.h
/// Fiducial corners found in an 8-bit grey image by OpenCV, as a user's pipeline would find them:
/// ArUco markers (cv::aruco::detectMarkers, contour refinement), ChArUco boards' chessboard corners
/// (OpenCV's local-homography interpolation from the detected markers, refined by cv::cornerSubPix
/// in windows clear of the markers; detect.cpp says why not interpolateCornersCharuco itself) and
/// checkerboards (cv::findChessboardCornersSB). Light header: OpenCV stays in detect.cpp.

#include <cstdint>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/scene/fiducial.h"

namespace pandora {

/// A corner found in an image.
struct Detection {
  int fiducial = -1;  ///< Index into the fiducials given.
  /// FiducialCorners' id; -1 for a checkerboard's corner (a detector cannot tell which of the
  /// board's two 180-degree turns it sees: the caller matches it to the truth).
  int id = -1;
  Vec2 pixel = Vec2::Zero();  ///< Camera pixel (OpenCV convention: pixel centres at integers).
  /// A ChArUco chessboard corner's cv::cornerSubPix window half-width (2 to 5 pixels: the window
  /// stops short of the nearest marker corner); 0 for markers and checkerboards. The detections'
  /// error grows as the window shrinks (validation.md: 0.03 px RMS at 5, 0.29 px at 2 on the
  /// trauma room), so a pipeline can weight a corner by it.
  int window = 0;
  /// The shape of a ChArUco chessboard corner's error covariance from its window's structure
  /// tensor G = sum w g g^T (the inverse, scaled to trace 2: per-coordinate RMS 1): a corner whose
  /// edges meet at a sharp angle (a foreshortened board) is less certain across the angle's
  /// bisector. Identity when not computed.
  Eigen::Matrix2d shape = Eigen::Matrix2d::Identity();
};

/// Finds the corners of `fiducials` in `grey` (width x height, row-major, y down), an image whose
/// pixel (0, 0) is the camera's pixel (origin_x, origin_y) (a window of the camera's image).
/// Markers and ChArUco boards are told apart by dictionary and id; a checkerboard is sought only
/// when it is the image's only checkerboard.
std::vector<Detection> DetectFiducials(const std::vector<Fiducial>& fiducials,
                                       const std::uint8_t* grey, int width, int height,
                                       int origin_x = 0, int origin_y = 0);

}  // namespace pandora
