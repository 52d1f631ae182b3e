// The long-double reference solvers (analysis/geometry/uncertainty_reference.h): the closed form
// against the double-precision one, against a brute-force Kalman recursion in long double and
// against the long-double doubling algorithm; the doubling's iteration count; scaling and the
// limits.
#include "analysis/geometry/uncertainty_reference.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "analysis/geometry/uncertainty.h"

namespace pandora {
namespace {

using Mat2L = Eigen::Matrix<long double, 2, 2>;

// r such that sqrt(q T^3 / r) = lambda.
long double RForLambda(long double q, long double T, long double lambda) {
  return q * T * T * T / (lambda * lambda);
}

// The scalar Kalman filter run to its steady state in long double: prior M = F P F^T + Q, then the
// update with a position measurement of variance r, from P = 0 until P stops changing.
long double BruteForcePosteriorVariance(long double q, long double T, long double r, int* steps) {
  Mat2L F, Q, P = Mat2L::Zero();
  F << 1, T, 0, 1;
  Q << T * T * T / 3, T * T / 2, T * T / 2, T;
  Q *= q;
  for (int k = 1; k <= 1000000; ++k) {
    const Mat2L M = F * P * F.transpose() + Q;
    const long double s = M(0, 0) + r;
    Mat2L next;
    next << M(0, 0) - M(0, 0) * M(0, 0) / s, M(0, 1) - M(0, 0) * M(0, 1) / s,
        M(1, 0) - M(1, 0) * M(0, 0) / s, M(1, 1) - M(1, 0) * M(0, 1) / s;
    const long double change = (next - P).cwiseAbs().maxCoeff() / next.cwiseAbs().maxCoeff();
    P = next;
    *steps = k;
    if (!(change > 16 * std::numeric_limits<long double>::epsilon())) break;
  }
  return P(0, 0);
}

TEST(UncertaintyReference, ClosedFormMatchesTheDoubleClosedForm) {
  const long double q = 1, T = 1.0L / 30;
  for (double lambda : {1e-6, 1e-3, 0.1, 1.0, 4.0, 30.0, 1e3, 1e5}) {
    const long double r = RForLambda(q, T, lambda);
    const double reference = static_cast<double>(SteadyPositionVarianceLong(q, T, r));
    const double fast = ScalarSteadyState(double(q), double(T), double(r))(0, 0);
    EXPECT_NEAR(fast, reference, 4e-16 * reference) << "lambda " << lambda;
  }
}

TEST(UncertaintyReference, ClosedFormEqualsTheKalmanRecursionRunToSteadyState) {
  // Moderate tracking indices, where the plain recursion converges in a few hundred steps.
  const long double T = 1.0L / 60;
  for (double lambda : {0.05, 0.5, 2.0, 20.0}) {
    const long double q = 2.5, r = RForLambda(q, T, lambda);
    int steps = 0;
    const long double brute = BruteForcePosteriorVariance(q, T, r, &steps);
    const long double closed = SteadyPositionVarianceLong(q, T, r);
    EXPECT_LT(std::fabs(brute - closed) / closed, 1e-16L)
        << "lambda " << lambda << ", " << steps << " steps";
    EXPECT_LT(steps, 1000000);
  }
}

TEST(UncertaintyReference, DoublingAgreesWithTheClosedFormBeyondDoublePrecision) {
  const long double q = 1, T = 1.0L / 30;
  for (double lambda : {5e-7, 1e-3, 3.2, 4.9, 5e4}) {
    const long double r = RForLambda(q, T, lambda);
    int iterations = 0;
    const long double doubling = SteadyPositionVarianceDoublingLong(q, T, r, &iterations);
    const long double closed = SteadyPositionVarianceLong(q, T, r);
    // Both in long double: far below double's 1.1e-16.
    EXPECT_LT(std::fabs(doubling - closed) / closed, 5e-17L) << "lambda " << lambda;
    EXPECT_GT(iterations, 0);
  }
}

TEST(UncertaintyReference, DoublingConvergesQuadratically) {
  // The number of doublings grows like log2(1 / Lambda) for small Lambda and stays small otherwise.
  const long double q = 1, T = 1.0L / 30;
  auto iterations_at = [&](double lambda) {
    int n = 0;
    SteadyPositionVarianceDoublingLong(q, T, RForLambda(q, T, lambda), &n);
    return n;
  };
  for (double lambda : {1.0, 3.2, 4.9, 100.0, 5e4}) EXPECT_LE(iterations_at(lambda), 8) << lambda;
  int previous = 0;
  for (double lambda : {1e-1, 1e-3, 1e-5, 1e-7}) {
    const int n = iterations_at(lambda);
    EXPECT_GE(n, previous) << lambda;
    previous = n;
  }
  EXPECT_GE(previous, 12);
  EXPECT_LE(previous, 24);
  // Each factor of 100 in Lambda costs a few more doublings, not a factor more.
  EXPECT_LE(iterations_at(1e-7) - iterations_at(1e-5), 5);
}

TEST(UncertaintyReference, ScalingAndLimits) {
  const long double T = 1.0L / 30, q = 3, r = 1e-6L;
  const long double v = SteadyPositionVarianceLong(q, T, r);
  // Same tracking index, everything scaled by c: the variance scales by c.
  EXPECT_LT(std::fabs(SteadyPositionVarianceLong(7 * q, T, 7 * r) - 7 * v) / (7 * v), 1e-18L);
  // Below one frame's measurement (filtering helps), positive.
  EXPECT_GT(v, 0);
  EXPECT_LT(v, r);
  // No process noise: the point is still, the variance goes to 0.
  EXPECT_EQ(SteadyPositionVarianceLong(0, T, r), 0);
  EXPECT_EQ(SteadyPositionVarianceDoublingLong(0, T, r), 0);
  // Very fast motion: each frame stands alone, the variance tends to r.
  const long double fast = SteadyPositionVarianceLong(1e16L, T, r);
  EXPECT_LT(std::fabs(fast - r) / r, 1e-4L);
}

}  // namespace
}  // namespace pandora
