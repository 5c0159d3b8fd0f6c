// SPDX-License-Identifier: MIT
// The listener model: one set of constants and one distance law for `strike render`, `strike
// hit` and libstrike. Target strike_synth (C++ standard library only).
//
// A sounding body is a point source at the listener's distance d: its modes' pressure weights
// are the radiated pressure at the reference distance (radiationWeights(bank, reference)), the
// level falls as reference / d (spherical spreading, Kinsler et al., Fundamentals of Acoustics,
// 4th ed., 2000, sec. 5.11) and each contact is heard d / c after it happens. Closer than
// kMinListenerDistance_m the point-source law would blow up, so it stops growing there.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

namespace strike {

constexpr double kSpeedOfSoundAir_m_s = 343.0;  ///< dry air at 20 C
constexpr double kAirDensity_kg_m3 = 1.204;     ///< dry air at 20 C, 101.325 kPa
/// The point-source law 1/d holds down to this distance; nearer, the level stays put.
constexpr double kMinListenerDistance_m = 0.05;
/// Distance at which a mode's pressure weight is computed (radiationWeights); the level at
/// distance d is this over d.
constexpr double kReferenceDistance_m = 1.0;

/// Gain relative to the level at reference_m for a source at distance_m.
inline double distanceGain(double distance_m, double reference_m = kReferenceDistance_m,
                           double min_distance_m = kMinListenerDistance_m) {
  return reference_m / std::max(distance_m, min_distance_m);
}

/// Seconds from a contact at distance_m to the listener hearing it.
inline double propagationDelay_s(double distance_m) { return distance_m / kSpeedOfSoundAir_m_s; }

inline double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace strike
