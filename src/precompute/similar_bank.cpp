// SPDX-License-Identifier: MIT
#include "strike/precompute/similar_bank.hpp"

#include <charconv>
#include <cmath>
#include <string>

#include "strike/precompute/precompute.hpp"
#include "strike/bank/radiation_strength.hpp"

namespace strike {

AcousticTransfer scaledTransfer(const AcousticTransfer& from, size_t keep, double scale, double shape_factor) {
  AcousticTransfer to = from;
  for (int a = 0; a < 3; ++a) to.centre_m[a] = from.centre_m[a] * scale;
  to.order.resize(keep);
  to.offset.resize(keep + 1);
  to.relative_error.resize(keep);
  to.coefficients.resize(to.offset[keep]);
  const float factor = static_cast<float>(shape_factor * scale * scale);
  for (std::complex<float>& c : to.coefficients) c *= factor;
  for (double& m : to.translation_dipole_m3) m *= scale * scale * scale;
  return to;
}

Result<ModeBank> similarBank(const ModeBank& solved, double scale, const Material& material, double max_freq_hz,
                             const std::string& mesh_spec, const TransferSettings* transfer_settings) {
  auto text = [](double v) {  // shortest round-trip form: 0.1, not 0.10000000000000001
    char buffer[32];
    const std::to_chars_result end = std::to_chars(buffer, buffer + sizeof buffer, v);
    return std::string(buffer, end.ptr);
  };
  if (!(scale > 0 && std::isfinite(scale))) return badInput("scale = " + text(scale) + " (must be > 0)");
  if (material.poisson != solved.material.poisson)
    return badInput("material poisson = " + text(material.poisson) + " differs from the solved bank's " +
                    text(solved.material.poisson) + ": the mode shapes are not similar; solve it");
  if (!(material.youngs_pa > 0 && material.density_kg_m3 > 0))
    return badInput("material youngs_pa = " + text(material.youngs_pa) +
                    ", density_kg_m3 = " + text(material.density_kg_m3) + " (must be > 0)");
  if (solved.shapes.size() != solved.modeCount() * solved.surfaceVertexCount() * 3)
    return badInput("the solved bank's shapes are not loaded");
  const double density_ratio = material.density_kg_m3 / solved.material.density_kg_m3;
  const double lambda_factor = (material.youngs_pa / solved.material.youngs_pa) / (density_ratio * scale * scale);
  const double shape_factor = 1.0 / std::sqrt(density_ratio * scale * scale * scale);

  // Which modes the new object keeps: those up to max_freq_hz, at most max_modes. The solved
  // bank holds every mode up to its own cut-off (or max_modes of them), so unless it was capped by
  // max_modes, a mode above its last one may be missing: the new cut-off must not reach past it.
  const double omega_max = 2.0 * M_PI * max_freq_hz;
  size_t keep = 0;
  while (keep < solved.modeCount() && keep < solved.max_modes &&
         solved.eigenvalues[keep] * lambda_factor <= omega_max * omega_max)
    ++keep;
  const bool capped = solved.modeCount() >= solved.max_modes;
  const double solved_band_lambda = std::pow(2.0 * M_PI * solved.max_freq_hz, 2) * lambda_factor;
  if (keep == solved.modeCount() && !capped && solved_band_lambda < omega_max * omega_max)
    return badInput("scale " + text(scale) + " and this material put the solved band's top (" +
                    text(solved.max_freq_hz) + " Hz) at " + text(std::sqrt(solved_band_lambda) / (2 * M_PI)) +
                    " Hz, below the cut-off " + text(max_freq_hz) + " Hz: modes above it were never solved");

  ModeBank out = solved;
  out.material = material;
  out.mesh_source = mesh_spec;
  out.mesh_hash = fnv1a64(mesh_spec.data(), mesh_spec.size());
  out.target_edge_m = solved.target_edge_m * scale;
  out.max_freq_hz = max_freq_hz;
  out.mass_kg = solved.mass_kg * density_ratio * scale * scale * scale;
  out.volume_m3 = solved.volume_m3 * scale * scale * scale;
  for (double& c : out.centre_m) c *= scale;
  for (double& i : out.inertia_kg_m2) i *= density_ratio * std::pow(scale, 5);
  for (double& p : out.surface_positions) p *= scale;
  out.eigenvalues.resize(keep);
  for (double& lambda : out.eigenvalues) lambda *= lambda_factor;
  if (!out.frequency_error_estimate.empty()) out.frequency_error_estimate.resize(keep);  // relative: unchanged
  out.shapes.resize(keep * solved.surfaceVertexCount() * 3);
  for (float& v : out.shapes) v = static_cast<float>(v * shape_factor);
  out.above_cutoff_dropped = 0;
  out.radiation_m2 = radiationStrengths(out);

  // The acoustic transfer. The exterior problem of the scaled body at k' = k sqrt(E'rho/(E rho'))
  // / s with data scaled by shape_factor has, when ka is unchanged (E/rho unchanged), the
  // solution p'(s x) = shape_factor s p(x), so F' = shape_factor s^2 F, the dipole tensor M s^3
  // and the centre s c. Otherwise ka changes and the far field is not similar: solve it again on
  // the scaled bank (so does a normalized solve, which has none).
  const double ka_factor = std::sqrt(lambda_factor) * scale;  // omega' / omega times s
  out.transfer = AcousticTransfer{};
  if (!solved.transfer.offset.empty() && std::abs(ka_factor - 1.0) <= 1e-12) {
    // The kept modes that have a transfer (format 6: the heard ones of the solved bank).
    out.transfer = scaledTransfer(solved.transfer, std::min(keep, solved.transfer.modeCount()), scale, shape_factor);
    out.transfer_seconds = 0.0;
  } else if (transfer_settings) {
    if (Status transfer = solveTransferInto(out, *transfer_settings, max_freq_hz); !transfer) return transfer.error();
  }
  return out;
}

}  // namespace strike
