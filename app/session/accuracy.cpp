// The accuracy studies (app/session/accuracy.h): voxel size, Monte Carlo trials, steady-state
// solvers.
#include "app/session/accuracy.h"

#include <tbb/global_control.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <optional>

#include "analysis/geometry/triangulation.h"
#include "analysis/geometry/uncertainty_reference.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "volume/fields.h"
#include "volume/summary.h"

namespace pandora {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string Millimetres(double metres) { return Format("%g mm", 1e3 * metres); }

// Calls fn (returning a double, kept so the work is not optimised away) in doubling batches until
// `min_seconds` have passed; returns the mean wall time per call.
template <class Fn>
double SecondsPerCall(Fn&& fn, double min_seconds) {
  volatile double sink = 0;
  long calls = 0, batch = 1;
  const Clock::time_point t0 = Clock::now();
  double elapsed = 0;
  for (;;) {
    for (long i = 0; i < batch; ++i) sink = sink + fn();
    calls += batch;
    elapsed = SecondsSince(t0);
    if (elapsed >= min_seconds) break;
    batch *= 2;
  }
  return elapsed / static_cast<double>(calls);
}

double RelativeError(double value, double reference) {
  return std::fabs(value - reference) / std::fabs(reference);
}

double Or(const std::optional<double>& v) { return v ? *v : kNaN; }

}  // namespace

AccuracyOptions AccuracyOptions::Quick() {
  AccuracyOptions o;
  o.voxel_factors = {4, 2, 1, 0.5};
  o.sample_points = 3;
  o.trials = {100, 300, 1000, 3000};
  o.min_timing_seconds = 0.01;
  o.run_on_iterations = 100000;
  o.gate_voxels = 12;
  return o;
}

void AccuracyOptions::Check() const {
  if (voxel_factors.empty())
    throw InputError("voxel_factors", "", "give at least one voxel size factor");
  for (double f : voxel_factors)
    if (!(f > 0 && std::isfinite(f)))
      throw InputError("voxel_factors", "",
                       "each factor must be a positive number, got " + Format("%g", f));
  if (!(max_reference_seconds > 0))
    throw InputError("max_reference_seconds", "", "must be a positive number of seconds");
  if (sample_points < 1) throw InputError("sample_points", "", "must be at least 1");
  if (trials.empty()) throw InputError("trials", "", "give at least one trial count");
  for (int n : trials)
    if (n < 2)
      throw InputError("trials", "",
                       "each trial count must be at least 2, got " + std::to_string(n));
  if (!(min_timing_seconds > 0 && std::isfinite(min_timing_seconds)))
    throw InputError("min_timing_seconds", "", "must be a positive number of seconds");
  if (run_on_iterations < 1) throw InputError("run_on_iterations", "", "must be at least 1");
  if (gate_voxels < 1) throw InputError("gate_voxels", "", "must be at least 1");
  if (gate_trials < 2) throw InputError("gate_trials", "", "must be at least 2");
}

// ---------------------------------------------------------------------------------------------
// (a) Voxel size.

