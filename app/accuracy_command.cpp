// `pandora accuracy`: error against run time for the approximations Pandora makes or could make
// (issue 3, point 6): (a) voxel size against the error of the coverage and uncertainty summaries,
// (b) Monte Carlo trials against the error of the triangulation covariance, with the closed-form
// prediction's own cost beside it, (c) the steady-state Riccati solvers against a long-double
// reference. Prints aligned tables and writes CSV files, SVG log-log plots and the tables as
// Markdown, all atomically.
#include <tbb/global_control.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/error.h"
#include "analysis/ray_caster.h"
#include "analysis/scene.h"
#include "analysis/uncertainty.h"
#include "analysis/visibility.h"
#include "app/commands.h"
#include "app/output.h"
#include "app/plot.h"
#include "suggest/triangulation.h"
#include "volume/fields.h"
#include "volume/summary.h"

namespace pandora::app {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string Format(const char* format, ...) {
  char buffer[256];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return buffer;
}

// A number for a table cell: `format` when finite, "-" otherwise.
std::string Cell(const char* format, double v) {
  return std::isfinite(v) ? Format(format, v) : "-";
}

// A number for a CSV field: full precision, "nan" / "inf" when not finite.
std::string CsvNumber(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return Format("%.9g", v);
}

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

// A table of strings: aligned text for the terminal (first column left, others right) and Markdown.
class Table {
 public:
  /// `align`: one 'l' or 'r' per column; default: the first column left, the others right.
  explicit Table(std::vector<std::string> header, std::string align = {})
      : header_(std::move(header)), align_(std::move(align)) {
    if (align_.empty()) align_ = "l" + std::string(header_.size() - 1, 'r');
    align_.resize(header_.size(), 'r');
  }
  void AddRow(std::vector<std::string> row) {
    row.resize(header_.size());
    rows_.push_back(std::move(row));
  }
  std::string Text() const {
    std::vector<std::size_t> width(header_.size());
    for (std::size_t c = 0; c < header_.size(); ++c) {
      width[c] = Length(header_[c]);
      for (const auto& r : rows_) width[c] = std::max(width[c], Length(r[c]));
    }
    std::string out;
    auto line = [&](const std::vector<std::string>& cells) {
      for (std::size_t c = 0; c < cells.size(); ++c) {
        const std::string pad(width[c] - Length(cells[c]), ' ');
        out += (c == 0 ? "" : "  ") + (align_[c] == 'l' ? cells[c] + pad : pad + cells[c]);
      }
      while (!out.empty() && out.back() == ' ') out.pop_back();
      out += '\n';
    };
    line(header_);
    for (const auto& r : rows_) line(r);
    return out;
  }
  std::string Markdown() const {
    std::string out = "|";
    for (const auto& h : header_) out += " " + h + " |";
    out += "\n|";
    for (std::size_t c = 0; c < header_.size(); ++c) out += align_[c] == 'l' ? "---|" : "---:|";
    out += "\n";
    for (const auto& r : rows_) {
      out += "|";
      for (const auto& cell : r) out += " " + cell + " |";
      out += "\n";
    }
    return out;
  }

