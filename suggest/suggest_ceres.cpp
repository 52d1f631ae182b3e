// The Ceres nudge (issue 5): a smooth surrogate of the objective over the selected cameras' pose
// parameters, minimised with Levenberg-Marquardt under bounds; occlusion re-evaluated between outer
// iterations; every accepted step judged by the exact evaluation. The only translation unit of
// suggest/ that includes Ceres for this.
#include <ceres/ceres.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>

#include "analysis/geometry/visibility.h"
#include "analysis/util/units.h"
#include "suggest/suggest.h"
#include "suggest/suggest_internal.h"
#include "suggest/suggest_run.h"

namespace pandora::suggest_detail {
namespace {

constexpr double kPenalty = 10.0;    // weight of the limit and keep-out penalties (cost ~ 1)
constexpr double kStep = 1e-4;       // central-difference step, in units of the limits
constexpr double kCountWidth = 0.4;  // soft ">= k": width of the sigmoid in cameras
constexpr double kIncidenceWidth = 0.1;
// Soft image border: margin and width as a fraction of the image width, halved at each of the first
// outer iterations (0.04, 0.02, then 0.01: about 41, 20, 10 px on a 1024 px image).
constexpr double kBorderWidth = 0.04;
// Occlusion slopes from centres moved by this fraction of the largest move.
constexpr double kOcclusionDelta = 0.25;

double Sigmoid(double z) {
  if (z >= 0) return 1.0 / (1.0 + std::exp(-z));
  const double e = std::exp(z);
  return e / (1.0 + e);
}

// A smooth clamp of v to [0, 1] (softplus differences, width 0.25), exactly 0 at 0 and 1 at 1.
double SoftClamp01(double v) {
  constexpr double kWidth = 0.25;
  auto softplus = [](double z) {
    const double a = z / kWidth;
    return kWidth * (a > 30 ? a : std::log1p(std::exp(a)));
  };
  const double s0 = softplus(0.0) - softplus(-1.0);
  const double r = (softplus(v) - softplus(v - 1.0) - s0) / (1.0 - 2.0 * s0);
  return std::clamp(r, 0.0, 1.0);
}

// Per selected camera and target point: the smooth visibility weight and what the camera adds.
struct Contribution {
  std::vector<double> w;   // soft visibility in [0, 1] (times the occlusion indicator)
  std::vector<double> d;   // pixel density, px/m
  std::vector<Mat3> info;  // A^T A / sigma^2 (only for the sigma term)
};

}  // namespace

// The surrogate objective: residuals over the target points for each active term, given the
// selected cameras' contributions.
class Surrogate {
 public:
  Surrogate(const ExactEvaluator& ev, bool need_info) : ev_(ev), need_info_(need_info) {
    const Objective& o = ev.objective();
    switch (o.kind) {
      case ObjectiveKind::kCoverage:
        weights_ = {1, 0, 0};
        break;
      case ObjectiveKind::kSigmaMean:
      case ObjectiveKind::kSigmaPercentile:
        weights_ = {0, 1, 0};
        break;
      case ObjectiveKind::kResolution:
        weights_ = {0, 0, 1};
        break;
      case ObjectiveKind::kMix:
        weights_ = {o.w_coverage, o.w_sigma, o.w_resolution};
        break;
      // N-1 has no smooth form of its own: a point seen by k + 1 cameras survives any one failure,
      // so the nudge pushes towards k + 1 (every step is judged by the exact N-1 share).
      case ObjectiveKind::kCoverageN1:
        weights_ = {1, 0, 0};
        k_ = o.k + 1;
        break;
      // Calibration: more target points seen by >= 2 cameras means more shared calibration poses;
      // the screening's exact jumps and the judge of every step do the rest.
      case ObjectiveKind::kCalibration:
        weights_ = {1, 0, 0};
        k_ = 2;
        break;
    }
    if (o.kind != ObjectiveKind::kCoverageN1 && o.kind != ObjectiveKind::kCalibration) k_ = o.k;
    for (int t = 0; t < 3; ++t)
      if (weights_[t] > 0) terms_.push_back(t);
    occlusion_.resize(ev.selected_cameras().size());
    scale_.assign(3, 1.0);
  }

  int rows() const { return static_cast<int>(terms_.size() * ev_.targets().size()); }
  void set_border_width(double fraction) { border_fraction_ = fraction; }