VoxelStudy RunVoxelStudy(const Scene& scene_in, const Rig& rig, const RayCaster& caster,
                         const AccuracyOptions& options) {
  options.Check();
  Scene scene = scene_in;  // its voxel size changes per row
  VoxelStudy study;
  study.steady = scene.study.motion.has_value();
  std::vector<std::string> names{"coverage", "sigma_max", "sigma_mean"};
  if (study.steady) {
    names.push_back("sigma_max_steady");
    names.push_back("sigma_mean_steady");
  }
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  const double study_voxel = scene.study.voxel_size;
  FieldOptions field_options;
  field_options.fields = names;
  field_options.scene_path = scene.path;
  field_options.memory_budget_bytes = scene.study.memory_budget_bytes;
  for (double factor : options.voxel_factors) {
    const double h = study_voxel * factor;
    const VoxelLattice lattice = MakeLattice(scene.study.region.box, h, scene.path);
    const double bytes = EstimateFieldBytes(lattice, names, rig.enabled_count());
    if (bytes > field_options.memory_budget_bytes) {
      study.notes.push_back(Format("voxel %s skipped: needs about %.3g MB, over the %.3g MB budget",
                                   Millimetres(h).c_str(), bytes / 1e6,
                                   field_options.memory_budget_bytes / 1e6));
      break;
    }
    if (!study.rows.empty() && 8 * study.rows.back().seconds > options.max_reference_seconds) {
      study.notes.push_back(Format(
          "voxel %s skipped: predicted %.0f s (8x the previous size) is over %.0f s",
          Millimetres(h).c_str(), 8 * study.rows.back().seconds, options.max_reference_seconds));
      break;
    }
    scene.study.voxel_size = h;
    VoxelRow row;
    row.factor = factor;
    row.voxel_size = h;
    // Small evaluations are repeated (best of up to 5, within ~0.3 s) to steady the timing.
    double total = 0, best = std::numeric_limits<double>::infinity();
    std::optional<Fields> kept;
    while (row.repeats == 0 || (total < 0.3 && row.repeats < 5)) {
      const Clock::time_point t0 = Clock::now();
      Fields fields = EvaluateFields(scene, rig, caster, field_options);
      const double t = SecondsSince(t0);
      total += t;
      best = std::min(best, t);
      ++row.repeats;
      kept = std::move(fields);
    }
    row.seconds = best;
    const Summary s = Summarize(scene, rig, *kept, names, threads);
    kept.reset();
    row.region_voxels = s.region_voxels;
    row.ge[0] = s.coverage.ge1;
    row.ge[1] = s.coverage.ge2;
    row.ge[2] = s.coverage.ge3;
    if (s.uncertainty) {
      row.triangulable_voxels = s.uncertainty->triangulable_voxels;
      row.p50 = Or(s.uncertainty->sigma_max_mm.p50);
      row.p90 = Or(s.uncertainty->sigma_max_mm.p90);
      if (s.uncertainty->motion) {
        row.steady_p50 = Or(s.uncertainty->sigma_max_steady_mm.p50);
        row.steady_p90 = Or(s.uncertainty->sigma_max_steady_mm.p90);
      }
    }
    study.rows.push_back(row);
  }
  return study;
}

// ---------------------------------------------------------------------------------------------
// (b) Monte Carlo.

std::vector<SamplePoint> SamplePoints(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                      std::size_t wanted) {
  const VisibilityTester tester(rig.cameras, caster, scene.Bounds().diagonal());
  const Aabb& box = scene.study.region.box;
  std::vector<SamplePoint> seen;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        SamplePoint p;
        p.X = box.min + Vec3((i + 0.5) / 3, (j + 0.5) / 3, (k + 0.5) / 3).cwiseProduct(box.size());
        for (int c = 0; c < static_cast<int>(rig.cameras.size()); ++c)
          if (tester.Test(c, p.X) == ViewResult::kSeen) p.cameras.push_back(rig.cameras[c]);
        if (p.cameras.size() >= 2) seen.push_back(std::move(p));
      }
  if (seen.size() > wanted) {
    std::vector<SamplePoint> spread;
    for (std::size_t q = 0; q < wanted; ++q)
      spread.push_back(seen[wanted == 1 ? 0 : q * (seen.size() - 1) / (wanted - 1)]);
    seen = std::move(spread);
  }
  return seen;
}

StaticUncertainty PredictUncertainty(const SamplePoint& p, double sigma_px, Information* info) {
  InformationBuilder builder;
  for (const Camera& camera : p.cameras) {
    Mat23 A;
    if (camera.Project(p.X, &A)) builder.Add(A, sigma_px);
  }
  const Information decomposed = builder.Decompose();
  if (info) *info = decomposed;
  return StaticFromInformation(decomposed, builder.cameras());
}

double PowerLawCrossing(const std::vector<double>& x, const std::vector<double>& y,
                        double y_target) {
  double n = 0, mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i)
    if (y[i] > 0 && x[i] > 0) {
      mx += std::log(x[i]);
      my += std::log(y[i]);
      ++n;
    }
  if (n < 2) return kNaN;
  mx /= n;
  my /= n;
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i)
    if (y[i] > 0 && x[i] > 0) {
      const double dx = std::log(x[i]) - mx;
      sxy += dx * (std::log(y[i]) - my);
      sxx += dx * dx;
    }
  const double b = sxx > 0 ? sxy / sxx : 0;
  return b < 0 ? std::exp(mx + (std::log(y_target) - my) / b) : kNaN;
}

std::string OwnPixelSigmaNote(const Rig& rig, double sigma_px) {
  for (const Camera& c : rig.cameras)
    if (c.enabled && c.pixel_sigma > 0 && c.pixel_sigma != sigma_px)
      return Format(
          "camera %s sets its own pixel_sigma; here every camera uses the study's %.3g px",
          c.id.c_str(), sigma_px);
  return {};
}

