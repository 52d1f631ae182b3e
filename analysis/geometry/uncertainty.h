#pragma once
/// \file uncertainty.h
/// Triangulation uncertainty of a point from the cameras that see it: the static (single-frame)
/// covariance and the steady-state covariance of a constant-velocity Kalman filter
/// (Artemis-style). Double precision; metres, seconds; covariances in m^2.
///
/// Measurement model. Camera i observes X through its distorted projection with isotropic pixel
/// noise sigma_i (pixels); linearised at X with the 2x3 Jacobian A_i (pixels per metre), the
/// information (Fisher) matrix of one synchronous frame is
///     J = sum_i A_i^T A_i / sigma_i^2            [1/m^2]
/// and the static covariance is Cov = J^-1. J is symmetric positive semi-definite; each camera adds
/// rank 2 (nothing along its viewing ray), so two cameras with distinct centres make it full rank.

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora {

/// Eigen-decomposition of an information matrix, with the observability decision.
struct Information {
  Mat3 J = Mat3::Zero();                 ///< sum_i A_i^T A_i / sigma_i^2, 1/m^2.
  Vec3 eigenvalues = Vec3::Zero();       ///< Ascending, clipped at 0 (round-off).
  Mat3 eigenvectors = Mat3::Identity();  ///< Columns, orthonormal, matching eigenvalues.
  /// True when every eigenvalue exceeds kRelativeObservability times the largest: the point can be
  /// located in all three directions.
  bool observable = false;
};

/// A direction whose information is below this fraction of the largest is unobservable: it lies
/// beyond double precision's reach (the covariance would be dominated by round-off in J).
inline constexpr double kRelativeObservability = 1e-12;

/// Decomposes a symmetric information matrix J (1/m^2). Uses the closed-form 3x3 solver and, when J
/// is stiff (smallest over largest eigenvalue below 1e-8), the iterative QL solver, whose small
/// eigenvalues are more accurate there. With `eigenvectors` false only eigenvalues are computed.
Information DecomposeInformation(const Mat3& J, bool eigenvectors = true);

/// R_camera_from_world / sigma_px, row-major (nine doubles): the whitened rotation with which
/// AddCameraInformation turns a camera-frame projection Jacobian into information.
inline void WhitenedRotation(const Mat3& R_camera_from_world, double sigma_px, double out[9]) {
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) out[3 * r + k] = R_camera_from_world(r, k) / sigma_px;
}

/// J += A^T A with A = Jc Rw (Rw from WhitenedRotation; Jc = d pixel / d camera-frame point), on
/// J's upper triangle I = (xx, xy, xz, yy, yz, zz). The one accumulation the volume fields and the
/// per-point evaluation share, written out in scalars (it runs once per seen voxel-camera pair).
inline void AddCameraInformation(const Mat23& Jc, const double Rw[9], double I[6]) {
  const double a00 = Jc(0, 0) * Rw[0] + Jc(0, 1) * Rw[3] + Jc(0, 2) * Rw[6];
  const double a01 = Jc(0, 0) * Rw[1] + Jc(0, 1) * Rw[4] + Jc(0, 2) * Rw[7];
  const double a02 = Jc(0, 0) * Rw[2] + Jc(0, 1) * Rw[5] + Jc(0, 2) * Rw[8];
  const double a10 = Jc(1, 0) * Rw[0] + Jc(1, 1) * Rw[3] + Jc(1, 2) * Rw[6];
  const double a11 = Jc(1, 0) * Rw[1] + Jc(1, 1) * Rw[4] + Jc(1, 2) * Rw[7];
  const double a12 = Jc(1, 0) * Rw[2] + Jc(1, 1) * Rw[5] + Jc(1, 2) * Rw[8];
  I[0] += a00 * a00 + a10 * a10;
  I[1] += a00 * a01 + a10 * a11;
  I[2] += a00 * a02 + a10 * a12;
  I[3] += a01 * a01 + a11 * a11;
  I[4] += a01 * a02 + a11 * a12;
  I[5] += a02 * a02 + a12 * a12;
}

/// Eigenvalues of n symmetric 3x3 matrices at once, for the field evaluation's per-block pass.
/// `upper` holds six arrays of n entries each (xx, xy, xz, yy, yz, zz); `values` receives three
/// arrays of n (ascending: smallest, middle, largest). Cyclic Jacobi rotations with a fixed number
/// of sweeps on the matrix scaled by its largest diagonal entry, one branch-free loop vectorised
/// over the matrices (AVX-512 / AVX2 chosen at run time). Accurate to about 1e-15 of the largest
/// eigenvalue at every conditioning, double roots included (where the closed form in
/// DecomposeInformation is good to about sqrt(eps)). `converged[i]` is set to 0 where the
/// off-diagonal part did not fall below 1e-15 of the diagonal; those values come from
/// DecomposeInformation instead. Values are not clipped.
void SymmetricEigenvalues3(const double* const upper[6], double* const values[3],
                           unsigned char* converged, std::size_t n);

/// Accumulates J from per-camera Jacobians and pixel sigmas, then decomposes it.
class InformationBuilder {
 public:
  /// Adds a camera's 2x3 Jacobian (pixels per metre) with its pixel noise sigma (pixels, > 0).
  void Add(const Mat23& d_pixel_d_world, double sigma_px);
  int cameras() const { return cameras_; }
  /// DecomposeInformation of the accumulated J.
  Information Decompose() const { return DecomposeInformation(J_); }

 private:
  Mat3 J_ = Mat3::Zero();
  int cameras_ = 0;
};

