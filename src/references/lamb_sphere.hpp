// SPDX-License-Identifier: MIT
// Free vibration of a homogeneous isotropic elastic sphere (Lamb, "On the vibrations of an
// elastic sphere", Proc. London Math. Soc. 13 (1882) 189-212), in the dimensionless frequency
// eta = omega R / c_s (c_s = sqrt(mu / rho), c_l = sqrt((lambda + 2 mu) / rho)):
//  - torsional (toroidal) modes of degree n >= 1, multiplicity 2n + 1:
//        (n - 1) j_n(eta) - eta j_{n+1}(eta) = 0
//    (Lamb 1882 sec. 8; D. B. Murray, "Torsional vibrational modes of an elastic sphere");
//    first roots T2 2.5011, T3 3.8647, T4 5.0946, T1 5.7635;
//  - spheroidal modes of degree n >= 1, multiplicity 2n + 1: det [[a, b], [c, d]] = 0 with
//    x = omega R / c_l, y = eta,
//        a = (1/2 - n(n-1)/y^2) j_n(x) - (2x/y^2) j_{n+1}(x)
//        b = -2n(n+1) ((n-1)/y^2 j_n(x) - (x/y^2) j_{n+1}(x))
//        c = (n-1)/y^2 j_n(y) - (1/y) j_{n+1}(y)
//        d = (2/y) j_{n+1}(y) + (2(n^2-1)/y^2 - 1) j_n(y)
//    (Sato & Usami, "Basic study on the oscillation of a homogeneous elastic sphere, part I",
//    Geophys. Mag. 31 (1962), eq. 2.2; the half-integer Bessel functions there are replaced by
//    spherical ones, which rescales each row by a positive factor and keeps the roots);
//  - the breathing mode n = 0 (multiplicity 1): sin x (4 - y^2) - 4 x cos x = 0 (Lamb eq. 59;
//    for nu = 1/4 his x / pi = 0.8160, i.e. eta = 4.440).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace strike::test {

inline double sphj(int n, double x) { return std::sph_bessel(static_cast<unsigned>(n), x); }

inline double lambTorsional(int n, double eta) { return (n - 1) * sphj(n, eta) - eta * sphj(n + 1, eta); }

inline double lambSpheroidal(int n, double eta, double cl_over_cs) {
  const double y = eta, x = eta / cl_over_cs, y2 = y * y;
  if (n == 0) return std::sin(x) * (4.0 - y2) - 4.0 * x * std::cos(x);
  const double a = (0.5 - n * (n - 1) / y2) * sphj(n, x) - (2.0 * x / y2) * sphj(n + 1, x);
  const double b = -2.0 * n * (n + 1) * ((n - 1) / y2 * sphj(n, x) - (x / y2) * sphj(n + 1, x));
  const double c = (n - 1) / y2 * sphj(n, y) - sphj(n + 1, y) / y;
  const double d = (2.0 / y) * sphj(n + 1, y) + (2.0 * (n * n - 1) / y2 - 1.0) * sphj(n, y);
  return a * d - b * c;
}

/// Roots of f in (lo, hi] by scanning (step) and bisection.
inline std::vector<double> scanRoots(const std::function<double(double)>& f, double lo, double hi, double step) {
  std::vector<double> roots;
  double x0 = lo, f0 = f(lo);
  for (double x1 = lo + step; x1 <= hi; x1 += step) {
    const double f1 = f(x1);
    if ((f0 < 0) != (f1 < 0)) {
      double a = x0, b = x1, fa = f0;
      for (int i = 0; i < 80; ++i) {
        const double m = 0.5 * (a + b), fm = f(m);
        if ((fa < 0) != (fm < 0))
          b = m;
        else {
          a = m;
          fa = fm;
        }
      }
      roots.push_back(0.5 * (a + b));
    }
    x0 = x1;
    f0 = f1;
  }
  return roots;
}

/// Every elastic mode of the free sphere with eta <= eta_max, each root repeated by its
/// multiplicity, ascending.
inline std::vector<double> lambSphereEtas(double poisson, double eta_max) {
  const double cl_over_cs = std::sqrt((2.0 - 2.0 * poisson) / (1.0 - 2.0 * poisson));
  std::vector<double> etas;
  for (int n = 0; n <= 12; ++n) {
    if (n >= 1)
      for (double r : scanRoots([&](double e) { return lambTorsional(n, e); }, 0.3, eta_max, 1e-3))
        etas.insert(etas.end(), static_cast<size_t>(2 * n + 1), r);
    for (double r : scanRoots([&](double e) { return lambSpheroidal(n, e, cl_over_cs); }, 0.3, eta_max, 1e-3))
      etas.insert(etas.end(), static_cast<size_t>(2 * n + 1), r);
  }
  std::sort(etas.begin(), etas.end());
  return etas;
}

}  // namespace strike::test
