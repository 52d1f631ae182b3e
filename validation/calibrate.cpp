#include "validation/calibrate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "analysis/geometry/visibility.h"
#include "analysis/util/text.h"
#include "validation/calibrate_internal.h"

namespace pandora {
namespace {

using calibration_internal::BundleAdjust;
using calibration_internal::BundleCamera;
using calibration_internal::BundleResult;
using calibration_internal::BundleView;
using calibration_internal::CalibrateIntrinsics;
using calibration_internal::IntrinsicResult;
using calibration_internal::ProjectWithIntrinsics;
using calibration_internal::ViewCorners;
using StudyClock = std::chrono::steady_clock;
constexpr double kCalibrateDegPerRad = 57.29577951308232;

// The board and the simulation the verdict comes from: the scene's board calibration when it has
// one (its board drawn as ChArUco), else a ChArUco board of the options' squares sized from the
// rig, simulated with 2000 poses and min_shared 20 (the defaults of "study.calibration").
Fiducial StudyBoard(const Scene& scene, const Rig& rig, const CalibrateOptions& o,
                    CalibrationSpec* spec, std::vector<std::string>* notes) {
  if (scene.study.calibration &&
      scene.study.calibration->target == CalibrationSpec::Target::kBoard) {
    *spec = *scene.study.calibration;
    return SizedCharucoBoard(scene, rig, spec->board.squares_x, spec->board.squares_y,
                             spec->board.square_m, kCalibrationCellPixels, "calibration board");
  }
  if (scene.study.calibration)
    notes->push_back(
        "The study calibrates with a wand; this study waves a ChArUco board (end-to-end "
        "calibration of a wand needs its own solver).");
  *spec = CalibrationSpec();
  if (scene.study.calibration) *spec = *scene.study.calibration;
  spec->target = CalibrationSpec::Target::kBoard;
  const Fiducial board = SizedCharucoBoard(scene, rig, o.squares_x, o.squares_y, o.square_m,
                                           kCalibrationCellPixels, "calibration board");
  spec->board.squares_x = board.squares_x;
  spec->board.squares_y = board.squares_y;
  spec->board.square_m = board.square_m;
  spec->board.min_px_per_square = 10;
  return board;
}

// Per camera, its views of >= min_view_corners detections, by pose.
std::vector<std::vector<ViewCorners>> GroupViews(const BoardCapture& capture,
                                                 const std::map<int, Vec2>& corner_xy,
                                                 std::size_t cameras, double pooled_sigma,
                                                 int min_view_corners) {
  std::map<std::pair<int, int>, ViewCorners> views;  // (camera, pose)
  for (const BoardObservation& ob : capture.observations) {
    ViewCorners& v = views[{ob.camera, ob.pose}];
    v.pose = ob.pose;
    v.board_xy.push_back(corner_xy.at(ob.id));
    v.pixels.push_back(ob.found);
    v.sigma_px = ob.view_sigma > 0 ? std::max(ob.view_sigma, 1e-3) : pooled_sigma;
  }
  std::vector<std::vector<ViewCorners>> out(cameras);
  for (auto& [key, v] : views)
    if (static_cast<int>(v.pixels.size()) >= min_view_corners)
      out[key.first].push_back(std::move(v));
  return out;
}

// The final model's pixel for each true ray against the true pixel (CameraCalibration::map_*).
void MappingError(const Camera& truth, const Intrinsics& estimate,
                  const std::vector<Vec2>& footprint, CameraCalibration* out) {
  const int W = truth.model.width(), H = truth.model.height();
  auto error = [&](const Vec2& pixel) {
    const std::optional<Vec3> ray = truth.model.Unproject(pixel);
    Vec2 uv;
    if (!ray || !ProjectWithIntrinsics(estimate, *ray, &uv))
      return std::numeric_limits<double>::quiet_NaN();
    return (uv - pixel).norm();
  };
  double sum2 = 0, max = 0;
  int n = 0;
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 32; ++i) {
      const double e = error(Vec2((i + 0.5) * W / 32.0 - 0.5, (j + 0.5) * H / 24.0 - 0.5));
      if (!std::isfinite(e)) continue;
      sum2 += e * e, max = std::max(max, e), ++n;
    }
  out->map_rms_px = n ? std::sqrt(sum2 / n) : std::numeric_limits<double>::quiet_NaN();
  out->map_max_px = n ? max : std::numeric_limits<double>::quiet_NaN();
  double fsum2 = 0;
  int fn = 0;
  const std::size_t step = std::max<std::size_t>(1, footprint.size() / 2000);
  for (std::size_t i = 0; i < footprint.size(); i += step) {
    const double e = error(footprint[i]);
    if (std::isfinite(e)) fsum2 += e * e, ++fn;
  }
  out->map_footprint_rms_px = fn ? std::sqrt(fsum2 / fn) : std::numeric_limits<double>::quiet_NaN();
}

// Link strength per camera: the smallest shared count on its path to `reference` in the
// predicted maximum spanning forest (0: not connected; the reference: its observed poses).
std::vector<std::int64_t> LinkStrength(const CalibrationResult& predicted, int reference) {
  const std::size_t n = predicted.observed.size();
  std::vector<std::int64_t> strength(n, 0);
  if (reference < 0) return strength;
  std::vector<std::vector<std::pair<int, std::int64_t>>> adjacent(n);
  for (const CalibrationLink& l : predicted.graph.weakest_links) {
    adjacent[l.a].push_back({l.b, l.shared});
    adjacent[l.b].push_back({l.a, l.shared});
  }
  std::vector<bool> seen(n, false);
  std::vector<int> stack = {reference};
  seen[reference] = true;
  strength[reference] = predicted.observed[reference];
  while (!stack.empty()) {
    const int a = stack.back();
    stack.pop_back();
    for (const auto& [b, shared] : adjacent[a])
      if (!seen[b]) {
        seen[b] = true;
        strength[b] = std::min(strength[a], shared);
        stack.push_back(b);
      }
  }
  return strength;
}

// The camera to hold: among those calibrated, the one sharing most poses with the others (ties:
// rig order); -1 when none.
int ChooseReference(const std::vector<std::vector<ViewCorners>>& views,
                    const std::vector<CameraCalibration>& cams) {
  std::map<int, int> pose_cameras;
  for (std::size_t c = 0; c < views.size(); ++c)
    if (cams[c].intrinsics_ok)
      for (const ViewCorners& v : views[c]) ++pose_cameras[v.pose];
  int best = -1, best_shared = -1;
  for (std::size_t c = 0; c < views.size(); ++c) {
    if (!cams[c].intrinsics_ok) continue;
    int shared = 0;
    for (const ViewCorners& v : views[c]) shared += pose_cameras[v.pose] > 1;
    if (shared > best_shared) best = static_cast<int>(c), best_shared = shared;
  }
  return best;
}

}  // namespace