/// Static (single-frame) position uncertainty.
struct StaticUncertainty {
  bool triangulable = false;       ///< >= 2 cameras and J observable in all directions.
  Mat3 covariance = Mat3::Zero();  ///< J^-1 from the eigen-decomposition, m^2 (when triangulable).
  double sigma_max = 0;            ///< sqrt(largest eigenvalue of Cov): worst-direction 1-sigma, m.
  double sigma_mean = 0;           ///< sqrt(trace(Cov) / 3), m.
  double condition = 0;            ///< Largest over smallest eigenvalue of J (>= 1).
};

/// Cov = J^-1 computed as V diag(1/lambda) V^T. Not triangulable (all values 0) when fewer than two
/// cameras contributed or a direction is unobservable; never a pseudo-inverse (that would report
/// zero variance along the unobserved direction, the opposite of the truth).
StaticUncertainty StaticFromInformation(const Information& info, int cameras);

/// Constant-velocity motion model: white acceleration of spectral density q (m^2/s^3) per axis,
/// isotropic, and all cameras sampling together at `rate_hz`.
struct MotionModel {
  double q = 1.0;         ///< m^2/s^3, >= 0.
  double rate_hz = 60.0;  ///< > 0.
};

/// Steady-state position covariance of the Kalman filter for one scalar axis with per-frame
/// position measurement variance r (m^2): F = [1 T; 0 1], Q = q [T^3/3 T^2/2; T^2/2 T], H = [1 0].
/// Returns the 2x2 posterior (after the update; `prior` = false) or prior (before it) covariance of
/// (position, velocity). Closed form: with Lambda^2 = q T^3 / r the gains are alpha = 1 - u^2,
/// beta = Lambda u, where u + 1/u = (Lambda + sqrt(Lambda^2 / 3 + 16)) / 2 (docs/uncertainty.md
/// derives it); evaluated without cancellation for every q >= 0 and rate > 0. r = +inf (no
/// measurement) gives an infinite covariance (no steady state).
Eigen::Matrix2d ScalarSteadyState(double q, double T, double r, bool prior = false);

/// ScalarSteadyState(q, T, r, prior)(0, 0), the position variance alone (m^2); the posterior costs
/// three square roots and no matrix.
double SteadyPositionVariance(double q, double T, double r, bool prior = false);

/// SteadyPositionVariance for many finite measurement variances at once: out[i] for r[i] (both m^2,
/// n entries, out may alias r). The same closed form as one branch-free loop that the compiler
/// vectorises (AVX-512 or AVX2 where the CPU has them, chosen at run time): the field evaluation
/// calls it once per block.
void SteadyPositionVariances(double q, double T, const double* r, double* out, std::size_t n,
                             bool prior = false);

/// Steady-state uncertainty: per eigen-direction of J the scalar problem above, recombined.
struct SteadyUncertainty {
  bool converged = false;          ///< False when not triangulable.
  Mat3 covariance = Mat3::Zero();  ///< Position block, m^2.
  double sigma_max = 0, sigma_mean = 0;
};

/// The steady-state position covariance for a point with information `info` under `motion`.
/// With isotropic process noise and synchronous cameras the 6x6 problem decouples along the
/// eigenvectors of J into three scalar position-velocity problems (measurement variance
/// 1/lambda_k).
SteadyUncertainty SteadyFromInformation(const Information& info, int cameras,
                                        const MotionModel& motion, bool prior = false);

/// The general discrete algebraic Riccati equation of filtering, solved by the structure-preserving
/// doubling algorithm (Chu, Fan and Lin 2005): the steady prior covariance M of
///   M = F (M - M H^T (H M H^T + R)^-1 H M) F^T + Q,
/// given G = H^T R^-1 H (information per step, n x n) instead of H and R. Converges quadratically
/// when the closed loop is stable. Returns nullopt when it has not converged within
/// `max_iterations` (relative change below `tolerance`).
std::optional<Eigen::MatrixXd> SolveDareDoubling(const Eigen::MatrixXd& F, const Eigen::MatrixXd& G,
                                                 const Eigen::MatrixXd& Q, double tolerance = 1e-15,
                                                 int max_iterations = 100,
                                                 int* iterations = nullptr);

/// Plain Riccati iteration from M = Q (the reference where it converges; slow when stiff).
/// Returns the last iterate and, in `converged`, whether the change of every entry relative to its
/// own scale (|dM_ij| / sqrt(M_ii M_jj)) stayed below `tolerance` for three steps in a row.
Eigen::MatrixXd SolveDareIteration(const Eigen::MatrixXd& F, const Eigen::MatrixXd& G,
                                   const Eigen::MatrixXd& Q, double tolerance, int max_iterations,
                                   bool* converged = nullptr, int* iterations = nullptr);

/// The full 6x6 constant-velocity model for a 3D point (state: position, velocity), for the general
/// solvers and tests: F = [I T I; 0 I], Q = q [T^3/3 I, T^2/2 I; T^2/2 I, T I], G = [J 0; 0 0].
struct ConstantVelocity6 {
  Eigen::Matrix<double, 6, 6> F, Q, G;
};
ConstantVelocity6 MakeConstantVelocity6(const Mat3& J, const MotionModel& motion);

/// Posterior from prior for the 6x6 model: P = (M^-1 + G)^-1, computed as M - M H^T(...)H M stably
/// via (I + M G)^-1 M.
Eigen::MatrixXd PosteriorFromPrior(const Eigen::MatrixXd& M, const Eigen::MatrixXd& G);

/// Largest angle (radians) between two of the given viewing directions (unit vectors from the
/// cameras to the point); 0 with fewer than two.
double MaxTriangulationAngle(const std::vector<Vec3>& directions);

}  // namespace pandora