MonteCarloStudy RunMonteCarloStudy(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                   const AccuracyOptions& options) {
  options.Check();
  MonteCarloStudy study;
  study.sigma_px = scene.study.pixel_sigma;
  study.points = SamplePoints(scene, rig, caster, static_cast<std::size_t>(options.sample_points));
  if (std::string note = OwnPixelSigmaNote(rig, study.sigma_px); !note.empty())
    study.notes.push_back(note);
  for (SamplePoint& p : study.points) {
    const StaticUncertainty u = PredictUncertainty(p, study.sigma_px, &p.info);
    p.sigma_max = u.sigma_max;
  }
  std::vector<SamplePoint> usable;
  for (SamplePoint& p : study.points)
    if (p.sigma_max > 0) usable.push_back(std::move(p));
  study.points = std::move(usable);
  if (study.points.empty()) {
    study.notes.push_back("no sample point of the region is triangulable: Monte Carlo skipped");
    return study;
  }
  // The prediction's own cost, single-threaded, averaged over the points.
  double prediction = 0;
  for (const SamplePoint& p : study.points)
    prediction += SecondsPerCall([&] { return PredictUncertainty(p, study.sigma_px).sigma_max; },
                                 options.min_timing_seconds);
  study.prediction_seconds = prediction / static_cast<double>(study.points.size());

  std::uint64_t seed = options.seed;
  for (int n : options.trials) {
    MonteCarloRow row;
    row.trials = n;
    double seconds = 0;
    for (const SamplePoint& p : study.points) {
      const MonteCarloResult r = MonteCarloCovariance(p.cameras, p.X, study.sigma_px, n, seed++);
      seconds += r.seconds;
      row.failures += r.failures;
      row.rel_mean += r.relative_error;
      row.rel_max = std::max(row.rel_max, r.relative_error);
      row.frob_mean += r.frobenius_relative_error;
      row.frob_max = std::max(row.frob_max, r.frobenius_relative_error);
      ++row.points;
    }
    row.seconds_per_point = seconds / row.points;
    row.rel_mean /= row.points;
    row.frob_mean /= row.points;
    study.rows.push_back(row);
  }
  // Least-squares line log(error) = a + b log(time); the time where it crosses 1%.
  std::vector<double> time, error;
  for (const MonteCarloRow& r : study.rows) {
    time.push_back(r.seconds_per_point);
    error.push_back(r.rel_mean);
  }
  study.seconds_for_1pct = PowerLawCrossing(time, error, 0.01);
  return study;
}

// ---------------------------------------------------------------------------------------------
// (c) Steady-state solvers.

namespace {

// The representative information matrix (the sample point with the median predicted sigma_max)
// into study->J, and where it comes from into study->J_source.
void ChooseSteadyJ(const MonteCarloStudy& mc, SteadyStudy* study) {
  if (!mc.points.empty()) {
    std::vector<const SamplePoint*> sorted;
    for (const SamplePoint& p : mc.points) sorted.push_back(&p);
    std::sort(sorted.begin(), sorted.end(), [](const SamplePoint* a, const SamplePoint* b) {
      return a->sigma_max < b->sigma_max;
    });
    const SamplePoint& p = *sorted[sorted.size() / 2];
    study->J = p.info.J;
    study->J_source =
        Format("J of sample point (%.3f, %.3f, %.3f) m, %zu cameras, sigma_max %.3g mm", p.X.x(),
               p.X.y(), p.X.z(), p.cameras.size(), 1e3 * p.sigma_max);
  } else {
    study->J = 1e6 * Mat3::Identity();
    study->J_source = "no triangulable sample point: isotropic J for sigma = 1 mm";
  }
}

// One steady-state case: its motion, the per-axis measurement variance r and eigen-directions V of
// J, the long-double reference variance per axis, and the row every solver's row starts from.
struct SteadyCaseRun {
  double q, T;
  Vec3 r;
  Mat3 V;
  double min_seconds;
  Vec3 reference;
  SteadyRow base;

