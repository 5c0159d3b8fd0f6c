// SPDX-License-Identifier: MIT
// Shared builders and closed forms for the synth tests.
#pragma once

#include <cmath>
#include <complex>
#include <vector>

#include "strike/synth/synth.hpp"

namespace strike::test {

using Cx = std::complex<double>;

/// One object with modes at the given undamped frequencies (Hz) and Rayleigh (a1, a2).
inline ModalObjectDesc makeObject(const std::vector<double>& freqs_hz, double a1, double a2,
                                  std::vector<double> weights = {}) {
  ModalObjectDesc d;
  for (double f : freqs_hz) d.eigenvalues.push_back(std::pow(2.0 * M_PI * f, 2));
  d.rayleigh_stiffness = a1;
  d.rayleigh_mass = a2;
  d.radiation_weight = std::move(weights);
  return d;
}

/// Output of an ideally struck ringing mode (R = g = 1) at time t after the impulse: the exact
/// acceleration without feedthrough, Im(p^2 e^{pt}) / w_d = (lambda / w_d) e^{-c t/2} sin(w_d t + 2 arg p).
inline double ringingImpulseResponse(double lambda, double c, double t) {
  const double sigma = 0.5 * c, wd = std::sqrt(lambda - sigma * sigma);
  const double arg_p = std::atan2(wd, -sigma);
  return lambda / wd * std::exp(-sigma * t) * std::sin(wd * t + 2.0 * arg_p);
}

/// Same for any damping via the real poles / double pole: output = -lambda q - c q'.
inline double generalImpulseResponse(double lambda, double c, double t) {
  const double sigma = 0.5 * c, disc = sigma * sigma - lambda;
  double q, dq;
  if (disc > 0) {
    const double k = std::sqrt(disc), r1 = -sigma + k, r2 = -sigma - k;
    q = (std::exp(r1 * t) - std::exp(r2 * t)) / (r1 - r2);
    dq = (r1 * std::exp(r1 * t) - r2 * std::exp(r2 * t)) / (r1 - r2);
  } else if (disc == 0) {
    q = t * std::exp(-sigma * t);
    dq = (1.0 - sigma * t) * std::exp(-sigma * t);
  } else {
    const double wd = std::sqrt(-disc);
    q = std::exp(-sigma * t) * std::sin(wd * t) / wd;
    dq = std::exp(-sigma * t) * (std::cos(wd * t) - sigma * std::sin(wd * t) / wd);
  }
  return -lambda * q - c * dq;
}

inline std::vector<float> renderAll(OscillatorBank& bank, size_t frames) {
  std::vector<float> out(frames);
  bank.render(out.data(), frames);
  return out;
}

inline double peakAbs(const std::vector<float>& v) {
  double p = 0;
  for (float x : v) p = std::fmax(p, std::fabs(static_cast<double>(x)));
  return p;
}

}  // namespace strike::test
