// SPDX-License-Identifier: MIT
// AcousticTransfer's data helpers and its evaluation at a direction (acoustic_transfer.hpp).
// C++ standard library only, no allocation in the evaluation: libstrike calls it per impact.
#include "strike/acoustic_transfer.hpp"

#include <cmath>

namespace strike {

uint32_t AcousticTransfer::maxOrder() const {
  uint32_t largest = 0;
  for (uint32_t n : order) largest = n > largest ? n : largest;
  return largest;
}

double AcousticTransfer::rmsFarField(size_t mode) const {
  if (mode + 1 >= offset.size() || offset[mode + 1] > coefficients.size()) return 0.0;
  double sum = 0.0;
  for (uint64_t j = offset[mode]; j < offset[mode + 1]; ++j) sum += std::norm(coefficients[j]);
  // Parseval over the unit sphere: int |F|^2 dOmega = sum |c|^2 (orthonormal Y_nm).
  return std::sqrt(sum / (4.0 * M_PI));
}

std::string AcousticTransfer::checkConsistency(size_t modes) const {
  if (order.size() != modes)
    return "transfer has " + std::to_string(order.size()) + " modes, the bank " + std::to_string(modes);
  if (offset.size() != modes + 1)
    return "transfer offsets: " + std::to_string(offset.size()) + " entries, expected " + std::to_string(modes + 1);
  if (relative_error.size() != modes)
    return "transfer errors: " + std::to_string(relative_error.size()) + " entries, expected " + std::to_string(modes);
  if (offset[0] != 0) return "transfer offset[0] = " + std::to_string(offset[0]) + " (must be 0)";
  for (size_t i = 0; i < modes; ++i) {
    const uint64_t count = uint64_t(order[i] + 1) * uint64_t(order[i] + 1);
    if (offset[i + 1] < offset[i] || offset[i + 1] - offset[i] != count)
      return "transfer mode " + std::to_string(i) + ": order " + std::to_string(order[i]) + " needs " +
             std::to_string(count) + " coefficients, offsets give " +
             std::to_string(static_cast<int64_t>(offset[i + 1] - offset[i]));
    if (!(relative_error[i] >= 0)) return "transfer mode " + std::to_string(i) + ": relative error is not >= 0";
  }
  if (offset[modes] != coefficients.size())
    return "transfer offsets end at " + std::to_string(offset[modes]) + ", " + std::to_string(coefficients.size()) +
           " coefficients stored";
  for (size_t j = 0; j < coefficients.size(); ++j)
    if (!std::isfinite(coefficients[j].real()) || !std::isfinite(coefficients[j].imag()))
      return "transfer coefficient " + std::to_string(j) + " is not finite";
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(centre_m[a])) return "transfer centre is not finite";
  for (double m : translation_dipole_m3)
    if (!std::isfinite(m)) return "transfer translation dipole is not finite";
  return {};
}

void realSphericalHarmonics(uint32_t order, const double direction[3], double* out) {
  double x = direction[0], y = direction[1], z = direction[2];
  const double length = std::sqrt(x * x + y * y + z * z);
  if (length > 0 && std::isfinite(length)) {
    x /= length;
    y /= length;
    z /= length;
  } else {
    x = 0.0;
    y = 0.0;
    z = 1.0;
  }
  // Fully normalized associated Legendre recurrences in z, times Re/Im (x + i y)^m, which is
  // sin^m(theta) cos/sin(m phi): no trigonometry, no pole special case, no Condon-Shortley phase
  // (so Y_11 = +sqrt(3/4pi) x). Q_n^m = N_n^m P_n^m / sin^m; stable to high order.
  const int n_max = static_cast<int>(order);
  double q_mm = 1.0 / std::sqrt(4.0 * M_PI);  // Q_0^0
  double c_m = 1.0, s_m = 0.0;                // Re, Im of (x + i y)^m
  for (int m = 0; m <= n_max; ++m) {
    if (m > 0) {
      q_mm *= std::sqrt((2.0 * m + 1.0) / (2.0 * m));
      const double c = x * c_m - y * s_m;
      s_m = x * s_m + y * c_m;
      c_m = c;
    }
    const double cos_factor = m == 0 ? 1.0 : M_SQRT2 * c_m;
    const double sin_factor = M_SQRT2 * s_m;
    double q_prev = 0.0, q = q_mm;  // Q_{n-1}^m, Q_n^m
    for (int n = m; n <= n_max; ++n) {
      if (n == m + 1) {
        q_prev = q;
        q = std::sqrt(2.0 * m + 3.0) * z * q_mm;
      } else if (n > m + 1) {
        const double nn = n, mm = m;
        const double a = std::sqrt((4.0 * nn * nn - 1.0) / (nn * nn - mm * mm));
        const double b = std::sqrt(((nn - 1.0) * (nn - 1.0) - mm * mm) / (4.0 * (nn - 1.0) * (nn - 1.0) - 1.0));
        const double next = a * (z * q - b * q_prev);
        q_prev = q;
        q = next;
      }
      out[n * n + n + m] = q * cos_factor;
      if (m > 0) out[n * n + n - m] = q * sin_factor;
    }
  }
}

void evaluateFarField(const AcousticTransfer& transfer, const double* sh, std::complex<double>* out) {
  const size_t modes = transfer.modeCount();
  for (size_t i = 0; i < modes; ++i) {
    const std::complex<float>* c = transfer.coefficients.data() + transfer.offset[i];
    const size_t count = static_cast<size_t>(transfer.offset[i + 1] - transfer.offset[i]);
    double re = 0.0, im = 0.0;
    for (size_t j = 0; j < count; ++j) {
      re += static_cast<double>(c[j].real()) * sh[j];
      im += static_cast<double>(c[j].imag()) * sh[j];
    }
    out[i] = {re, im};
  }
}

}  // namespace strike
