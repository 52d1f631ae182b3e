#include "analysis/geometry/uncertainty.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

namespace pandora {

void InformationBuilder::Add(const Mat23& A, double sigma_px) {
  J_.noalias() += A.transpose() * A / (sigma_px * sigma_px);
  ++cameras_;
}

Information DecomposeInformation(const Mat3& J, bool eigenvectors) {
  Information info;
  info.J = 0.5 * (J + J.transpose());
  // The closed-form 3x3 solver, or the iterative QL solver when J is stiff or singular (there the
  // closed form loses relative accuracy on the small eigenvalue).
  const int options = eigenvectors ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly;
  Eigen::SelfAdjointEigenSolver<Mat3> solver;
  solver.computeDirect(info.J, options);
  if (!(solver.eigenvalues()[0] > 1e-8 * solver.eigenvalues()[2])) solver.compute(info.J, options);
  const Vec3 values = solver.eigenvalues();
  if (eigenvectors) info.eigenvectors = solver.eigenvectors();
  info.eigenvalues = values.cwiseMax(0.0);
  const double largest = info.eigenvalues[2];
  info.observable = largest > 0 && std::isfinite(largest) &&
                    info.eigenvalues[0] > kRelativeObservability * largest;
  return info;
}

namespace {

// One Jacobi rotation zeroing a_pq; r is the third index. Branch-free: a_pq = 0 with a_pp = a_qq
// gives t = 0 (the denominator's tiny term), no rotation.
// By value, unlike std::min/max: references to temporaries stop GCC's vectoriser.
inline double Min(double a, double b) { return a < b ? a : b; }
inline double Max(double a, double b) { return a > b ? a : b; }

inline void JacobiRotate(double& app, double& aqq, double& apq, double& arp, double& arq) {
  const double d = aqq - app;
  const double sign = std::copysign(1.0, d);
  const double t = sign * 2.0 * apq / (std::abs(d) + std::sqrt(d * d + 4.0 * apq * apq) + 1e-300);
  const double c = 1.0 / std::sqrt(1.0 + t * t);
  const double s = t * c;
  app -= t * apq;
  aqq += t * apq;
  apq = 0.0;
  const double rp = arp, rq = arq;
  arp = c * rp - s * rq;
  arq = s * rp + c * rq;
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void JacobiLoop(const double* __restrict xx, const double* __restrict xy, const double* __restrict xz,
                const double* __restrict yy, const double* __restrict yz, const double* __restrict zz,
                double* __restrict v0, double* __restrict v1, double* __restrict v2,
                double* __restrict residual, std::size_t n) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    // Scale by the largest diagonal entry (J is positive semi-definite: that bounds every entry),
    // so squares neither overflow nor underflow at any scene scale.
    const double scale = Max(Max(xx[i], yy[i]), Max(zz[i], 1e-300));
    const double inv = 1.0 / scale;
    double a00 = xx[i] * inv, a01 = xy[i] * inv, a02 = xz[i] * inv;
    double a11 = yy[i] * inv, a12 = yz[i] * inv, a22 = zz[i] * inv;
    // Convergence is quadratic once the rotations are small; four sweeps take any 3x3 from O(1)
    // off-diagonal entries to round-off, and the check below catches the rest.
    // (Unrolled so that the outer loop is a single basic block the vectoriser accepts.)
#pragma GCC unroll 4
    for (int sweep = 0; sweep < 4; ++sweep) {
      JacobiRotate(a00, a11, a01, a02, a12);  // (0,1), r = 2
      JacobiRotate(a00, a22, a02, a01, a12);  // (0,2), r = 1: a_10 -> a01, a_12 -> a12
      JacobiRotate(a11, a22, a12, a01, a02);  // (1,2), r = 0: a_01 -> a01, a_02 -> a02
    }
    const double off = a01 * a01 + a02 * a02 + a12 * a12;
    const double diag = a00 * a00 + a11 * a11 + a22 * a22;
    residual[i] = off / (diag + 1e-300);
    // Sort: smallest, largest, and the median of three.
    const double lo = Min(Min(a00, a11), a22);
    const double hi = Max(Max(a00, a11), a22);
    const double mid = Max(Min(a00, a11), Min(Max(a00, a11), a22));
    v0[i] = lo * scale;
    v1[i] = mid * scale;
    v2[i] = hi * scale;
  }
}

}  // namespace

