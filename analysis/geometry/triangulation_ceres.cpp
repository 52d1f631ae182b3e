// Triangulation by nonlinear least squares with Ceres, and the Monte Carlo covariance check. The
// only translation unit that includes Ceres for triangulation; the header is plain.
#include <ceres/ceres.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>

#include "analysis/geometry/triangulation.h"
#include "analysis/geometry/uncertainty.h"

namespace pandora {
namespace {

// Whitened reprojection residual of one camera: r = (Project(X) - pixel) / sigma, with the analytic
// Jacobian d r / d X = (d pixel / d X) / sigma from Camera::Project. Fails (returns false) where X
// does not project; Levenberg-Marquardt then rejects the step.
class ReprojectionCost final : public ceres::SizedCostFunction<2, 3> {
 public:
  ReprojectionCost(const Camera& camera, const Vec2& pixel, double sigma_px)
      : camera_(camera), pixel_(pixel), inv_sigma_(1.0 / sigma_px) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Vec3> X(parameters[0]);
    const bool want_jacobian = jacobians != nullptr && jacobians[0] != nullptr;
    Mat23 d_pixel_d_world;
    const std::optional<Vec2> pixel =
        camera_.Project(X, want_jacobian ? &d_pixel_d_world : nullptr);
    if (!pixel) return false;
    Eigen::Map<Vec2> r(residuals);
    r = (*pixel - pixel_) * inv_sigma_;
    if (want_jacobian) {
      // Ceres wants row-major 2x3.
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> dr_dX(jacobians[0]);
      dr_dX = d_pixel_d_world * inv_sigma_;
    }
    return true;
  }

