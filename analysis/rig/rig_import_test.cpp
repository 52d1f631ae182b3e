// Rig formats (analysis/rig/rig_formats.h) and import-rig (analysis/rig/rig_import.h): round trips
// export -> import give back the same rig (poses to 1e-9, intrinsics bit for bit), the layouts
// calibration tools write read to their closed forms, and damaged files end in InputError with
// nothing written.
#include "analysis/rig/rig_import.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "analysis/rig/rig_formats.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "tests/temp_dir.h"

namespace pandora {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::string kScenePath = "tests/data/rigio.json";

Scene LoadRigioScene() {
  LoadOptions load;
  load.load_meshes = false;
  return LoadScene(kScenePath, load);
}

double AngleBetween(const Mat3& a, const Mat3& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

// Poses to 1e-9 (metres, radians), every intrinsic bit for bit, ids and lens models equal.
void ExpectSameRig(const Rig& expected, const Rig& actual, bool names = true) {
  ASSERT_EQ(expected.cameras.size(), actual.cameras.size());
  for (std::size_t i = 0; i < expected.cameras.size(); ++i) {
    const Camera& e = expected.cameras[i];
    const Camera& a = actual.cameras[i];
    SCOPED_TRACE("camera " + e.id);
    EXPECT_EQ(e.id, a.id);
    if (names) {
      EXPECT_EQ(e.name, a.name);
    }
    EXPECT_LE((e.center() - a.center()).norm(), 1e-9);
    EXPECT_LE(AngleBetween(e.world_from_camera.linear(), a.world_from_camera.linear()), 1e-9);
    const Intrinsics& x = e.model.intrinsics();
    const Intrinsics& y = a.model.intrinsics();
    EXPECT_EQ(x.width, y.width);
    EXPECT_EQ(x.height, y.height);
    EXPECT_EQ(x.model, y.model);
    EXPECT_EQ(x.fx, y.fx);
    EXPECT_EQ(x.fy, y.fy);
    EXPECT_EQ(x.cx, y.cx);
    EXPECT_EQ(x.cy, y.cy);
    EXPECT_EQ(x.k1, y.k1);
    EXPECT_EQ(x.k2, y.k2);
    EXPECT_EQ(x.p1, y.p1);
    EXPECT_EQ(x.p2, y.p2);
    EXPECT_EQ(x.k3, y.k3);
    EXPECT_EQ(x.k4, y.k4);
  }
}

// A rig of `n` random cameras: random poses in a 20 m cube, random focal lengths, principal points
// and coefficients with full 53-bit mantissas, each lens model in turn.
Rig RandomRig(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Rig rig;
  rig.name = "random";
  for (int i = 0; i < n; ++i) {
    Camera c;
    c.id = "r" + std::to_string(i) + (i % 3 == 0 ? " odd/ünï" : "");
    c.name = c.id;
    Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
    q.normalize();
    c.world_from_camera.linear() = q.toRotationMatrix();
    c.world_from_camera.translation() = Vec3(u(rng), u(rng), u(rng)) * 10.0;
    Intrinsics k;
    k.width = 640 + 64 * (i % 20);
    k.height = 480 + 32 * (i % 15);
    k.fx = 300 + 1500 * (0.5 + 0.5 * u(rng));
    k.fy = k.fx * (1 + 0.01 * u(rng));
    k.cx = 0.5 * k.width + 40 * u(rng);
    k.cy = 0.5 * k.height + 40 * u(rng);
    k.model = static_cast<LensModel>(i % 3);
    if (k.model == LensModel::kBrownConrady) {
      k.k1 = 0.2 * u(rng), k.k2 = 0.05 * u(rng), k.p1 = 1e-3 * u(rng), k.p2 = 1e-3 * u(rng);
      k.k3 = i % 2 ? 0.01 * u(rng) : 0.0;  // OPENCV and FULL_OPENCV in COLMAP
    } else if (k.model == LensModel::kFisheye) {
      k.k1 = 0.05 * u(rng), k.k2 = 0.01 * u(rng), k.k3 = 1e-3 * u(rng), k.k4 = 1e-4 * u(rng);
    }
    c.model = CameraModel(k);
    rig.cameras.push_back(c);
  }
  return rig;
}

Rig ViaOpenCv(const Rig& rig) { return ParseOpenCvYaml(RigToOpenCvYaml(rig), "rig.yml"); }
Rig ViaColmap(const Rig& rig) {
  const ColmapText t = RigToColmap(rig);
  return ParseColmap(t.cameras, "cameras.txt", t.images, "images.txt", rig.name);
}

TEST(RigFormats, OpenCvRoundTripOfTheSceneRig) {
  const Scene scene = LoadRigioScene();
  const Rig& rig = scene.FindRig("design");
  const Rig back = ViaOpenCv(rig);
  EXPECT_EQ(back.name, "design");
  ExpectSameRig(rig, back);
}

TEST(RigFormats, ColmapRoundTripOfTheSceneRig) {
  const Scene scene = LoadRigioScene();
  ExpectSameRig(scene.FindRig("design"), ViaColmap(scene.FindRig("design")), false);
}

TEST(RigFormats, RandomRigsRoundTripExactly) {
  const Rig rig = RandomRig(300, 7);
  const Rig opencv = ViaOpenCv(rig), colmap = ViaColmap(rig);
  ExpectSameRig(rig, opencv);
  ExpectSameRig(rig, colmap, false);
  // The measured round-trip error (docs/tool-chain.md).
  for (const auto& [name, back] :
       {std::pair<const char*, const Rig*>{"opencv", &opencv}, {"colmap", &colmap}}) {
    double centre = 0, angle = 0;
    for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
      centre = std::max(centre, (rig.cameras[i].center() - back->cameras[i].center()).norm());
      angle = std::max(angle, AngleBetween(rig.cameras[i].world_from_camera.linear(),
                                           back->cameras[i].world_from_camera.linear()));
    }
    std::printf(
        "%s round trip, 300 cameras within 17 m of the origin: centres %.3g m, angles %.3g rad\n",
        name, centre, angle);
  }
}

// The pose written is OpenCV's world -> camera: a world point maps to T + R X in the camera frame.
TEST(RigFormats, OpenCvPoseIsWorldToCamera) {
  const Scene scene = LoadRigioScene();
  const Rig& rig = scene.FindRig("design");
  const std::string yaml = RigToOpenCvYaml(rig);
  // Camera "north 1" at (0, 2.5, 2.3) m looks at (0, 0, 0.8): its optical axis (R's third row) is
  // the unit vector from its centre to the target, and its x axis (R's first row) is horizontal.
  const Camera& c = rig.cameras[0];
  const Vec3 axis = (Vec3(0, 0, 0.8) - Vec3(0, 2.5, 2.3)).normalized();
  const Mat3 r = c.camera_from_world().linear();
  EXPECT_LE((r.row(2).transpose() - axis).norm(), 1e-12);
  EXPECT_LE(std::abs(r(0, 2)), 1e-12);
  EXPECT_NE(yaml.find("%YAML:1.0\n"), std::string::npos);
  EXPECT_NE(yaml.find("id: \"north 1\""), std::string::npos);
  EXPECT_NE(yaml.find("name: \"corner \\\"seven\\\"\""), std::string::npos);
}

// What calibration tools write: one camera at the top level, K and D aliases, a 4-coefficient
// vector (k1 k2 p1 p2), rvec/tvec; an Nx1 vector of 8 with zero rational terms.
TEST(RigFormats, OpenCvCalibrationFileLayouts) {
  const std::string text =
      "%YAML:1.0\n---\ncalibration_time: \"Mon Nov 24 2026\"\nimage_width: 1280\nimage_height: "
      "720\n"
      "board_width: 9\nboard_height: 6\nsquare_size: 0.025\nflags: 0\n"
      "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
      "   data: [ 1000., 0., 640.25, 0., 1001., 360.75, 0., 0., 1. ]\n"
      "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 4\n   dt: d\n"
      "   data: [ -0.25, 0.125, 1.e-03, -2.e-03 ]\n"
      "rvec: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ 0., 0., "
      "1.5707963267948966 ]\n"
      "tvec: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ 1., 2., 3. ]\n"
      "avg_reprojection_error: 0.21\n";
  const Rig rig = ParseOpenCvYaml(text, "/calib/cam_left.yml");
  ASSERT_EQ(rig.cameras.size(), 1u);
  const Camera& c = rig.cameras[0];
  EXPECT_EQ(c.id, "cam_left");
  const Intrinsics& k = c.model.intrinsics();
  EXPECT_EQ(k.model, LensModel::kBrownConrady);
  EXPECT_EQ(k.fx, 1000.0);
  EXPECT_EQ(k.fy, 1001.0);
  EXPECT_EQ(k.cx, 640.25);
  EXPECT_EQ(k.cy, 360.75);
  EXPECT_EQ(k.k1, -0.25);
  EXPECT_EQ(k.k2, 0.125);
  EXPECT_EQ(k.p1, 1e-3);
  EXPECT_EQ(k.p2, -2e-3);
  EXPECT_EQ(k.k3, 0.0);
  // R = Rz(90 deg): world -> camera; the centre is -R^T t = -(Rz(-90) (1, 2, 3)) = -(2, -1, 3).
  EXPECT_LE((c.center() - Vec3(-2, 1, -3)).norm(), 1e-15);

  const std::string eight =
      "%YAML:1.0\ncameras:\n  -\n    id: \"x\"\n    image_width: 10\n    image_height: 8\n"
      "    K: !!opencv-matrix\n      rows: 3\n      cols: 3\n      dt: f\n"
      "      data: [ 10, 0, 4.5, 0, 10, 3.5,\n          0, 0, 1 ]\n"
      "    D: !!opencv-matrix\n      rows: 8\n      cols: 1\n      dt: d\n"
      "      data: [ 0.5, 0.25, 0, 0, 0.125, 0, 0, 0 ]\n"
      "    R: !!opencv-matrix\n      rows: 3\n      cols: 3\n      dt: d\n      data: [ 1, 0, 0, "
      "0, 1, 0, 0, 0, 1 ]\n"
      "    T: !!opencv-matrix\n      rows: 3\n      cols: 1\n      dt: d\n      data: [ 0, 0, -2 ] "
      " # comment\n";
  const Rig r8 = ParseOpenCvYaml(eight, "eight.yml");
  ASSERT_EQ(r8.cameras.size(), 1u);
  EXPECT_EQ(r8.cameras[0].model.intrinsics().k3, 0.125);
  EXPECT_LE((r8.cameras[0].center() - Vec3(0, 0, 2)).norm(), 0.0);
  // A non-zero rational term is refused, naming the line of the vector.
  std::string rational = eight;
  rational.replace(rational.find("0.125, 0, 0, 0"), 14, "0.125, 0.5, 0, 0");
  try {
    ParseOpenCvYaml(rational, "eight.yml");
    ADD_FAILURE() << "accepted a rational term";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("eight.yml: line 13: cameras[0].D"), std::string::npos)
        << e.what();
  }
}

