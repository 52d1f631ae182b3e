#include "validation/validate.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
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
#include "validation/detect.h"
#include "validation/print.h"

namespace pandora {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}
constexpr double kValidateDegPerRad = 57.29577951308232;

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The board's square: its markers' cells about kBoardCellPixels at the median distance from the
// enabled cameras to the region's centre, through their median focal length; rounded to 5 mm.
double BoardSquare(const Scene& scene, const Rig& rig, const ValidateOptions& o, int cells) {
  if (o.square_m > 0) return o.square_m;
  std::vector<double> distance, focal;
  const Vec3 centre = scene.study.region.box.center();
  for (const Camera& c : rig.cameras)
    if (c.enabled) {
      distance.push_back((c.center() - centre).norm());
      focal.push_back(c.model.intrinsics().fx);
    }
  const double cell = kBoardCellPixels * Median(distance) / std::max(Median(focal), 1.0);
  const double square = cell * cells / 0.75;
  return std::max(0.005, 0.005 * std::round(square / 0.005));
}

// Where the sheet of fiducial `f` shows in camera `camera`: the bounding box of a 9 x 9 grid over
// the sheet's projections, padded by 8 pixels and clipped to the image (empty when none projects).
RenderView::Window SheetWindow(const Scene& scene, const Fiducial& f, const Camera& camera) {
  const double hx = 0.5 * f.SheetWidth(), hy = 0.5 * f.SheetHeight();
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  for (int i = 0; i <= 8; ++i)
    for (int j = 0; j <= 8; ++j) {
      const Vec3 X = FiducialPoint(scene, f, Vec2(-hx + hx * i / 4.0, -hy + hy * j / 4.0));
      const std::optional<Vec2> p = camera.Project(X);
      if (!p) continue;
      x0 = std::min(x0, p->x()), y0 = std::min(y0, p->y());
      x1 = std::max(x1, p->x()), y1 = std::max(y1, p->y());
    }
  RenderView::Window w;
  const int W = camera.model.width(), H = camera.model.height();
  const int ax = std::clamp(static_cast<int>(std::floor(x0 - 8)), 0, W);
  const int ay = std::clamp(static_cast<int>(std::floor(y0 - 8)), 0, H);
  const int bx = std::clamp(static_cast<int>(std::ceil(x1 + 8)), 0, W);
  const int by = std::clamp(static_cast<int>(std::ceil(y1 + 8)), 0, H);
  if (bx - ax < 8 || by - ay < 8) return w;
  w.x = ax, w.y = ay, w.width = bx - ax, w.height = by - ay;
  return w;
}

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

// Whether a neighbouring square's centre of the board corner at `xy` (pattern frame) is hidden
// from camera `c`: the corner shows, but at an occluding edge.
bool NeighbourhoodHidden(const Scene& s, const Fiducial& f, const Vec2& xy,
                         const VisibilityTester& tester, const RayCaster& caster, int c) {
  const Camera& cam = tester.cameras()[c];
  const double h = 0.5 * f.square_m;
  for (const Vec2& d : {Vec2(h, h), Vec2(-h, h), Vec2(h, -h), Vec2(-h, -h)}) {
    const Vec3 X = FiducialPoint(s, f, xy + d);
    const Vec3 to = X - cam.center();
    const double distance = to.norm();
    const double tolerance = tester.Tolerance(c, distance);
    Ray ray;
    ray.origin = cam.center();
    ray.direction = to / distance;
    ray.t_near = tolerance;
    ray.t_far = distance - tolerance;
    if (caster.Occluded(ray)) return true;
  }
  return false;
}

constexpr double kViewOutlier = 5.0;

struct Observation {
  int pose, camera, id;
  Vec2 found, truth;
  double view_sigma;  // its view's residual RMS per coordinate (0: too few to tell)
};

// One view's detections against the truth: inliers into `out`, the rest counted.
struct ViewDetections {
  std::vector<Observation> inliers;
  std::int64_t expected = 0, misdetected = 0;
  double render_s = 0, detect_s = 0;
  std::shared_ptr<SynthImage> image;
  std::vector<Vec2> found, truth;
};

