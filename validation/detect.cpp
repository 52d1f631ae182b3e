#include "validation/detect.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/aruco.hpp>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

namespace pandora {
namespace {

// A single marker's corners: sub-pixel refinement (its white margin keeps the window clean; within
// 0.1 px on a crisp print). A ChArUco board's markers: contour line fitting, whose corners sit half
// a pixel inside a crisp edge but are only the homography's guesses there; CORNER_REFINE_SUBPIX's
// window would reach the chessboard squares a few pixels from a ChArUco marker's corners and be
// pulled by them (1-2 px guesses).
cv::Ptr<cv::aruco::DetectorParameters> Parameters(bool board) {
  cv::Ptr<cv::aruco::DetectorParameters> p = cv::aruco::DetectorParameters::create();
  p->cornerRefinementMethod =
      board ? cv::aruco::CORNER_REFINE_CONTOUR : cv::aruco::CORNER_REFINE_SUBPIX;
  return p;
}

// A ChArUco board's chessboard corners from its detected markers, OpenCV's local-homography method
// (interpolateCornersCharuco's without a camera) with a window that cannot reach a marker: each
// corner's guess is the homography of its adjacent markers' detected corners (8 points, or 4 when
// one of them is found) applied to its board position; cv::cornerSubPix then refines it in a
// window whose half-width is the Chebyshev distance to the nearest of those marker corners less
// one pixel (2 to 5), and a corner that runs out of its window is dropped. OpenCV 4.6's own
// interpolateCornersCharuco sizes its windows so that some corners snap to a marker corner 5-7
// pixels away (opencv/opencv_contrib#3301) and adds (0.5, 0.5) to every corner
// (opencv/opencv#25539): on the small validation rig it left 8 % of the corner views as
// misdetections and every other corner half a pixel off; this finds 791 of 792 within 1.5 px.
// The shape of corner `q`'s error covariance (Detection::shape) over cv::cornerSubPix's window
// of half-width `half` (its mask w = exp(-(dx/half)^2 - (dy/half)^2), central-difference
// gradients): each edge pixel constrains the corner along its gradient, so the corner's
// covariance is proportional to G^-1. Eigenvalues are kept within a factor 100 of each other.
Eigen::Matrix2d CornerShape(const cv::Mat& image, const cv::Point2f& q, int half) {
  const int cx = static_cast<int>(std::lround(q.x)), cy = static_cast<int>(std::lround(q.y));
  Eigen::Matrix2d G = Eigen::Matrix2d::Zero();
  for (int y = cy - half; y <= cy + half; ++y)
    for (int x = cx - half; x <= cx + half; ++x) {
      if (x < 1 || y < 1 || x >= image.cols - 1 || y >= image.rows - 1) continue;
      const Vec2 g(0.5 * (image.at<std::uint8_t>(y, x + 1) - image.at<std::uint8_t>(y, x - 1)),
                   0.5 * (image.at<std::uint8_t>(y + 1, x) - image.at<std::uint8_t>(y - 1, x)));
      const double dx = x - q.x, dy = y - q.y;
      G += std::exp(-(dx * dx + dy * dy) / double(half * half)) * g * g.transpose();
    }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(G);
  const double top = eig.eigenvalues()[1];
  if (!(top > 0)) return Eigen::Matrix2d::Identity();
  const Eigen::Vector2d inverse(1 / std::max(eig.eigenvalues()[0], 0.01 * top), 1 / top);
  const Eigen::Matrix2d C =
      eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose();
  return 2 * C / C.trace();
}

void CharucoCorners(const cv::Mat& image, const cv::aruco::CharucoBoard& board,
                    const std::map<int, std::vector<cv::Point2f>>& markers,
                    std::vector<cv::Point2f>* corners, std::vector<int>* ids,
                    std::vector<int>* windows, std::vector<Eigen::Matrix2d>* shapes) {
  for (std::size_t i = 0; i < board.chessboardCorners.size(); ++i) {
    std::vector<cv::Point2f> object, seen;
    for (int m : board.nearestMarkerIdx[i]) {
      const auto it = markers.find(board.ids[m]);
      if (it == markers.end()) continue;
      for (int k = 0; k < 4; ++k) {
        object.emplace_back(board.objPoints[m][k].x, board.objPoints[m][k].y);
        seen.push_back(it->second[k]);
      }
    }
    if (seen.size() < 4) continue;
    const cv::Mat H = cv::findHomography(object, seen);
    if (H.empty()) continue;
    std::vector<cv::Point2f> guess;
    const cv::Point3f& c = board.chessboardCorners[i];
    cv::perspectiveTransform(std::vector<cv::Point2f>{cv::Point2f(c.x, c.y)}, guess, H);
    // The window [-half, half]^2 must leave out every marker corner: Chebyshev distance - 1.
    double nearest = 1e9;
    for (const cv::Point2f& p : seen)
      nearest = std::min(nearest,
                         double(std::max(std::abs(guess[0].x - p.x), std::abs(guess[0].y - p.y))));
    const int half = std::clamp(static_cast<int>(nearest) - 1, 2, 5);
    if (guess[0].x < half + 1 || guess[0].y < half + 1 || guess[0].x > image.cols - half - 2 ||
        guess[0].y > image.rows - half - 2)
      continue;
    std::vector<cv::Point2f> refined = guess;
    cv::cornerSubPix(
        image, refined, cv::Size(half, half), cv::Size(-1, -1),
        cv::TermCriteria(cv::TermCriteria::MAX_ITER | cv::TermCriteria::EPS, 50, 1e-4));
    if (cv::norm(refined[0] - guess[0]) > half) continue;
    corners->push_back(refined[0]);
    ids->push_back(static_cast<int>(i));
    windows->push_back(half);
    shapes->push_back(CornerShape(image, refined[0], half));
  }
}

}  // namespace

std::vector<Detection> DetectFiducials(const std::vector<Fiducial>& fiducials,
                                       const std::uint8_t* grey, int width, int height,
                                       int origin_x, int origin_y) {
  std::vector<Detection> found;
  const cv::Mat image(height, width, CV_8UC1, const_cast<std::uint8_t*>(grey));
  const Vec2 origin(origin_x, origin_y);
  std::set<std::string> dictionaries;
  int checkerboards = 0;
  for (const Fiducial& f : fiducials) {
    if (f.kind == Fiducial::Kind::kCheckerboard)
      ++checkerboards;
    else
      dictionaries.insert(f.dictionary);
  }
  for (const std::string& name : dictionaries) {
    const cv::Ptr<cv::aruco::Dictionary> dictionary =
        cv::aruco::getPredefinedDictionary(FindArucoDictionary(name)->opencv_id);
    bool any_marker = false, any_board = false;
    for (const Fiducial& f : fiducials) {
      any_marker |= f.dictionary == name && f.kind == Fiducial::Kind::kMarker;
      any_board |= f.dictionary == name && f.kind == Fiducial::Kind::kCharuco;
    }
    std::vector<std::vector<cv::Point2f>> marker_corners, board_corners;
    std::vector<int> marker_ids, board_ids;
    if (any_marker)
      cv::aruco::detectMarkers(image, dictionary, marker_corners, marker_ids, Parameters(false));
    if (any_board)
      cv::aruco::detectMarkers(image, dictionary, board_corners, board_ids, Parameters(true));
    for (int fi = 0; fi < static_cast<int>(fiducials.size()); ++fi) {
      const Fiducial& f = fiducials[fi];
      if (f.dictionary != name || f.kind == Fiducial::Kind::kCheckerboard) continue;
      const bool board_kind = f.kind == Fiducial::Kind::kCharuco;
      const std::vector<std::vector<cv::Point2f>>& corners =
          board_kind ? board_corners : marker_corners;
      const std::vector<int>& ids = board_kind ? board_ids : marker_ids;
      if (f.kind == Fiducial::Kind::kMarker) {
        for (std::size_t m = 0; m < ids.size(); ++m)
          if (ids[m] == f.id)
            for (int k = 0; k < 4; ++k)
              found.push_back({fi, 4 * f.id + k, origin + Vec2(corners[m][k].x, corners[m][k].y)});
        continue;
      }
      // ChArUco: this board's markers only, then its chessboard corners between them.
      std::map<int, std::vector<cv::Point2f>> mine;
      for (std::size_t m = 0; m < ids.size(); ++m)
        if (ids[m] >= f.id && ids[m] < f.id + f.Markers()) mine[ids[m]] = corners[m];
      if (mine.empty()) continue;
      const cv::Ptr<cv::aruco::CharucoBoard> board =
          cv::aruco::CharucoBoard::create(f.squares_x, f.squares_y, static_cast<float>(f.square_m),
                                          static_cast<float>(f.marker_m), dictionary);
      for (int& id : board->ids) id += f.id;
      std::vector<cv::Point2f> chess;
      std::vector<int> chess_ids;
      std::vector<int> windows;
      std::vector<Eigen::Matrix2d> shapes;
      CharucoCorners(image, *board, mine, &chess, &chess_ids, &windows, &shapes);
      for (std::size_t k = 0; k < chess_ids.size(); ++k)
        found.push_back(
            {fi, chess_ids[k], origin + Vec2(chess[k].x, chess[k].y), windows[k], shapes[k]});
    }
  }
  if (checkerboards == 1) {
    for (int fi = 0; fi < static_cast<int>(fiducials.size()); ++fi) {
      const Fiducial& f = fiducials[fi];
      if (f.kind != Fiducial::Kind::kCheckerboard) continue;
      std::vector<cv::Point2f> corners;
      if (cv::findChessboardCornersSB(image, cv::Size(f.squares_x - 1, f.squares_y - 1), corners,
                                      cv::CALIB_CB_ACCURACY))
        for (const cv::Point2f& c : corners) found.push_back({fi, -1, origin + Vec2(c.x, c.y)});
    }
  }
  return found;
}

}  // namespace pandora