  // Occlusion of the segments from camera c at `pose` to every target point, linearised in the
  // camera centre: the exact indicator at the centre plus a central-difference slope from the
  // centres moved by +-delta along each axis (7 rays per point). The weight is a soft clamp of the
  // linear model to [0, 1], so the optimiser sees an occluder's edge within about delta.
  void UpdateOcclusion(int c, const Eigen::Isometry3d& pose, double delta) {
    const auto& targets = ev_.targets();
    const std::size_t n = targets.size();
    const double eps = VisibilityTester::kRelativeEpsilon * ev_.scene_scale();
    const int samples = delta > 0 ? 7 : 1;
    std::vector<Ray> rays(n * samples);
    const Vec3 C0 = pose.translation();
    for (int k = 0; k < samples; ++k) {
      Vec3 C = C0;
      if (k > 0) C[(k - 1) / 2] += (k % 2 == 1 ? delta : -delta);
      for (std::size_t i = 0; i < n; ++i) {
        const Vec3 v = targets[i].p - C;
        const double dist = v.norm();
        Ray& r = rays[k * n + i];
        r.origin = C;
        r.direction = dist > 0 ? Vec3(v / dist) : Vec3::UnitX();
        r.t_near = eps;
        r.t_far = std::max(eps, dist - eps);
      }
    }
    std::vector<uint8_t> occluded;
    ev_.OccludedByPoint(rays, &occluded);
    auto clear = [&](int k, std::size_t i) {
      const Ray& r = rays[k * n + i];
      return r.t_far <= r.t_near || !occluded[k * n + i] ? 1.0 : 0.0;
    };
    Occlusion& o = occlusion_[c];
    o.centre = C0;
    o.clear.assign(n, 1.0);
    o.slope.assign(n, Vec3::Zero());
    for (std::size_t i = 0; i < n; ++i) {
      o.clear[i] = clear(0, i);
      if (samples > 1)
        for (int a = 0; a < 3; ++a)
          o.slope[i][a] = (clear(1 + 2 * a, i) - clear(2 + 2 * a, i)) / (2 * delta);
    }
  }

