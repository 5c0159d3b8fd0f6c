// SPDX-License-Identifier: MIT
// The far field of a solve, projected on spherical harmonics.
#pragma once

#include <vector>

#include "../modal/two_parts.hpp"
#include "pieces.hpp"
#include "surface.hpp"

namespace strike::transfer {

/// Spherical-harmonic coefficients of the far fields of several solutions at one wavenumber.
/// F(d) = (1/4pi) int (p dE/dn - q E) dS with E = e^{-ik d.(y - c)} (c: the centre), summed
/// over the pieces with their moments (E over a piece ~ E(centroid) (1 - k^2 d.C.d / 2), and
/// int q E ~ E(centroid) (Q - ik d.D)), at the nodes of a product rule (Gauss-Legendre in
/// cos theta, uniform in phi) that integrates Y_nm Y_n'm' exactly up to n_cap + 1; then
/// c_nm = int F Y_nm dOmega. A direction d and its opposite share their exponentials
/// (E(-d) = conj E(d)). p[r], p_diff[r]: per cluster; coef[r], dcoef[r]: (n_cap + 1)^2 each.
void projectFarField(const Surface& s, const Pieces& pc, const PieceData& pd, const std::vector<NodeData>& data,
                     double k, int n_cap, const std::vector<Eigen::VectorXcd>& p,
                     const std::vector<Eigen::VectorXcd>& p_diff, std::vector<std::vector<cd>>& coef,
                     std::vector<std::vector<cd>>& dcoef, TwoParts& parts);

}  // namespace strike::transfer
