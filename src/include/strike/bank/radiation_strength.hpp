// SPDX-License-Identifier: MIT
// The listener model's radiation strength of each mode, computed from a bank's surface and
// shapes: the precompute stores it in the bank (radiation_m2), the synthesizer reads it.
#pragma once

#include <vector>

#include "strike/bank/bank.hpp"

namespace strike {

/// The distance-free part of radiationWeights: R_i per mode (m^2 / sqrt(kg)), computed from the
/// surface and shapes. radiationWeights uses bank.radiation_m2 instead when the bank has it.
std::vector<double> radiationStrengths(const ModeBank& bank);

}  // namespace strike
