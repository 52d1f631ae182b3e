#pragma once
/// \file uncertainty_reference.h
/// Reference solvers of the scalar steady-state Kalman problem (analysis/geometry/uncertainty.h,
/// ScalarSteadyState) in long double (x87 extended precision: a 64-bit mantissa, eps
/// about 1.1e-19), for measuring the round-off of the double-precision solvers (`pandora accuracy`,
/// table (c)). Not for the fields: each call costs microseconds.
///
/// The problem: one axis of a constant-velocity model, F = [1 T; 0 1], Q = q [T^3/3 T^2/2; T^2/2
/// T], a position measurement of variance r (m^2) per frame; the result is the steady posterior
/// position variance (m^2), the (0, 0) entry of ScalarSteadyState(q, T, r).

namespace pandora {

/// The closed form of ScalarSteadyState (docs/uncertainty.md) evaluated in long double: with the
/// tracking index Lambda = sqrt(q T^3 / r), R = sqrt(Lambda^2 / 3 + 16), w = 2 + (Lambda +
/// (Lambda^2 / 3) / (R + 4)) / 2, s = sqrt((w - 2)(w + 2)), u = 2 / (w + s), the variance is u s r.
/// q >= 0, T > 0, r > 0; q = 0 gives 0 (infinitely many frames of a still point).
long double SteadyPositionVarianceLong(long double q, long double T, long double r);

/// An independent check of the closed form: the structure-preserving doubling algorithm (Chu, Fan
/// and Lin 2005) on the 2x2 problem in long double, iterated until the largest change of the
/// information-side iterate falls to 4 eps of long double (at most 200 doublings), then the
/// posterior from the prior. `iterations` (if given) receives the doublings done; doubling
/// converges quadratically, so it grows only like log2(1 / Lambda) for slow motion or fast frame
/// rates (6 at Lambda = 3 .. 5e4, 17 at Lambda = 5e-7).
long double SteadyPositionVarianceDoublingLong(long double q, long double T, long double r,
                                               int* iterations = nullptr);

}  // namespace pandora