// COLMAP's other models read to their closed forms; the principal point moves by 0.5 px.
TEST(RigFormats, ColmapModelsAndPixelConvention) {
  const std::string cameras =
      "# c\n1 SIMPLE_RADIAL 800 600 700 400.5 300.5 -0.125\n2 RADIAL 800 600 701 400 300 -0.1 "
      "0.02\n"
      "3 SIMPLE_PINHOLE 800 600 650 400.5 300.5\n";
  const std::string images =
      "# i\n5 1 0 0 0 0 0 1 1 a.jpg\n1.5 2.5 -1 3 4 7\n6 0 1 0 0 1 2 3 2 sub%2Fb.JPG\n\n"
      "9 0.70710678118654757 0 0 0.70710678118654757 0 0 0 3 c\n\n";
  const Rig rig = ParseColmap(cameras, "cameras.txt", images, "images.txt", "calib");
  ASSERT_EQ(rig.cameras.size(), 3u);
  EXPECT_EQ(rig.cameras[0].id, "a");
  EXPECT_EQ(rig.cameras[1].id, "sub/b");
  EXPECT_EQ(rig.cameras[2].id, "c");
  const Intrinsics& a = rig.cameras[0].model.intrinsics();
  EXPECT_EQ(a.model, LensModel::kBrownConrady);
  EXPECT_EQ(a.fx, 700.0);
  EXPECT_EQ(a.fy, 700.0);
  EXPECT_EQ(a.cx, 400.0);
  EXPECT_EQ(a.cy, 300.0);
  EXPECT_EQ(a.k1, -0.125);
  EXPECT_LE((rig.cameras[0].center() - Vec3(0, 0, -1)).norm(), 1e-15);
  // q = (0, 1, 0, 0): 180 deg about x, R = diag(1, -1, -1); centre -R^T t = (-1, 2, 3).
  EXPECT_LE((rig.cameras[1].center() - Vec3(-1, 2, 3)).norm(), 1e-15);
  EXPECT_EQ(rig.cameras[1].model.intrinsics().k2, 0.02);
  EXPECT_EQ(rig.cameras[2].model.intrinsics().model, LensModel::kPinhole);
}