  // The largest relative error of `variance` over the axes (NaN when one is not finite).
  double AxisError(const Vec3& variance) const {
    double e = 0;
    for (int k = 0; k < 3; ++k) {
      const double ek = RelativeError(variance[k], reference[k]);
      e = std::isfinite(ek) ? std::max(e, ek) : kNaN;
      if (std::isnan(e)) break;
    }
    return e;
  }
};

// Long-double doubling: how far the reference itself can be trusted.
SteadyRow ReferenceCheckRow(const SteadyCaseRun& sc, double reference_check,
                            int reference_iterations) {
  const double q = sc.q, T = sc.T;
  const Vec3& r = sc.r;
  SteadyRow row = sc.base;
  row.method = "doubling 2x2 in long double (reference check)";
  row.label = "long-double doubling (check)";
  row.iterations = reference_iterations;
  row.error = reference_check;
  row.seconds =
      3 * SecondsPerCall(
              [&] {
                int its;
                return static_cast<double>(SteadyPositionVarianceDoublingLong(q, T, r[0], &its));
              },
              sc.min_seconds);
  return row;
}

// Closed form, three axes.
SteadyRow ClosedFormRow(const SteadyCaseRun& sc) {
  const double q = sc.q, T = sc.T;
  const Vec3& r = sc.r;
  SteadyRow row = sc.base;
  row.method = "closed form (ScalarSteadyState x 3)";
  row.label = "closed form";
  Vec3 v;
  for (int k = 0; k < 3; ++k) v[k] = ScalarSteadyState(q, T, r[k])(0, 0);
  row.error = sc.AxisError(v);
  row.seconds = SecondsPerCall(
      [&] {
        return ScalarSteadyState(q, T, r[0])(0, 0) + ScalarSteadyState(q, T, r[1])(0, 0) +
               ScalarSteadyState(q, T, r[2])(0, 0);
      },
      sc.min_seconds);
  return row;
}

// Doubling on the three 2x2 axis problems.
SteadyRow Doubling2x2Row(const SteadyCaseRun& sc) {
  const double q = sc.q, T = sc.T;
  const Vec3& r = sc.r;
  Eigen::Matrix2d F2, Q2;
  F2 << 1, T, 0, 1;
  Q2 << T * T * T / 3, T * T / 2, T * T / 2, T;
  Q2 *= q;
  std::vector<Eigen::MatrixXd> G2(3, Eigen::MatrixXd::Zero(2, 2));
  for (int k = 0; k < 3; ++k) G2[k](0, 0) = 1.0 / r[k];
  SteadyRow row = sc.base;
  row.method = "doubling 2x2 x 3 (tol 1e-15)";
  row.label = "doubling 2x2";
  Vec3 v;
  for (int k = 0; k < 3; ++k) {
    int its = 0;
    const std::optional<Eigen::MatrixXd> M = SolveDareDoubling(F2, G2[k], Q2, 1e-15, 100, &its);
    row.iterations = std::max(row.iterations, its);
    row.converged = row.converged && M.has_value();
    v[k] = M ? PosteriorFromPrior(*M, G2[k])(0, 0) : kNaN;
  }
  row.error = sc.AxisError(v);
  row.seconds = SecondsPerCall(
      [&] {
        double sum = 0;
        for (int k = 0; k < 3; ++k) {
          const auto M = SolveDareDoubling(F2, G2[k], Q2);
          if (M) sum += PosteriorFromPrior(*M, G2[k])(0, 0);
        }
        return sum;
      },
      sc.min_seconds);
  return row;
}

// The rows of the full 6x6 problem of the case: doubling, then plain Riccati iteration to each
// tolerance (the last, 0, runs `run_on_iterations` steps with no early stop).
void AddSixBySixRows(const SteadyCaseRun& sc, const Mat3& J, const MotionModel& motion,
                     int run_on_iterations, std::vector<SteadyRow>* rows) {
  const Mat3& V = sc.V;
  const double min_seconds = sc.min_seconds;
  const int kMaxIterations = 1000000;
  const int kRunOnIterations = run_on_iterations;  // the "tol 0" row: no early stop
  const ConstantVelocity6 m6 = MakeConstantVelocity6(J, motion);
  const Eigen::MatrixXd F6 = m6.F, G6 = m6.G, Q6 = m6.Q;
  // Position variance of a 6x6 prior along each eigen-direction of J.
  auto project = [&](const Eigen::MatrixXd& M) {
    const Eigen::MatrixXd P = PosteriorFromPrior(M, G6);
    const Mat3 pos = P.topLeftCorner(3, 3);
    Vec3 v;
    for (int k = 0; k < 3; ++k) v[k] = V.col(k).dot(pos * V.col(k));
    return v;
  };
  {  // Doubling on the full 6x6 problem.
    SteadyRow row = sc.base;
    row.method = "doubling 6x6 (tol 1e-15)";
    row.label = "doubling 6x6";
    const std::optional<Eigen::MatrixXd> M =
        SolveDareDoubling(F6, G6, Q6, 1e-15, 100, &row.iterations);
    row.converged = M.has_value();
    row.error = M ? sc.AxisError(project(*M)) : kNaN;
    row.seconds = SecondsPerCall(
        [&] {
          const auto M = SolveDareDoubling(F6, G6, Q6);
          return M ? PosteriorFromPrior(*M, G6)(0, 0) : 0.0;
        },
        min_seconds);
    rows->push_back(row);
  }
  for (double tolerance : {1e-4, 1e-8, 1e-12, 0.0}) {  // Plain Riccati iteration on the 6x6.
    SteadyRow row = sc.base;
    row.method = tolerance > 0 ? Format("iteration 6x6 (tol %.0e)", tolerance)
                               : Format("iteration 6x6 (tol 0: %d steps)", kRunOnIterations);
    row.label = tolerance > 0 ? Format("iteration, tol %.0e", tolerance)
                              : Format("iteration, %.0e steps", double(kRunOnIterations));
    const int max_iterations = tolerance > 0 ? kMaxIterations : kRunOnIterations;
    row.run_on = tolerance == 0;
    const Eigen::MatrixXd M =
        SolveDareIteration(F6, G6, Q6, tolerance, max_iterations, &row.converged, &row.iterations);
    row.error = sc.AxisError(project(M));
    row.seconds = SecondsPerCall(
        [&] {
          const Eigen::MatrixXd Mi = SolveDareIteration(F6, G6, Q6, tolerance, max_iterations);
          return PosteriorFromPrior(Mi, G6)(0, 0);
        },
        min_seconds);
    rows->push_back(row);
  }
}

// The rows of case `c`: the reference check, then every solver, into `rows`.
void AddSteadyCaseRows(const SteadyCase& c, const Mat3& J, const Vec3& r, const Mat3& V,
                       double min_seconds, int run_on_iterations, std::vector<SteadyRow>* rows) {
  const double q = c.motion.q, T = 1.0 / c.motion.rate_hz;
  Vec3 reference;
  double reference_check = 0;
  int reference_iterations = 0;
  for (int k = 0; k < 3; ++k) {
    reference[k] = static_cast<double>(SteadyPositionVarianceLong(q, T, r[k]));
    int its = 0;
    const long double check = SteadyPositionVarianceDoublingLong(q, T, r[k], &its);
    reference_check =
        std::max(reference_check,
                 static_cast<double>(std::fabs(check - SteadyPositionVarianceLong(q, T, r[k])) /
                                     SteadyPositionVarianceLong(q, T, r[k])));
    reference_iterations = std::max(reference_iterations, its);
  }
  SteadyRow base;
  base.case_name = c.name;
  base.motion = c.motion;
  base.lambda_min = std::sqrt(q * T * T * T / r.maxCoeff());
  base.lambda_max = std::sqrt(q * T * T * T / r.minCoeff());
  const SteadyCaseRun sc{q, T, r, V, min_seconds, reference, base};

  rows->push_back(ReferenceCheckRow(sc, reference_check, reference_iterations));
  rows->push_back(ClosedFormRow(sc));
  rows->push_back(Doubling2x2Row(sc));
  AddSixBySixRows(sc, J, c.motion, run_on_iterations, rows);
}

}  // namespace

SteadyStudy RunSteadyStudy(const Scene& scene, const MonteCarloStudy& mc,
                           const AccuracyOptions& options) {
  options.Check();
  SteadyStudy study;
  // A representative information matrix: the sample point with the median predicted sigma_max.
  ChooseSteadyJ(mc, &study);
  const Information info = DecomposeInformation(study.J);
  const Vec3 r = info.eigenvalues.cwiseInverse();  // per-axis measurement variance, m^2
  const Mat3 V = info.eigenvectors;

  if (scene.study.motion)
    study.cases.push_back({"study", *scene.study.motion});
  else
    study.cases.push_back({"nominal", MotionModel{1.0, 30.0}});
  study.cases.push_back({"fast motion", MotionModel{1e8, 30.0}});
  study.cases.push_back({"1 MHz", MotionModel{1.0, 1e6}});

  const double min_seconds = options.min_timing_seconds;
  const int kRunOnIterations = options.run_on_iterations;  // the "tol 0" row: no early stop
  for (const SteadyCase& c : study.cases)
    AddSteadyCaseRows(c, study.J, r, V, min_seconds, kRunOnIterations, &study.rows);
  return study;
}

}  // namespace pandora
