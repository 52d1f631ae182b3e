// Long-double reference solvers of the scalar steady state
// (analysis/geometry/uncertainty_reference.h).
#include "analysis/geometry/uncertainty_reference.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

namespace pandora {

using Mat2L = Eigen::Matrix<long double, 2, 2>;

long double SteadyPositionVarianceLong(long double q, long double T, long double r) {
  const long double lambda = std::sqrt(q * T * T * T / r);
  const long double R = std::sqrt(lambda * lambda / 3.0L + 16.0L);
  const long double w_minus_2 = 0.5L * (lambda + (lambda * lambda / 3.0L) / (R + 4.0L));
  const long double w = 2.0L + w_minus_2;
  const long double s = std::sqrt(w_minus_2 * (w + 2.0L));
  const long double u = 2.0L / (w + s);
  return u * s * r;
}

long double SteadyPositionVarianceDoublingLong(long double q, long double T, long double r,
                                               int* iterations) {
  Mat2L F, Q, G, I = Mat2L::Identity();
  F << 1, T, 0, 1;
  Q << T * T * T / 3, T * T / 2, T * T / 2, T;
  Q *= q;
  G << 1 / r, 0, 0, 0;
  Mat2L A = F.transpose(), Gk = G, H = Q;
  int done = 0;
  for (int k = 1; k <= 200; ++k) {
    const Mat2L Winv = (I + Gk * H).inverse();
    const Mat2L H_next = H + A.transpose() * H * Winv * A;
    const Mat2L G_next = Gk + A * Winv * Gk * A.transpose();
    const Mat2L A_next = A * Winv * A;
    const long double change = (H_next - H).cwiseAbs().maxCoeff() / H_next.cwiseAbs().maxCoeff();
    H = 0.5L * (H_next + H_next.transpose());
    Gk = 0.5L * (G_next + G_next.transpose());
    A = A_next;
    done = k;
    if (!(change > 4 * std::numeric_limits<long double>::epsilon())) break;
  }
  if (iterations) *iterations = done;
  const Mat2L P = (I + H * G).inverse() * H;
  return P(0, 0);
}

}  // namespace pandora
