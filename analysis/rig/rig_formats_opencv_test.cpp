// OpenCV's own cv::FileStorage against Pandora's YAML (analysis/rig/rig_formats.h), both ways: it
// reads what RigToOpenCvYaml writes to the same doubles, and ParseOpenCvYaml reads what it writes
// (the rig layout and a calibrateCamera-style file). Built only where OpenCV's core headers are
// installed (libopencv-core-dev); the library itself never uses OpenCV.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <random>

#include "analysis/rig/rig_formats.h"
#include "analysis/scene/scene.h"

namespace pandora {
namespace {

Rig TestRig() {
  LoadOptions load;
  load.load_meshes = false;
  Rig rig = LoadScene("tests/data/rigio.json", load).FindRig("design");
  // And cameras with random full-precision values.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 30; ++i) {
    Camera c = rig.cameras[static_cast<std::size_t>(i % 4)];
    c.id = "rand " + std::to_string(i);
    c.name = c.id;
    Intrinsics k = c.model.intrinsics();
    k.fx *= 1 + 0.1 * u(rng), k.fy *= 1 + 0.1 * u(rng), k.cx += u(rng), k.cy += u(rng);
    if (k.model != LensModel::kPinhole) k.k1 = 0.1 * u(rng), k.k2 = 0.01 * u(rng);
    c.model = CameraModel(k);
    Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
    c.world_from_camera.linear() = q.normalized().toRotationMatrix();
    c.world_from_camera.translation() = Vec3(u(rng), u(rng), u(rng)) * 5;
    rig.cameras.push_back(c);
  }
  return rig;
}

TEST(RigFormatsOpenCv, FileStorageReadsPandorasYaml) {
  const Rig rig = TestRig();
  cv::FileStorage fs(RigToOpenCvYaml(rig), cv::FileStorage::READ | cv::FileStorage::MEMORY);
  ASSERT_TRUE(fs.isOpened());
  EXPECT_EQ(static_cast<std::string>(fs["rig"]), "design");
  EXPECT_EQ(static_cast<int>(fs["camera_count"]), static_cast<int>(rig.cameras.size()));
  const cv::FileNode cameras = fs["cameras"];
  ASSERT_TRUE(cameras.isSeq());
  ASSERT_EQ(cameras.size(), rig.cameras.size());
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
    const Camera& c = rig.cameras[i];
    const Intrinsics& k = c.model.intrinsics();
    const cv::FileNode n = cameras[static_cast<int>(i)];
    SCOPED_TRACE(c.id);
    EXPECT_EQ(static_cast<std::string>(n["id"]), c.id);
    EXPECT_EQ(static_cast<std::string>(n["name"]), c.name);
    EXPECT_EQ(static_cast<int>(n["image_width"]), k.width);
    EXPECT_EQ(static_cast<int>(n["image_height"]), k.height);
    cv::Mat km, d, r, t;
    n["camera_matrix"] >> km;
    n["distortion_coefficients"] >> d;
    n["R"] >> r;
    n["T"] >> t;
    ASSERT_EQ(km.type(), CV_64F);
    EXPECT_EQ(km.at<double>(0, 0), k.fx);
    EXPECT_EQ(km.at<double>(1, 1), k.fy);
    EXPECT_EQ(km.at<double>(0, 2), k.cx);
    EXPECT_EQ(km.at<double>(1, 2), k.cy);
    EXPECT_EQ(km.at<double>(2, 2), 1.0);
    if (k.model == LensModel::kFisheye) {
      ASSERT_EQ(d.total(), 4u);
      EXPECT_EQ(d.at<double>(0), k.k1);
      EXPECT_EQ(d.at<double>(3), k.k4);
    } else {
      ASSERT_EQ(d.total(), 5u);
      EXPECT_EQ(d.at<double>(0), k.k1);
      EXPECT_EQ(d.at<double>(2), k.p1);
      EXPECT_EQ(d.at<double>(4), k.k3);
    }
    const Eigen::Isometry3d cw = c.camera_from_world();
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(t.at<double>(a), cw.translation()[a]);
      for (int b = 0; b < 3; ++b) EXPECT_EQ(r.at<double>(a, b), cw.linear()(a, b));
    }
  }
}

