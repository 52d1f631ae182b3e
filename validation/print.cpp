#include "validation/print.h"

#include <memory>
#include <opencv2/aruco.hpp>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace pandora {

PrintedPattern PrintFiducial(const Fiducial& f) {
  int tw = 0, th = 0;
  FiducialTextureSize(f, &tw, &th);
  cv::Mat print(th, tw, CV_8UC1, cv::Scalar(255));
  const int margin = f.MarginTexels();
  const cv::Rect pattern(1 + margin, 1 + margin, f.PatternTexelsX(), f.PatternTexelsY());
  cv::Mat target = print(pattern);
  if (f.kind == Fiducial::Kind::kCheckerboard) {
    const int square = f.PatternTexelsX() / f.squares_x;
    for (int row = 0; row < f.squares_y; ++row)  // the top-left square is black
      for (int col = 0; col < f.squares_x; ++col)
        if ((row + col) % 2 == 0)
          target(cv::Rect(col * square, row * square, square, square)).setTo(cv::Scalar(0));
  } else {
    const ArucoDictionaryInfo* info = FindArucoDictionary(f.dictionary);
    if (!info) throw std::invalid_argument("PrintFiducial: unknown dictionary " + f.dictionary);
    const cv::Ptr<cv::aruco::Dictionary> dictionary =
        cv::aruco::getPredefinedDictionary(info->opencv_id);
    cv::Mat drawn;
    if (f.kind == Fiducial::Kind::kMarker) {
      cv::aruco::drawMarker(dictionary, f.id, f.PatternTexelsX(), drawn, 1);
    } else {
      const cv::Ptr<cv::aruco::CharucoBoard> board =
          cv::aruco::CharucoBoard::create(f.squares_x, f.squares_y, static_cast<float>(f.square_m),
                                          static_cast<float>(f.marker_m), dictionary);
      for (int& id : board->ids) id += f.id;
      board->draw(cv::Size(f.PatternTexelsX(), f.PatternTexelsY()), drawn, 0, 1);
    }
    if (drawn.size() != target.size() || drawn.type() != CV_8UC1)
      throw std::runtime_error("PrintFiducial: OpenCV drew the pattern at another size");
    drawn.copyTo(target);
  }
  PrintedPattern out;
  out.width = tw;
  out.height = th;
  out.grey.assign(print.datastart, print.dataend);
  return out;
}

void PrintFiducials(Scene* scene) {
  for (const Fiducial& f : scene->fiducials) {
    Material& m = scene->materials[f.material];
    if (!m.printed) m.printed = std::make_shared<const PrintedPattern>(PrintFiducial(f));
  }
}

}  // namespace pandora