void CalibrateOptions::Check() const {
  synth.Check();
  CheckBoardStudyOptions(poses, square_m, squares_x, squares_y);
  if (!(outlier_px > 0)) throw std::invalid_argument("CalibrateOptions: outlier_px must be > 0");
  if (!(bound_px > 0)) throw std::invalid_argument("CalibrateOptions: bound_px must be > 0");
  if (min_view_corners < 6 || min_views < 3)
    throw std::invalid_argument("CalibrateOptions: min_view_corners >= 6 and min_views >= 3");
}

double SpearmanCorrelation(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = std::min(x.size(), y.size());
  if (n < 3) return std::numeric_limits<double>::quiet_NaN();
  auto ranks = [n](const std::vector<double>& v) {
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
    std::vector<double> r(n);
    for (std::size_t i = 0; i < n;) {
      std::size_t j = i;
      while (j + 1 < n && v[order[j + 1]] == v[order[i]]) ++j;
      for (std::size_t k = i; k <= j; ++k) r[order[k]] = 0.5 * (i + j);
      i = j + 1;
    }
    return r;
  };
  const std::vector<double> rx = ranks(x), ry = ranks(y);
  const double mean = 0.5 * (n - 1.0);
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxy += (rx[i] - mean) * (ry[i] - mean);
    sxx += (rx[i] - mean) * (rx[i] - mean);
    syy += (ry[i] - mean) * (ry[i] - mean);
  }
  if (!(sxx > 0 && syy > 0)) return std::numeric_limits<double>::quiet_NaN();
  return sxy / std::sqrt(sxx * syy);
}

