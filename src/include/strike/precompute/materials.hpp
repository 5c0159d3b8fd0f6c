// SPDX-License-Identifier: MIT
// The material table (assets/materials.json, compiled into the tool) and material checks.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "strike/core/material.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// Rigid-body contact coefficients (for the simulator only).
struct ContactProperties {
  double restitution = 0.5;
  double friction = 0.5;
  /// Coefficient of rolling resistance c_rr = F / N, dimensionless (docs/contact.md).
  double rolling_resistance = 0.001;
  /// Surface roughness for rolling and sliding sound (docs/contact.md): rms height R_q and
  /// correlation length of the surface profile, m. 0 rms: smooth (silent rolling and sliding).
  double roughness_rms_m = 0.0;
  double roughness_correlation_m = 0.0;
};

struct MaterialTable {
  std::map<std::string, Material> materials;         ///< by lower-case name
  std::map<std::string, std::string> sources;        ///< where each entry's numbers come from
  std::map<std::string, ContactProperties> contact;  ///< by lower-case name
  double fit_band_low_hz = 500.0, fit_band_high_hz = 5000.0;

  /// The named material's contact coefficients, or the defaults for custom materials.
  ContactProperties contactProperties(const std::string& name) const;

  /// The named material (case-insensitive), or an error listing the known names.
  Result<Material> find(const std::string& name) const;
  std::vector<std::string> names() const;
};

/// Parses a material table in the format of assets/materials.json; `source` names it in errors.
Result<MaterialTable> parseMaterialTable(const std::string& json_text, const std::string& source);
/// The table compiled into this build from assets/materials.json.
const MaterialTable& builtinMaterials();

/// Rayleigh coefficients whose damping ratio equals loss_factor / 2 at f_low and f_high:
/// xi(w) = a2 / (2 w) + a1 w / 2  =>  a1 = eta / (w1 + w2),  a2 = eta w1 w2 / (w1 + w2).
void rayleighFromLossFactor(double loss_factor, double f_low_hz, double f_high_hz, double& rayleigh_stiffness,
                            double& rayleigh_mass);

/// Checks ranges: E > 0, -1 < nu < 0.5, rho > 0, a1 >= 0, a2 >= 0, all finite. The error names
/// the field and value, prefixed by `where` (e.g. "--poisson" or "objects[2].material").
Status validateMaterial(const Material& material, const std::string& where);

}  // namespace strike