void SymmetricEigenvalues3(const double* const upper[6], double* const values[3],
                           unsigned char* converged, std::size_t n) {
  // The residual goes through a double array: a byte store in the loop kept some clones scalar.
  constexpr std::size_t kChunk = 512;
  double residual[kChunk];
  for (std::size_t start = 0; start < n; start += kChunk) {
    const std::size_t m = std::min(kChunk, n - start);
    JacobiLoop(upper[0] + start, upper[1] + start, upper[2] + start, upper[3] + start,
               upper[4] + start, upper[5] + start, values[0] + start, values[1] + start,
               values[2] + start, residual, m);
    for (std::size_t i = 0; i < m; ++i) {
      converged[start + i] = residual[i] <= 1e-30;
      if (converged[start + i]) continue;
      // The general solver as a safety net (never needed on the trauma room).
      const std::size_t j = start + i;
      Mat3 J;
      J << upper[0][j], upper[1][j], upper[2][j], upper[1][j], upper[3][j], upper[4][j],
          upper[2][j], upper[4][j], upper[5][j];
      const Vec3 e = DecomposeInformation(J, /*eigenvectors=*/false).eigenvalues;
      for (int k = 0; k < 3; ++k) values[k][j] = e[k];
    }
  }
}

StaticUncertainty StaticFromInformation(const Information& info, int cameras) {
  StaticUncertainty out;
  if (cameras < 2 || !info.observable) return out;
  const Vec3 variances = info.eigenvalues.cwiseInverse();  // ascending lambda -> descending var
  out.triangulable = true;
  out.covariance = info.eigenvectors * variances.asDiagonal() * info.eigenvectors.transpose();
  out.sigma_max = std::sqrt(variances[0]);
  out.sigma_mean = std::sqrt(variances.sum() / 3.0);
  out.condition = info.eigenvalues[2] / info.eigenvalues[0];
  return out;
}

namespace {

// The closed form's common part: Lambda, R, s and u (see ScalarSteadyState).
struct SteadyTerms {
  double lambda, R, s, u;
};

SteadyTerms Terms(double q, double T, double r) {
  // Tracking index Lambda = sqrt(q T^3 / r). The steady-state gains alpha = 1 - u^2, beta = Lambda
  // u follow from u + 1/u = w = (Lambda + R) / 2, R = sqrt(Lambda^2 / 3 + 16), with u in (0, 1].
  SteadyTerms t;
  t.lambda = std::sqrt(q * T * T * T / r);
  t.R = std::sqrt(t.lambda * t.lambda / 3.0 + 16.0);
  const double w_minus_2 = 0.5 * (t.lambda + (t.lambda * t.lambda / 3.0) / (t.R + 4.0));  // exact
  const double w = 2.0 + w_minus_2;
  t.s = std::sqrt(w_minus_2 * (w + 2.0));  // 1/u - u = sqrt(w^2 - 4)
  t.u = 2.0 / (w + t.s);                   // the root below 1, no cancellation
  return t;
}

}  // namespace