 private:
  // Display width: UTF-8 continuation bytes do not count.
  static std::size_t Length(const std::string& s) {
    std::size_t n = 0;
    for (unsigned char ch : s)
      if ((ch & 0xC0) != 0x80) ++n;
    return n;
  }
  std::vector<std::string> header_;
  std::string align_;
  std::vector<std::vector<std::string>> rows_;
};

// CSV text: a header and rows of already formatted fields. Fields are plain (no quoting): a comma
// or a quote inside one becomes a semicolon or an apostrophe, so `awk -F,` and spreadsheets agree.
std::string CsvText(const std::vector<std::string>& header,
                    const std::vector<std::vector<std::string>>& rows) {
  std::string out;
  auto line = [&](const std::vector<std::string>& cells) {
    for (std::size_t c = 0; c < cells.size(); ++c) {
      std::string field = cells[c];
      std::replace(field.begin(), field.end(), ',', ';');
      std::replace(field.begin(), field.end(), '"', '\'');
      out += (c ? "," : "") + field;
    }
    out += '\n';
  };
  line(header);
  for (const auto& r : rows) line(r);
  return out;
}

std::string Millimetres(double metres) { return Format("%g mm", 1e3 * metres); }

// --------------------------------------------------------------------------------------------
// (a) Voxel size.

struct VoxelRow {
  double factor = 1, voxel_size = 0;
  std::int64_t region_voxels = 0, triangulable_voxels = 0;
  double seconds = 0;
  int repeats = 0;
  double ge[3] = {kNaN, kNaN, kNaN};
  double p50 = kNaN, p90 = kNaN, steady_p50 = kNaN, steady_p90 = kNaN;
};

double JsonNumber(const nlohmann::json& j) { return j.is_number() ? j.get<double>() : kNaN; }

double RelativeError(double value, double reference) {
  return std::fabs(value - reference) / std::fabs(reference);
}

struct VoxelStudy {
  std::vector<VoxelRow> rows;  ///< Coarse to fine; the last is the reference.
  std::vector<std::string> notes;
  bool steady = false;
};

VoxelStudy RunVoxelStudy(Scene& scene, const Rig& rig, const RayCaster& caster, bool quick,
                         int threads) {
  // Above this predicted time the next finer size is not evaluated (it scales as 1 / size^3).
  constexpr double kMaxReferenceSeconds = 30.0;
  VoxelStudy study;
  study.steady = scene.study.motion.has_value();
  std::vector<std::string> names{"coverage", "sigma_max", "sigma_mean"};
  if (study.steady) {
    names.push_back("sigma_max_steady");
    names.push_back("sigma_mean_steady");
  }
  const double study_voxel = scene.study.voxel_size;
  const std::vector<double> factors =
      quick ? std::vector<double>{4, 2, 1, 0.5} : std::vector<double>{4, 2, 1, 0.5, 0.25};
  FieldOptions options;
  options.fields = names;
  options.scene_path = scene.path;
  options.memory_budget_bytes = scene.study.memory_budget_bytes;
  for (double factor : factors) {
    const double h = study_voxel * factor;
    const VoxelLattice lattice = MakeLattice(scene.study.region.box, h, scene.path);
    const double bytes = EstimateFieldBytes(lattice, names, rig.enabled_count());
    if (bytes > options.memory_budget_bytes) {
      study.notes.push_back(Format("voxel %s skipped: needs about %.3g MB, over the %.3g MB budget",
                                   Millimetres(h).c_str(), bytes / 1e6,
                                   options.memory_budget_bytes / 1e6));
      break;
    }
    if (!study.rows.empty() && 8 * study.rows.back().seconds > kMaxReferenceSeconds) {
      study.notes.push_back(
          Format("voxel %s skipped: predicted %.0f s (8x the previous size) is over %.0f s",
                 Millimetres(h).c_str(), 8 * study.rows.back().seconds, kMaxReferenceSeconds));
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
      Fields fields = EvaluateFields(scene, rig, caster, options);
      const double t = SecondsSince(t0);
      total += t;
      best = std::min(best, t);
      ++row.repeats;
      kept = std::move(fields);
    }
    row.seconds = best;
    const nlohmann::json s = MakeSummary(scene, rig, *kept, names, threads);
    kept.reset();
    row.region_voxels = s["region_voxels"].get<std::int64_t>();
    row.ge[0] = s["coverage"]["ge1"].get<double>();
    row.ge[1] = s["coverage"]["ge2"].get<double>();
    row.ge[2] = s["coverage"]["ge3"].get<double>();
    const nlohmann::json& u = s["uncertainty"];
    row.triangulable_voxels = u["triangulable_voxels"].get<std::int64_t>();
    row.p50 = JsonNumber(u["sigma_max_mm"]["p50"]);
    row.p90 = JsonNumber(u["sigma_max_mm"]["p90"]);
    if (u.contains("sigma_max_steady_mm")) {
      row.steady_p50 = JsonNumber(u["sigma_max_steady_mm"]["p50"]);
      row.steady_p90 = JsonNumber(u["sigma_max_steady_mm"]["p90"]);
    }
    study.rows.push_back(row);
  }
  scene.study.voxel_size = study_voxel;
  return study;
}

// --------------------------------------------------------------------------------------------
// (b) Monte Carlo.

struct SamplePoint {
  Vec3 X;
  std::vector<Camera> cameras;  ///< The enabled cameras that see X.
  Information info;
  double sigma_max = 0;  ///< Predicted, m.
};

// The centres of the region box's 3 x 3 x 3 cells that at least two cameras see (exact visibility,
// occlusion included), then `wanted` of them spread evenly over that list (as
// suggest/triangulation_test.cpp does).
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

// The closed-form prediction at one point: Jacobians, information, eigen-decomposition, J^-1.
StaticUncertainty Predict(const SamplePoint& p, double sigma_px, Information* info = nullptr) {
  InformationBuilder builder;
  for (const Camera& camera : p.cameras) {
    Mat23 A;
    if (camera.Project(p.X, &A)) builder.Add(A, sigma_px);
  }
  const Information decomposed = builder.Decompose();
  if (info) *info = decomposed;
  return StaticFromInformation(decomposed, builder.cameras());
}

struct MonteCarloRow {
  int trials = 0, points = 0, failures = 0;
  double seconds_per_point = 0;
  double rel_mean = 0, rel_max = 0, frob_mean = 0, frob_max = 0;
};

struct MonteCarloStudy {
  std::vector<SamplePoint> points;
  std::vector<MonteCarloRow> rows;
  double prediction_seconds = kNaN;  ///< Per point, single thread.
  double seconds_for_1pct = kNaN;    ///< Monte Carlo time per point for 1% sigma_max error (fit).
  double sigma_px = 0;
  std::vector<std::string> notes;
};

MonteCarloStudy RunMonteCarloStudy(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                   bool quick) {
  MonteCarloStudy study;
  study.sigma_px = scene.study.pixel_sigma;
  study.points = SamplePoints(scene, rig, caster, quick ? 3 : 5);
  for (const Camera& c : rig.cameras)
    if (c.enabled && c.pixel_sigma > 0 && c.pixel_sigma != study.sigma_px) {
      study.notes.push_back(
          Format("camera %s sets its own pixel_sigma; here every camera uses the study's %.3g px",
                 c.id.c_str(), study.sigma_px));
      break;
    }
  for (SamplePoint& p : study.points) {
    const StaticUncertainty u = Predict(p, study.sigma_px, &p.info);
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
    prediction +=
        SecondsPerCall([&] { return Predict(p, study.sigma_px).sigma_max; }, quick ? 0.01 : 0.05);
  study.prediction_seconds = prediction / static_cast<double>(study.points.size());

  const std::vector<int> trials = quick ? std::vector<int>{100, 300, 1000, 3000}
                                        : std::vector<int>{100, 300, 1000, 3000, 10000};
  std::uint64_t seed = 1;
  for (int n : trials) {
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
  double n = 0, mx = 0, my = 0;
  for (const MonteCarloRow& r : study.rows)
    if (r.rel_mean > 0 && r.seconds_per_point > 0) {
      mx += std::log(r.seconds_per_point);
      my += std::log(r.rel_mean);
      ++n;
    }
  if (n >= 2) {
    mx /= n;
    my /= n;
    double sxy = 0, sxx = 0;
    for (const MonteCarloRow& r : study.rows)
      if (r.rel_mean > 0 && r.seconds_per_point > 0) {
        const double dx = std::log(r.seconds_per_point) - mx;
        sxy += dx * (std::log(r.rel_mean) - my);
        sxx += dx * dx;
      }
    const double b = sxx > 0 ? sxy / sxx : 0;
    if (b < 0) study.seconds_for_1pct = std::exp(mx + (std::log(0.01) - my) / b);
  }
  return study;
}

// --------------------------------------------------------------------------------------------
// (c) Steady-state solvers.

using Mat2L = Eigen::Matrix<long double, 2, 2>;

// The closed form of ScalarSteadyState (posterior position variance), evaluated in long double
// (64-bit mantissa): the reference for round-off.
long double ClosedFormLong(long double q, long double T, long double r) {
  const long double lambda = std::sqrt(q * T * T * T / r);
  const long double R = std::sqrt(lambda * lambda / 3.0L + 16.0L);
  const long double w_minus_2 = 0.5L * (lambda + (lambda * lambda / 3.0L) / (R + 4.0L));
  const long double w = 2.0L + w_minus_2;
  const long double s = std::sqrt(w_minus_2 * (w + 2.0L));
  const long double u = 2.0L / (w + s);
  return u * s * r;
}

// An independent check of the reference: structure-preserving doubling on the scalar axis in long
// double, to convergence; posterior position variance.
long double DoublingLong(long double q, long double T, long double r, int* iterations) {
  Mat2L F, Q, G, I = Mat2L::Identity();
  F << 1, T, 0, 1;
  Q << T * T * T / 3, T * T / 2, T * T / 2, T;
  Q *= q;
  G << 1 / r, 0, 0, 0;
  Mat2L A = F.transpose(), Gk = G, H = Q;
  for (int k = 1; k <= 200; ++k) {
    const Mat2L Winv = (I + Gk * H).inverse();
    const Mat2L H_next = H + A.transpose() * H * Winv * A;
    const Mat2L G_next = Gk + A * Winv * Gk * A.transpose();
    const Mat2L A_next = A * Winv * A;
    const long double change = (H_next - H).cwiseAbs().maxCoeff() / H_next.cwiseAbs().maxCoeff();
    H = 0.5L * (H_next + H_next.transpose());
    Gk = 0.5L * (G_next + G_next.transpose());
    A = A_next;
    *iterations = k;
    if (!(change > 4 * std::numeric_limits<long double>::epsilon())) break;
  }
  const Mat2L P = (I + H * G).inverse() * H;
  return P(0, 0);
}

struct SteadyCase {
  std::string name;
  MotionModel motion;
};

struct SteadyRow {
  std::string case_name, method, label;  ///< label: short method name for the plot.
  MotionModel motion;
  double lambda_min = 0, lambda_max = 0;  ///< Tracking index of the axes, sqrt(q T^3 / r).
  int iterations = 0;                     ///< Largest over the axes; 0 for the closed form.
  bool converged = true;
  bool run_on = false;  ///< Iteration with tolerance 0: runs its step budget, never "converges".
  double seconds = 0;   ///< Per voxel (all three axes).
  double error = 0;     ///< Largest relative error of the posterior position variance over axes.
};

struct SteadyStudy {
  std::vector<SteadyCase> cases;
  std::vector<SteadyRow> rows;
  Mat3 J = Mat3::Zero();
  std::string J_source;
  std::vector<std::string> notes;
};

SteadyStudy RunSteadyStudy(const Scene& scene, const MonteCarloStudy& mc, bool quick) {
  SteadyStudy study;
  // A representative information matrix: the sample point with the median predicted sigma_max.
  if (!mc.points.empty()) {
    std::vector<const SamplePoint*> sorted;
    for (const SamplePoint& p : mc.points) sorted.push_back(&p);
    std::sort(sorted.begin(), sorted.end(), [](const SamplePoint* a, const SamplePoint* b) {
      return a->sigma_max < b->sigma_max;
    });
    const SamplePoint& p = *sorted[sorted.size() / 2];
    study.J = p.info.J;
    study.J_source =
        Format("J of sample point (%.3f, %.3f, %.3f) m, %zu cameras, sigma_max %.3g mm", p.X.x(),
               p.X.y(), p.X.z(), p.cameras.size(), 1e3 * p.sigma_max);
  } else {
    study.J = 1e6 * Mat3::Identity();
    study.J_source = "no triangulable sample point: isotropic J for sigma = 1 mm";
  }
  const Information info = DecomposeInformation(study.J);
  const Vec3 r = info.eigenvalues.cwiseInverse();  // per-axis measurement variance, m^2
  const Mat3 V = info.eigenvectors;

  if (scene.study.motion)
    study.cases.push_back({"study", *scene.study.motion});
  else
    study.cases.push_back({"nominal", MotionModel{1.0, 30.0}});
  study.cases.push_back({"fast motion", MotionModel{1e8, 30.0}});
  study.cases.push_back({"1 MHz", MotionModel{1.0, 1e6}});

  const double min_seconds = quick ? 0.01 : 0.05;
  const int kMaxIterations = 1000000;
  const int kRunOnIterations = quick ? 100000 : 1000000;  // the "tol 0" row: no early stop
  for (const SteadyCase& c : study.cases) {
    const double q = c.motion.q, T = 1.0 / c.motion.rate_hz;
    Vec3 reference;
    double reference_check = 0;
    int reference_iterations = 0;
    for (int k = 0; k < 3; ++k) {
      reference[k] = static_cast<double>(ClosedFormLong(q, T, r[k]));
      int its = 0;
      const long double check = DoublingLong(q, T, r[k], &its);
      reference_check = std::max(reference_check,
                                 static_cast<double>(std::fabs(check - ClosedFormLong(q, T, r[k])) /
                                                     ClosedFormLong(q, T, r[k])));
      reference_iterations = std::max(reference_iterations, its);
    }
    auto axis_error = [&](const Vec3& variance) {
      double e = 0;
      for (int k = 0; k < 3; ++k) {
        const double ek = RelativeError(variance[k], reference[k]);
        e = std::isfinite(ek) ? std::max(e, ek) : kNaN;
        if (std::isnan(e)) break;
      }
      return e;
    };
    SteadyRow base;
    base.case_name = c.name;
    base.motion = c.motion;
    base.lambda_min = std::sqrt(q * T * T * T / r.maxCoeff());
    base.lambda_max = std::sqrt(q * T * T * T / r.minCoeff());

    {  // Long-double doubling: how far the reference itself can be trusted.
      SteadyRow row = base;
      row.method = "doubling 2x2 in long double (reference check)";
      row.label = "long-double doubling (check)";
      row.iterations = reference_iterations;
      row.error = reference_check;
      row.seconds = 3 * SecondsPerCall(
                            [&] {
                              int its;
                              return static_cast<double>(DoublingLong(q, T, r[0], &its));
                            },
                            min_seconds);
      study.rows.push_back(row);
    }
    {  // Closed form, three axes.
      SteadyRow row = base;
      row.method = "closed form (ScalarSteadyState x 3)";
      row.label = "closed form";
      Vec3 v;
      for (int k = 0; k < 3; ++k) v[k] = ScalarSteadyState(q, T, r[k])(0, 0);
      row.error = axis_error(v);
      row.seconds = SecondsPerCall(
          [&] {
            return ScalarSteadyState(q, T, r[0])(0, 0) + ScalarSteadyState(q, T, r[1])(0, 0) +
                   ScalarSteadyState(q, T, r[2])(0, 0);
          },
          min_seconds);
      study.rows.push_back(row);
    }
    Eigen::Matrix2d F2, Q2;
    F2 << 1, T, 0, 1;
    Q2 << T * T * T / 3, T * T / 2, T * T / 2, T;
    Q2 *= q;
    std::vector<Eigen::MatrixXd> G2(3, Eigen::MatrixXd::Zero(2, 2));
    for (int k = 0; k < 3; ++k) G2[k](0, 0) = 1.0 / r[k];
    {  // Doubling on the three 2x2 axis problems.
      SteadyRow row = base;
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
      row.error = axis_error(v);
      row.seconds = SecondsPerCall(
          [&] {
            double sum = 0;
            for (int k = 0; k < 3; ++k) {
              const auto M = SolveDareDoubling(F2, G2[k], Q2);
              if (M) sum += PosteriorFromPrior(*M, G2[k])(0, 0);
            }
            return sum;
          },
          min_seconds);
      study.rows.push_back(row);
    }
    const ConstantVelocity6 m6 = MakeConstantVelocity6(study.J, c.motion);
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
      SteadyRow row = base;
      row.method = "doubling 6x6 (tol 1e-15)";
      row.label = "doubling 6x6";
      const std::optional<Eigen::MatrixXd> M =
          SolveDareDoubling(F6, G6, Q6, 1e-15, 100, &row.iterations);
      row.converged = M.has_value();
      row.error = M ? axis_error(project(*M)) : kNaN;
      row.seconds = SecondsPerCall(
          [&] {
            const auto M = SolveDareDoubling(F6, G6, Q6);
            return M ? PosteriorFromPrior(*M, G6)(0, 0) : 0.0;
          },
          min_seconds);
      study.rows.push_back(row);
    }
    for (double tolerance : {1e-4, 1e-8, 1e-12, 0.0}) {  // Plain Riccati iteration on the 6x6.
      SteadyRow row = base;
      row.method = tolerance > 0 ? Format("iteration 6x6 (tol %.0e)", tolerance)
                                 : Format("iteration 6x6 (tol 0: %d steps)", kRunOnIterations);
      row.label = tolerance > 0 ? Format("iteration, tol %.0e", tolerance)
                                : Format("iteration, %.0e steps", double(kRunOnIterations));
      const int max_iterations = tolerance > 0 ? kMaxIterations : kRunOnIterations;
      row.run_on = tolerance == 0;
      const Eigen::MatrixXd M = SolveDareIteration(F6, G6, Q6, tolerance, max_iterations,
                                                   &row.converged, &row.iterations);
      row.error = axis_error(project(M));
      row.seconds = SecondsPerCall(
          [&] {
            const Eigen::MatrixXd Mi = SolveDareIteration(F6, G6, Q6, tolerance, max_iterations);
            return PosteriorFromPrior(Mi, G6)(0, 0);
          },
          min_seconds);
      study.rows.push_back(row);
    }
  }
  return study;
}

// --------------------------------------------------------------------------------------------
// Output.

// Every file of the run goes through one transaction: they appear together at the end.
struct Outputs {
  std::filesystem::path dir;
  std::string markdown;
  std::vector<std::string> written;
  OutputTransaction* transaction = nullptr;
  void Write(const std::string& name, const std::string& text) {
    const std::string path = (dir / name).string();
    transaction->Write(path, "--out", text);
    written.push_back(path);
  }
};

void PrintSection(const std::string& title, const Table& table,
                  const std::vector<std::string>& notes, Outputs* out) {
  std::printf("\n%s\n%s", title.c_str(), table.Text().c_str());
  for (const std::string& n : notes) std::printf("  note: %s\n", n.c_str());
  std::fflush(stdout);
  out->markdown += "## " + title + "\n\n" + table.Markdown();
  for (const std::string& n : notes) out->markdown += "\n- " + n;
  out->markdown += "\n\n";
}

void ReportVoxel(const VoxelStudy& v, Outputs* out) {
  const std::string title =
      "(a) Voxel size against the error of the summaries (reference: the finest size)";
  std::vector<std::string> header{"voxel_size_m",
                                  "factor",
                                  "reference",
                                  "region_voxels",
                                  "triangulable_voxels",
                                  "seconds",
                                  "repeats",
                                  "time_ratio",
                                  "ge1",
                                  "ge2",
                                  "ge3",
                                  "ge1_err_pp",
                                  "ge2_err_pp",
                                  "ge3_err_pp",
                                  "sigma_max_p50_mm",
                                  "sigma_max_p90_mm",
                                  "sigma_max_p50_err_pct",
                                  "sigma_max_p90_err_pct"};
  if (v.steady)
    for (const char* h : {"sigma_max_steady_p50_mm", "sigma_max_steady_p90_mm",
                          "sigma_max_steady_p50_err_pct", "sigma_max_steady_p90_err_pct"})
      header.push_back(h);
  std::vector<std::string> th{"voxel",    "voxels",      "time (s)", "x ref",
                              "|Δ≥1| pp", "|Δ≥2| pp",    "|Δ≥3| pp", "σmax p50 mm",
                              "err %",    "σmax p90 mm", "err %"};
  if (v.steady)
    for (const char* h : {"steady p50 mm", "err %", "steady p90 mm", "err %"}) th.push_back(h);
  Table table(th);
  std::vector<std::vector<std::string>> csv;
  LogLogPlot plot;
  plot.title = "Voxel size: summary error against run time";
  plot.x_label = "evaluation time (s)";
  plot.y_label = "error against the finest size (pp or %)";
  if (v.rows.empty()) {  // not even the coarsest size fits the memory budget
    PrintSection(title, table, v.notes, out);
    out->Write("accuracy_voxel.csv", CsvText(header, csv));
    out->Write("accuracy_voxel.svg", RenderLogLogSvg(plot));
    return;
  }
  const VoxelRow& ref = v.rows.back();
  plot.note = Format("reference: %s voxels; zero errors are not drawn (log axis)",
                     Millimetres(ref.voxel_size).c_str());
  std::vector<PlotSeries> series(v.steady ? 7 : 5);
  series[0].label = "|Δ coverage ≥1| (pp)";
  series[1].label = "|Δ coverage ≥2| (pp)";
  series[2].label = "|Δ coverage ≥3| (pp)";
  series[3].label = "σmax p50 (%)";
  series[4].label = "σmax p90 (%)";
  if (v.steady) {
    series[5].label = "steady σmax p50 (%)";
    series[6].label = "steady σmax p90 (%)";
    series[5].dashed = series[6].dashed = true;  // they lie on the static curves
  }
  for (const VoxelRow& r : v.rows) {
    const bool is_ref = &r == &ref;
    double ge_err[3];
    for (int m = 0; m < 3; ++m) ge_err[m] = 100 * std::fabs(r.ge[m] - ref.ge[m]);
    const double p50e = 100 * RelativeError(r.p50, ref.p50),
                 p90e = 100 * RelativeError(r.p90, ref.p90);
    const double s50e = 100 * RelativeError(r.steady_p50, ref.steady_p50);
    const double s90e = 100 * RelativeError(r.steady_p90, ref.steady_p90);
    std::vector<std::string> row{CsvNumber(r.voxel_size),
                                 CsvNumber(r.factor),
                                 is_ref ? "1" : "0",
                                 std::to_string(r.region_voxels),
                                 std::to_string(r.triangulable_voxels),
                                 CsvNumber(r.seconds),
                                 std::to_string(r.repeats),
                                 CsvNumber(r.seconds / ref.seconds)};
    for (int m = 0; m < 3; ++m) row.push_back(CsvNumber(r.ge[m]));
    for (int m = 0; m < 3; ++m) row.push_back(CsvNumber(ge_err[m]));
    for (double x : {r.p50, r.p90, p50e, p90e}) row.push_back(CsvNumber(x));
    if (v.steady)
      for (double x : {r.steady_p50, r.steady_p90, s50e, s90e}) row.push_back(CsvNumber(x));
    csv.push_back(row);
    std::vector<std::string> cells{Millimetres(r.voxel_size) + (is_ref ? " (ref)" : ""),
                                   std::to_string(r.region_voxels), Format("%.3g", r.seconds),
                                   Format("%.3g", r.seconds / ref.seconds)};
    for (int m = 0; m < 3; ++m) cells.push_back(Cell("%.2f", ge_err[m]));
    cells.push_back(Cell("%.4f", r.p50));
    cells.push_back(Cell("%.2f", p50e));
    cells.push_back(Cell("%.4f", r.p90));
    cells.push_back(Cell("%.2f", p90e));
    if (v.steady) {
      cells.push_back(Cell("%.4f", r.steady_p50));
      cells.push_back(Cell("%.2f", s50e));
      cells.push_back(Cell("%.4f", r.steady_p90));
      cells.push_back(Cell("%.2f", s90e));
    }
    table.AddRow(cells);
    if (is_ref) continue;
    const double errors[7] = {ge_err[0], ge_err[1], ge_err[2], p50e, p90e, s50e, s90e};
    for (std::size_t s = 0; s < series.size(); ++s) {
      series[s].x.push_back(r.seconds);
      series[s].y.push_back(errors[s]);
      series[s].point_labels.push_back(s == 3 ? Millimetres(r.voxel_size) : "");
    }
  }
  plot.series = series;
  plot.vertical_lines.push_back({ref.seconds, "reference " + Millimetres(ref.voxel_size)});
  PrintSection(title, table, v.notes, out);
  out->Write("accuracy_voxel.csv", CsvText(header, csv));
  out->Write("accuracy_voxel.svg", RenderLogLogSvg(plot));
}

void ReportMonteCarlo(const MonteCarloStudy& mc, Outputs* out) {
  const std::vector<std::string> header{"trials",
                                        "points",
                                        "seconds_per_point",
                                        "sigma_max_rel_err_mean_pct",
                                        "sigma_max_rel_err_max_pct",
                                        "frobenius_rel_err_mean_pct",
                                        "frobenius_rel_err_max_pct",
                                        "failures",
                                        "prediction_seconds_per_point",
                                        "time_ratio_to_prediction"};
  Table table({"trials", "points", "time/point (s)", "σmax err mean %", "max %", "Frobenius mean %",
               "max %", "failures", "x prediction"});
  std::vector<std::vector<std::string>> csv;
  PlotSeries rel, frob, guide;
  rel.label = "σmax rel. error (mean)";
  frob.label = "Frobenius rel. error (mean)";
  guide.label = "1/sqrt(πN) (expected σ error)";
  guide.markers = false;
  guide.dashed = true;
  for (const MonteCarloRow& r : mc.rows) {
    const double ratio = r.seconds_per_point / mc.prediction_seconds;
    csv.push_back({std::to_string(r.trials), std::to_string(r.points),
                   CsvNumber(r.seconds_per_point), CsvNumber(100 * r.rel_mean),
                   CsvNumber(100 * r.rel_max), CsvNumber(100 * r.frob_mean),
                   CsvNumber(100 * r.frob_max), std::to_string(r.failures),
                   CsvNumber(mc.prediction_seconds), CsvNumber(ratio)});
    table.AddRow({std::to_string(r.trials), std::to_string(r.points),
                  Format("%.3g", r.seconds_per_point), Format("%.2f", 100 * r.rel_mean),
                  Format("%.2f", 100 * r.rel_max), Format("%.2f", 100 * r.frob_mean),
                  Format("%.2f", 100 * r.frob_max), std::to_string(r.failures),
                  Format("%.3g", ratio)});
    rel.x.push_back(r.seconds_per_point);
    rel.y.push_back(100 * r.rel_mean);
    rel.point_labels.push_back(Format("N=%d", r.trials));
    rel.labels_below = true;
    frob.x.push_back(r.seconds_per_point);
    frob.y.push_back(100 * r.frob_mean);
    guide.x.push_back(r.seconds_per_point);
    guide.y.push_back(100 / std::sqrt(M_PI * r.trials));
  }
  table.AddRow({"prediction", std::to_string(mc.points.size()), Cell("%.3g", mc.prediction_seconds),
                "(reference)", "", "", "", "", "1"});
  std::vector<std::string> notes = mc.notes;
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  notes.push_back(Format(
      "pixel sigma %.3g px; Monte Carlo runs its trials on %d threads (wall time), the prediction "
      "(Jacobians, J, eigen-decomposition, J^-1) on one",
      mc.sigma_px, threads));
  if (std::isfinite(mc.seconds_for_1pct))
    notes.push_back(Format(
        "1%% mean sigma_max error (fitted power law): Monte Carlo %.3g s per point, %.3g x the "
        "prediction's %.3g us",
        mc.seconds_for_1pct, mc.seconds_for_1pct / mc.prediction_seconds,
        1e6 * mc.prediction_seconds));
  for (const SamplePoint& p : mc.points)
    notes.push_back(Format("point (%.3f, %.3f, %.3f) m: %zu cameras, predicted sigma_max %.4f mm",
                           p.X.x(), p.X.y(), p.X.z(), p.cameras.size(), 1e3 * p.sigma_max));
  PrintSection(
      "(b) Monte Carlo trials against the error of sigma (reference: the closed-form J^-1)", table,
      notes, out);
  LogLogPlot plot;
  plot.title = "Monte Carlo covariance against the closed-form prediction";
  plot.x_label = "time per point (s)";
  plot.y_label = "relative error against J^-1 (%)";
  plot.note = Format("mean over %zu sample points seen by >= 2 cameras; %d threads",
                     mc.points.size(), threads);
  plot.series = {rel, frob, guide};
  if (std::isfinite(mc.prediction_seconds))
    plot.vertical_lines.push_back(
        {mc.prediction_seconds, Format("prediction %.2g µs", 1e6 * mc.prediction_seconds)});
  out->Write("accuracy_montecarlo.csv", CsvText(header, csv));
  out->Write("accuracy_montecarlo.svg", RenderLogLogSvg(plot));
}

void ReportSteady(const SteadyStudy& st, Outputs* out) {
  const std::vector<std::string> header{
      "case",   "q_m2_s3",    "rate_hz",   "tracking_index_min", "tracking_index_max",
      "method", "iterations", "converged", "seconds_per_voxel",  "rel_err"};
  Table table({"case", "q m²/s³", "rate Hz", "Λ min..max", "method", "iter.", "conv.",
               "time/voxel (s)", "rel. error"},
              "lrrrlrlrr");
  std::vector<std::vector<std::string>> csv;
  LogLogPlot plot;
  plot.title = "Steady-state solvers: error against time";
  plot.x_label = "time per voxel, 3 axes (s)";
  plot.y_label = "relative error of the posterior position variance";
  constexpr double kFloor = 1e-17;
  plot.note = "reference: the closed form in long double; errors below 1e-17 are drawn at 1e-17";
  // Colour: the method; marker shape: the case. Legend-only keys for both.
  std::vector<std::string> methods;  // plot labels, in table order
  for (const SteadyRow& r : st.rows)
    if (std::find(methods.begin(), methods.end(), r.label) == methods.end())
      methods.push_back(r.label);
  constexpr const char* kMethodColors[] = {"#7f7f7f", "#1f77b4", "#2ca02c", "#17becf", "#ff7f0e",
                                           "#d62728", "#9467bd", "#8c564b", "#e377c2", "#bcbd22"};
  auto method_color = [&](const std::string& m) {
    const std::size_t i = std::find(methods.begin(), methods.end(), m) - methods.begin();
    return std::string(kMethodColors[i % 10]);
  };
  for (std::size_t ci = 0; ci < st.cases.size(); ++ci)
    for (const SteadyRow& r : st.rows) {
      if (r.case_name != st.cases[ci].name) continue;
      PlotSeries s;
      s.line = false;
      s.in_legend = false;
      s.color = method_color(r.label);
      s.shape = static_cast<int>(ci);
      s.x.push_back(r.seconds);
      s.y.push_back(std::isfinite(r.error) ? std::max(r.error, kFloor) : kNaN);
      plot.series.push_back(s);
    }
  for (const std::string& m : methods) {
    PlotSeries key;
    key.label = m;
    key.markers = false;
    key.color = method_color(m);
    plot.series.push_back(key);
  }
  for (std::size_t ci = 0; ci < st.cases.size(); ++ci) {
    PlotSeries key;
    key.label = st.cases[ci].name +
                Format(" (q %g, %g Hz)", st.cases[ci].motion.q, st.cases[ci].motion.rate_hz);
    key.line = false;
    key.color = "#444";
    key.shape = static_cast<int>(ci);
    plot.series.push_back(key);
  }
  for (const SteadyRow& r : st.rows) {
    csv.push_back({r.case_name, CsvNumber(r.motion.q), CsvNumber(r.motion.rate_hz),
                   CsvNumber(r.lambda_min), CsvNumber(r.lambda_max), r.method,
                   std::to_string(r.iterations), r.converged ? "1" : "0", CsvNumber(r.seconds),
                   CsvNumber(r.error)});
    table.AddRow({r.case_name, Format("%g", r.motion.q), Format("%g", r.motion.rate_hz),
                  Format("%.2g..%.2g", r.lambda_min, r.lambda_max), r.method,
                  r.iterations ? std::to_string(r.iterations) : "-",
                  r.run_on      ? "-"
                  : r.converged ? "yes"
                                : "NO",
                  Format("%.3g", r.seconds), Cell("%.2g", r.error)});
  }
  std::vector<std::string> notes = st.notes;
  notes.push_back(st.J_source);
  notes.push_back(
      "error: largest over the three eigen-directions of J of |variance - reference| / reference, "
      "posterior position variance; reference: the closed form evaluated in long double");
  PrintSection("(c) Steady-state solvers (per voxel: three axes)", table, notes, out);
  out->Write("accuracy_steady.csv", CsvText(header, csv));
  out->Write("accuracy_steady.svg", RenderLogLogSvg(plot));
}

}  // namespace

int RunAccuracy(const AccuracyArgs& args) {
  const Clock::time_point start = Clock::now();
  Scene scene = LoadScene(args.scene);
  const Rig rig = FindRigOption(scene, args.rig);
  OutputTransaction output;
  AddSceneInputs(output, scene);
  // Staged first, so that a bad --out fails before minutes of work; written last.
  const std::string tables_path =
      output.Stage((std::filesystem::path(args.out) / "accuracy_tables.md").string(), "--out");
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  std::printf(
      "accuracy: %s, rig %s (%d cameras), study voxel %s, pixel sigma %.3g px, %d threads%s\n",
      scene.path.c_str(), rig.name.c_str(), rig.enabled_count(),
      Millimetres(scene.study.voxel_size).c_str(), scene.study.pixel_sigma, threads,
      args.quick ? ", quick" : "");
  std::fflush(stdout);
  const std::unique_ptr<RayCaster> caster = MakeEmbreeRayCaster(scene.AllTriangles());

  Outputs out;
  out.dir = args.out;
  out.transaction = &output;
  out.markdown = Format("# pandora accuracy: %s, rig %s\n\n", scene.path.c_str(), rig.name.c_str());

  const VoxelStudy voxel = RunVoxelStudy(scene, rig, *caster, args.quick, threads);
  ReportVoxel(voxel, &out);
  const MonteCarloStudy mc = RunMonteCarloStudy(scene, rig, *caster, args.quick);
  ReportMonteCarlo(mc, &out);
  const SteadyStudy steady = RunSteadyStudy(scene, mc, args.quick);
  ReportSteady(steady, &out);

  WriteFileAtomically(tables_path, out.markdown);
  out.written.push_back(tables_path);
  output.Commit();
  std::printf("\n%.1f s; wrote", SecondsSince(start));
  for (const std::string& path : out.written)
    std::printf(" %s", std::filesystem::path(path).filename().c_str());
  std::printf(" in %s\n", args.out.c_str());
  return 0;
}

}  // namespace pandora::app