// Export, import into the scene file's text (new rig, and replacing the design's cameras by id),
// load: the same rig, in a centimetre scene.
TEST(RigImport, SceneTextRoundTripInCentimetres) {
  const std::string text = ReadText(kScenePath);
  const Scene scene = LoadRigioScene();
  const Rig& design = scene.FindRig("design");
  LoadOptions load;
  load.load_meshes = false;
  for (const std::string format : {"opencv", "colmap"}) {
    SCOPED_TRACE(format);
    const Rig imported = format == "opencv" ? ViaOpenCv(design) : ViaColmap(design);
    const Scene added = ParseScene(WriteRigIntoSceneText(text, kScenePath, imported, "calib", true),
                                   kScenePath, load);
    ASSERT_EQ(added.rigs.size(), 2u);
    ExpectSameRig(design, added.FindRig("calib"), format == "opencv");
    ExpectSameRig(design, added.FindRig("design"));
    const Scene replaced = ParseScene(
        WriteRigIntoSceneText(text, kScenePath, imported, "design", false), kScenePath, load);
    ASSERT_EQ(replaced.rigs.size(), 1u);
    ExpectSameRig(design, replaced.FindRig("design"));
  }
}

// Replacing by id keeps every other key and the keys' order: the orientation is written at the
// place of look_at / euler_deg / quaternion, the focal length at the place of hfov_deg / focal_px /
// lens; name, range and the other cameras stay as they were.
TEST(RigImport, ReplaceKeepsOtherKeysAndOrder) {
  const std::string text = ReadText(kScenePath);
  Rig calibrated = LoadRigioScene().FindRig("design");
  calibrated.cameras.erase(calibrated.cameras.begin() + 2);  // the fisheye stays as designed
  const nlohmann::ordered_json before = nlohmann::ordered_json::parse(text);
  const nlohmann::ordered_json after = nlohmann::ordered_json::parse(
      WriteRigIntoSceneText(text, kScenePath, ViaOpenCv(calibrated), "design", false));
  const auto keys = [](const nlohmann::ordered_json& camera) {
    std::vector<std::string> k;
    for (auto it = camera.begin(); it != camera.end(); ++it) k.push_back(it.key());
    return k;
  };
  const auto& cams = after["rigs"][0]["cameras"];
  EXPECT_EQ(keys(cams[0]), (std::vector<std::string>{"id", "position", "quaternion", "resolution",
                                                     "focal_px", "principal_point"}));
  EXPECT_EQ(keys(cams[1]),
            (std::vector<std::string>{"id", "name", "position", "quaternion", "resolution",
                                      "focal_px", "principal_point", "distortion"}));
  EXPECT_EQ(cams[1]["name"], "corner \"seven\"");
  EXPECT_EQ(cams[1]["id"], 7);  // a number stays a number
  EXPECT_EQ(cams[2], before["rigs"][0]["cameras"][2]);
  EXPECT_EQ(keys(cams[3]), (std::vector<std::string>{"id", "position", "quaternion", "resolution",
                                                     "focal_px", "distortion", "principal_point"}));
  EXPECT_EQ(after["study"], before["study"]);
  EXPECT_EQ(after["objects"], before["objects"]);
}