  // With a zoom the focal lengths are scaled about the principal point: pixel' = c + s (pixel - c)
  // for every lens model (the distortion acts on normalised coordinates), so the lens's valid
  // domain is unchanged and only the pixels and the Jacobian scale.
  void Contribute(int c, const Eigen::Isometry3d& pose, double focal_scale,
                  Contribution* out) const {
    const Camera& cam = ev_.selected_cameras()[c];
    const auto& targets = ev_.targets();
    const std::size_t n = targets.size();
    out->w.assign(n, 0.0);
    out->d.assign(n, 0.0);
    if (need_info_) out->info.assign(n, Mat3::Zero());
    const Mat3 Rt = pose.linear().transpose();
    const Vec3 C = pose.translation();
    const int W = cam.model.width(), H = cam.model.height();
    const double tau = std::max(1.0, border_fraction_ * W);
    const double range_width = 0.01 * ev_.scene_scale();
    const double sigma = ev_.PixelSigma(cam);
    const Occlusion& occl = occlusion_[c];
    const Vec3 dC = C - occl.centre;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 128), [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            double o = 1.0;
            if (!occl.clear.empty()) {
              o = SoftClamp01(occl.clear[i] + occl.slope[i].dot(dC));
              if (!(o > 0)) continue;
            }
            const Vec3 v = targets[i].p - C;
            const double dist = v.norm();
            Mat23 Jc;
            std::optional<Vec2> px = cam.model.Project(Rt * v, &Jc);
            if (!px) continue;
            if (focal_scale != 1.0) {
              const Vec2 pp(cam.model.intrinsics().cx, cam.model.intrinsics().cy);
              px = pp + focal_scale * (*px - pp);
              Jc *= focal_scale;
            }
            const double border = std::min(std::min(px->x() + 0.5, W - 0.5 - px->x()),
                                           std::min(px->y() + 0.5, H - 0.5 - px->y()));
            double w = Sigmoid((border - tau) / tau);
            if (cam.near > 0) w *= Sigmoid((dist - cam.near) / range_width);
            if (std::isfinite(cam.far)) w *= Sigmoid((cam.far - dist) / range_width);
            if (targets[i].normal) {
              const double cosine = targets[i].normal->dot(-v) / (targets[i].normal->norm() * dist);
              w *= Sigmoid(cosine / kIncidenceWidth);
            }
            const Mat23 A = Jc * Rt;
            w *= o;
            out->w[i] = w;
            out->d[i] = PixelDensity(A);
            if (need_info_) out->info[i] = A.transpose() * A / (sigma * sigma);
          }
        });
  }

  // Unscaled residuals of every active term (rows() values).
  void Residuals(const std::vector<const Contribution*>& contributions, double* r) const {
    const auto& fixed = ev_.fixed();
    const std::size_t n = ev_.targets().size();
    const double k = k_;
    const double eps = 1.0 / (ev_.region_scale() * ev_.region_scale());
    const double ds = ev_.density_scale();
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 128),
        [&](const tbb::blocked_range<std::size_t>& range) {
          for (std::size_t i = range.begin(); i != range.end(); ++i) {
            int row = 0;
            for (int t : terms_) {
              double value = 0;
              if (t == 0) {
                double s = fixed.count[i];
                for (const Contribution* c : contributions) s += c->w[i];
                value = 1.0 - Sigmoid((s - (k - 0.5)) / kCountWidth);
              } else if (t == 1) {
                Mat3 J = fixed.J[i] + eps * Mat3::Identity();
                for (const Contribution* c : contributions) J += c->w[i] * c->info[i];
                value = std::sqrt(std::max(0.0, J.inverse().trace()));
              } else {
                double p = fixed.dpow[i];
                for (const Contribution* c : contributions)
                  p += std::pow(c->w[i] * c->d[i] / ds, suggest_detail::kSoftMaxPower);
                const double res = std::pow(p, 1.0 / suggest_detail::kSoftMaxPower);  // in ds units
                value = 1.0 / (res + 1e-3);
              }
              r[row * n + i] = value * scale_[t];
              ++row;
            }
          }
        });
    evaluations_.fetch_add(1);
  }

  // Scales each term so that its cost at the given residuals is its weight (cost ~ 1 in all).
  void Normalise(const std::vector<const Contribution*>& contributions) {
    scale_.assign(3, 1.0);
    std::vector<double> r(rows());
    Residuals(contributions, r.data());
    const std::size_t n = ev_.targets().size();
    int row = 0;
    for (int t : terms_) {
      double cost = 0;
      for (std::size_t i = 0; i < n; ++i) cost += r[row * n + i] * r[row * n + i];
      scale_[t] = std::sqrt(weights_[t] / std::max(cost, 1e-300));
      ++row;
    }
  }

  std::int64_t evaluations() const { return evaluations_.load(); }

 private:
  const ExactEvaluator& ev_;
  bool need_info_;
  std::vector<double> weights_;
  int k_ = 2;  // the count of the coverage term
  std::vector<int> terms_;
  std::vector<double> scale_;
  struct Occlusion {
    Vec3 centre = Vec3::Zero();
    std::vector<double> clear;  // 1 when the segment from the centre is clear
    std::vector<Vec3> slope;    // d(clear)/d(centre), from +-delta samples
  };
  std::vector<Occlusion> occlusion_;
  double border_fraction_ = 0.02;
  mutable std::atomic<std::int64_t> evaluations_{0};
};

