// Suggest() (suggest/suggest.h): the orchestration of one suggestion, and its exact stages: the
// screening across the whole limits and the levelling of the best poses. The Ceres nudge between
// them is suggest_ceres.cpp's (suggest/suggest_run.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "analysis/geometry/pose.h"
#include "analysis/util/units.h"
#include "suggest/suggest.h"
#include "suggest/suggest_internal.h"
#include "suggest/suggest_run.h"

namespace pandora {
namespace suggest_detail {

// Uniform in the ball of `radius` (in units of the limits) around `centre`, per part, projected
// onto the limits.
std::vector<double> SuggestRun::Sample(const PoseChart& chart, const std::vector<double>& centre,
                                       double radius) {
  std::vector<double> xs = centre;
  auto ball = [&](int from, int n) {
    if (n == 0) return;
    std::vector<double> u(n);
    double r2;
    do {
      r2 = 0;
      for (int i = 0; i < n; ++i) {
        u[i] = uniform(rng);
        r2 += u[i] * u[i];
      }
    } while (r2 > 1.0);
    for (int i = 0; i < n; ++i) xs[from + i] += radius * u[i];
  };
  ball(0, chart.dims_t);
  ball(chart.dims_t, chart.dims_r);
  if (chart.dims_f > 0) xs[chart.dims_t + chart.dims_r] += radius * uniform(rng);
  chart.Project(xs.data());
  return xs;
}

// Tries moving the cameras in `group` to `xs` (indexed by selected camera); keeps it if better.
void SuggestRun::TryMove(const std::vector<int>& group, std::vector<std::vector<double>>& xs) {
  for (int c : group)
    if (!placement.Admissible(c, charts[c].Pose(xs[c].data()).translation())) return;  // free
  std::vector<CameraView> v(nsel);
  for (int c : group) {
    v[c] = ev.View(c, charts[c].Pose(xs[c].data()), charts[c].FocalScale(xs[c].data()));
    ptrs[c] = &v[c];
  }
  const Metrics m = ev.Combine(ptrs, /*objective_only=*/true);
  for (int c : group) ptrs[c] = &cur_view[c];
  const double score = ev.Score(m);
  if (!(score > cur_score)) return;
  cur_score = score;
  for (int c : group) {
    cur_x[c] = std::move(xs[c]);
    cur_view[c] = std::move(v[c]);
  }
  if (score > best_score) {
    best_score = score;
    s.trace.push_back({Elapsed(), ev.evaluations() + SurrogateEvaluations(surrogate), m.objective});
  }
}

// One screening chain from the current poses: single-camera moves within each radius, then joint
// moves of all movable cameras.
void SuggestRun::ScreenChain(int candidates, int joint_candidates) {
  constexpr double kJointRadius = 0.15;
  cur_x = x;  // the current poses
  for (std::size_t c = 0; c < nsel; ++c) {
    cur_view[c] = ev.View(static_cast<int>(c), start[c]);
    ptrs[c] = &cur_view[c];
  }
  cur_score = start_score;
  for (double radius : {1.0, 0.4, 0.15})
    for (int c : movable)
      for (int k = 0; k < candidates; ++k) {
        if (Stopped()) return;
        std::vector<std::vector<double>> xs = cur_x;
        xs[c] = Sample(charts[c], cur_x[c], radius);
        TryMove({c}, xs);
      }
  for (int k = 0; k < joint_candidates; ++k) {
    if (Stopped()) return;
    std::vector<std::vector<double>> xs = cur_x;
    for (int c : movable) xs[c] = Sample(charts[c], cur_x[c], kJointRadius);
    TryMove(movable, xs);
  }
}

// Screening (exact), before the Ceres nudge: look across the whole limits for a better start. The
// smooth surrogate sees occluders only through a local linearisation, so from the current poses
// it cannot cross the medics' occlusion shadows; exact jumps can, and they are cheap. A chain
// moves one active camera at a time: a candidate pose is tested once against the target points (a
// CameraView, one visibility test per point) and combined with the other cameras' cached views,
// which is one exact evaluation of the objective at a joint pose; a better one is kept at once.
// Each camera gets `screening_candidates` candidates uniform in the ball of radius 1 (the whole
// limits) around its best pose, then as many within 0.4 and within 0.15; last, joint moves of all
// movable cameras within 0.15 (some points are gained only when two selected cameras move
// together). Three independent chains from the current poses; the best end is polished below.
// Deterministic (fixed seed).
void SuggestRun::Screen() {
  cur_view.resize(nsel);
  ptrs.resize(nsel);
  constexpr int kChains = 3;
  // Coverage (and its N-1 form) is judged from counts alone; the other objectives need every
  // point's covariance or density at each evaluation (about 2x the cost, and a slower polish), or
  // for calibration a test of every calibration pose per candidate, so they get a quarter of the
  // candidates (sigma-p90 on the trauma room: 3.2 s with all, 0.8 s with a quarter).
  const int candidates = options.objective.kind == ObjectiveKind::kCoverage ||
                                 options.objective.kind == ObjectiveKind::kCoverageN1
                             ? options.screening_candidates
                             : std::max(1, options.screening_candidates / 4);
  // Every movable camera is screened, also one without a gradient at the start (it sees no target
  // point, e.g. a camera turned away whose calibration links are what is asked): exact jumps
  // need no gradient.
  const int joint_candidates = movable.size() > 1 ? candidates * 3 / 4 : 0;
  std::vector<CameraView> screened_view;
  for (int chain = 0; chain < kChains && !Stopped(); ++chain) {
    ScreenChain(candidates, joint_candidates);
    if (cur_score > screened_score && cur_score > start_score) {
      screened_score = cur_score;
      screened_x = cur_x;
      screened_view = cur_view;
    }
    Progress(kScreeningShare * (chain + 1) / kChains);
  }
  if (!screened_x.empty()) {
    for (std::size_t c = 0; c < nsel; ++c) ptrs[c] = &screened_view[c];
    best_m = ev.Summary(ptrs);  // the full metrics of the best pose found (already counted)
    best_score = screened_score;
    best_x = screened_x;
  }
  s.screened = static_cast<int>(ev.evaluations());
  s.screened_objective = best_m.objective;
  s.trace.push_back(
      {Elapsed(), ev.evaluations() + SurrogateEvaluations(surrogate), best_m.objective});
}

// orientations with the same optical axis and within +-1 degree of it in yaw and pitch (25,
// judged exactly); the best is taken when it is no worse than the rolled pose.
void SuggestRun::LevelPoses(std::vector<Eigen::Isometry3d>& best_poses,
                            const std::vector<double>& best_scales) {
  for (std::size_t c = 0; c < nsel; ++c) {
    const Mat3& R0 = start[c].linear();
    const Mat3 R = best_poses[c].linear();
    if (std::abs(R0(2, 0)) > 1e-9 || std::abs(R(2, 0)) <= 1e-12) continue;
    const Vec3 ypr = YawPitchRollDeg(R);
    if (std::abs(ypr.y()) > 89.0) continue;  // looking straight up or down: no horizon
    const double limit = charts[c].max_rotate * 180.0 / kPi * (1 + 1e-9);
    // Yaw and pitch of the optical axis (the Euler angles with the roll taken out).
    const Vec3 axis = R.col(2);
    const double yaw = std::atan2(axis.y(), axis.x()) * 180.0 / kPi;
    const double pitch = std::asin(std::clamp(axis.z(), -1.0, 1.0)) * 180.0 / kPi;
    std::vector<Eigen::Isometry3d> best_trial;
    Metrics best_level;
    double best_level_score = -kInf;
    for (double dy : {0.0, -0.5, 0.5, -1.0, 1.0})
      for (double dp : {0.0, -0.5, 0.5, -1.0, 1.0}) {
        const Mat3 L = RotationFromYawPitchRollDeg(Vec3(yaw + dy, pitch + dp, 0.0));
        if (RotationAngleDeg(R0, L) > limit) continue;
        std::vector<Eigen::Isometry3d> trial = best_poses;
        trial[c].linear() = L;
        const Metrics m = ev.Evaluate(trial, best_scales);
        if (ev.Score(m) > best_level_score) {
          best_level_score = ev.Score(m);
          best_level = m;
          best_trial = trial;
        }
      }
    if (!best_trial.empty() && best_level_score >= best_score) {
      best_poses = best_trial;
      best_m = best_level;
      best_score = best_level_score;
    }
  }
}

}  // namespace suggest_detail

namespace {

std::string Num(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

}  // namespace

Suggestion Suggest(const Scene& scene, const Rig& rig, const RayCaster& caster,
                   const std::vector<TargetPoint>& targets, const SuggestOptions& options) {
  using namespace suggest_detail;
  options.Check(scene, rig);
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t nsel = options.cameras.size();
  ExactEvaluator ev(scene, rig, caster, targets, options.objective, options.cameras,
                    options.sample_casters);
  const Placement placement(scene, rig, options);
  SearchStart begin = BeginSearch(rig, options, static_cast<int>(targets.size()), ev);
  const std::vector<PoseChart>& charts = begin.charts;
  const std::vector<Eigen::Isometry3d>& start = begin.start;
  Suggestion& s = begin.suggestion;
  s.after = s.before;
  FillChanges(rig, options, start, {}, placement, &s);
  const double start_score = ev.Score(s.before);
  const std::string name = ObjectiveName(options.objective);

  // Parameters (scaled so that +-1 is the limit), all starting at the start pose.
  std::vector<std::vector<double>> x(nsel), best_x(nsel);
  for (std::size_t c = 0; c < nsel; ++c) x[c].assign(charts[c].dims(), 0.0);
  best_x = x;
  Metrics best_m = s.before;
  double best_score = start_score;
  s.trace.push_back({SecondsSince(t0), ev.evaluations(), best_m.objective});

  const bool need_info = options.objective.kind == ObjectiveKind::kSigmaMean ||
                         options.objective.kind == ObjectiveKind::kSigmaPercentile ||
                         options.objective.kind == ObjectiveKind::kMix;
  const auto surrogate = MakeSurrogate(ev, need_info);
  SuggestRun run(options, ev, placement, charts, start, s, *surrogate, t0, start_score, x, best_x,
                 best_m, best_score);

  for (std::size_t c = 0; c < nsel; ++c)
    if (charts[c].dims() > 0) run.movable.push_back(static_cast<int>(c));
  if (run.movable.empty())
    return run.Finish(
        "the limits are zero: every selected camera keeps its pose; nothing to suggest");

  run.FindActive();
  const std::string no_gradient =
      "no improvement found: no selected camera sees any target point, so the smooth objective has "
      "no gradient; aim the cameras at the region first";
  if (run.active.empty() && options.screening_candidates <= 0) return run.Finish(no_gradient);
  const bool start_without_gradient = run.active.empty();

  if (options.screening_candidates > 0) run.Screen();
  run.Polish();
  run.Progress(1.0);

  std::vector<Eigen::Isometry3d> best_poses = start;
  std::vector<double> best_scales(nsel, 1.0);
  for (std::size_t c = 0; c < nsel; ++c) {
    best_poses[c] = charts[c].Pose(best_x[c].data());
    best_scales[c] = charts[c].FocalScale(best_x[c].data());
  }
  s.stopped = run.Stopped();
  if (best_score > start_score && !s.stopped) run.LevelPoses(best_poses, best_scales);
  if (options.snap_move > 0 || options.snap_rotate_deg > 0) {
    if (best_score > start_score) {
      s.unsnapped = best_m;
      best_poses = SnapPoses(charts, best_poses, options, placement);
      best_m = ev.Evaluate(best_poses, best_scales);
      best_score = ev.Score(best_m);
    }
  }
  s.improved = best_score > start_score;
  const bool higher = ObjectiveHigherIsBetter(options.objective);
  if (s.improved) {
    s.after = best_m;
    FillChanges(rig, options, best_poses, best_scales, placement, &s);
    for (CameraChange& c : s.cameras)
      if (c.move_m > 0 || c.rotate_deg > 0 || c.focal_scale != 1.0) c.note.clear();
    std::string extra;
    if (std::isinf(s.after.objective))
      extra = "; the percentile still falls on an untriangulable point, whose share fell from " +
              Num("%.4g", s.before.untriangulable) + " to " + Num("%.4g", s.after.untriangulable);
    return run.Finish(std::string(s.stopped ? "stopped early; " : "") + name + " improved from " +
                      Num("%.6g", s.before.objective) + " to " + Num("%.6g", s.after.objective) +
                      (higher ? " (higher is better)" : " (lower is better)") + extra);
  }
  if (s.unsnapped)
    return run.Finish("no improvement found: the optimum improved " + name + " to " +
                      Num("%.6g", s.unsnapped->objective) +
                      " but the snapped poses do not; use finer snap steps");
  if (s.stopped) return run.Finish("stopped early: no improvement found yet");
  if (start_without_gradient) return run.Finish(no_gradient);
  return run.Finish("no improvement found: the exact " + name +
                    " did not improve within the limits (it stays " +
                    Num("%.6g", s.before.objective) + ")");
}

}  // namespace pandora