Eigen::Matrix2d ScalarSteadyState(double q, double T, double r, bool prior) {
  Eigen::Matrix2d P;
  if (!(r < std::numeric_limits<double>::infinity())) {
    P.setConstant(std::numeric_limits<double>::infinity());
    return P;
  }
  const SteadyTerms t = Terms(q, T, r);
  // Posterior: p11 = alpha r = u s r, p12 = beta r / T, p22 = (r Lambda / T^2) (s - Lambda / 2),
  // with s - Lambda/2 = Lambda (2R + Lambda/3) / (4 (s + Lambda/2)) (all terms positive).
  const double p11 = t.u * t.s * r;
  const double p12 = t.lambda * t.u * r / T;
  const double s_minus =
      t.lambda > 0 ? t.lambda * (2.0 * t.R + t.lambda / 3.0) / (4.0 * (t.s + 0.5 * t.lambda)) : 0.0;
  const double p22 = r * t.lambda * s_minus / (T * T);
  P << p11, p12, p12, p22;
  if (!prior) return P;
  // Prior M = F P F^T + Q.
  Eigen::Matrix2d F, Q;
  F << 1, T, 0, 1;
  Q << T * T * T / 3.0, T * T / 2.0, T * T / 2.0, T;
  return F * P * F.transpose() + q * Q;
}

double SteadyPositionVariance(double q, double T, double r, bool prior) {
  if (prior || !(r < std::numeric_limits<double>::infinity()))
    return ScalarSteadyState(q, T, r, prior)(0, 0);
  const SteadyTerms t = Terms(q, T, r);
  return t.u * t.s * r;
}

namespace {

// One function body, compiled for AVX-512, AVX2 and baseline x86-64; the loader picks the best the
// CPU has. The loop has no branches, so each clone vectorises at its own width.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void SteadyPosteriorLoop(double qT3, const double* r, double* out, std::size_t n) {
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    // Terms() inlined: Lambda, R, w - 2, s, u; then the posterior u s r.
    const double ri = r[i];
    const double lambda = std::sqrt(qT3 / ri);
    const double lambda2_3 = lambda * lambda / 3.0;
    const double big_r = std::sqrt(lambda2_3 + 16.0);
    const double w_minus_2 = 0.5 * (lambda + lambda2_3 / (big_r + 4.0));
    const double w = 2.0 + w_minus_2;
    const double s = std::sqrt(w_minus_2 * (w + 2.0));
    out[i] = 2.0 / (w + s) * s * ri;
  }
}

}  // namespace

void SteadyPositionVariances(double q, double T, const double* r, double* out, std::size_t n,
                             bool prior) {
  if (prior) {
    for (std::size_t i = 0; i < n; ++i) out[i] = SteadyPositionVariance(q, T, r[i], true);
    return;
  }
  SteadyPosteriorLoop(q * T * T * T, r, out, n);
}

SteadyUncertainty SteadyFromInformation(const Information& info, int cameras,
                                        const MotionModel& motion, bool prior) {
  SteadyUncertainty out;
  if (cameras < 2 || !info.observable) return out;
  const double T = 1.0 / motion.rate_hz;
  Vec3 variances;
  for (int k = 0; k < 3; ++k)
    variances[k] = SteadyPositionVariance(motion.q, T, 1.0 / info.eigenvalues[k], prior);
  out.converged = variances.allFinite();
  out.covariance = info.eigenvectors * variances.asDiagonal() * info.eigenvectors.transpose();
  out.sigma_max = std::sqrt(variances.maxCoeff());
  out.sigma_mean = std::sqrt(variances.sum() / 3.0);
  return out;
}

namespace {

// Largest change of an entry relative to its own scale, |dM_ij| / sqrt(M_ii M_jj): blocks of very
// different units (m^2 against m^2/s^2 at 1 MHz) are each judged on their own scale.
double RelativeChange(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  double worst = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      const double scale =
          std::sqrt(std::max(std::abs(a(i, i) * a(j, j)), std::abs(b(i, i) * b(j, j))));
      const double change = std::abs(a(i, j) - b(i, j));
      if (change == 0) continue;
      worst = std::max(worst, scale > 0 ? change / scale : std::numeric_limits<double>::infinity());
    }
  return worst;
}

}  // namespace

