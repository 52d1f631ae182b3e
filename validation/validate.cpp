#include "validation/validate.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>

#include "analysis/geometry/triangulation.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/rig/calibration.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "render/prepared_scene.h"
#include "validation/board_capture.h"

namespace pandora {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}
constexpr double kValidateDegPerRad = 57.29577951308232;

// The point nearest (least squares) to the cameras' rays through `pixels`: the start of the
// nonlinear triangulation, as a user's pipeline would make it (no truth involved).
Vec3 RayMidpoint(const std::vector<Camera>& cameras, const std::vector<Vec2>& pixels) {
  Mat3 A = Mat3::Zero();
  Vec3 b = Vec3::Zero();
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const std::optional<Vec3> d = cameras[i].model.Unproject(pixels[i]);
    if (!d) continue;
    const Vec3 dw = cameras[i].world_from_camera.linear() * *d;
    const Mat3 P = Mat3::Identity() - dw * dw.transpose();
    A += P;
    b += P * cameras[i].center();
  }
  return A.ldlt().solve(b);
}

// The maximum-likelihood point for detections `pixels` with whitening matrices `whiten` (each
// W^T W = the detection's inverse covariance): Gauss-Newton on sum |W (Project(X) - pixel)|^2
// from `initial`, steps halved while they do not lower the cost; nullopt when a camera cannot
// project the start.
std::optional<Vec3> TriangulateWhitened(const std::vector<Camera>& cameras,
                                        const std::vector<Vec2>& pixels,
                                        const std::vector<Eigen::Matrix2d>& whiten,
                                        const Vec3& initial) {
  auto cost = [&](const Vec3& X, Mat3* H, Vec3* g) {
    double c = 0;
    if (H) H->setZero(), g->setZero();
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      Mat23 A;
      const std::optional<Vec2> p = cameras[i].Project(X, H ? &A : nullptr);
      if (!p) return std::numeric_limits<double>::infinity();
      const Vec2 r = whiten[i] * (*p - pixels[i]);
      c += r.squaredNorm();
      if (H) {
        const Mat23 WA = whiten[i] * A;
        *H += WA.transpose() * WA;
        *g += WA.transpose() * r;
      }
    }
    return c;
  };
  Vec3 X = initial;
  Mat3 H;
  Vec3 g;
  double c = cost(X, &H, &g);
  if (!std::isfinite(c)) return std::nullopt;
  for (int iteration = 0; iteration < 50; ++iteration) {
    Vec3 step = -H.ldlt().solve(g);
    double next = c;
    for (int halving = 0; halving < 30; ++halving, step *= 0.5) {
      next = cost(X + step, nullptr, nullptr);
      if (next <= c) break;
    }
    if (!(next <= c)) break;
    X += step;
    const bool converged = step.norm() < 1e-12 * std::max(1.0, X.norm()) || c - next < 1e-15 * c;
    c = cost(X, &H, &g);
    if (converged) break;
  }
  return X;
}

