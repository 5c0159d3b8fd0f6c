// SPDX-License-Identifier: MIT
// AcousticTransfer's data helpers and its evaluation at a direction (acoustic_transfer.hpp).
#include "strike/acoustic_transfer.hpp"

#include <cmath>

namespace strike {

uint32_t AcousticTransfer::maxOrder() const {
  uint32_t n = 0;
  for (uint32_t o : order) n = o > n ? o : n;
  return n;
}

double AcousticTransfer::rmsFarField(size_t mode) const {
  if (mode >= order.size() || offset.size() != order.size() + 1) return 0.0;
  double sum = 0.0;
  for (uint64_t j = offset[mode]; j < offset[mode + 1] && j < coefficients.size(); ++j)
    sum += std::norm(std::complex<double>(coefficients[j]));
  return std::sqrt(sum / (4.0 * M_PI));
}

std::string AcousticTransfer::checkConsistency(size_t modes) const {
  if (order.size() != modes)
    return "transfer holds " + std::to_string(order.size()) + " modes, the bank " + std::to_string(modes);
  if (offset.size() != modes + 1 || offset[0] != 0) return "transfer offsets do not match its modes";
  for (size_t i = 0; i < modes; ++i)
    if (offset[i + 1] - offset[i] != uint64_t(order[i] + 1) * (order[i] + 1))
      return "transfer mode " + std::to_string(i) + " has the wrong number of coefficients";
  if (offset[modes] != coefficients.size()) return "transfer coefficient count does not match its orders";
  if (relative_error.size() != modes) return "transfer error estimates do not match its modes";
  for (const std::complex<float>& c : coefficients)
    if (!std::isfinite(c.real()) || !std::isfinite(c.imag())) return "a transfer coefficient is not finite";
  for (float e : relative_error)
    if (!(e >= 0.0f)) return "a transfer error estimate is negative or not a number";
  for (double v : centre_m)
    if (!std::isfinite(v)) return "the transfer centre is not finite";
  for (double v : translation_dipole_m3)
    if (!std::isfinite(v)) return "the translation dipole is not finite";
  return {};
}

void realSphericalHarmonics(uint32_t order, const double direction[3], double* out) {
  double x = direction[0], y = direction[1], z = direction[2];
  const double r = std::sqrt(x * x + y * y + z * z);
  if (r > 0.0 && std::isfinite(r)) {
    x /= r, y /= r, z /= r;
  } else {
    x = 0.0, y = 0.0, z = 1.0;
  }
  const int L = static_cast<int>(order);
  // Fully normalized associated Legendre functions divided by sin^m(theta), by the standard
  // stable recurrences (no factorials, so no overflow at high order):
  //   Pbar_m^m = sqrt((2m+1)/(2m)) Pbar_{m-1}^{m-1},  Pbar_0^0 = 1/sqrt(4 pi),
  //   Pbar_n^m = a (z Pbar_{n-1}^m - b Pbar_{n-2}^m),  a = sqrt((4n^2-1)/(n^2-m^2)),
  //   b = sqrt(((n-1)^2-m^2)/(4(n-1)^2-1));
  // sin^m(theta) cos(m phi) and sin^m(theta) sin(m phi) are Re and Im of (x + i y)^m.
  double cos_m = 1.0, sin_m = 0.0;      // Re, Im of (x + i y)^m
  double p_mm = 0.5 / std::sqrt(M_PI);  // Pbar_m^m / sin^m
  for (int m = 0; m <= L; ++m) {
    if (m > 0) {
      const double c = cos_m * x - sin_m * y, s = cos_m * y + sin_m * x;
      cos_m = c, sin_m = s;
      p_mm *= std::sqrt((2.0 * m + 1.0) / (2.0 * m));
    }
    double p_prev = 0.0, p = p_mm;
    for (int n = m; n <= L; ++n) {
      if (n > m) {
        const double nn = n, mm = m;
        const double a = std::sqrt((4.0 * nn * nn - 1.0) / (nn * nn - mm * mm));
        const double b = std::sqrt(((nn - 1.0) * (nn - 1.0) - mm * mm) / (4.0 * (nn - 1.0) * (nn - 1.0) - 1.0));
        const double next = a * (z * p - b * p_prev);
        p_prev = p, p = next;
      }
      if (m == 0) {
        out[n * n + n] = p;
      } else {
        out[n * n + n + m] = M_SQRT2 * p * cos_m;
        out[n * n + n - m] = M_SQRT2 * p * sin_m;
      }
    }
  }
}

void evaluateFarField(const AcousticTransfer& transfer, const double* sh, std::complex<double>* out) {
  const size_t modes = transfer.modeCount();
  for (size_t i = 0; i < modes; ++i) {
    double re = 0.0, im = 0.0;
    const std::complex<float>* c = transfer.coefficients.data() + transfer.offset[i];
    const uint64_t count = transfer.offset[i + 1] - transfer.offset[i];
    for (uint64_t j = 0; j < count; ++j) {
      re += sh[j] * c[j].real();
      im += sh[j] * c[j].imag();
    }
    out[i] = {re, im};
  }
}

}  // namespace strike
