#include "validation/board_capture.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "analysis/geometry/visibility.h"
#include "analysis/util/error.h"
#include "render/prepared_scene.h"
#include "validation/detect.h"
#include "validation/print.h"

namespace pandora {
namespace {

using CaptureClock = std::chrono::steady_clock;
double CaptureSince(CaptureClock::time_point t) {
  return std::chrono::duration<double>(CaptureClock::now() - t).count();
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

// Whether any part of the corner at `xy`'s four neighbouring squares (pattern frame) is hidden
// from camera `c`: the corner shows, but an occluding edge crosses the squares its detector reads
// (OpenCV refines a chessboard corner from the gradients in a window over them). Tested on a 7 x 7
// grid over the squares (to 0.9 of a square from the corner: a board that enters the patient cuts
// a square anywhere, not only at its centre).
bool NeighbourhoodHidden(const Scene& s, const Fiducial& f, const Vec2& xy,
                         const VisibilityTester& tester, const RayCaster& caster, int c) {
  const Camera& cam = tester.cameras()[c];
  const double h = 0.9 * f.square_m;
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 7; ++j) {
      const Vec3 X = FiducialPoint(s, f, xy + Vec2(h * (i - 3) / 3.0, h * (j - 3) / 3.0));
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

// One view's detections against the truth: the kept ones, the rest counted.
struct ViewDetections {
  std::vector<BoardObservation> inliers;
  std::int64_t expected = 0, misdetected = 0;
  double render_s = 0, detect_s = 0;
  std::shared_ptr<SynthImage> image;
  std::vector<Vec2> found, truth;
};

// The view's robust noise (1.4826 x the median absolute coordinate residual); a detection beyond
// kViewOutlierSigmas of it (and 0.05 px) is a misdetection, as a pipeline's reprojection check
// would reject it; the view's noise is the RMS of the rest. Views of fewer than 6 are left alone.
void RejectViewOutliers(ViewDetections* v) {
  if (v->inliers.size() < 6) return;
  std::vector<double> coordinates;
  for (const BoardObservation& ob : v->inliers) {
    coordinates.push_back(std::abs(ob.found.x() - ob.truth.x()));
    coordinates.push_back(std::abs(ob.found.y() - ob.truth.y()));
  }
  const double limit = OutlierLimitPx(std::move(coordinates));
  std::vector<BoardObservation> kept;
  for (const BoardObservation& ob : v->inliers)
    if ((ob.found - ob.truth).norm() <= limit) kept.push_back(ob);
  v->misdetected += static_cast<std::int64_t>(v->inliers.size() - kept.size());
  v->inliers = std::move(kept);
  double sum2 = 0;
  for (const BoardObservation& ob : v->inliers) sum2 += (ob.found - ob.truth).squaredNorm();
  const double sigma = std::sqrt(sum2 / (2.0 * v->inliers.size()));
  for (BoardObservation& ob : v->inliers) ob.view_sigma = sigma;
}

ViewDetections RunView(const Scene& s, const PreparedScene& prepared, const Rig& rig, int pose,
                       int c, int fiducial, const std::map<int, Vec2>& truth,
                       const std::set<int>& near_edge, const BoardCaptureOptions& o) {
  ViewDetections v;
  v.expected = static_cast<std::int64_t>(truth.size());
  const Fiducial& f = s.fiducials[fiducial];
  const RenderView::Window window = SheetWindow(s, f, rig.cameras[c]);
  if (window.empty()) return v;
  SynthOptions synth = o.synth;
  synth.seed = o.seed + 1 + 7919ull * static_cast<std::uint64_t>(pose) + c;
  const CaptureClock::time_point t0 = CaptureClock::now();
  auto image = std::make_shared<SynthImage>(RenderSynth(prepared, rig, c, synth, window));
  v.render_s = CaptureSince(t0);
  const CaptureClock::time_point t1 = CaptureClock::now();
  const std::vector<Detection> found =
      DetectFiducials({f}, image->grey.data(), image->width, image->height, window.x, window.y);
  v.detect_s = CaptureSince(t1);
  for (const Detection& d : found) {
    if (near_edge.count(d.id)) continue;
    const auto it = truth.find(d.id);
    if (it == truth.end() || (d.pixel - it->second).norm() > o.outlier_px) {
      ++v.misdetected;
      continue;
    }
    v.inliers.push_back({pose, c, d.id, d.pixel, it->second, 0.0, d.window, d.shape});
    v.found.push_back(d.pixel - Vec2(window.x, window.y));
    v.truth.push_back(it->second - Vec2(window.x, window.y));
  }
  RejectViewOutliers(&v);
  v.image = std::move(image);
  return v;
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

// Adds pose `k`'s views to `r`, in camera order.
void CollectViews(int k, std::vector<ViewDetections>* views, BoardCapture* r,
                  std::size_t* best_sample) {
  for (std::size_t c = 0; c < views->size(); ++c) {
    ViewDetections& v = (*views)[c];
    if (!v.image) continue;
    ++r->views;
    r->expected += v.expected;
    r->misdetected += v.misdetected;
    r->render_seconds += v.render_s;
    r->detect_seconds += v.detect_s;
    r->observations.insert(r->observations.end(), v.inliers.begin(), v.inliers.end());
    if (!v.inliers.empty() && v.inliers.front().view_sigma > 0)
      r->view_sigma.push_back(v.inliers.front().view_sigma);
    if (v.found.size() > *best_sample) {
      *best_sample = v.found.size();
      r->sample.pose = k;
      r->sample.camera = static_cast<int>(c);
      r->sample.image = *v.image;
      r->sample.found = v.found;
      r->sample.truth = v.truth;
    }
  }
}

}  // namespace

double SampleMedian(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double OutlierLimitPx(std::vector<double> coordinates) {
  return std::max(kViewOutlierSigmas * 1.4826 * SampleMedian(std::move(coordinates)), 0.05);
}

Vec3 BoardPoint(const CalibrationPose& pose, const Vec2& xy) {
  return pose.position + pose.orientation.col(0) * xy.x() + pose.orientation.col(1) * xy.y();
}

void CheckBoardStudyOptions(int poses, double square_m, int squares_x, int squares_y) {
  if (poses < 1 || poses > 100000) throw InputError("--poses", "", "must be 1 to 100000");
  if (!(square_m >= 0 && square_m < 100)) throw InputError("--square", "", "must be >= 0 m");
  if (squares_x < 3 || squares_y < 3 || squares_x > 20 || squares_y > 20)
    throw InputError("--squares", "", "each must be 3 to 20");
}

Fiducial SizedCharucoBoard(const Scene& scene, const Rig& rig, int squares_x, int squares_y,
                           double square_m, double cell_pixels, const std::string& name) {
  Fiducial board;
  board.kind = Fiducial::Kind::kCharuco;
  board.name = name;
  board.dictionary = "DICT_4X4_50";
  for (const Fiducial& f : scene.fiducials)
    if (f.dictionary == board.dictionary) board.dictionary = "DICT_6X6_250";
  board.squares_x = squares_x;
  board.squares_y = squares_y;
  if (!(square_m > 0)) {
    std::vector<double> distance, focal;
    const Vec3 centre = scene.study.region.box.center();
    for (const Camera& c : rig.cameras)
      if (c.enabled) {
        distance.push_back((c.center() - centre).norm());
        focal.push_back(c.model.intrinsics().fx);
      }
    const int cells = FindArucoDictionary(board.dictionary)->bits + 2;
    const double cell = cell_pixels * SampleMedian(distance) / std::max(SampleMedian(focal), 1.0);
    square_m = std::max(0.005, 0.005 * std::round(cell * cells / kCharucoMarkerRatio / 0.005));
  }
  board.square_m = square_m;
  board.marker_m = kCharucoMarkerRatio * board.square_m;
  board.margin_m = 0.5 * board.square_m;
  board.margin_m = board.MarginTexels() / board.TexelsPerMetre();
  board.thickness_m = 0.005;
  return board;
}

BoardCapture CaptureBoard(const Scene& scene, const RayCaster& scene_caster, const Rig& rig,
                          const Fiducial& board, const std::vector<CalibrationPose>& poses,
                          const CalibrationBoard& rules, const BoardCaptureOptions& o,
                          const std::function<void(int, int)>& progress) {
  BoardCapture r;
  const auto print = std::make_shared<const PrintedPattern>(PrintFiducial(board));
  const VisibilityTester tester(rig.cameras, scene_caster, scene.ContentBounds().diagonal());
  std::map<int, Vec2> corner_xy;
  for (const FiducialCorner& c : FiducialCorners(board)) corner_xy[c.id] = c.xy;
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
      const BoardView rule = TestBoard(tester, static_cast<int>(c), rules, poses[k]);
      if (rule != BoardView::kSeen && !(o.partial_views && rule == BoardView::kOccluded)) return;
      if (truth[c].size() >= 4)
        views[c] = RunView(s, prepared, rig, static_cast<int>(k), static_cast<int>(c), fi, truth[c],
                           near_edge[c], o);
    });
    CollectViews(static_cast<int>(k), &views, &r, &best_sample);
    ++r.poses;
    if (progress) progress(static_cast<int>(k) + 1, static_cast<int>(poses.size()));
  }
  return r;
}

}  // namespace pandora