ViewDetections RunView(const Scene& s, const PreparedScene& prepared, const Rig& rig, int pose,
                       int c, int fiducial, const std::map<int, Vec2>& truth,
                       const std::set<int>& near_edge, const ValidateOptions& o) {
  ViewDetections v;
  v.expected = static_cast<std::int64_t>(truth.size());
  const Fiducial& f = s.fiducials[fiducial];
  const RenderView::Window window = SheetWindow(s, f, rig.cameras[c]);
  if (window.empty()) return v;
  SynthOptions synth = o.synth;
  synth.seed = o.seed + 1 + 7919ull * static_cast<std::uint64_t>(pose) + c;
  const Clock::time_point t0 = Clock::now();
  auto image = std::make_shared<SynthImage>(RenderSynth(prepared, rig, c, synth, window));
  v.render_s = Since(t0);
  const Clock::time_point t1 = Clock::now();
  const std::vector<Detection> found =
      DetectFiducials({f}, image->grey.data(), image->width, image->height, window.x, window.y);
  v.detect_s = Since(t1);
  for (const Detection& d : found) {
    if (near_edge.count(d.id)) continue;
    const auto it = truth.find(d.id);
    if (it == truth.end() || (d.pixel - it->second).norm() > o.outlier_px) {
      ++v.misdetected;
      continue;
    }
    v.inliers.push_back({pose, c, d.id, d.pixel, it->second, 0.0});
    v.found.push_back(d.pixel - Vec2(window.x, window.y));
    v.truth.push_back(it->second - Vec2(window.x, window.y));
  }
  if (v.inliers.size() >= 6) {
    // The view's robust noise (1.4826 x the median absolute coordinate residual); a detection
    // beyond kViewOutlier of it (and 0.05 px) is a misdetection, as a pipeline's reprojection check
    // would reject it; the view's noise is the RMS of the rest.
    std::vector<double> coordinates;
    for (const Observation& ob : v.inliers) {
      coordinates.push_back(std::abs(ob.found.x() - ob.truth.x()));
      coordinates.push_back(std::abs(ob.found.y() - ob.truth.y()));
    }
    const double robust = 1.4826 * Median(coordinates);
    const double limit = std::max(kViewOutlier * robust, 0.05);
    std::vector<Observation> kept;
    for (const Observation& ob : v.inliers)
      if ((ob.found - ob.truth).norm() <= limit) kept.push_back(ob);
    v.misdetected += static_cast<std::int64_t>(v.inliers.size() - kept.size());
    v.inliers = std::move(kept);
    double sum2 = 0;
    for (const Observation& ob : v.inliers) sum2 += (ob.found - ob.truth).squaredNorm();
    const double sigma = std::sqrt(sum2 / (2.0 * v.inliers.size()));
    for (Observation& ob : v.inliers) ob.view_sigma = sigma;
  }
  v.image = std::move(image);
  return v;
}

// The validation board: a ChArUco board of options' squares, sized by BoardSquare, its margin in
// whole texels; DICT_6X6_250 when the scene prints DICT_4X4_50 markers of its own.
Fiducial ValidationBoard(const Scene& scene, const Rig& rig, const ValidateOptions& o) {
  Fiducial board;
  board.kind = Fiducial::Kind::kCharuco;
  board.name = "validation board";
  board.dictionary = "DICT_4X4_50";
  for (const Fiducial& f : scene.fiducials)
    if (f.dictionary == board.dictionary) board.dictionary = "DICT_6X6_250";
  board.squares_x = o.squares_x;
  board.squares_y = o.squares_y;
  board.square_m = BoardSquare(scene, rig, o, FindArucoDictionary(board.dictionary)->bits + 2);
  board.marker_m = 0.75 * board.square_m;
  board.margin_m = 0.5 * board.square_m;
  board.margin_m = board.MarginTexels() / board.TexelsPerMetre();
  board.thickness_m = 0.005;
  return board;
}