// Every corner seen by >= 2 cameras, triangulated from its detections (weighted by each view's own
// noise: the maximum-likelihood estimate the prediction describes), against the prediction at its
// true point: per-view noise, and one noise `sigma_px` for every camera.
std::vector<ValidatedPoint> TriangulateAndPredict(const Rig& rig,
                                                  const std::vector<BoardObservation>& observations,
                                                  const std::vector<CalibrationPose>& poses,
                                                  const std::map<int, Vec2>& corner_xy,
                                                  double sigma_px) {
  std::vector<ValidatedPoint> out;
  if (!(sigma_px > 0)) return out;
  std::map<std::pair<int, int>, std::vector<const BoardObservation*>> corners;
  for (const BoardObservation& ob : observations) corners[{ob.pose, ob.id}].push_back(&ob);
  const std::vector<std::pair<std::pair<int, int>, std::vector<const BoardObservation*>>> list(
      corners.begin(), corners.end());
  std::vector<std::optional<ValidatedPoint>> points(list.size());
  // Per detection used, the square root of its inverse covariance (sigma^2 x shape): W^T W =
  // Sigma^-1, so that W r is the whitened residual.
  std::vector<std::vector<Eigen::Matrix2d>> whiten(list.size());
  tbb::parallel_for(std::size_t(0), list.size(), [&](std::size_t i) {
    const auto& obs = list[i].second;
    if (obs.size() < 2) return;
    std::vector<Camera> cams;
    std::vector<Vec2> found;
    ValidatedPoint p;
    p.pose = list[i].first.first;
    p.id = list[i].first.second;
    for (const BoardObservation* ob : obs) {
      cams.push_back(rig.cameras[ob->camera]);
      found.push_back(ob->found);
      p.cameras.push_back(ob->camera);
      const double sigma = ob->view_sigma > 0 ? std::max(ob->view_sigma, 1e-3) : sigma_px;
      const Eigen::Matrix2d information = (sigma * sigma * ob->shape).inverse();
      whiten[i].push_back(Eigen::LLT<Eigen::Matrix2d>(information).matrixU());
    }
    const std::optional<Vec3> estimate =
        TriangulateWhitened(cams, found, whiten[i], RayMidpoint(cams, found));
    if (!estimate) return;
    p.estimate = *estimate;
    points[i] = p;
  });
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i]) continue;
    ValidatedPoint p = *points[i];
    const CalibrationPose& pose = poses[p.pose];
    const Vec2 xy = corner_xy.at(p.id);
    p.truth = BoardPoint(pose, xy);
    InformationBuilder builder, one_sigma;
    std::vector<Vec3> directions;
    for (std::size_t j = 0; j < p.cameras.size(); ++j) {
      const Camera& cam = rig.cameras[p.cameras[j]];
      Mat23 A;
      if (!cam.Project(p.truth, &A)) continue;
      builder.Add(whiten[i][j] * A, 1.0);
      one_sigma.Add(A, sigma_px);
      directions.push_back((p.truth - cam.center()).normalized());
    }
    const Information info = builder.Decompose(), info_one = one_sigma.Decompose();
    if (!info.observable || !info_one.observable) continue;
    const Vec3 e = p.estimate - p.truth;
    for (int a = 0; a < 3; ++a) {
      p.variances[a] = 1.0 / info.eigenvalues[a];  // J ascending: covariance descending
      p.axes.col(a) = info.eigenvectors.col(a);
      p.whitened[a] = e.dot(p.axes.col(a)) / std::sqrt(p.variances[a]);
      p.whitened_one_sigma[a] =
          e.dot(info_one.eigenvectors.col(a)) * std::sqrt(info_one.eigenvalues[a]);
    }
    p.angle_deg = MaxTriangulationAngle(directions) * kValidateDegPerRad;
    out.push_back(std::move(p));
  }
  return out;
}

double Skewness(const std::vector<double>& v) {
  const double n = static_cast<double>(v.size());
  if (n < 3) return 0;
  double mean = 0;
  for (double x : v) mean += x;
  mean /= n;
  double m2 = 0, m3 = 0;
  for (double x : v) {
    m2 += (x - mean) * (x - mean);
    m3 += (x - mean) * (x - mean) * (x - mean);
  }
  m2 /= n;
  m3 /= n;
  return m2 > 0 ? m3 / std::pow(m2, 1.5) : 0;
}

ValidateBin MakeBin(const std::vector<const ValidatedPoint*>& points, std::string label) {
  ValidateBin bin;
  bin.label = std::move(label);
  bin.points = static_cast<int>(points.size());
  if (points.empty()) return bin;
  Vec3 sum2 = Vec3::Zero(), sum2_one = Vec3::Zero(), measured = Vec3::Zero(),
       predicted = Vec3::Zero();
  std::vector<double> major, cameras, angles;
  for (const ValidatedPoint* p : points) {
    sum2 += p->whitened.cwiseProduct(p->whitened);
    sum2_one += p->whitened_one_sigma.cwiseProduct(p->whitened_one_sigma);
    for (int a = 0; a < 3; ++a) {
      const double along = (p->estimate - p->truth).dot(p->axes.col(a));
      measured[a] += along * along;
      predicted[a] += p->variances[a];
    }
    major.push_back(p->whitened[0]);
    cameras.push_back(static_cast<double>(p->cameras.size()));
    angles.push_back(p->angle_deg);
  }
  const double n = static_cast<double>(points.size());
  bin.ratio = (sum2 / n).cwiseSqrt();
  bin.ratio_one_sigma = (sum2_one / n).cwiseSqrt();
  bin.measured_mm = 1e3 * (measured / n).cwiseSqrt();
  bin.predicted_mm = 1e3 * (predicted / n).cwiseSqrt();
  bin.skew_major = Skewness(major);
  bin.median_cameras = SampleMedian(cameras);
  bin.median_angle_deg = SampleMedian(angles);
  return bin;
}

// A detection's squared residual in units of its covariance shape: r^T S^-1 r.
double Mahalanobis2(const BoardObservation& ob) {
  const Vec2 r = ob.found - ob.truth;
  return r.dot(ob.shape.ldlt().solve(r));
}