namespace {

// Each camera's intrinsics from its own views (OpenCV); fills `cams` and `camera_from_board`.
void CalibrateEachCamera(const Rig& rig, const std::vector<std::vector<ViewCorners>>& views,
                         const CalibrateOptions& o, std::vector<CameraCalibration>* cams,
                         std::vector<std::map<int, Eigen::Isometry3d>>* camera_from_board) {
  camera_from_board->assign(rig.cameras.size(), {});
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    CameraCalibration& cc = (*cams)[c];
    if (!cc.enabled) {
      cc.status = "disabled";
      continue;
    }
    if (cc.views < o.min_views) {
      cc.status = Format("too few views (%d of %d)", cc.views, o.min_views);
      continue;
    }
    const IntrinsicResult ir = CalibrateIntrinsics(cc.truth, views[c]);
    if (!ir.ok) {
      cc.status = "calibration failed" + (ir.error.empty() ? std::string() : ": " + ir.error);
      continue;
    }
    cc.intrinsics_ok = true;
    cc.opencv = cc.final = ir.intrinsics;
    cc.opencv_rms_px = ir.rms_px;
    cc.std_fx = cc.opencv_std_fx = ir.std_px[0], cc.std_fy = ir.std_px[1];
    cc.std_cx = cc.opencv_std_cx = ir.std_px[2], cc.std_cy = ir.std_px[3];
    for (std::size_t v = 0; v < views[c].size(); ++v)
      (*camera_from_board)[c][views[c][v].pose] = ir.camera_from_board[v];
  }
}

// Chains the calibrated cameras from `reference` (held at its design pose) through shared board
// poses, strongest link first, and starts every board pose from a linked camera's view of it.
void ChainCameras(const Rig& rig, int reference,
                  const std::vector<std::map<int, Eigen::Isometry3d>>& camera_from_board,
                  std::vector<CameraCalibration>* cams,
                  std::vector<Eigen::Isometry3d>* camera_from_world,
                  std::map<int, Eigen::Isometry3d>* world_from_board) {
  camera_from_world->assign(rig.cameras.size(), Eigen::Isometry3d::Identity());
  auto link = [&](int c, const Eigen::Isometry3d& cw) {
    (*cams)[c].linked = true;
    (*camera_from_world)[c] = cw;
    for (const auto& [k, cb] : camera_from_board[c])
      if (!world_from_board->count(k)) (*world_from_board)[k] = cw.inverse() * cb;
  };
  link(reference, rig.cameras[reference].camera_from_world());
  (*cams)[reference].reference = true;
  for (;;) {
    int best = -1, best_count = 0, best_pose = -1;
    for (std::size_t c = 0; c < cams->size(); ++c) {
      if (!(*cams)[c].intrinsics_ok || (*cams)[c].linked) continue;
      int count = 0, pose = -1;
      for (const auto& [k, cb] : camera_from_board[c])
        if (world_from_board->count(k)) {
          ++count;
          if (pose < 0) pose = k;
        }
      if (count > best_count) best = static_cast<int>(c), best_count = count, best_pose = pose;
    }
    if (best < 0) break;
    link(best, camera_from_board[best].at(best_pose) * world_from_board->at(best_pose).inverse());
  }
}

