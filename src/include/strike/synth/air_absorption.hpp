// SPDX-License-Identifier: MIT
// Air absorption: how much a pure tone weakens per metre of air, per ISO 9613-1:1993
// ("Acoustics - Attenuation of sound during propagation outdoors - Part 1: Calculation of the
// absorption of sound by the atmosphere"), from temperature, humidity and pressure. Every mode is
// a sinusoid, so a path of length r weakens mode i by 10^(-alpha(f_i) r / 20): one gain per mode
// and path, applied when the path is evaluated (sound_paths.cpp; docs/listener.md).
#pragma once

namespace strike {

struct AirConditions {
  double temperature_c = 20.0;
  double relative_humidity_percent = 50.0;
  double pressure_kpa = 101.325;
};

/// The pure-tone attenuation coefficient alpha of ISO 9613-1 eq. (5), dB per metre, at f_hz.
double airAttenuationDbPerM(double f_hz, const AirConditions& air);

}  // namespace strike