// The per-corner noise model. Each detector window size w has a robust noise (1.4826 x the median
// absolute coordinate residual of its detections); a detection in a view of fewer than 6 (which
// the view's own 5-sigma rule cannot check) beyond OutlierLimitPx of its window size's residuals is
// a misdetection, as a pipeline's reprojection check would reject it. f(w), the RMS of the rest in
// units of each detection's covariance shape (Detection::shape), is each window size's noise; a
// view of >= 6 detections scales it to its own residuals (alpha_v^2 = sum r^2 / (2 sum f^2)), the
// small views together to theirs. Detections without a window keep their view's noise. Every noise
// goes into view_sigma (the prediction's input: the detection's covariance is view_sigma^2 x
// shape).
void CornerNoise(std::vector<BoardObservation>* observations, ValidateResult* r) {
  std::map<int, std::vector<double>> coordinates;
  for (const BoardObservation& ob : *observations)
    if (ob.window > 0) {
      coordinates[ob.window].push_back(std::abs(ob.found.x() - ob.truth.x()));
      coordinates[ob.window].push_back(std::abs(ob.found.y() - ob.truth.y()));
    }
  std::map<int, double> limit;
  for (auto& [window, v] : coordinates) limit[window] = OutlierLimitPx(std::move(v));
  std::vector<BoardObservation> kept;
  for (const BoardObservation& ob : *observations)
    if (ob.window > 0 && !(ob.view_sigma > 0) && (ob.found - ob.truth).norm() > limit[ob.window])
      ++r->misdetected;
    else
      kept.push_back(ob);
  *observations = std::move(kept);
  std::map<int, std::pair<double, std::int64_t>> by_window;  // sum r^T S^-1 r, count
  for (const BoardObservation& ob : *observations)
    if (ob.window > 0) {
      auto& w = by_window[ob.window];
      w.first += Mahalanobis2(ob), ++w.second;
    }
  r->window_sigma.clear();
  for (const auto& [window, sums] : by_window)
    r->window_sigma[window] = std::sqrt(sums.first / (2.0 * sums.second));
  std::map<std::pair<int, int>, std::pair<double, double>> view_sums;  // r^2 and f^2 sums
  double small_r2 = 0, small_f2 = 0;
  for (const BoardObservation& ob : *observations) {
    if (ob.window <= 0) continue;
    const double r2 = Mahalanobis2(ob);
    const double f = r->window_sigma.at(ob.window);
    if (ob.view_sigma > 0) {
      auto& sums = view_sums[{ob.pose, ob.camera}];
      sums.first += r2, sums.second += 2 * f * f;
    } else {
      small_r2 += r2, small_f2 += 2 * f * f;
    }
  }
  r->corner_noise_scale = small_f2 > 0 ? std::sqrt(small_r2 / small_f2) : 0;
  for (BoardObservation& ob : *observations) {
    if (ob.window <= 0) continue;
    double scale = r->corner_noise_scale;
    if (ob.view_sigma > 0) {
      const auto& sums = view_sums[{ob.pose, ob.camera}];
      scale = std::sqrt(sums.first / sums.second);
    }
    if (scale > 0) ob.view_sigma = std::max(scale * r->window_sigma.at(ob.window), 1e-3);
  }
}

}  // namespace

void ValidateOptions::Check() const {
  synth.Check();
  CheckBoardStudyOptions(poses, square_m, squares_x, squares_y);
  if (!(outlier_px > 0)) throw InputError("--outlier", "", "must be a positive number of pixels");
  if (min_bin < 2) throw InputError("--min-bin", "", "must be at least 2");
}

void BinValidatedPoints(ValidateResult* r, int min_bin) {
  std::vector<const ValidatedPoint*> all;
  for (const ValidatedPoint& p : r->points) all.push_back(&p);
  r->all = MakeBin(all, "all");
  std::sort(all.begin(), all.end(), [](const ValidatedPoint* a, const ValidatedPoint* b) {
    return a->sigma_max() < b->sigma_max();
  });
  r->sigma_bins.clear();
  const int bins = std::min<int>(6, static_cast<int>(all.size()) / min_bin);
  for (int b = 0; b < bins; ++b) {
    const std::size_t lo = all.size() * b / bins, hi = all.size() * (b + 1) / bins;
    std::vector<const ValidatedPoint*> part(all.begin() + lo, all.begin() + hi);
    r->sigma_bins.push_back(MakeBin(part, Format("%.3g-%.3g mm", 1e3 * part.front()->sigma_max(),
                                                 1e3 * part.back()->sigma_max())));
  }
  r->angle_bins.clear();
  const double edges[] = {0, 5, 10, 20, 45, 180.0001};
  for (int b = 0; b + 1 < 6; ++b) {
    std::vector<const ValidatedPoint*> part;
    for (const ValidatedPoint* p : all)
      if (p->angle_deg >= edges[b] && p->angle_deg < edges[b + 1]) part.push_back(p);
    if (part.size() >= 2)
      r->angle_bins.push_back(
          MakeBin(part, Format("%.0f-%.0f deg", edges[b], std::min(180.0, edges[b + 1]))));
  }
}

