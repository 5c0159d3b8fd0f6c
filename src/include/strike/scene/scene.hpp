// SPDX-License-Identifier: MIT
// The scene file (JSON, docs/scene-format.md): what is in the world, how it moves at t = 0, and
// where the listener is. Parsing is strict: unknown keys and wrong types are errors that name
// the key path and the value.
#pragma once

#include "strike/synth/air_absorption.hpp"

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "strike/core/material.hpp"
#include "strike/sim/path.hpp"
#include "strike/core/result.hpp"

namespace strike {

struct SceneObject {
  std::string name;
  std::string mesh;  ///< primitive spec, or a path resolved against the scene's folder
  std::string bank;  ///< optional precomputed bank path (resolved); empty: compute or cache
  Material material;
  std::string units = "m";     ///< unit of the mesh file's coordinates: "m", "cm" or "mm"
  double mesh_scale = 1.0;     ///< metres per mesh unit (1, 0.01, 0.001), from units
  int order = 0;               ///< element order when the bank is computed; 0: kAutoOrder
  double size_m = 0.0;         ///< target tet edge when the bank is computed (0 = automatic)
  bool is_static = false;      ///< never moves (a table); still sounds when struck
  std::string shape = "auto";  ///< collision shape: auto, convex, pieces, concave (docs/contact.md)
  std::array<double, 3> position_m{};
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};
  std::array<double, 3> velocity_m_s{};
  std::array<double, 3> angular_velocity_rad_s{};
  /// Own contact coefficients, overriding the material's ("restitution", "friction",
  /// "rolling_resistance"); NaN: the material's. Two bodies combine theirs (docs/contact.md).
  double restitution = NAN, friction = NAN, rolling_resistance = NAN;
  /// Own surface roughness for rolling and sliding sound ("roughness_rms_m",
  /// "roughness_correlation_m", m); NaN: the material's (docs/contact.md).
  double roughness_rms_m = NAN, roughness_correlation_m = NAN;
  /// "path": keyframes a hand moves the object along (a driven body, SimBodyDesc::path); empty:
  /// it moves freely from position_m with its velocities.
  std::vector<PathKey> path;
};

/// A scene's "contacts" entry: coefficients for one pair of objects ("ground" names the ground),
/// used as they are (no combination). NaN: not overridden.
struct ContactPairSpec {
  std::string object_a, object_b;
  double restitution = NAN, friction = NAN, rolling_resistance = NAN;
};

struct Scene {
  std::string path;  ///< the scene file, for messages
  double sample_rate_hz = 48000.0;
  double duration_s = 3.0;
  std::array<double, 3> gravity_m_s2{0, 0, -9.81};
  std::array<double, 3> listener_position_m{0, -1, 0.5};
  /// World from listener (w, x, y, z): the listener faces its +y with +x to its right and +z up
  /// (docs/listener.md). Identity: facing +y. From listener.orientation or listener.look_at.
  std::array<double, 4> listener_orientation_wxyz{1, 0, 0, 0};
  /// Air absorption (ISO 9613-1) on every path, from "air": off unless the scene has it.
  bool air_absorption = false;
  AirConditions air;
  bool has_ground = true;
  Material ground_material;  ///< concrete unless given
  double ground_height_m = 0.0;
  double ground_restitution = NAN, ground_friction = NAN;  ///< NaN: the ground material's
  double ground_rolling_resistance = NAN;                  ///< NaN: the ground material's
  /// The ground reflects sound (an image source). ground.reflection: false turns it off.
  bool ground_reflects = true;
  /// Pressure reflection coefficient; NaN: the ground material's at normal incidence,
  /// groundReflectionCoefficient().
  double ground_reflection = NAN;
  std::vector<ContactPairSpec> contact_pairs;
  /// Extra amplitude decay (1/s) of a body's modes while it rests on or slides along something:
  /// the vibration it loses into its support. A phenomenological model (the support's impedance
  /// is not computed); 0 turns it off. 8/s gives a ringing body at rest a T60 under 0.9 s.
  double contact_damping_per_s = 8.0;
  double max_freq_hz = 20000.0;  ///< modes computed up to this (and never above 0.45 sample rate when synthesized)
  int max_modes = 200;
  std::vector<SceneObject> objects;
};

/// The keys the parser accepts, per place in the file ("top level", "listener", "ground",
/// "objects[]", "material"): the one table both the parser and the documentation test read.
struct SceneKeyTable {
  const char* where;
  std::vector<const char*> keys;
};
const std::vector<SceneKeyTable>& sceneKeyTables();

/// A solid half-space's pressure reflection coefficient at normal incidence,
/// (Z - rho c) / (Z + rho c) with Z = rho_s c_p its longitudinal impedance and rho c the air's
/// [Kinsler et al. 2000, sec. 6.2]: 0.9999 for concrete, so solid floors are rigid to air.
double groundReflectionCoefficient(const Material& material);

/// Parses scene JSON. `path` names the file in messages and anchors relative paths.
Result<Scene> parseScene(const std::string& json_text, const std::string& path);
/// Reads and parses a scene file (at most 64 MiB).
Result<Scene> loadScene(const std::string& path);

}  // namespace strike
