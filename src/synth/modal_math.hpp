// SPDX-License-Identifier: MIT
// Exact single-mode mathematics shared by the oscillator bank and its tests: poles, the
// half-sine contact pulse integrated in closed form, and a small matrix exponential for the
// modes that do not ring (over-damped, critically damped, or nearly so).
#pragma once

#include <array>
#include <complex>

namespace strike::detail {

using Complex = std::complex<double>;

/// E(a, p, U) = integral_0^U e^{p (U - u)} e^{a u} du = (e^{aU} - e^{pU}) / (a - p), evaluated
/// without cancellation when a ~ p (then U e^{pU} (e^z - 1)/z with z = (a - p) U by series).
/// Requires Re(p) <= 0, Re(a) <= 0 (no overflow); U may be slightly negative.
Complex expDividedDifference(Complex a, Complex p, double u_s);

/// E(a_plus, p, U) and E(a_minus, p, U) (a_minus = -a_plus, as the caller writes it) sharing
/// e^{pU}, and e^{a_plus U} itself: each the very bits expDividedDifference and std::exp give,
/// with three complex exponentials instead of five. The half-sine pulse needs all three.
struct ExpPair {
  Complex plus, minus;  ///< E(a_plus, p, U), E(a_minus, p, U)
  Complex exp_plus;     ///< e^{a_plus U}
};
ExpPair expDividedDifferencePair(Complex a_plus, Complex a_minus, Complex p, double u_s);

/// y(U) = integral_0^U e^{p (U - u)} f(u) du for the unit-area half-sine pulse
/// f(u) = (pi / (2 tau)) sin(pi u / tau) on [0, tau], at 0 <= U <= tau (Re p <= 0).
/// y(tau) -> 1 as tau -> 0 (the ideal impulse).
Complex halfSineResponse(Complex pole, double tau_s, double u_s);

/// y(U) for the unit-area box pulse f(u) = 1 / tau on [0, tau], at 0 <= U <= tau:
/// (1 / tau) E(0, p, U) = (e^{pU} - 1) / (p tau), without cancellation for small |p| U.
inline Complex boxResponse(Complex pole, double tau_s, double u_s) {
  return expDividedDifference(Complex(0.0, 0.0), pole, u_s) / tau_s;
}

/// Row-major 4x4 real matrix.
using Mat4 = std::array<double, 16>;

/// exp(A t) by scaling and squaring of a degree-18 Taylor polynomial (||A t|| / 2^s <= 1/2),
/// accurate to a few ulps of ||exp(A t)|| for the small, stable matrices used here; never NaN
/// for finite input.
Mat4 expm4(const Mat4& a, double t_s);

/// State of a non-ringing mode in scaled coordinates x = (omega0 q, q') (omega0 = sqrt(lambda)),
/// augmented by the pulse as (f, f' / Omega) with Omega = pi / tau, so that the pulse is itself a
/// linear ODE and the forced response is exact: x' = A x with
///   A = [0, w0, 0, 0;  -w0, -c, 1, 0;  0, 0, 0, Om;  0, 0, -Om, 0].
Mat4 augmentedMatrix(double omega0, double damping_c, double pulse_omega);

inline std::array<double, 4> mul4(const Mat4& m, const std::array<double, 4>& x) {
  std::array<double, 4> y{};
  for (int r = 0; r < 4; ++r)
    y[r] = m[r * 4 + 0] * x[0] + m[r * 4 + 1] * x[1] + m[r * 4 + 2] * x[2] + m[r * 4 + 3] * x[3];
  return y;
}

}  // namespace strike::detail