TEST(RigFormatsOpenCv, PandoraReadsWhatFileStorageWrites) {
  const Rig rig = TestRig();
  cv::FileStorage fs(
      "rig.yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  fs << "rig" << rig.name << "camera_count" << static_cast<int>(rig.cameras.size()) << "cameras"
     << "[";
  for (const Camera& c : rig.cameras) {
    const Intrinsics& k = c.model.intrinsics();
    const Eigen::Isometry3d cw = c.camera_from_world();
    cv::Mat r(3, 3, CV_64F), t(3, 1, CV_64F);
    for (int a = 0; a < 3; ++a) {
      t.at<double>(a) = cw.translation()[a];
      for (int b = 0; b < 3; ++b) r.at<double>(a, b) = cw.linear()(a, b);
    }
    const cv::Mat d = k.model == LensModel::kFisheye
                          ? cv::Mat(cv::Matx14d(k.k1, k.k2, k.k3, k.k4))
                          : cv::Mat(cv::Matx<double, 1, 5>(k.k1, k.k2, k.p1, k.p2, k.k3));
    fs << "{"
       << "id" << c.id << "name" << c.name << "image_width" << k.width << "image_height" << k.height
       << "camera_matrix" << cv::Mat(cv::Matx33d(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1))
       << "distortion_model" << LensModelName(k.model) << "distortion_coefficients" << d << "R" << r
       << "T" << t << "}";
  }
  fs << "]";
  const std::string text = fs.releaseAndGetString();
  const Rig back = ParseOpenCvYaml(text, "rig.yml");
  ASSERT_EQ(back.cameras.size(), rig.cameras.size());
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
    const Camera& a = rig.cameras[i];
    const Camera& b = back.cameras[i];
    SCOPED_TRACE(a.id);
    EXPECT_EQ(a.id, b.id);
    const Intrinsics& x = a.model.intrinsics();
    const Intrinsics& y = b.model.intrinsics();
    EXPECT_EQ(x.model, y.model);
    EXPECT_EQ(x.fx, y.fx);
    EXPECT_EQ(x.fy, y.fy);
    EXPECT_EQ(x.cx, y.cx);
    EXPECT_EQ(x.cy, y.cy);
    EXPECT_EQ(x.k1, y.k1);
    EXPECT_EQ(x.k2, y.k2);
    EXPECT_EQ(x.k4, y.k4);
    EXPECT_LE((a.center() - b.center()).norm(), 1e-12);
    EXPECT_LE(
        Eigen::AngleAxisd(a.world_from_camera.linear().transpose() * b.world_from_camera.linear())
            .angle(),
        1e-12);
  }

  // One camera as a calibration program writes it (the OpenCV calibration sample's keys).
  cv::FileStorage one(
      "cam.yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  one << "calibration_time"
      << "Mon Nov 24 08:00:00 2026"
      << "nr_of_frames" << 25 << "image_width" << 1280 << "image_height" << 720 << "board_width"
      << 9 << "board_height" << 6 << "square_size" << 0.025 << "flags" << 0 << "camera_matrix"
      << cv::Mat(cv::Matx33d(1000.5, 0, 639.25, 0, 1000.75, 359.5, 0, 0, 1))
      << "distortion_coefficients" << cv::Mat(cv::Matx<double, 5, 1>(-0.2, 0.05, 1e-3, -1e-3, 0.01))
      << "avg_reprojection_error" << 0.23 << "R" << cv::Mat(cv::Matx33d::eye()) << "T"
      << cv::Mat(cv::Matx31d(0, 0, 2));
  const Rig cam = ParseOpenCvYaml(one.releaseAndGetString(), "/calib/cam.yml");
  ASSERT_EQ(cam.cameras.size(), 1u);
  EXPECT_EQ(cam.cameras[0].id, "cam");
  EXPECT_EQ(cam.cameras[0].model.intrinsics().fy, 1000.75);
  EXPECT_EQ(cam.cameras[0].model.intrinsics().k3, 0.01);
  EXPECT_LE((cam.cameras[0].center() - Vec3(0, 0, -2)).norm(), 0.0);
}

}  // namespace
}  // namespace pandora