// Errors against the truth, Pandora's verdict per camera, and the summary checks.
void CompareWithTruth(const Rig& rig, const BoardCapture& capture,
                      const std::vector<CalibrationPose>& poses,
                      const std::map<int, Vec2>& corner_xy,
                      const std::vector<Eigen::Isometry3d>& camera_from_world, double bound_px,
                      CalibrationStudy* r) {
  std::vector<std::vector<Vec2>> footprint(rig.cameras.size());
  std::vector<double> world_sum2(rig.cameras.size(), 0);
  std::vector<int> world_n(rig.cameras.size(), 0);
  for (const BoardObservation& ob : capture.observations) {
    footprint[ob.camera].push_back(ob.truth);
    const CameraCalibration& cc = r->cameras[ob.camera];
    if (!cc.linked) continue;
    const CalibrationPose& pose = poses[ob.pose];
    const Vec2 xy = corner_xy.at(ob.id);
    const Vec3 X = BoardPoint(pose, xy);
    Vec2 uv;
    if (!ProjectWithIntrinsics(cc.final, camera_from_world[ob.camera] * X, &uv)) continue;
    world_sum2[ob.camera] += (uv - ob.truth).squaredNorm();
    ++world_n[ob.camera];
  }
  const std::vector<std::int64_t> strength = LinkStrength(
      r->predicted, r->reference >= 0 ? r->reference
                    : r->predicted.graph.largest >= 0
                        ? r->predicted.graph.components[r->predicted.graph.largest].front()
                        : -1);
  std::vector<bool> uncalibratable(rig.cameras.size(), false);
  for (int c : r->predicted.graph.uncalibratable) uncalibratable[c] = true;
  r->verdict_holds = true;
  std::vector<double> link, error;
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    CameraCalibration& cc = r->cameras[c];
    cc.predicted_observed = r->predicted.observed[c];
    cc.link_strength = strength[c];
    cc.predicted_calibratable = cc.enabled && !uncalibratable[c];
    if (!cc.enabled) continue;
    if (cc.intrinsics_ok) {
      MappingError(rig.cameras[c], cc.final, footprint[c], &cc);
      cc.map_within_bound = cc.map_rms_px <= bound_px;
    }
    cc.world_rms_px = world_n[c] ? std::sqrt(world_sum2[c] / world_n[c])
                                 : std::numeric_limits<double>::quiet_NaN();
    if (cc.linked) {
      cc.calibrated = cc.world_rms_px <= bound_px;
      cc.status =
          cc.calibrated ? "calibrated" : Format("out of bounds (world %.3g px)", cc.world_rms_px);
      const Eigen::Isometry3d truth = rig.cameras[c].camera_from_world();
      const Eigen::Isometry3d& est = camera_from_world[c];
      cc.rotation_error_deg = Eigen::AngleAxisd(est.linear() * truth.linear().transpose()).angle() *
                              kCalibrateDegPerRad;
      cc.position_error_mm =
          1e3 * (est.inverse().translation() - truth.inverse().translation()).norm();
      if (!cc.reference) {
        link.push_back(static_cast<double>(cc.link_strength));
        error.push_back(cc.position_error_mm);
      }
    } else if (cc.intrinsics_ok) {
      cc.status = "not linked to the rig";
    }
    if (cc.predicted_calibratable != cc.calibrated) r->verdict_holds = false;
  }
  r->link_error_correlation = SpearmanCorrelation(link, error);
}

}  // namespace