// The corners of fiducial `fi` each camera images, and those of them near an occluding edge (a
// neighbouring square's centre hidden: no detector finds those reliably; their detections are
// ignored).
void PoseTruth(const Scene& s, const Rig& rig, const RayCaster& caster, int fi,
               const std::map<int, Vec2>& corner_xy, std::vector<std::map<int, Vec2>>* truth,
               std::vector<std::set<int>>* near_edge) {
  truth->assign(rig.cameras.size(), {});
  near_edge->assign(rig.cameras.size(), {});
  const VisibilityTester tester(rig.cameras, caster, s.ContentBounds().diagonal());
  for (const CornerTruth& t : FiducialCornerTruth(s, rig, caster)) {
    if (t.fiducial != fi) continue;
    for (const CornerView& v : t.views) {
      if (NeighbourhoodHidden(s, s.fiducials[fi], corner_xy.at(t.id), tester, caster, v.camera))
        (*near_edge)[v.camera].insert(t.id);
      else
        (*truth)[v.camera][t.id] = v.pixel;
    }
  }
}

// Every corner seen by >= 2 cameras, triangulated from its detections (weighted by each view's own
// noise: the maximum-likelihood estimate the prediction describes), against the prediction at its
// true point: per-view noise, and one noise `sigma_px` for every camera.
std::vector<ValidatedPoint> TriangulateAndPredict(const Rig& rig,
                                                  const std::vector<Observation>& observations,
                                                  const std::vector<CalibrationPose>& poses,
                                                  const std::map<int, Vec2>& corner_xy,
                                                  double sigma_px) {
  std::vector<ValidatedPoint> out;
  if (!(sigma_px > 0)) return out;
  std::map<std::pair<int, int>, std::vector<const Observation*>> corners;
  for (const Observation& ob : observations) corners[{ob.pose, ob.id}].push_back(&ob);
  const std::vector<std::pair<std::pair<int, int>, std::vector<const Observation*>>> list(
      corners.begin(), corners.end());
  std::vector<std::optional<ValidatedPoint>> points(list.size());
  std::vector<std::vector<double>> sigmas(list.size());  // per detection used, pixels
  tbb::parallel_for(std::size_t(0), list.size(), [&](std::size_t i) {
    const auto& obs = list[i].second;
    if (obs.size() < 2) return;
    std::vector<Camera> cams;
    std::vector<Vec2> found;
    ValidatedPoint p;
    p.pose = list[i].first.first;
    p.id = list[i].first.second;
    for (const Observation* ob : obs) {
      cams.push_back(rig.cameras[ob->camera]);
      found.push_back(ob->found);
      p.cameras.push_back(ob->camera);
      sigmas[i].push_back(ob->view_sigma > 0 ? std::max(ob->view_sigma, 1e-3) : sigma_px);
    }
    const std::optional<Vec3> estimate =
        TriangulatePoint(cams, found, sigmas[i], RayMidpoint(cams, found));
    if (!estimate) return;
    p.estimate = *estimate;
    points[i] = p;
  });
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i]) continue;
    ValidatedPoint p = *points[i];
    const CalibrationPose& pose = poses[p.pose];
    const Vec2 xy = corner_xy.at(p.id);
    p.truth = pose.position + pose.orientation.col(0) * xy.x() + pose.orientation.col(1) * xy.y();
    InformationBuilder builder, one_sigma;
    std::vector<Vec3> directions;
    for (std::size_t j = 0; j < p.cameras.size(); ++j) {
      const Camera& cam = rig.cameras[p.cameras[j]];
      Mat23 A;
      if (!cam.Project(p.truth, &A)) continue;
      builder.Add(A, sigmas[i][j]);
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
  bin.median_cameras = Median(cameras);
  bin.median_angle_deg = Median(angles);
  return bin;
}

}  // namespace

