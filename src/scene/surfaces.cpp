// SPDX-License-Identifier: MIT
#include "surfaces.hpp"

#include <cmath>

#include "strike/core/hash.hpp"
#include "strike/precompute/materials.hpp"

namespace strike {
namespace {

double orDefault(double given, double fallback) { return std::isnan(given) ? fallback : given; }

SurfaceProperties resolve(const Material& material, double restitution, double friction, double rolling_resistance,
                          double roughness_rms_m, double roughness_correlation_m, const std::string& name) {
  const ContactProperties table = builtinMaterials().contactProperties(material.name);
  SurfaceProperties s;
  s.restitution = orDefault(restitution, table.restitution);
  s.friction = orDefault(friction, table.friction);
  s.rolling_resistance = orDefault(rolling_resistance, table.rolling_resistance);
  s.compliance_per_pa = (1.0 - material.poisson * material.poisson) / material.youngs_pa;
  s.roughness.rms_m = orDefault(roughness_rms_m, table.roughness_rms_m);
  s.roughness.correlation_m = orDefault(roughness_correlation_m, table.roughness_correlation_m);
  s.roughness.seed = fnv1a64(name.data(), name.size());
  if (!(s.roughness.correlation_m > 0.0)) s.roughness.rms_m = 0.0;
  return s;
}

}  // namespace

SurfaceProperties objectSurface(const SceneObject& object, const Material& material) {
  return resolve(material, object.restitution, object.friction, object.rolling_resistance, object.roughness_rms_m,
                 object.roughness_correlation_m, object.name);
}

SurfaceProperties groundSurface(const Scene& scene) {
  return resolve(scene.ground_material, scene.ground_restitution, scene.ground_friction,
                 scene.ground_rolling_resistance, NAN, NAN, "ground");
}

}  // namespace strike
