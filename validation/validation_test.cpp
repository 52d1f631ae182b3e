// Fiducials, synthetic images and detection (validation/): the prints are OpenCV's and sit where
// the scene says, the ChArUco corners are OpenCV's, and OpenCV finds the corners of a synthetic
// image where Camera::Project puts them (pinhole, Brown-Conrady and fisheye lenses); the corner
// truth follows occlusion and the printed side.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <opencv2/aruco.hpp>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>

#include "analysis/geometry/ray_caster.h"
#include "analysis/rig/rig_formats.h"
#include "analysis/util/error.h"
#include "render/prepared_scene.h"
#include "tests/fixtures.h"
#include "validation/calibrate.h"
#include "validation/detect.h"
#include "validation/print.h"
#include "validation/synth.h"
#include "validation/validate.h"

namespace pandora {
namespace {

Fiducial Charuco(int sx, int sy, double square, double marker, int first_id = 0) {
  Fiducial f;
  f.kind = Fiducial::Kind::kCharuco;
  f.name = "board";
  f.dictionary = "DICT_4X4_50";
  f.id = first_id;
  f.squares_x = sx;
  f.squares_y = sy;
  f.square_m = square;
  f.marker_m = marker;
  f.margin_m = 0.5 * square;
  f.margin_m = f.MarginTexels() / f.TexelsPerMetre();
  f.thickness_m = 0.003;
  return f;
}

Fiducial Marker(int id, double size) {
  Fiducial f;
  f.kind = Fiducial::Kind::kMarker;
  f.name = "marker" + std::to_string(id);
  f.dictionary = "DICT_4X4_50";
  f.id = id;
  f.square_m = size;
  f.margin_m = size / 6;
  f.margin_m = f.MarginTexels() / f.TexelsPerMetre();
  f.thickness_m = 0.003;
  return f;
}

TEST(Print, CharucoCornersAreOpenCvs) {
  const Fiducial f = Charuco(7, 5, 0.04, 0.03);
  const cv::Ptr<cv::aruco::CharucoBoard> board = cv::aruco::CharucoBoard::create(
      7, 5, 0.04f, 0.03f, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50));
  const std::vector<FiducialCorner> corners = FiducialCorners(f);
  ASSERT_EQ(corners.size(), board->chessboardCorners.size());
  for (const FiducialCorner& c : corners) {
    const cv::Point3f& p = board->chessboardCorners[c.id];
    EXPECT_NEAR(c.xy.x() + 0.5 * f.PatternWidth(), p.x, 1e-6);   // OpenCV: from the top-left,
    EXPECT_NEAR(0.5 * f.PatternHeight() - c.xy.y(), p.y, 1e-6);  // y down the print
  }
}

// The print seen square-on is an image OpenCV reads: the marker's corners lie on the pattern's
// edges (pixel-centre convention: texel edge e is coordinate e - 0.5), and a ChArUco print gives
// every chessboard corner where FiducialCorners puts it (texel scale TexelsPerMetre).
TEST(Print, DetectedWherePrinted) {
  const Fiducial marker = Marker(7, 0.15);
  const PrintedPattern print = PrintFiducial(marker);
  const std::vector<Detection> found =
      DetectFiducials({marker}, print.grey.data(), print.width, print.height);
  ASSERT_EQ(found.size(), 4u);
  const double lo = 1 + marker.MarginTexels() - 0.5, hi = lo + marker.PatternTexelsX();
  const Vec2 expected[4] = {Vec2(lo, lo), Vec2(hi, lo), Vec2(hi, hi), Vec2(lo, hi)};
  for (const Detection& d : found) {
    EXPECT_EQ(d.id / 4, 7);
    EXPECT_LT((d.pixel - expected[d.id % 4]).norm(), 0.1) << d.id;
  }

  const Fiducial board = Charuco(5, 4, 0.1, 0.075, 10);
  const PrintedPattern board_print = PrintFiducial(board);
  const std::vector<Detection> corners =
      DetectFiducials({board}, board_print.grey.data(), board_print.width, board_print.height);
  ASSERT_EQ(corners.size(), 12u);
  const double t = board.TexelsPerMetre();
  std::map<int, Vec2> truth;
  for (const FiducialCorner& c : FiducialCorners(board))
    truth[c.id] = Vec2(1 + board.MarginTexels() + (c.xy.x() + 0.5 * board.PatternWidth()) * t,
                       1 + board.MarginTexels() + (0.5 * board.PatternHeight() - c.xy.y()) * t) -
                  Vec2(0.5, 0.5);
  for (const Detection& d : corners)
    EXPECT_LT((d.pixel - truth.at(d.id)).norm(), 0.1)
        << d.id << " at " << d.pixel.transpose() << " truth " << truth.at(d.id).transpose();
}

// A room with a ChArUco board facing three cameras (pinhole, strong Brown-Conrady, fisheye):
// OpenCV finds the board's corners in each synthetic image where Camera::Project puts the truth.
Scene BoardRoom(Rig* rig) {
  Scene scene = testing::BoxRoom(Vec3(5, 5, 3), 0.1);
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
  pose.translation() = Vec3(0, 0, 1.2);
  pose.linear() =
      (Eigen::AngleAxisd(0.5 * kPi, Vec3::UnitX()) * Eigen::AngleAxisd(0.1, Vec3::UnitY()))
          .toRotationMatrix();  // upright, facing -y
  AddFiducial(&scene, Charuco(6, 5, 0.08, 0.06), pose);
  rig->name = "three";
  rig->cameras.push_back(
      testing::TestCamera("pin", Vec3(0.3, -1.6, 1.5), Vec3(0, 0, 1.2), 50, 1280, 800));
  rig->cameras.push_back(testing::WithIntrinsics(
      testing::TestCamera("brown", Vec3(-0.8, -1.5, 1.0), Vec3(0, 0, 1.2), 60, 1280, 800),
      [](Intrinsics& k) {
        k.model = LensModel::kBrownConrady;
        k.k1 = -0.25;
        k.k2 = 0.08;
        k.p1 = 0.001;
        k.p2 = -0.0015;
        k.cx += 13.3;
        k.cy -= 7.9;
      }));
  rig->cameras.push_back(
      testing::WithIntrinsics(testing::TestCamera("fish", Vec3(0.45, -0.75, 1.5), Vec3(0, 0, 1.2),
                                                  140, 1280, 1024, LensModel::kFisheye),
                              [](Intrinsics& k) {
                                k.k1 = 0.02;
                                k.k2 = -0.01;
                              }));
  scene.rigs = {*rig};
  PrintFiducials(&scene);
  return scene;
}

TEST(Synth, CornersFoundWhereProjected) {
  Rig rig;
  const Scene scene = BoardRoom(&rig);
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const PreparedScene prepared(scene, *caster);
  const std::vector<CornerTruth> truth = FiducialCornerTruth(scene, rig, *caster);
  ASSERT_EQ(truth.size(), 20u);
  SynthOptions options;
  for (int c = 0; c < 3; ++c) {
    const SynthImage image = RenderSynth(prepared, rig, c, options);
    ASSERT_EQ(image.width, rig.cameras[c].model.width());
    const std::vector<Detection> found =
        DetectFiducials(scene.fiducials, image.grey.data(), image.width, image.height);
    std::map<int, Vec2> expected;
    for (const CornerTruth& t : truth)
      for (const CornerView& v : t.views)
        if (v.camera == c) expected[t.id] = v.pixel;
    EXPECT_EQ(expected.size(), 20u) << rig.cameras[c].id;
    // OpenCV 4.6's ChArUco interpolation now and then puts a corner on a neighbouring edge
    // (opencv/opencv_contrib#3301): a misdetection, counted apart (at most one here).
    double sum2 = 0, worst = 0;
    int inliers = 0, misplaced = 0;
    Vec2 mean = Vec2::Zero();
    for (const Detection& d : found) {
      ASSERT_TRUE(expected.count(d.id)) << d.id;
      const Vec2 e = d.pixel - expected.at(d.id);
      if (e.norm() > 1.0) {
        ++misplaced;
        continue;
      }
      ++inliers;
      sum2 += e.squaredNorm();
      worst = std::max(worst, e.norm());
      mean += e;
    }
    EXPECT_GE(inliers, 19) << rig.cameras[c].id;
    EXPECT_LE(misplaced, 1) << rig.cameras[c].id;
    mean /= inliers;
    const double rms = std::sqrt(sum2 / inliers);
    std::printf(
        "%s: %d corners within 1 px (%d misplaced), rms %.4f px, worst %.4f, mean "
        "(%.4f, %.4f)\n",
        rig.cameras[c].id.c_str(), inliers, misplaced, rms, worst, mean.x(), mean.y());
    EXPECT_LT(rms, 0.1) << rig.cameras[c].id;
    EXPECT_LT(mean.norm(), 0.05) << rig.cameras[c].id;  // no half-pixel shift
  }
}

// The truth `pandora synth` writes (corners.csv) is what OpenCV computes from the rig it writes
// (rig.yaml): every corner view's pixel equals cv::projectPoints (cv::fisheye::projectPoints for
// the fisheye) of the corner's world point with the YAML's camera to 0.01 px.
TEST(Synth, TruthPixelsAreOpenCvsProjectionsOfTheExportedRig) {
  Rig rig;
  const Scene scene = BoardRoom(&rig);
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<CornerTruth> truth = FiducialCornerTruth(scene, rig, *caster);
  cv::FileStorage fs(RigToOpenCvYaml(rig), cv::FileStorage::READ | cv::FileStorage::MEMORY);
  ASSERT_TRUE(fs.isOpened());
  const cv::FileNode cameras = fs["cameras"];
  double worst = 0;
  int views = 0;
  for (const CornerTruth& t : truth)
    for (const CornerView& v : t.views) {
      const cv::FileNode n = cameras[v.camera];
      cv::Mat K, D, R, T, rvec;
      n["camera_matrix"] >> K;
      n["distortion_coefficients"] >> D;
      n["R"] >> R;
      n["T"] >> T;
      cv::Rodrigues(R, rvec);
      std::vector<cv::Point3d> X{cv::Point3d(t.X.x(), t.X.y(), t.X.z())};
      std::vector<cv::Point2d> px;
      if (static_cast<std::string>(n["distortion_model"]) == "fisheye")
        cv::fisheye::projectPoints(X, px, rvec, T, K, D);
      else
        cv::projectPoints(X, rvec, T, K, D, px);
      worst = std::max(worst, (Vec2(px[0].x, px[0].y) - v.pixel).norm());
      ++views;
    }
  EXPECT_EQ(views, 60);
  EXPECT_LT(worst, 0.01);
  std::printf("%d corner views, largest difference from OpenCV %.2e px\n", views, worst);
}

// The corner truth follows the print and the scene: a box between a camera and the board hides the
// corners behind it from that camera only, and a camera behind the board sees none.
TEST(Synth, CornerTruthFollowsOcclusionAndThePrintedSide) {
  Rig rig;
  Scene scene = BoardRoom(&rig);
  Camera behind = testing::TestCamera("behind", Vec3(0.2, 1.5, 1.3), Vec3(0, 0, 1.2), 60, 800, 600);
  rig.cameras.push_back(behind);
  // A 10 cm post between camera "pin" and the board's left half.
  TriangleMesh post = MakeBox(Vec3(0.1, 0.1, 2.0));
  for (Vec3& v : post.vertices) v += Vec3(0.06, -0.8, 1.0);
  scene.objects.push_back(testing::TestObject("post", post));
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<CornerTruth> truth = FiducialCornerTruth(scene, rig, *caster);
  int pin = 0, brown = 0, behind_views = 0, hidden = 0;
  for (const CornerTruth& t : truth) {
    bool seen_by_pin = false;
    for (const CornerView& v : t.views) {
      pin += v.camera == 0, brown += v.camera == 1, behind_views += v.camera == 3;
      seen_by_pin |= v.camera == 0;
    }
    if (!seen_by_pin) {
      ++hidden;
      // Hidden: the segment from "pin" to the corner passes through the post.
      Ray ray;
      ray.origin = rig.cameras[0].center();
      ray.direction = (t.X - ray.origin).normalized();
      ray.t_far = (t.X - ray.origin).norm() - 1e-4;
      EXPECT_TRUE(caster->Occluded(ray)) << t.id;
    }
  }
  EXPECT_GT(hidden, 0);
  EXPECT_LT(hidden, 20);
  EXPECT_EQ(pin, 20 - hidden);
  EXPECT_EQ(brown, 20);
  EXPECT_EQ(behind_views, 0);
}

// The study end to end on a small rig (four 800 x 600 cameras around a 1 m region): OpenCV finds
// most corner views, the detections' own noise is sub-pixel, every corner seen twice is
// triangulated, and the measured errors match the prediction at that noise within the stated
// tolerance in every bin (30 corners per bin, so the sampling error of an RMS ratio is about
// 1 / sqrt(2 x 30) = 13 %: 0.35 is under three of them).
TEST(Validation, SmallRigMatchesThePrediction) {
  Scene scene = testing::BoxRoom(Vec3(5, 5, 3), 0.1, Vec3(-0.5, -0.5, 0.5), Vec3(0.5, 0.5, 1.5));
  Rig rig;  // four cameras on an arc of 120 degrees, 2 m out, 0.6 m above the region's centre
  rig.name = "arc";
  for (int i = 0; i < 4; ++i) {
    const double a = (-60.0 + 40.0 * i) * kPi / 180.0;
    rig.cameras.push_back(testing::TestCamera("c" + std::to_string(i),
                                              Vec3(-2.0 * std::cos(a), 2.0 * std::sin(a), 1.6),
                                              Vec3(0, 0, 1.0), 60, 800, 600));
  }
  scene.rigs.push_back(rig);
  ValidateOptions options;
  options.poses = 30;
  options.min_bin = 30;
  const ValidateResult r = RunValidation(scene, scene.rigs[0], options);
  std::printf(
      "board %s; %d poses, %lld views; %lld of %lld detected, %lld misdetected; sigma "
      "%.4f px, mean residual (%.4f, %.4f); %zu points; %.1f s\n",
      r.board.c_str(), r.poses, (long long)r.views, (long long)r.detected, (long long)r.expected,
      (long long)r.misdetected, r.sigma_px, r.mean_residual.x(), r.mean_residual.y(),
      r.points.size(), r.total_seconds);
  for (const ValidateBin& b : r.sigma_bins)
    std::printf(
        "  %s: %d points, ratio %.3f %.3f %.3f (one sigma %.3f %.3f %.3f), skew %.2f, "
        "angle %.1f\n",
        b.label.c_str(), b.points, b.ratio[0], b.ratio[1], b.ratio[2], b.ratio_one_sigma[0],
        b.ratio_one_sigma[1], b.ratio_one_sigma[2], b.skew_major, b.median_angle_deg);
  EXPECT_EQ(r.poses, 30);
  EXPECT_GT(r.detected, 0.8 * r.expected);
  EXPECT_LT(r.misdetected, 0.05 * r.expected);  // beyond 5 robust sigma of their view
  EXPECT_GT(r.sigma_px, 0.01);
  EXPECT_LT(r.sigma_px, 0.5);
  EXPECT_LT(r.mean_residual.norm(), 0.05);  // no half-pixel bias left
  ASSERT_GE(r.points.size(), 60u);
  ASSERT_GE(r.sigma_bins.size(), 2u);
  for (const ValidateBin& b : r.sigma_bins)
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(b.ratio[a], 1.0, 0.35) << b.label << " axis " << a;
  for (const ValidatedPoint& p : r.points) {
    EXPECT_GE(p.cameras.size(), 2u);
    EXPECT_LT((p.estimate - p.truth).norm(), 0.01);  // millimetres, not centimetres
  }
}

// Calibration end to end: four cameras on an arc and a fifth facing them from the far side of the
// region. The board is printed on one side, so the fifth camera sees only boards turned away from
// the arc: it calibrates its own intrinsics but shares no view with the others. Pandora's
// simulation calls it uncalibratable and the end-to-end calibration cannot place it. The arc is
// calibrated within the bounds docs/validation.md states: OpenCV's per-camera focal length and
// principal point within 4 of its own standard deviations; after the bundle adjustment focal
// lengths within 0.1 %, principal points within 1 px, the calibrated cameras' pixels of the board
// corners they saw within 1 px RMS of the true cameras', poses within 0.1 degree and 3 mm (a
// 0.06 px detection noise over 2.2 m through a 693 px focal length).
TEST(Validation, CalibrationEndToEndFollowsTheVerdict) {
  Scene scene = testing::BoxRoom(Vec3(6, 6, 3), 0.1, Vec3(-0.6, -0.6, 0.6), Vec3(0.6, 0.6, 1.6));
  Rig rig;
  rig.name = "arc and opposite";
  for (int i = 0; i < 4; ++i) {
    const double a = (-40.0 + 80.0 / 3 * i) * kPi / 180.0;
    rig.cameras.push_back(testing::TestCamera("c" + std::to_string(i),
                                              Vec3(-2.2 * std::cos(a), 2.2 * std::sin(a), 1.7),
                                              Vec3(0, 0, 1.1), 60, 800, 600));
  }
  rig.cameras.push_back(
      testing::TestCamera("far", Vec3(2.2, 0.1, 1.7), Vec3(0, 0, 1.1), 60, 800, 600));
  scene.rigs.push_back(rig);
  CalibrateOptions options;
  options.poses = 60;
  options.synth.samples = 2;
  const CalibrationStudy s = RunCalibrationStudy(scene, scene.rigs[0], options);
  std::printf("board %s; %d poses, %lld views, %zu detections; BA %.4f px, %d iterations; %.1f s\n",
              s.board.c_str(), s.capture.poses, (long long)s.capture.views,
              s.capture.observations.size(), s.ba_rms_px, s.ba_iterations, s.total_seconds);
  for (const CameraCalibration& c : s.cameras)
    std::printf(
        "  %s: %d views, predicted %lld poses link %lld %s; %s; OpenCV fx %+.3f (sd %.3f) cx "
        "%+.3f (sd %.3f); final fx %+.3f (sd %.3f) fy %+.3f cx %+.3f (sd %.3f) cy %+.3f; map "
        "%.3f/%.3f footprint %.3f world %.3f px; %.4f deg (sd %.4f) %.2f mm (sd %.2f)\n",
        c.id.c_str(), c.views, (long long)c.predicted_observed, (long long)c.link_strength,
        c.predicted_calibratable ? "calibratable" : "uncalibratable", c.status.c_str(),
        c.opencv.fx - c.truth.fx, c.opencv_std_fx, c.opencv.cx - c.truth.cx, c.opencv_std_cx,
        c.final.fx - c.truth.fx, c.std_fx, c.final.fy - c.truth.fy, c.final.cx - c.truth.cx,
        c.std_cx, c.final.cy - c.truth.cy, c.map_rms_px, c.map_max_px, c.map_footprint_rms_px,
        c.world_rms_px, c.rotation_error_deg, c.rotation_sd_deg, c.position_error_mm,
        c.position_sd_mm);
  ASSERT_EQ(s.cameras.size(), 5u);
  EXPECT_TRUE(s.verdict_holds);
  const CameraCalibration& far = s.cameras[4];
  EXPECT_FALSE(far.predicted_calibratable);
  EXPECT_FALSE(far.linked);
  EXPECT_EQ(far.status, "not linked to the rig");
  EXPECT_TRUE(far.intrinsics_ok);  // its own views calibrate its lens
  for (int c = 0; c < 4; ++c) {
    const CameraCalibration& k = s.cameras[c];
    SCOPED_TRACE(k.id);
    EXPECT_TRUE(k.predicted_calibratable);
    ASSERT_TRUE(k.calibrated) << k.status;
    ASSERT_GT(k.opencv_std_fx, 0);
    EXPECT_LT(std::abs(k.opencv.fx - k.truth.fx), 4 * k.opencv_std_fx);
    EXPECT_LT(std::abs(k.opencv.cx - k.truth.cx), 4 * k.opencv_std_cx);
    EXPECT_LT(std::abs(k.final.fx - k.truth.fx), 1e-3 * k.truth.fx);
    EXPECT_LT(std::abs(k.final.fy - k.truth.fy), 1e-3 * k.truth.fy);
    EXPECT_LT(std::abs(k.final.cx - k.truth.cx), 1.0);
    EXPECT_LT(std::abs(k.final.cy - k.truth.cy), 1.0);
    EXPECT_LT(k.world_rms_px, 1.0);
    EXPECT_LT(k.rotation_error_deg, 0.1);
    EXPECT_LT(k.position_error_mm, 3.0);
  }
  EXPECT_LT(s.ba_rms_px, 0.5);
}

}  // namespace
}  // namespace pandora