TEST(RigImport, MovedCameraIsReportedAndWrittenWithBackup) {
  testing::TempDir dir("rigio");
  const std::string scene = dir.File("scene.json");
  std::filesystem::copy_file(kScenePath, scene);
  const Scene loaded = LoadRigioScene();
  Rig calibrated = loaded.FindRig("design");
  // The installer put camera 7 5 cm lower and turned it 1 degree about its optical axis.
  Camera& c = calibrated.cameras[1];
  c.world_from_camera.translation() += Vec3(0, 0, -0.05);
  c.world_from_camera.linear() =
      c.world_from_camera.linear() * Eigen::AngleAxisd(kPi / 180, Vec3::UnitZ()).toRotationMatrix();
  dir.Write("calib.yml", RigToOpenCvYaml(calibrated));
  const std::string before = ReadText(scene);
  RigImportOptions options{scene, "opencv", dir.File("calib.yml"), "design", ""};
  const RigImportResult r = ImportRig(options);
  EXPECT_FALSE(r.new_rig);
  EXPECT_EQ(ReadText(r.backup_path), before);
  ASSERT_EQ(r.differences.size(), 4u);
  EXPECT_NEAR(r.differences[1].moved_m, 0.05, 1e-12);
  EXPECT_NEAR(r.differences[1].turned_deg, 1.0, 1e-9);
  EXPECT_NEAR(r.differences[0].moved_m, 0.0, 1e-12);
  LoadOptions load;
  load.load_meshes = false;
  ExpectSameRig(calibrated, LoadScene(scene, load).FindRig("design"));
}