namespace {

// Penalty rows of one camera: translation beyond the move limit, rotation beyond the rotation
// limit, one row per keep-out box (depth of the centre inside it, relative to the move limit), and
// the clearance (how much closer to a surface than required, relative to the move limit, with a
// margin of 2 % of it so the nudge stays clear of the boundary the exact check enforces).
int PenaltyRows(const std::vector<Aabb>& keep_out) { return 3 + static_cast<int>(keep_out.size()); }

void Penalties(const PoseChart& chart, const suggest_detail::Placement& placement,
               std::size_t camera, const double* x, double* r) {
  const std::vector<Aabb>& keep_out = placement.keep_out();
  double t2 = 0, w2 = 0;
  for (int i = 0; i < chart.dims_t; ++i) t2 += x[i] * x[i];
  for (int i = chart.dims_t; i < chart.dims_t + chart.dims_r; ++i) w2 += x[i] * x[i];
  r[0] = kPenalty * std::max(0.0, std::sqrt(t2) - 1.0);
  r[1] = kPenalty * std::max(0.0, std::sqrt(w2) - 1.0);
  const Vec3 C = chart.Pose(x).translation();
  for (std::size_t b = 0; b < keep_out.size(); ++b) {
    const Aabb& box = keep_out[b];
    double depth = kInf;
    for (int a = 0; a < 3; ++a) depth = std::min({depth, C[a] - box.min[a], box.max[a] - C[a]});
    const double scale = chart.max_move > 0 ? chart.max_move : 1.0;
    r[2 + b] = kPenalty * std::max(0.0, depth / scale + 0.02);
  }
  const double required = placement.required(camera);
  double clearance = 0;
  if (required > 0 && chart.max_move > 0) {
    const double margin = 0.02 * chart.max_move;
    const double d = placement.SurfaceDistanceAt(C, required + margin);
    clearance = std::max(0.0, (required + margin - d) / chart.max_move);
  }
  r[2 + keep_out.size()] = kPenalty * clearance;
}

// One cost function for the whole problem: a parameter block per active camera. Jacobians by
// central differences per camera parameter (only that camera's contribution is recomputed).
class SurrogateCost final : public ceres::CostFunction {
 public:
  SurrogateCost(const Surrogate& surrogate, const std::vector<PoseChart>& charts,
                const std::vector<int>& active, const suggest_detail::Placement& placement,
                std::vector<Contribution>* frozen)
      : s_(surrogate), charts_(charts), active_(active), placement_(placement), frozen_(frozen) {
    for (int c : active_) mutable_parameter_block_sizes()->push_back(charts_[c].dims());
    set_num_residuals(s_.rows() +
                      static_cast<int>(active_.size()) * PenaltyRows(placement_.keep_out()));
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const std::size_t na = active_.size();
    std::vector<Contribution> current(na);
    std::vector<const Contribution*> ptrs;
    // Frozen (inactive) cameras contribute at the polish's start pose.
    for (const Contribution& f : *frozen_) ptrs.push_back(&f);
    const std::size_t base = ptrs.size();
    for (std::size_t a = 0; a < na; ++a) {
      const PoseChart& chart = charts_[active_[a]];
      s_.Contribute(active_[a], chart.Pose(parameters[a]), chart.FocalScale(parameters[a]),
                    &current[a]);
      ptrs.push_back(&current[a]);
    }
    const int rows = s_.rows();
    const int prow = PenaltyRows(placement_.keep_out());
    s_.Residuals(ptrs, residuals);
    for (std::size_t a = 0; a < na; ++a)
      Penalties(charts_[active_[a]], placement_, active_[a], parameters[a],
                residuals + rows + a * prow);
    if (!jacobians) return true;
    const int total = num_residuals();
    std::vector<double> rp(total), rm(total), x;
    Contribution shifted;
    for (std::size_t a = 0; a < na; ++a) {
      if (!jacobians[a]) continue;
      const PoseChart& chart = charts_[active_[a]];
      const int dims = chart.dims();
      double* jac = jacobians[a];
      std::fill(jac, jac + static_cast<std::size_t>(total) * dims, 0.0);
      x.assign(parameters[a], parameters[a] + dims);
      for (int j = 0; j < dims; ++j) {
        for (int sign = 0; sign < 2; ++sign) {
          std::vector<double> xs = x;
          xs[j] += sign == 0 ? kStep : -kStep;
          s_.Contribute(active_[a], chart.Pose(xs.data()), chart.FocalScale(xs.data()), &shifted);
          ptrs[base + a] = &shifted;
          double* out = sign == 0 ? rp.data() : rm.data();
          s_.Residuals(ptrs, out);
          Penalties(chart, placement_, active_[a], xs.data(), out + rows + a * prow);
        }
        ptrs[base + a] = &current[a];
        for (int i = 0; i < rows; ++i) jac[i * dims + j] = (rp[i] - rm[i]) / (2 * kStep);
        const int first = rows + static_cast<int>(a) * prow;
        for (int i = first; i < first + prow; ++i)
          jac[i * dims + j] = (rp[i] - rm[i]) / (2 * kStep);
      }
    }
    return true;
  }

 private:
  const Surrogate& s_;
  const std::vector<PoseChart>& charts_;
  const std::vector<int>& active_;
  const suggest_detail::Placement& placement_;
  std::vector<Contribution>* frozen_;
};

// Judges every successful Ceres step with the exact evaluation; keeps the best.
// Aborts the solve once `stop` says so (SuggestOptions::cancel).
class ExactJudge final : public ceres::IterationCallback {
 public:
  std::function<void()> on_step;
  std::function<bool()> stop;
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration > 0 && summary.step_is_successful) on_step();
    return stop() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }
};