ValidateResult RunValidation(const Scene& scene, const Rig& rig, const ValidateOptions& o,
                             const std::function<void(int, int)>& progress) {
  o.Check();
  const Clock::time_point start = Clock::now();
  ValidateResult r;
  // The board and its poses.
  const Fiducial board = SizedCharucoBoard(scene, rig, o.squares_x, o.squares_y, o.square_m,
                                           kBoardCellPixels, "validation board");
  r.square_m = board.square_m;
  r.board =
      Format("%d x %d squares of %.0f mm, %s markers of %.1f mm", board.squares_x, board.squares_y,
             1e3 * board.square_m, board.dictionary.c_str(), 1e3 * board.marker_m);
  CalibrationSpec spec;
  spec.target = CalibrationSpec::Target::kBoard;
  spec.samples = o.poses;
  spec.seed = o.seed;
  spec.board.squares_x = board.squares_x;
  spec.board.squares_y = board.squares_y;
  spec.board.square_m = board.square_m;
  spec.board.tilt_max_deg = o.tilt_max_deg;
  spec.board.min_px_per_square = o.min_px_per_square;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  std::vector<CalibrationPose> poses;
  {
    const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
    poses = SampleCalibrationPoses(scene, tester, spec);
  }
  if (static_cast<int>(poses.size()) < o.poses)
    r.notes.push_back(
        Format("%zu of %d board poses fit the free space of the region", poses.size(), o.poses));
  std::map<int, Vec2> corner_xy;
  for (const FiducialCorner& c : FiducialCorners(board)) corner_xy[c.id] = c.xy;

  BoardCaptureOptions capture_options;
  capture_options.synth = o.synth;
  capture_options.seed = o.seed;
  capture_options.outlier_px = o.outlier_px;
  BoardCapture capture =
      CaptureBoard(scene, *caster, rig, board, poses, spec.board, capture_options, progress);
  std::vector<BoardObservation>& observations = capture.observations;
  r.poses = capture.poses;
  r.views = capture.views;
  r.expected = capture.expected;
  r.misdetected = capture.misdetected;
  r.render_seconds = capture.render_seconds;
  r.detect_seconds = capture.detect_seconds;
  r.view_sigma = capture.view_sigma;
  r.sample = std::move(capture.sample);
  if (o.noise_model == ValidateOptions::NoiseModel::kCorner)
    CornerNoise(&observations, &r);
  else
    for (BoardObservation& ob : observations) ob.shape = Eigen::Matrix2d::Identity();
  r.detected = static_cast<std::int64_t>(observations.size());

  // The detections' own noise: RMS per coordinate of their residuals.
  double sum2 = 0;
  for (const BoardObservation& ob : observations) {
    sum2 += (ob.found - ob.truth).squaredNorm();
    r.mean_residual += ob.found - ob.truth;
  }
  if (!observations.empty()) {
    r.sigma_px = std::sqrt(sum2 / (2.0 * observations.size()));
    r.mean_residual /= static_cast<double>(observations.size());
  }

  // Views of fewer than 6 corners cannot tell their own noise: they share the RMS of theirs
  // pooled (mostly partly hidden or small boards, noisier than the rest).
  double small_sum2 = 0;
  std::size_t small = 0;
  for (const BoardObservation& ob : observations)
    if (!(ob.view_sigma > 0)) small_sum2 += (ob.found - ob.truth).squaredNorm(), ++small;
  if (small >= 6) {
    r.small_view_sigma = std::sqrt(small_sum2 / (2.0 * small));
    for (BoardObservation& ob : observations)
      if (!(ob.view_sigma > 0)) ob.view_sigma = r.small_view_sigma;
  }
  r.points = TriangulateAndPredict(rig, observations, poses, corner_xy, r.sigma_px);
  r.observations = observations;
  BinValidatedPoints(&r, o.min_bin);
  r.total_seconds = Since(start);
  return r;
}

}  // namespace pandora