// Damage: hundreds of mutations of valid files. Each read ends in a rig or in InputError (never
// another exception), every value read is finite, and a failed import leaves the scene file as
// it was without a backup.
std::string Mutate(const std::string& text, std::mt19937_64& rng) {
  static const std::vector<std::string> kInserts = {
      "nan", "1e400", "-",  "9999999999999",   ":", "[",    "]",       ",", "\"", " ",
      "\n",  "#",     "- ", "!!opencv-matrix", "0", ".Inf", "FISHEYE", "\t"};
  std::string s = text;
  std::uniform_int_distribution<std::size_t> pos(0, s.size() - 1);
  switch (rng() % 6) {
    case 0:
      s.erase(pos(rng), 1 + rng() % 8);
      break;
    case 1:
      s[pos(rng)] = static_cast<char>(32 + rng() % 95);
      break;
    case 2:
      s.insert(pos(rng), kInserts[rng() % kInserts.size()]);
      break;
    case 3:
      s.resize(pos(rng));
      break;
    case 4: {  // duplicate a line
      std::size_t a = s.rfind('\n', pos(rng));
      a = a == std::string::npos ? 0 : a + 1;
      const std::size_t b = s.find('\n', a);
      if (b != std::string::npos) s.insert(a, s.substr(a, b - a + 1));
      break;
    }
    default: {  // replace a number by another
      const std::size_t a = s.find_first_of("0123456789", pos(rng));
      if (a != std::string::npos) s.replace(a, 1, kInserts[rng() % 5]);
    }
  }
  return s;
}

void ExpectFinite(const Rig& rig) {
  for (const Camera& c : rig.cameras) {
    const Intrinsics& k = c.model.intrinsics();
    for (double v : {k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1, k.p2, k.k3, k.k4})
      ASSERT_TRUE(std::isfinite(v));
    ASSERT_TRUE(c.world_from_camera.matrix().allFinite());
    ASSERT_GT(k.width, 0);
  }
}