CalibrationStudy RunCalibrationStudy(const Scene& scene, const Rig& rig, const CalibrateOptions& o,
                                     const std::function<void(int, int)>& progress) {
  o.Check();
  const StudyClock::time_point start = StudyClock::now();
  CalibrationStudy r;
  const Fiducial board = StudyBoard(scene, rig, o, &r.spec, &r.notes);
  r.board =
      Format("%d x %d squares of %.0f mm, %s markers of %.1f mm", board.squares_x, board.squares_y,
             1e3 * board.square_m, board.dictionary.c_str(), 1e3 * board.marker_m);
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  r.predicted = SimulateCalibration(scene, rig, *caster, r.spec);
  CalibrationSpec render_spec = r.spec;
  render_spec.samples = o.poses;
  render_spec.seed = o.seed;
  std::vector<CalibrationPose> poses;
  {
    const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
    poses = SampleCalibrationPoses(scene, tester, render_spec);
  }
  BoardCaptureOptions capture_options;
  capture_options.synth = o.synth;
  capture_options.seed = o.seed;
  capture_options.outlier_px = o.outlier_px;
  capture_options.partial_views = o.partial_views;
  r.capture =
      CaptureBoard(scene, *caster, rig, board, poses, r.spec.board, capture_options, progress);

  const StudyClock::time_point calibrate_start = StudyClock::now();
  double sum2 = 0;
  for (const BoardObservation& ob : r.capture.observations)
    sum2 += (ob.found - ob.truth).squaredNorm();
  const double pooled =
      r.capture.observations.empty()
          ? 0.1
          : std::max(1e-3, std::sqrt(sum2 / (2.0 * r.capture.observations.size())));
  std::map<int, Vec2> corner_xy;
  for (const FiducialCorner& c : FiducialCorners(board)) corner_xy[c.id] = c.xy;
  const std::vector<std::vector<ViewCorners>> views =
      GroupViews(r.capture, corner_xy, rig.cameras.size(), pooled, o.min_view_corners);
  r.cameras.resize(rig.cameras.size());
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    CameraCalibration& cc = r.cameras[c];
    cc.id = rig.cameras[c].id;
    cc.enabled = rig.cameras[c].enabled;
    cc.truth = rig.cameras[c].model.intrinsics();
    cc.views = static_cast<int>(views[c].size());
    for (const ViewCorners& v : views[c]) cc.corners += static_cast<int>(v.pixels.size());
  }
  std::vector<std::map<int, Eigen::Isometry3d>> camera_from_board;
  CalibrateEachCamera(rig, views, o, &r.cameras, &camera_from_board);
  r.reference = ChooseReference(views, r.cameras);
  std::vector<Eigen::Isometry3d> camera_from_world;
  if (r.reference >= 0) {
    std::map<int, Eigen::Isometry3d> world_from_board;
    ChainCameras(rig, r.reference, camera_from_board, &r.cameras, &camera_from_world,
                 &world_from_board);
    // The adjustment over every linked camera's views.
    std::vector<BundleCamera> bundle;
    std::vector<int> bundle_index(rig.cameras.size(), -1);
    for (std::size_t c = 0; c < rig.cameras.size(); ++c)
      if (r.cameras[c].linked) {
        bundle_index[c] = static_cast<int>(bundle.size());
        bundle.push_back({r.cameras[c].truth.model,
                          r.cameras[c].opencv,
                          camera_from_world[c],
                          r.cameras[c].reference,
                          {},
                          0,
                          0});
      }
    std::vector<Eigen::Isometry3d> boards;
    std::map<int, int> board_index;
    for (const auto& [k, T] : world_from_board) {
      board_index[k] = static_cast<int>(boards.size());
      boards.push_back(T);
    }
    std::vector<BundleView> bundle_views;
    std::map<int, int> pose_users;
    for (std::size_t c = 0; c < rig.cameras.size(); ++c)
      if (r.cameras[c].linked)
        for (const ViewCorners& v : views[c]) {
          bundle_views.push_back({bundle_index[c], board_index.at(v.pose), &v});
          ++pose_users[v.pose];
        }
    const BundleResult ba = BundleAdjust(&bundle, &boards, bundle_views);
    r.ba_rms_px = ba.rms_px;
    r.ba_iterations = ba.iterations;
    r.ba_residuals = ba.residuals;
    if (!ba.converged) r.notes.push_back("The bundle adjustment stopped: " + ba.message);
    for (std::size_t c = 0; c < rig.cameras.size(); ++c)
      if (r.cameras[c].linked) {
        const BundleCamera& b = bundle[bundle_index[c]];
        r.cameras[c].final = b.intrinsics;
        r.cameras[c].std_fx = b.std_px[0], r.cameras[c].std_fy = b.std_px[1];
        r.cameras[c].std_cx = b.std_px[2], r.cameras[c].std_cy = b.std_px[3];
        r.cameras[c].rotation_sd_deg = b.rotation_sd_deg;
        r.cameras[c].position_sd_mm = b.position_sd_mm;
        camera_from_world[c] = bundle[bundle_index[c]].camera_from_world;
        for (const ViewCorners& v : views[c]) r.cameras[c].shared_views += pose_users[v.pose] > 1;
      }
  }
  CompareWithTruth(rig, r.capture, poses, corner_xy, camera_from_world, o.bound_px, &r);
  r.calibrate_seconds = std::chrono::duration<double>(StudyClock::now() - calibrate_start).count();
  r.total_seconds = std::chrono::duration<double>(StudyClock::now() - start).count();
  return r;
}

}  // namespace pandora
