// SPDX-License-Identifier: MIT
#include "modal_math.hpp"

#include <cmath>

namespace strike::detail {

namespace {

/// U e^{pU} phi1(z), phi1(z) = (e^z - 1) / z = sum z^k / (k+1)!; |z| < 1/2 so 20 terms reach
/// double precision.
Complex seriesForm(Complex z, double u_s, Complex exp_pu) {
  Complex term(1.0, 0.0), sum(1.0, 0.0);
  for (int k = 1; k < 20; ++k) {
    term *= z / static_cast<double>(k + 1);
    sum += term;
  }
  return u_s * exp_pu * sum;
}

/// E(a, p, U) given e^{pU}, and e^{aU} when the caller has it (else computed here if needed).
Complex expDividedDifference(Complex a, Complex p, double u_s, Complex exp_pu, const Complex* exp_au) {
  const Complex z = (a - p) * u_s;
  if (std::abs(z) < 0.5) return seriesForm(z, u_s, exp_pu);
  // |a - p| U >= 1/2: the difference loses at most a bounded factor, no catastrophic cancellation.
  return ((exp_au ? *exp_au : std::exp(a * u_s)) - exp_pu) / (a - p);
}

}  // namespace

Complex expDividedDifference(Complex a, Complex p, double u_s) {
  return expDividedDifference(a, p, u_s, std::exp(p * u_s), nullptr);
}

ExpPair expDividedDifferencePair(Complex a_plus, Complex a_minus, Complex p, double u_s) {
  const Complex exp_pu = std::exp(p * u_s);
  ExpPair out;
  out.exp_plus = std::exp(a_plus * u_s);
  out.plus = expDividedDifference(a_plus, p, u_s, exp_pu, &out.exp_plus);
  out.minus = expDividedDifference(a_minus, p, u_s, exp_pu, nullptr);
  return out;
}

Complex halfSineResponse(Complex pole, double tau_s, double u_s) {
  // f(u) = (pi/(2 tau)) (e^{i Om u} - e^{-i Om u}) / (2i): two geometric sequences in u.
  const double omega = M_PI / tau_s;
  const ExpPair e = expDividedDifferencePair(Complex(0.0, omega), Complex(0.0, -omega), pole, u_s);
  return (M_PI / (2.0 * tau_s)) * (e.plus - e.minus) / Complex(0.0, 2.0);
}

Mat4 expm4(const Mat4& a, double t_s) {
  Mat4 x{};
  double norm = 0.0;  // infinity norm of A t
  for (int r = 0; r < 4; ++r) {
    double row = 0.0;
    for (int c = 0; c < 4; ++c) row += std::fabs(a[r * 4 + c] * t_s);
    norm = std::fmax(norm, row);
  }
  int squarings = 0;
  if (norm > 0.5) squarings = static_cast<int>(std::ceil(std::log2(norm / 0.5)));
  if (!(squarings >= 0)) squarings = 0;  // NaN norm
  if (squarings > 1000) squarings = 1000;
  const double scale = std::ldexp(t_s, -squarings);
  for (int i = 0; i < 16; ++i) x[i] = a[i] * scale;

  auto matmul = [](const Mat4& l, const Mat4& r) {
    Mat4 out{};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        double s = 0.0;
        for (int k = 0; k < 4; ++k) s += l[i * 4 + k] * r[k * 4 + j];
        out[i * 4 + j] = s;
      }
    return out;
  };
  // Horner: T = I + X (I + X/2 (I + X/3 (... (I + X/18)))).
  Mat4 t{};
  for (int i = 0; i < 4; ++i) t[i * 5] = 1.0;
  for (int k = 18; k >= 1; --k) {
    Mat4 xt = matmul(x, t);
    for (int i = 0; i < 16; ++i) t[i] = xt[i] / static_cast<double>(k);
    for (int i = 0; i < 4; ++i) t[i * 5] += 1.0;
  }
  for (int s = 0; s < squarings; ++s) t = matmul(t, t);
  return t;
}

Mat4 augmentedMatrix(double omega0, double damping_c, double pulse_omega) {
  return Mat4{0.0,     omega0,     0.0,          0.0,          //
              -omega0, -damping_c, 1.0,          0.0,          //
              0.0,     0.0,        0.0,          pulse_omega,  //
              0.0,     0.0,        -pulse_omega, 0.0};
}

}  // namespace strike::detail