TEST(RigImport, DamagedFilesEndInInputErrorAndWriteNothing) {
  testing::TempDir dir("rigio_damage");
  const std::string scene = dir.File("scene.json");
  std::filesystem::copy_file(kScenePath, scene);
  const std::string scene_bytes = ReadText(scene);
  const Rig design = LoadRigioScene().FindRig("design");
  const std::string yaml = RigToOpenCvYaml(design);
  const ColmapText colmap = RigToColmap(design);
  std::filesystem::create_directories(dir.path() / "model");
  std::mt19937_64 rng(14);
  int errors = 0, accepted = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const std::string format = trial % 2 ? "colmap" : "opencv";
    std::string from;
    if (format == "opencv") {
      from = dir.File("rig.yml");
      dir.Write("rig.yml", Mutate(yaml, rng));
    } else {
      from = dir.File("model");
      const bool cams = rng() % 2;
      dir.Write("model/cameras.txt", cams ? Mutate(colmap.cameras, rng) : colmap.cameras);
      dir.Write("model/images.txt", cams ? colmap.images : Mutate(colmap.images, rng));
    }
    try {
      const Rig rig = ReadCalibratedRig(format, from, "calib");
      ExpectFinite(rig);
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "trial " << trial << ": " << e.what();
    }
    try {
      ImportRig({scene, format, from, "design", "calib"});
      ++accepted;
      LoadOptions load;
      load.load_meshes = false;
      ExpectFinite(LoadScene(scene, load).FindRig("calib"));
    } catch (const InputError& e) {
      ++errors;
      ASSERT_EQ(ReadText(scene), scene_bytes) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << "trial " << trial << ": " << e.what();
    }
    // Restore: only the scene file and its backups.
    for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
      if (entry.path().filename().string().rfind("scene.json.bak", 0) == 0) {
        EXPECT_GT(accepted, 0) << "a backup after a failed import";
        std::filesystem::remove(entry.path());
      }
    dir.Write("scene.json", scene_bytes);
  }
  std::printf("damage: %d refused, %d accepted (still valid)\n", errors, accepted);
  EXPECT_GT(errors, 300);
}