// Scales the surrogate's terms at `poses`: the frozen cameras' contributions and the active ones'.
void NormaliseAt(Surrogate& surrogate, const std::vector<int>& active,
                 const std::vector<Contribution>& frozen,
                 const std::vector<Eigen::Isometry3d>& poses, const std::vector<double>& scales) {
  std::vector<Contribution> current(active.size());
  std::vector<const Contribution*> ptrs;
  for (const Contribution& f : frozen) ptrs.push_back(&f);
  for (std::size_t a = 0; a < active.size(); ++a) {
    surrogate.Contribute(active[a], poses[active[a]], scales[active[a]], &current[a]);
    ptrs.push_back(&current[a]);
  }
  surrogate.Normalise(ptrs);
}

}  // namespace

void SurrogateDeleter::operator()(Surrogate* surrogate) const { delete surrogate; }

std::unique_ptr<Surrogate, SurrogateDeleter> MakeSurrogate(const ExactEvaluator& ev,
                                                           bool need_info) {
  return std::unique_ptr<Surrogate, SurrogateDeleter>(new Surrogate(ev, need_info));
}

std::int64_t SurrogateEvaluations(const Surrogate& surrogate) { return surrogate.evaluations(); }

double SuggestRun::OcclusionDelta(std::size_t c) const {
  return kOcclusionDelta * charts[c].max_move;
}

// A camera whose smooth weight is zero at every target point (nothing in its image, its range, or
// everything occluded) has no gradient: the nudge leaves it where it is and says so (the exact
// screening still tries to move it).
void SuggestRun::FindActive() {
  std::vector<Contribution> start_weights(nsel);
  for (std::size_t c = 0; c < nsel; ++c)
    surrogate.UpdateOcclusion(static_cast<int>(c), start[c], OcclusionDelta(c));
  surrogate.set_border_width(kBorderWidth);
  for (int c : movable) {
    surrogate.Contribute(c, start[c], 1.0, &start_weights[c]);
    double wmax = 0;
    for (double w : start_weights[c].w) wmax = std::max(wmax, w);
    if (wmax > 1e-12) {
      active.push_back(c);
    } else {
      s.cameras[c].note =
          "sees none of the target points (outside its image or range, or occluded): "
          "no gradient, left in place";
    }
  }
}

// camera's centre is admissible.
std::pair<std::vector<Eigen::Isometry3d>, bool> SuggestRun::PosesOf(
    std::vector<std::vector<double>>& xs) {
  std::vector<Eigen::Isometry3d> poses = start;
  bool ok = true;
  for (std::size_t c = 0; c < nsel; ++c) {
    charts[c].Project(xs[c].data());
    poses[c] = charts[c].Pose(xs[c].data());
    scales[c] = charts[c].FocalScale(xs[c].data());
    ok = ok && placement.Admissible(c, poses[c].translation());
  }
  return std::make_pair(poses, ok);
}

// the best of all.
void SuggestRun::JudgeStep() {
  std::vector<std::vector<double>> xs = x;
  auto [poses, ok] = PosesOf(xs);
  if (!ok) return;
  const Metrics m = ev.Evaluate(poses, scales);
  const double score = ev.Score(m);
  if (score > run_score) {
    run_score = score;
    run_x = xs;
  }
  if (score > best_score) {
    best_score = score;
    best_m = m;
    best_x = xs;
  }
  s.trace.push_back({Elapsed(), ev.evaluations() + surrogate.evaluations(), best_m.objective});
}

