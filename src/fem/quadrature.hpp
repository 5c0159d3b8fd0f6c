// SPDX-License-Identifier: MIT
// Quadrature rules on the reference tetrahedron {xi, eta, zeta >= 0, xi + eta + zeta <= 1}
// (volume 1/6). Points are barycentric (L0, L1, L2, L3) with xi = L1, eta = L2, zeta = L3;
// weights sum to 1/6. Internal to strike_fem (tests include it to check the rules' degrees).
#pragma once

#include <array>
#include <vector>

namespace strike::fem {

struct QuadPoint {
  std::array<double, 4> bary;
  double weight;
};

/// Degree 2, 4 points (Keast 1986, rule 2): exact for the Tet10 stiffness integrand on
/// straight-edged tets (products of linear gradients).
const std::vector<QuadPoint>& tetRuleDegree2();

/// Degree 5, 14 points, all weights positive (Walkington, "Quadrature on simplices of
/// arbitrary dimension", 2000): exact for the Tet10 consistent mass (degree 4) on
/// straight-edged tets, and positive weights keep M positive definite on curved ones.
const std::vector<QuadPoint>& tetRuleDegree5();

}  // namespace strike::fem