// Named damages: each refused with its line, field and reason.
TEST(RigImport, NamedDamagesNameLineFieldAndReason) {
  const Rig design = LoadRigioScene().FindRig("design");
  const std::string yaml = RigToOpenCvYaml(design);
  const ColmapText colmap = RigToColmap(design);
  const auto replace = [](std::string text, const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
  };
  const auto expect = [](const std::function<void()>& read, const std::string& message) {
    try {
      read();
      ADD_FAILURE() << "accepted; expected " << message;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  const auto yml = [&](const std::string& text, const std::string& message) {
    expect([&] { ParseOpenCvYaml(text, "rig.yml"); }, message);
  };
  yml(replace(yaml, "camera_count: 4", "camera_count: 5"),
      "rig.yml: line 4: camera_count: says 5 cameras but 'cameras' holds 4");
  yml(replace(yaml, "rows: 3\n         cols: 3", "rows: 2\n         cols: 3"),
      "rig.yml: line 15: cameras[0].camera_matrix.data: expected 6 numbers (rows x cols), got 9");
  yml(replace(yaml, "1371.0220864724301, 0.", "1e400, 0."),
      "cameras[0].camera_matrix.data[0]: expected a finite number, got '1e400'");
  yml(replace(yaml, "1371.0220864724301, 0.", "1e9, 0."), "fx and fy must be in (0, 1e7] pixels");
  yml(replace(yaml, "distortion_model: brown_conrady", "distortion_model: rational"),
      "cameras[1].distortion_model: unknown distortion model 'rational'");
  yml(replace(yaml, "      T: !!opencv-matrix", "      U: !!opencv-matrix"),
      "cameras[0].U: unknown field 'U'");
  yml(replace(yaml, "      image_width: 1920\n", ""), "cameras[0].image_width: missing field");
  {
    // The first camera's R with its first entry changed: no longer a rotation.
    std::string bad = yaml;
    const std::size_t data = bad.find("data: [ ", bad.find("R: !!opencv-matrix")) + 8;
    bad.replace(data, bad.find(',', data) - data, "0.5");
    yml(bad, "rig.yml: line 25: cameras[0].R: not a rotation matrix");
  }
  yml(replace(yaml, "id: \"7\"", "id: \"north 1\""),
      "cameras[1].id: camera id 'north 1' appears twice");
  yml(replace(yaml, "%YAML:1.0", "%YAML:2.0"), "rig.yml: line 1: not an OpenCV YAML file");

  const auto col = [&](const std::string& cameras, const std::string& images,
                       const std::string& message) {
    expect([&] { ParseColmap(cameras, "cameras.txt", images, "images.txt", "calib"); }, message);
  };
  col(replace(colmap.cameras, "1 PINHOLE 1920 1080 1371.0220864724301 ", "1 PINHOLE 1920 1080 "),
      colmap.images, "cameras.txt: line 4: PARAMS: PINHOLE has 4 parameters, got 3");
  col(replace(colmap.cameras, "OPENCV_FISHEYE", "FOV"), colmap.images,
      "cameras.txt: line 6: MODEL: unsupported camera model 'FOV'");
  col(replace(colmap.cameras, "1920 1080", "1920 nan"), colmap.images,
      "cameras.txt: line 4: HEIGHT: expected a whole number");
  col(replace(colmap.cameras, "FULL_OPENCV 2048 1536 1450.25 1449.75",
              "FULL_OPENCV 2048 1536 1e400 1449.75"),
      colmap.images, "cameras.txt: line 5: PARAMS[0]: expected a finite number, got '1e400'");
  col(colmap.cameras, replace(colmap.images, " 1 north%201.png", " 9 north%201.png"),
      "images.txt: line 5: CAMERA_ID: no camera '9' in the cameras file");
  col(colmap.cameras,
      replace(colmap.images, "1 0 0 0.8701999067534788", "1 0 0 0.9701999067534788"),
      "images.txt: line 5: QW QX QY QZ: not a unit quaternion");
  // Names that cannot be camera ids in a JSON scene file (once exit 1, an internal error).
  col(colmap.cameras, replace(colmap.images, "north%201.png", "north\x01x.png"),
      "images.txt: line 5: NAME: the image name (a camera id) holds a control character (0x01) at "
      "byte 5");
  col(colmap.cameras, replace(colmap.images, "north%201.png", "north\xff\xfe.png"),
      "images.txt: line 5: NAME: the image name (a camera id) holds invalid UTF-8 at byte 5");
  col(colmap.cameras, replace(colmap.images, "north%201.png", "north%01.png"),
      "images.txt: line 5: NAME: the image name (a camera id) holds a control character (0x01)");
  col(colmap.cameras, replace(colmap.images, "north%201.png", "north%C3.png"),
      "images.txt: line 5: NAME: the image name (a camera id) holds invalid UTF-8");
  col(colmap.cameras, replace(colmap.images, "north%201.png\n\n", "north%201.png\n1 2\n"),
      "images.txt: line 6: POINTS2D: expected (X, Y, POINT3D_ID) triples, got 2 numbers");
  col(colmap.cameras, colmap.images.substr(0, colmap.images.size() - 1),
      "images.txt: line 11: POINTS2D: missing the POINTS2D line after the image line");
  col(colmap.cameras, replace(colmap.images, "north%201.png", "7.jpg"),
      "images.txt: line 7: NAME: two images give the camera id '7'");
}

// glTF: one camera node per camera at its centre (Y up) looking down its -Z along the optical axis.
TEST(RigFormats, GltfCameraNodes) {
  const Scene scene = LoadScene(kScenePath);
  const Rig& rig = scene.FindRig("design");
  const nlohmann::json doc = nlohmann::json::parse(SceneToGltf(scene, rig));
  ASSERT_EQ(doc["cameras"].size(), rig.cameras.size());
  EXPECT_EQ(doc["meshes"].size(), scene.objects.size());
  std::size_t found = 0;
  for (const auto& node : doc["nodes"]) {
    if (!node.contains("camera")) continue;
    const Camera& c = rig.cameras[rig.FindCamera(node["name"].get<std::string>())];
    ++found;
    const Vec3 t(node["translation"][0], node["translation"][1], node["translation"][2]);
    EXPECT_LE((t - Vec3(c.center().x(), c.center().z(), -c.center().y())).norm(), 1e-12);
    const Eigen::Quaterniond q(node["rotation"][3].get<double>(), node["rotation"][0].get<double>(),
                               node["rotation"][1].get<double>(),
                               node["rotation"][2].get<double>());
    const Vec3 forward = q * Vec3(0, 0, -1);
    const Vec3 up = q * Vec3(0, 1, 0);
    const Vec3 axis = c.world_from_camera.linear().col(2);
    const Vec3 down = c.world_from_camera.linear().col(1);
    EXPECT_LE((forward - Vec3(axis.x(), axis.z(), -axis.y())).norm(), 1e-12);
    EXPECT_LE((up + Vec3(down.x(), down.z(), -down.y())).norm(), 1e-12);
    const auto& p = doc["cameras"][node["camera"].get<std::size_t>()]["perspective"];
    const Intrinsics& k = c.model.intrinsics();
    EXPECT_NEAR(std::tan(0.5 * p["yfov"].get<double>()), 0.5 * k.height / k.fy, 1e-12);
  }
  EXPECT_EQ(found, rig.cameras.size());
}

// The glTF's meshes read back through Pandora's own mesh loader (assimp, Y up): the same
// triangles, the same bounds to float precision, one part per material with its colour.
TEST(RigFormats, GltfMeshesLoadBack) {
  const Scene scene = LoadScene(kScenePath);
  for (const bool binary : {false, true}) {
    SCOPED_TRACE(binary ? "glb" : "gltf");
    testing::TempDir dir("rigio_gltf");
    const std::string bytes = SceneToGltf(scene, scene.FindRig("design"), binary);
    if (binary) {
      ASSERT_EQ(bytes.substr(0, 4), "glTF");
      std::uint32_t length = 0;
      std::memcpy(&length, bytes.data() + 8, 4);
      EXPECT_EQ(length, bytes.size());
      EXPECT_EQ(bytes.size() % 4, 0u);
    }
    const std::string name = binary ? "scene.glb" : "scene.gltf";
    dir.Write(name, bytes);
    dir.Write("back.json", R"({"objects": [{"name": "all", "mesh": {"file": ")" + name + R"("}}],
                "rigs": [{"name": "r", "cameras": [{"id": "a", "position": [0, -3, 1], "look_at": [0, 0, 1],
                          "resolution": [64, 48], "hfov_deg": 60}]}],
                "study": {"region": {"box": {"min": [-1, -1, 0], "max": [1, 1, 2]}}}})");
    const Scene back = LoadScene(dir.File("back.json"));
    EXPECT_EQ(back.AllTriangles().triangles.size(), scene.AllTriangles().triangles.size());
    const Aabb b = back.AllTriangles().Bounds();
    const Aabb o = scene.AllTriangles().Bounds();
    EXPECT_LE((o.min - b.min).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_LE((o.max - b.max).cwiseAbs().maxCoeff(), 1e-6);
    ASSERT_EQ(back.objects.size(), scene.objects.size());
    for (const SceneObject& part : back.objects) {
      // "all/<material>": the material's colour came through baseColorFactor.
      const std::string material = part.name.substr(part.name.find('/') + 1);
      const Material* original = nullptr;
      for (const SceneObject& object : scene.objects)
        if (object.material >= 0 &&
            scene.materials[static_cast<std::size_t>(object.material)].name == material)
          original = &scene.materials[static_cast<std::size_t>(object.material)];
      ASSERT_NE(original, nullptr) << part.name;
      ASSERT_GE(part.material, 0);
      EXPECT_LE(
          (back.materials[static_cast<std::size_t>(part.material)].color - original->color).norm(),
          1e-6);
    }
  }
}

}  // namespace
}  // namespace pandora