 private:
  const Camera& camera_;
  Vec2 pixel_;
  double inv_sigma_;
};

// SplitMix64 finaliser: a bijective 64-bit mix, so (seed, trial) pairs give well-spread seeds.
uint64_t Mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

double SigmaMax(const Mat3& covariance) {
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(covariance, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

}  // namespace

std::optional<Vec3> TriangulatePoint(const std::vector<Camera>& cameras,
                                     const std::vector<Vec2>& pixels,
                                     const std::vector<double>& sigmas_px, const Vec3& initial,
                                     const TriangulationOptions& options) {
  if (pixels.size() != cameras.size() || sigmas_px.size() != cameras.size())
    throw std::invalid_argument("TriangulatePoint: " + std::to_string(cameras.size()) +
                                " cameras, " + std::to_string(pixels.size()) + " pixels and " +
                                std::to_string(sigmas_px.size()) +
                                " sigmas: give one pixel and one sigma per camera");
  for (double s : sigmas_px)
    if (!(s > 0))
      throw std::invalid_argument("TriangulatePoint: pixel sigma " + std::to_string(s) +
                                  " is not > 0");
  if (!options.Check())
    throw std::invalid_argument("TriangulatePoint: tolerances must be >= 0 and max_iterations > 0");
  if (cameras.size() < 2) return std::nullopt;
  for (const Camera& camera : cameras)
    if (!camera.Project(initial)) return std::nullopt;

  // The cost functions outlive the problem, which does not own them.
  std::vector<std::unique_ptr<ReprojectionCost>> costs;
  costs.reserve(cameras.size());
  for (std::size_t i = 0; i < cameras.size(); ++i)
    costs.push_back(std::make_unique<ReprojectionCost>(cameras[i], pixels[i], sigmas_px[i]));

  double X[3] = {initial.x(), initial.y(), initial.z()};
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (const auto& cost : costs) problem.AddResidualBlock(cost.get(), nullptr, X);

  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.gradient_tolerance = options.gradient_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;

  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  if (summary.termination_type != ceres::CONVERGENCE) return std::nullopt;

  const Vec3 estimate(X[0], X[1], X[2]);
  if (!estimate.allFinite()) return std::nullopt;
  for (const Camera& camera : cameras)
    if (!camera.Project(estimate)) return std::nullopt;
  return estimate;
}

MonteCarloResult MonteCarloCovariance(const std::vector<Camera>& cameras, const Vec3& X,
                                      double sigma_px, int trials, uint64_t seed,
                                      const TriangulationOptions& options,
                                      std::vector<Vec3>* offsets) {
  const auto start = std::chrono::steady_clock::now();
  if (!(sigma_px > 0))
    throw std::invalid_argument("MonteCarloCovariance: sigma_px " + std::to_string(sigma_px) +
                                " is not > 0");
  if (trials < 2)
    throw std::invalid_argument("MonteCarloCovariance: " + std::to_string(trials) +
                                " trials; a covariance needs at least 2");

  // True pixels and the predicted covariance, both at the true point.
  const std::size_t n = cameras.size();
  std::vector<Vec2> true_pixels(n);
  InformationBuilder builder;
  for (std::size_t i = 0; i < n; ++i) {
    Mat23 d_pixel_d_world;
    const std::optional<Vec2> pixel = cameras[i].Project(X, &d_pixel_d_world);
    if (!pixel)
      throw std::invalid_argument("MonteCarloCovariance: camera '" + cameras[i].id +
                                  "' does not project the point; pass only cameras that see it");
    true_pixels[i] = *pixel;
    builder.Add(d_pixel_d_world, sigma_px);
  }
  const StaticUncertainty predicted = StaticFromInformation(builder.Decompose(), builder.cameras());
  if (!predicted.triangulable)
    throw std::invalid_argument("MonteCarloCovariance: the point is not triangulable from these " +
                                std::to_string(n) +
                                " cameras (fewer than two, or a direction without information)");

  // Trials in parallel; each writes its own slot, so the reduction below runs in trial order.
  const std::vector<double> sigmas(n, sigma_px);
  std::vector<Vec3> estimates(static_cast<std::size_t>(trials), Vec3::Zero());
  std::vector<uint8_t> ok(static_cast<std::size_t>(trials), 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, trials), [&](const tbb::blocked_range<int>& range) {
    std::vector<Vec2> noisy(n);
    for (int k = range.begin(); k != range.end(); ++k) {
      std::mt19937_64 rng(Mix64(Mix64(seed) ^ static_cast<uint64_t>(k)));
      std::normal_distribution<double> noise(0.0, sigma_px);
      for (std::size_t i = 0; i < n; ++i) {
        const double du = noise(rng);
        const double dv = noise(rng);
        noisy[i] = true_pixels[i] + Vec2(du, dv);
      }
      const std::optional<Vec3> estimate = TriangulatePoint(cameras, noisy, sigmas, X, options);
      if (estimate) {
        estimates[k] = *estimate;
        ok[k] = 1;
      }
    }
  });

  MonteCarloResult result;
  result.trials = trials;
  result.predicted_covariance = predicted.covariance;
  result.sigma_max_predicted = predicted.sigma_max;
  // Two passes on offsets from X (small numbers, in metres: no cancellation against |X|).
  int good = 0;
  Vec3 sum = Vec3::Zero();
  for (int k = 0; k < trials; ++k) {
    if (!ok[k]) continue;
    sum += estimates[k] - X;
    ++good;
  }
  result.failures = trials - good;
  if (offsets) {
    offsets->clear();
    offsets->reserve(static_cast<std::size_t>(good));
    for (int k = 0; k < trials; ++k)
      if (ok[k]) offsets->push_back(estimates[k] - X);
  }
  if (good >= 2) {
    const Vec3 mean_offset = sum / good;
    Mat3 scatter = Mat3::Zero();
    for (int k = 0; k < trials; ++k) {
      if (!ok[k]) continue;
      const Vec3 d = estimates[k] - X - mean_offset;
      scatter.noalias() += d * d.transpose();
    }
    result.empirical_covariance = scatter / (good - 1);
    result.mean_minus_true = mean_offset;
    result.sigma_max_empirical = SigmaMax(result.empirical_covariance);
    result.relative_error = std::abs(result.sigma_max_empirical - result.sigma_max_predicted) /
                            result.sigma_max_predicted;
    result.frobenius_relative_error =
        (result.empirical_covariance - result.predicted_covariance).norm() /
        result.predicted_covariance.norm();
  } else {
    result.relative_error = std::numeric_limits<double>::infinity();
    result.frobenius_relative_error = std::numeric_limits<double>::infinity();
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace pandora
