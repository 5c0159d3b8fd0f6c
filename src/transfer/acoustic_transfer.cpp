// SPDX-License-Identifier: MIT
// AcousticTransfer's data helpers (acoustic_transfer.hpp). C++ standard library only: libstrike
// reads banks with a transfer.
#include "strike/transfer/acoustic_transfer.hpp"

#include <cmath>
#include <string>

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

}  // namespace strike