std::optional<Eigen::MatrixXd> SolveDareDoubling(const Eigen::MatrixXd& F, const Eigen::MatrixXd& G,
                                                 const Eigen::MatrixXd& Q, double tolerance,
                                                 int max_iterations, int* iterations) {
  // Dual (filtering) form: A_0 = F^T, G_0 = G, H_0 = Q. Each step squares the horizon:
  //   W = I + G_k H_k,  A_{k+1} = A_k W^-1 A_k,  G_{k+1} = G_k + A_k W^-1 G_k A_k^T,
  //   H_{k+1} = H_k + A_k^T H_k W^-1 A_k;  H_k -> M.
  const Eigen::Index n = F.rows();
  Eigen::MatrixXd A = F.transpose(), Gk = G, H = Q;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  for (int k = 1; k <= max_iterations; ++k) {
    const Eigen::PartialPivLU<Eigen::MatrixXd> W(I + Gk * H);
    const Eigen::MatrixXd WinvA = W.solve(A);
    const Eigen::MatrixXd WinvG = W.solve(Gk);
    const Eigen::MatrixXd H_next = H + A.transpose() * H * WinvA;
    const Eigen::MatrixXd G_next = Gk + A * WinvG * A.transpose();
    const Eigen::MatrixXd A_next = A * WinvA;
    const double change = RelativeChange(H_next, H);
    H = 0.5 * (H_next + H_next.transpose());
    Gk = 0.5 * (G_next + G_next.transpose());
    A = A_next;
    if (iterations) *iterations = k;
    if (!H.allFinite()) return std::nullopt;
    if (change <= tolerance) return H;
  }
  return std::nullopt;
}

Eigen::MatrixXd SolveDareIteration(const Eigen::MatrixXd& F, const Eigen::MatrixXd& G,
                                   const Eigen::MatrixXd& Q, double tolerance, int max_iterations,
                                   bool* converged, int* iterations) {
  Eigen::MatrixXd M = Q;
  if (converged) *converged = false;
  // The approach can oscillate when stiff: stop only after three steps in a row below tolerance.
  int calm_steps = 0;
  for (int k = 1; k <= max_iterations; ++k) {
    const Eigen::MatrixXd P = PosteriorFromPrior(M, G);
    Eigen::MatrixXd next = F * P * F.transpose() + Q;
    next = 0.5 * (next + next.transpose());
    const double change = RelativeChange(next, M);
    M = next;
    if (iterations) *iterations = k;
    calm_steps = change <= tolerance ? calm_steps + 1 : 0;
    if (calm_steps >= 3) {
      if (converged) *converged = true;
      break;
    }
  }
  return M;
}

ConstantVelocity6 MakeConstantVelocity6(const Mat3& J, const MotionModel& motion) {
  const double T = 1.0 / motion.rate_hz;
  ConstantVelocity6 m;
  const Mat3 I = Mat3::Identity();
  m.F.setIdentity();
  m.F.block<3, 3>(0, 3) = T * I;
  m.Q << T * T * T / 3.0 * I, T * T / 2.0 * I, T * T / 2.0 * I, T * I;
  m.Q *= motion.q;
  m.G.setZero();
  m.G.block<3, 3>(0, 0) = J;
  return m;
}

Eigen::MatrixXd PosteriorFromPrior(const Eigen::MatrixXd& M, const Eigen::MatrixXd& G) {
  const Eigen::Index n = M.rows();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd P = (I + M * G).partialPivLu().solve(M);
  return 0.5 * (P + P.transpose());
}

double MaxTriangulationAngle(const std::vector<Vec3>& d) {
  double best = 0;
  for (std::size_t i = 0; i < d.size(); ++i)
    for (std::size_t j = i + 1; j < d.size(); ++j) {
      // atan2 of |cross| and dot is accurate at tiny and near-pi angles, unlike acos.
      const double angle = std::atan2(d[i].cross(d[j]).norm(), d[i].dot(d[j]));
      best = std::max(best, angle);
    }
  return best;
}

}  // namespace pandora