namespace {

// polish's best pose, then one Ceres solve from there; true when it converged (stop).
bool OuterIteration(SuggestRun& run, int o, const std::vector<int>& inactive,
                    std::vector<Contribution>& frozen, ExactJudge& judge) {
  // Soft border: wide first (a gradient from far outside the image), then a few % of the width.
  run.surrogate.set_border_width(o == 0 ? kBorderWidth
                                        : (o == 1 ? kBorderWidth / 2 : kBorderWidth / 4));
  run.x = run.run_x;
  auto [poses, ok] = run.PosesOf(run.x);
  (void)ok;
  for (int c : run.active) run.surrogate.UpdateOcclusion(c, poses[c], run.OcclusionDelta(c));
  for (std::size_t f = 0; f < inactive.size(); ++f)
    run.surrogate.Contribute(inactive[f], poses[inactive[f]], run.scales[inactive[f]], &frozen[f]);
  NormaliseAt(run.surrogate, run.active, frozen, poses, run.scales);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  SurrogateCost cost(run.surrogate, run.charts, run.active, run.placement, &frozen);
  std::vector<double*> blocks;
  for (int c : run.active) blocks.push_back(run.x[c].data());
  problem.AddResidualBlock(&cost, nullptr, blocks);
  for (int c : run.active)
    for (int i = 0; i < run.charts[c].dims(); ++i) {
      // A flat mount box gives lower == upper on one axis, which Ceres rejects as infeasible
      // (and then does not iterate at all); the projection onto the limits before every exact
      // evaluation holds that axis anyway.
      if (!(run.charts[c].lower[i] < run.charts[c].upper[i])) continue;
      problem.SetParameterLowerBound(run.x[c].data(), i, run.charts[c].lower[i]);
      problem.SetParameterUpperBound(run.x[c].data(), i, run.charts[c].upper[i]);
    }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = std::max(1, run.options.max_inner_iterations);
  so.update_state_every_iteration = true;
  so.callbacks.push_back(&judge);
  so.logging_type =
      std::getenv("PANDORA_SUGGEST_DEBUG") ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  so.minimizer_progress_to_stdout = std::getenv("PANDORA_SUGGEST_DEBUG") != nullptr;
  so.num_threads = 1;
  so.function_tolerance = 1e-7;
  so.parameter_tolerance = 1e-7;
  so.initial_trust_region_radius = 1.0;
  ceres::Solver::Summary summary;
  const double score_before_outer = run.run_score;
  ceres::Solve(so, &problem, &summary);
  run.s.iterations += std::max(0, static_cast<int>(summary.iterations.size()) - 1);
  run.s.outer_iterations = o + 1;
  // The final state too (the callback saw every successful step already; this is cheap
  // insurance).
  judge.on_step();
  return o >= 2 && !(run.run_score > score_before_outer);  // converged at the final width
}

// The Ceres nudge: outer iterations of the surrogate'run.s minimisation from the best start, every

}  // namespace

void SuggestRun::Polish() {
  ExactJudge judge;
  scales.assign(nsel, 1.0);
  judge.on_step = [&]() { JudgeStep(); };
  judge.stop = [&]() { return Stopped(); };

  // Polish the best start with the Ceres nudge: the screening's best pose when it beat the current
  // poses, else the current poses. (Polishing the current poses as well, as a second start, never
  // ended best on the trauma-room benchmark and doubled the time.)
  run_x = screened_x.empty() ? x : screened_x;
  run_score = screened_x.empty() ? start_score : screened_score;
  // The polish moves the cameras with a gradient where it starts (a camera the screening turned
  // towards the target points gains one); the others contribute where they are.
  if (!screened_x.empty()) {
    std::vector<std::vector<double>> xs = run_x;
    auto [poses, ok] = PosesOf(xs);
    (void)ok;
    active.clear();
    for (int c : movable) {
      surrogate.UpdateOcclusion(c, poses[c], OcclusionDelta(c));
      Contribution w;
      surrogate.Contribute(c, poses[c], scales[c], &w);
      double wmax = 0;
      for (double v : w.w) wmax = std::max(wmax, v);
      if (wmax > 1e-12) active.push_back(c);
    }
  }
  std::vector<int> inactive;
  for (std::size_t c = 0; c < nsel; ++c)
    if (std::find(active.begin(), active.end(), static_cast<int>(c)) == active.end())
      inactive.push_back(static_cast<int>(c));
  std::vector<Contribution> frozen(inactive.size());
  const int outer = active.empty() ? 0 : std::max(1, options.outer_iterations);
  for (int o = 0; o < outer && !Stopped(); ++o) {
    const bool converged = OuterIteration(*this, o, inactive, frozen, judge);
    Progress(kScreeningShare + (1 - kScreeningShare) * (o + 1) / outer);
    if (converged) break;
  }
}

// A level camera (image x axis horizontal, as look_at with up +z makes it) stays level when that
// costs nothing: the screening's random turns leave a roll about the optical axis that coverage

}  // namespace pandora::suggest_detail
