// SPDX-License-Identifier: MIT
// What a mode's estimate is made of beyond the coarse solve's difference (clusters.hpp): the
// spherical-harmonic series' tail.
#pragma once

#include <vector>

#include "kernels.hpp"

namespace strike::transfer {

/// The energy a mode's far field may leave beyond its kept order, relative to its total: 1e-8
/// (-80 dB), far below the target, so that the modes of a degenerate pair, truncated apart,
/// still sum basis-free.
constexpr double kTailEnergy = 1e-8;

/// Whether the far fields `coef` (up to order n_top) of the modes not yet done have converged
/// there: their two top orders hold at most kTailEnergy of their energy, so that the order kept
/// is below n_top - 1 and the orders beyond n_top (falling faster still past kR) hold less.
bool seriesConverged(const std::vector<std::vector<cd>>& coef, const std::vector<char>& done, int n_top);

}  // namespace strike::transfer
