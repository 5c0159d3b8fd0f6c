// SPDX-License-Identifier: MIT
// The contact properties of a scene's objects and of its ground, resolved once: the scene's own
// value where it gives one, else its material's (assets/materials.json). The simulation
// (restitution, friction, rolling resistance, compliance) and the sound engine (restitution,
// roughness) read the same numbers.
#pragma once

#include "strike/synth/contact_noise.hpp"
#include "strike/core/material.hpp"
#include "strike/scene/scene.hpp"

namespace strike {

struct SurfaceProperties {
  double restitution = 0.5;
  double friction = 0.5;
  double rolling_resistance = 0.001;
  double compliance_per_pa = 0.0;  ///< (1 - nu^2) / E: how its restitution weighs (combineContact)
  /// For rolling and sliding sound, seeded by the surface's name: each surface has its own
  /// profile, the same in every render. rms 0 (smooth) without a correlation length.
  SurfaceRoughness roughness;
};

/// An object of `material` (its bank's), with the object's own keys where it gives them.
SurfaceProperties objectSurface(const SceneObject& object, const Material& material);
/// The scene's ground: its material's, with the scene's "ground" keys where it gives them.
SurfaceProperties groundSurface(const Scene& scene);

}  // namespace strike
