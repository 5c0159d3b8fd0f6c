// SPDX-License-Identifier: MIT
// The acoustic transfer's memory forecast and its budget check (precompute.hpp). The figure is
// the transfer solver's: whoever changes what the solver holds changes it here in the same commit.
#include <cstdio>
#include <string>

#include "strike/modal.hpp"
#include "strike/precompute.hpp"

namespace strike {

double transferMemoryForecastBytes(const ModeBank& bank, const TransferSettings& settings) {
  // One group's system at a time (transferSystemBytes, transfer_solver.hpp): a dense complex
  // matrix of at most max_elements unknowns (rows: the collocation points and the interior CHIEF
  // points, at most a tenth more) in double with its single-precision copy (LU / QR), and the
  // coarse solve's beside it; GMRES's basis above 700 unknowns is 61 vectors, small beside it.
  // Beside it the surface's quadrature data (~1 KB a triangle) and each mode's far field (a few
  // KB). An upper bound of the order of what the solver holds, not a measurement.
  const double elements = settings.fixed_elements > 0 ? settings.fixed_elements : settings.max_elements;
  const double system = transferSystemBytes(static_cast<uint64_t>(elements));
  const double surface = 1024.0 * static_cast<double>(bank.surface_triangles.size() / 3);
  const double far_fields = 8192.0 * static_cast<double>(bank.modeCount());
  return system + surface + far_fields;
}

Status checkTransferMemory(const ModeBank& bank, const TransferSettings& settings, double max_bytes) {
  const double forecast = transferMemoryForecastBytes(bank, settings);
  if (!(max_bytes > 0.0) || forecast <= max_bytes) return {};
  return badInput("the acoustic transfer of " + std::to_string(bank.modeCount()) + " modes would need about " +
                  memoryText(forecast) + ": more than the memory budget of " + memoryText(max_bytes) +
                  ". Raise --max-memory (default: the memory available), or skip the transfer (--no-transfer)");
}

}  // namespace strike
