// SPDX-License-Identifier: MIT
// An isotropic linear-elastic material with Rayleigh damping C = a1 K + a2 M.
#pragma once

#include <string>

namespace strike {

struct Material {
  std::string name;                 ///< "steel", or "custom" when given by numbers
  double youngs_pa = 0.0;           ///< Young's modulus E, Pa (steel ~2.0e11)
  double poisson = 0.0;             ///< Poisson ratio nu, in (-1, 0.5)
  double density_kg_m3 = 0.0;       ///< rho, kg/m^3 (steel ~7850)
  double rayleigh_stiffness = 0.0;  ///< a1, s: damping proportional to K (grows with frequency)
  double rayleigh_mass = 0.0;       ///< a2, 1/s: damping proportional to M (uniform decay)
};

/// Damping coefficient c = a1 lambda + a2 (1/s) of a mode with eigenvalue lambda (rad^2/s^2).
/// Under-damped modes decay as exp(-c t / 2).
inline double rayleighDamping(double rayleigh_stiffness, double rayleigh_mass, double lambda) {
  return rayleigh_stiffness * lambda + rayleigh_mass;
}

}  // namespace strike
