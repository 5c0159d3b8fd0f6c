// SPDX-License-Identifier: MIT
// Exact similarity of linear-elastic modes. An object that differs from a
// solved one only by a uniform scale s of its geometry and by Young's modulus E and density rho
// (the same Poisson ratio) has K' = (E'/E) s K and M' = (rho'/rho) s^3 M on the scaled mesh, so
// the same mode shapes with
//   lambda' = lambda (E'/E) / ((rho'/rho) s^2)      (frequencies scale as sqrt(E/rho) / L)
//   phi'    = phi / sqrt((rho'/rho) s^3)            (mass normalization phi^T M phi = 1)
// Rayleigh damping is the new material's (applied per mode from lambda', as always), and the
// radiation strengths are recomputed from the scaled surface and shapes. The acoustic transfer
// is scaled exactly when ka is unchanged (E/rho unchanged: F' = F s^2 / sqrt((rho'/rho) s^3)),
// else solved again on the scaled bank (src/precompute/similar_bank.cpp). Banks scaled from a
// normalized solve get theirs from the unit transfer of their wave speed instead
// (attachUnitTransfer, normalized_problem.hpp), solved once for every size.
#pragma once

#include <string>

#include "strike/bank/bank.hpp"
#include "strike/core/material.hpp"
#include "strike/core/result.hpp"
#include "strike/transfer/transfer_solver.hpp"

namespace strike {

/// The bank of `solved`'s object scaled by `scale` and made of `material` (same Poisson ratio),
/// keeping the modes up to `max_freq_hz` (at most the bank's own max_modes). `mesh_spec` names
/// the new object in the bank's provenance (its hash becomes mesh_hash). Fails, naming the value,
/// when the Poisson ratio differs, the scale is not positive, or the new object needs modes above
/// the highest one solved (its cut-off would fall above the solved band).
/// `transfer`: how to solve the acoustic transfer when it cannot be scaled (null: leave it empty
/// then).
Result<ModeBank> similarBank(const ModeBank& solved, double scale, const Material& material, double max_freq_hz,
                             const std::string& mesh_spec, const TransferSettings* transfer = nullptr);

/// The transfer of a body scaled by `scale` whose mode shapes are `shape_factor` times those
/// `from` was solved for, at the same ka per mode (the frequencies times 1 / scale): its first
/// `keep` modes (keep <= from.modeCount()), F' = shape_factor scale^2 F (rounded once to float),
/// the dipole tensor times scale^3 and the centre times scale. The same bits from the same inputs,
/// whichever body is scaled first.
AcousticTransfer scaledTransfer(const AcousticTransfer& from, size_t keep, double scale, double shape_factor);

}  // namespace strike
