#pragma once
/// \file triangulation.h
/// Nonlinear least-squares triangulation of one point from several cameras, and the Monte Carlo
/// check of the predicted triangulation covariance (analysis/geometry/uncertainty.h) against it.
///
/// Plain interface: Ceres is used by the implementation (analysis/geometry/triangulation_ceres.cpp)
/// only. Double precision; world frame, metres; pixels as Camera::Project (distorted, OpenCV
/// convention).

#include <cstdint>
#include <optional>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/geometry.h"

namespace pandora {

/// Stopping rules of the Levenberg-Marquardt solve (Ceres' meanings).
struct TriangulationOptions {
  /// Stop when |cost change| < function_tolerance * cost (relative).
  double function_tolerance = 1e-14;
  /// Stop when the max-norm of the gradient step falls below this (absolute, in units of the
  /// whitened cost per metre).
  double gradient_tolerance = 1e-14;
  /// Stop when |step| <= parameter_tolerance * (|X| + parameter_tolerance) (relative, metres).
  double parameter_tolerance = 1e-12;
  /// Iterations of Levenberg-Marquardt; hitting the limit counts as failure.
  int max_iterations = 50;

  /// True when every tolerance is >= 0 and max_iterations > 0.
  bool Check() const {
    return function_tolerance >= 0 && gradient_tolerance >= 0 && parameter_tolerance >= 0 &&
           max_iterations > 0;
  }
};

/// The maximum-likelihood point under isotropic Gaussian pixel noise: minimizes
///     sum_i || (Project_i(X) - pixels[i]) / sigmas_px[i] ||^2
/// over the world point X (metres) by Levenberg-Marquardt (Ceres, dense QR, analytic Jacobians from
/// Camera::Project), starting at `initial`. `pixels[i]` is the observed distorted pixel in camera
/// i.
///
/// Returns nullopt when fewer than two cameras are given, when `initial` or the final estimate does
/// not project in every camera (Camera::Project returns nullopt: behind the camera or beyond the
/// lens's monotonic domain), or when Ceres does not report convergence (failure, or the iteration
/// limit). A trial step that leaves some camera's domain is rejected and the step shrinks, as
/// Levenberg-Marquardt does for any failed evaluation; it does not end the solve. Image bounds and
/// working ranges are not checked: the estimate is a point, not an observation.
/// Throws std::invalid_argument when the three vectors differ in size, a sigma is not > 0, or
/// `options.Check()` fails. Thread-safe (no shared state).
std::optional<Vec3> TriangulatePoint(const std::vector<Camera>& cameras,
                                     const std::vector<Vec2>& pixels,
                                     const std::vector<double>& sigmas_px, const Vec3& initial,
                                     const TriangulationOptions& options = {});

/// Empirical against predicted covariance of a triangulated point.
struct MonteCarloResult {
  /// Sample covariance of the successful estimates about their sample mean (divisor n - 1), m^2.
  Mat3 empirical_covariance = Mat3::Zero();
  /// J^-1 from InformationBuilder / StaticFromInformation at the true point, m^2.
  Mat3 predicted_covariance = Mat3::Zero();
  /// Sample mean of the estimates minus the true point, m: the estimator's bias (O(sigma^2) from
  /// the curvature of the projections) plus its sampling error (~ sigma_max / sqrt(trials)).
  Vec3 mean_minus_true = Vec3::Zero();
  /// sqrt(largest eigenvalue) of each covariance: the worst-direction 1-sigma, m.
  double sigma_max_empirical = 0, sigma_max_predicted = 0;
  /// |sigma_max_empirical - sigma_max_predicted| / sigma_max_predicted.
  double relative_error = 0;
  /// ||empirical - predicted||_F / ||predicted||_F.
  double frobenius_relative_error = 0;
  int trials = 0;  ///< Trials run.
  int failures =
      0;  ///< Trials where TriangulatePoint returned nullopt (excluded from the statistics).
  double seconds = 0;  ///< Wall time of the whole call.
};

/// Monte Carlo validation of the predicted covariance at the world point X (metres).
///
/// Each trial adds independent N(0, sigma_px^2) noise to both coordinates of every true pixel
/// Project_i(X), then triangulates with TriangulatePoint (every sigma = sigma_px), starting from
/// the true X: the estimator studied is the local minimum nearest the truth, which is what the
/// linearised prediction describes (a real pipeline would start from a linear DLT estimate; at
/// pixel-level noise it converges to the same minimum). The empirical covariance is taken about
/// the sample mean, the standard unbiased estimator: the prediction J^-1 is a covariance, and the
/// small bias of the nonlinear estimator is reported separately (mean_minus_true) rather than
/// folded into the spread. Its statistical error shrinks like 1/sqrt(trials) (about sqrt(2 /
/// trials) relative for a variance).
///
/// Trial k draws its noise from a std::mt19937_64 seeded from (seed, k) alone, and the estimates
/// are reduced in trial order, so the result does not depend on the number of threads (TBB) and is
/// reproducible bit for bit on one platform.
///
/// `cameras` should be those that see X (the caller decides visibility; every one must project X).
/// Throws std::invalid_argument when some camera does not project X, when the point is not
/// triangulable from them (fewer than two cameras, or a direction without information), when
/// sigma_px <= 0, or when trials < 2. When fewer than two trials succeed the empirical statistics
/// stay zero and both relative errors are +infinity.
/// `offsets` (if given) receives every successful estimate minus X, in trial order (for statistics
/// beyond the covariance: the skew of the errors, their distribution).
MonteCarloResult MonteCarloCovariance(const std::vector<Camera>& cameras, const Vec3& X,
                                      double sigma_px, int trials, uint64_t seed,
                                      const TriangulationOptions& options = {},
                                      std::vector<Vec3>* offsets = nullptr);

}  // namespace pandora