void ValidateOptions::Check() const {
  synth.Check();
  if (poses < 1 || poses > 100000) throw InputError("--poses", "", "must be 1 to 100000");
  if (!(square_m >= 0 && square_m < 100)) throw InputError("--square", "", "must be >= 0 m");
  if (squares_x < 3 || squares_y < 3 || squares_x > 20 || squares_y > 20)
    throw InputError("--squares", "", "each must be 3 to 20");
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
  // The board, its print once, and its poses.
  const Fiducial board = ValidationBoard(scene, rig, o);
  r.square_m = board.square_m;
  r.board =
      Format("%d x %d squares of %.0f mm, %s markers of %.1f mm", board.squares_x, board.squares_y,
             1e3 * board.square_m, board.dictionary.c_str(), 1e3 * board.marker_m);
  const auto print = std::make_shared<const PrintedPattern>(PrintFiducial(board));

  const auto base_caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const VisibilityTester tester(rig.cameras, *base_caster, scene.ContentBounds().diagonal());
  CalibrationSpec spec;
  spec.target = CalibrationSpec::Target::kBoard;
  spec.samples = o.poses;
  spec.seed = o.seed;
  spec.board.squares_x = board.squares_x;
  spec.board.squares_y = board.squares_y;
  spec.board.square_m = board.square_m;
  spec.board.tilt_max_deg = o.tilt_max_deg;
  spec.board.min_px_per_square = o.min_px_per_square;
  const std::vector<CalibrationPose> poses = SampleCalibrationPoses(scene, tester, spec);
  if (static_cast<int>(poses.size()) < o.poses)
    r.notes.push_back(
        Format("%zu of %d board poses fit the free space of the region", poses.size(), o.poses));

  std::map<int, Vec2> corner_xy;
  for (const FiducialCorner& c : FiducialCorners(board)) corner_xy[c.id] = c.xy;
  std::vector<Observation> observations;
  std::size_t best_sample = 0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    Scene s = scene;
    Eigen::Affine3d pose = Eigen::Affine3d::Identity();
    pose.linear() = poses[k].orientation;
    pose.translation() = poses[k].position;
    const int fi = AddFiducial(&s, board, pose);
    s.materials[s.fiducials[fi].material].printed = print;
    const auto caster = MakeEmbreeRayCaster(s.AllTriangles());
    const PreparedScene prepared(s, *caster);
    std::vector<std::map<int, Vec2>> truth;
    std::vector<std::set<int>> near_edge;
    PoseTruth(s, rig, *caster, fi, corner_xy, &truth, &near_edge);
    std::vector<ViewDetections> views(rig.cameras.size());
    tbb::parallel_for(std::size_t(0), rig.cameras.size(), [&](std::size_t c) {
      // Views a calibration tool would use (the simulation's rules): the whole board in the
      // image, turned at most tilt_max_deg from facing the camera, squares >= min_px_per_square;
      // partly hidden boards too (the truth knows which corners show).
      const BoardView rule = TestBoard(tester, static_cast<int>(c), spec.board, poses[k]);
      if (rule != BoardView::kSeen && rule != BoardView::kOccluded) return;
      if (truth[c].size() >= 4)
        views[c] = RunView(s, prepared, rig, static_cast<int>(k), static_cast<int>(c), fi, truth[c],
                           near_edge[c], o);
    });
    for (std::size_t c = 0; c < views.size(); ++c) {
      ViewDetections& v = views[c];
      if (!v.image) continue;
      ++r.views;
      r.expected += v.expected;
      r.misdetected += v.misdetected;
      r.render_seconds += v.render_s;
      r.detect_seconds += v.detect_s;
      observations.insert(observations.end(), v.inliers.begin(), v.inliers.end());
      if (!v.inliers.empty() && v.inliers.front().view_sigma > 0)
        r.view_sigma.push_back(v.inliers.front().view_sigma);
      if (v.found.size() > best_sample) {
        best_sample = v.found.size();
        r.sample.pose = static_cast<int>(k);
        r.sample.camera = static_cast<int>(c);
        r.sample.image = *v.image;
        r.sample.found = v.found;
        r.sample.truth = v.truth;
      }
    }
    ++r.poses;
    if (progress) progress(static_cast<int>(k) + 1, static_cast<int>(poses.size()));
  }
  r.detected = static_cast<std::int64_t>(observations.size());

  // The detections' own noise: RMS per coordinate of their residuals.
  double sum2 = 0;
  for (const Observation& ob : observations) {
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
  for (const Observation& ob : observations)
    if (!(ob.view_sigma > 0)) small_sum2 += (ob.found - ob.truth).squaredNorm(), ++small;
  if (small >= 6) {
    r.small_view_sigma = std::sqrt(small_sum2 / (2.0 * small));
    for (Observation& ob : observations)
      if (!(ob.view_sigma > 0)) ob.view_sigma = r.small_view_sigma;
  }
  r.points = TriangulateAndPredict(rig, observations, poses, corner_xy, r.sigma_px);
  BinValidatedPoints(&r, o.min_bin);
  r.total_seconds = Since(start);
  return r;
}

}  // namespace pandora
